// Options whose value is a word: --help lists the words, a bad word is one line naming them.
#include "sensornet/io/word_option.hpp"

#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "sensornet/core/arrival_mode.hpp"
#include "sensornet/planning/planner.hpp"
#include "sensornet/io/command_line.hpp"

namespace sensornet {
namespace {

struct Program {
  CLI::App app{"test program", "prog"};
  PlanSurrogate surrogate = PlanSurrogate::Covariance;
  std::string arrivals;
  std::string network = "auto";
  int bits = 2048;
  Program() {
    wordOption<PlanSurrogate>(app.add_option("--surrogate", surrogate, "how to plan"));
    wordOption(app.add_option("--arrivals", arrivals, "instants"), wordTexts<ArrivalMode>());
    wordOption(app.add_option("--network-aware", network, "plan for the network"),
               {"auto", "yes", "no"});
    wordOption(app.add_option("--rsa-bits", bits, "key size"), {"2048", "3072", "4096"});
  }
  // The exit code parseCommandLine asks for (-1: go on) and what went to standard error.
  std::pair<int, std::string> parse(std::vector<std::string> args) {
    args.insert(args.begin(), "prog");
    std::vector<char*> argv;
    for (std::string& a : args) argv.push_back(a.data());
    testing::internal::CaptureStderr();
    const int code = parseCommandLine(app, static_cast<int>(argv.size()), argv.data()).value_or(-1);
    return {code, testing::internal::GetCapturedStderr()};
  }
};

TEST(WordOption, HelpShowsTheWordsAndTheDefaultAsAWord) {
  Program p;
  const std::string help = p.app.help();
  // CLI11 by itself shows "ENUM:value in {cov->1,info->0,...}" or "TEXT:{poisson,timetable}".
  EXPECT_NE(help.find("--surrogate {info,cov,uniform,mc} [cov]"), std::string::npos) << help;
  EXPECT_NE(help.find("--arrivals {poisson,timetable}"), std::string::npos) << help;
  EXPECT_NE(help.find("--network-aware {auto,yes,no} [auto]"), std::string::npos) << help;
  EXPECT_NE(help.find("--rsa-bits {2048,3072,4096} [2048]"), std::string::npos) << help;
  EXPECT_EQ(help.find("->"), std::string::npos) << help;
  EXPECT_EQ(help.find("ENUM"), std::string::npos) << help;
}

TEST(WordOption, TakesTheWordsInAnyCase) {
  Program p;
  const auto [code, err] =
      p.parse({"--surrogate", "INFO", "--arrivals", "Timetable", "--rsa-bits", "4096"});
  EXPECT_EQ(code, -1) << err;
  EXPECT_EQ(p.surrogate, PlanSurrogate::Information);
  EXPECT_EQ(p.arrivals, "timetable");
  EXPECT_EQ(p.bits, 4096);
}

TEST(WordOption, ABadWordIsOneLineNamingTheWords) {
  Program p;
  const auto [code, err] = p.parse({"--surrogate", "covariance"});
  EXPECT_EQ(code, kExitBadInput);
  EXPECT_EQ(err,
            "prog: error: --surrogate: 'covariance' is not one of info, cov, uniform, mc "
            "(see --help)\n");
  Program q;
  const auto [code2, err2] = q.parse({"--rsa-bits", "1024"});
  EXPECT_EQ(code2, kExitBadInput);
  EXPECT_EQ(err2, "prog: error: --rsa-bits: '1024' is not one of 2048, 3072, 4096 (see --help)\n");
}

}  // namespace
}  // namespace sensornet
