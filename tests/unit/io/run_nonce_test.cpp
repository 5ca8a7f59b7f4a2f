// The run nonce (run_nonce.hpp): files started under one deployment's nonce are not taken for
// another's, files of no recorded nonce are no deployment's, and no nonce at all accepts any
// files (the launcher's restarts, which pass none).

#include "sensornet/io/run_nonce.hpp"

#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <string>

#include "../../support/scratch_dir.hpp"

namespace sensornet {
namespace {

using testing::ScratchDir;

TEST(RunNonce, FilesBelongToTheDeploymentThatStartedThem) {
  ScratchDir dir;
  const std::string journal = dir.write("state/journal.json", "{}");
  EXPECT_TRUE(writtenUnderNonce(journal, "")) << "no nonce given: any files are this run's";
  EXPECT_FALSE(writtenUnderNonce(journal, "svc-1")) << "none recorded: an earlier deployment's";
  EXPECT_EQ(recordedNonce(journal), std::nullopt);

  recordNonce(journal, "svc-1");
  EXPECT_EQ(nonceFileOf(journal), dir / "state/journal.json.nonce");
  EXPECT_EQ(recordedNonce(journal), "svc-1");
  EXPECT_TRUE(writtenUnderNonce(journal, "svc-1"));
  EXPECT_FALSE(writtenUnderNonce(journal, "svc-2"));
  EXPECT_FALSE(writtenUnderNonce(journal, "svc-")) << "a prefix is another nonce";

  recordNonce(journal, "svc-2");  // the next deployment, started afresh over the files
  EXPECT_TRUE(writtenUnderNonce(journal, "svc-2"));
  EXPECT_FALSE(writtenUnderNonce(journal, "svc-1"));

  recordNonce(journal, "");  // started without one: no deployment's files any more
  EXPECT_FALSE(std::filesystem::exists(nonceFileOf(journal)));
  EXPECT_FALSE(writtenUnderNonce(journal, "svc-2"));
}

TEST(RunNonce, TheOptionReadsTheEnvironmentAndTheCommandLineWins) {
  const auto parsed = [](std::vector<std::string> argv) {
    CLI::App app;
    std::string nonce;
    addRunNonceOption(app, nonce, "a journal");
    argv.insert(argv.begin(), "serve");
    std::vector<const char*> args;
    for (const std::string& a : argv) args.push_back(a.c_str());
    app.parse(static_cast<int>(args.size()), args.data());
    return nonce;
  };
  ::unsetenv("SENSORNET_RUN_NONCE");
  EXPECT_EQ(parsed({}), "");
  EXPECT_EQ(parsed({"--run-nonce", "abc"}), "abc");
  ::setenv("SENSORNET_RUN_NONCE", "from-env", 1);
  EXPECT_EQ(parsed({}), "from-env");
  EXPECT_EQ(parsed({"--run-nonce", "abc"}), "abc");
  ::unsetenv("SENSORNET_RUN_NONCE");
}

}  // namespace
}  // namespace sensornet
