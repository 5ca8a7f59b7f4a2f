// What every program's command line does beyond CLI11: --version, and a mistyped option answered
// with the nearest one the program knows.
#include "sensornet/io/command_line.hpp"

#include <gtest/gtest.h>

#include <fstream>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

namespace sensornet {
namespace {

// A program with a subcommand, as the real ones are built.
struct Program {
  CLI::App app{"test program", "prog"};
  int episodes = 0;
  double scale = 1.0;
  Program() {
    CLI::App* launch = app.add_subcommand("launch", "launch a run");
    launch->add_option("--episodes", episodes);
    launch->add_option("--time-scale", scale);
    launch->add_flag("--json");
    launch->add_flag("--no-html");
  }
  int parse(std::vector<std::string> args) {
    args.insert(args.begin(), "prog");
    std::vector<char*> argv;
    for (std::string& a : args) argv.push_back(a.data());
    return parseCommandLine(app, static_cast<int>(argv.size()), argv.data()).value_or(-1);
  }
};

TEST(CommandLine, NamesTheNearestOptionOfAMistypedOne) {
  Program p;
  (void)p.parse({"launch", "--episodes", "2"});
  EXPECT_EQ(nearestOption(p.app, "--episdoes"), "--episodes");      // two letters swapped
  EXPECT_EQ(nearestOption(p.app, "--time-sclae=2"), "--time-scale");  // with its value
  EXPECT_EQ(nearestOption(p.app, "--jsn"), "--json");
  EXPECT_EQ(nearestOption(p.app, "--html"), "--no-html");          // held in the option
  EXPECT_EQ(nearestOption(p.app, "--episodes-count"), "--episodes");  // holds the option
  EXPECT_FALSE(nearestOption(p.app, "--frobnicate").has_value());  // nothing near
  EXPECT_FALSE(nearestOption(p.app, "-e").has_value());            // not a long option
}

TEST(CommandLine, AMistypedOptionIsOneLineWithTheSuggestionAndExitsTwo) {
  Program p;
  testing::internal::CaptureStderr();
  const int code = p.parse({"launch", "--episdoes", "8"});
  const std::string err = testing::internal::GetCapturedStderr();
  EXPECT_EQ(code, kExitBadInput);
  EXPECT_EQ(err, "prog: error: unknown option --episdoes (did you mean --episodes?) (see --help)\n");
}

TEST(CommandLine, AnUnknownOptionWithAValueIsNamedWithoutCLI11sText) {
  // CLI11 says "The following arguments were not expected: /tmp/x/report.html --html".
  Program p;
  testing::internal::CaptureStderr();
  const int code = p.parse({"launch", "--html", "/tmp/x/report.html"});
  const std::string err = testing::internal::GetCapturedStderr();
  EXPECT_EQ(code, kExitBadInput);
  EXPECT_EQ(err, "prog: error: unknown option --html (did you mean --no-html?) (see --help)\n");
}

TEST(CommandLine, AMistypedRequiredOptionIsNamedRatherThanMissing) {
  // CLI11 says "--scenario is required" and leaves the typo unsaid.
  CLI::App app{"test program", "prog"};
  std::string scenario;
  app.add_option("--scenario", scenario)->required();
  std::vector<std::string> args = {"prog", "--scenaro", "a.yaml"};
  std::vector<char*> argv;
  for (std::string& a : args) argv.push_back(a.data());
  testing::internal::CaptureStderr();
  const auto code = parseCommandLine(app, static_cast<int>(argv.size()), argv.data());
  const std::string err = testing::internal::GetCapturedStderr();
  EXPECT_EQ(code, kExitBadInput);
  EXPECT_EQ(err, "prog: error: unknown option --scenaro (did you mean --scenario?) (see --help)\n");
}

TEST(CommandLine, OptionsOfAnOptionGroupAreNearToo) {
  // sensornet replan's changes are an option group: --inlcude must find --include.
  CLI::App app{"test program", "prog"};
  std::vector<int> include;
  CLI::Option_group* change = app.add_option_group("change", "what to change");
  change->add_option("--include", include);
  change->require_option(1);
  std::vector<std::string> args = {"prog", "--inlcude", "1"};
  std::vector<char*> argv;
  for (std::string& a : args) argv.push_back(a.data());
  testing::internal::CaptureStderr();
  const auto code = parseCommandLine(app, static_cast<int>(argv.size()), argv.data());
  const std::string err = testing::internal::GetCapturedStderr();
  EXPECT_EQ(code, kExitBadInput);
  EXPECT_EQ(err, "prog: error: unknown option --inlcude (did you mean --include?) (see --help)\n");
}

TEST(CommandLine, AStrayArgumentIsNamed) {
  Program p;
  testing::internal::CaptureStderr();
  const int code = p.parse({"launch", "--episodes", "2", "stray.yaml"});
  const std::string err = testing::internal::GetCapturedStderr();
  EXPECT_EQ(code, kExitBadInput);
  EXPECT_EQ(err, "prog: error: unexpected argument 'stray.yaml' (see --help)\n");
}

TEST(CommandLine, VersionPrintsTheProjectsVersionAndExitsZero) {
  // The version CMakeLists.txt declares, read independently of the build's definition.
  std::ifstream cmake(std::string(SENSORNET_SOURCE_DIR) + "/CMakeLists.txt");
  std::stringstream text;
  text << cmake.rdbuf();
  std::smatch m;
  const std::string all = text.str();
  ASSERT_TRUE(std::regex_search(all, m, std::regex(R"(project\(sensornet VERSION ([0-9.]+))")));
  Program p;
  testing::internal::CaptureStdout();
  const int code = p.parse({"--version"});
  const std::string out = testing::internal::GetCapturedStdout();
  EXPECT_EQ(code, kExitOk);
  EXPECT_EQ(out, "prog (sensornet " + m[1].str() + ")\n");
}

}  // namespace
}  // namespace sensornet
