// The launcher's child processes (ProcessGroup) and its one-launch-per-run lock (RunLock), on
// real processes and a real lock file: an exit status and a killing signal are reported as
// they happened, a program that cannot start says so in its log (status 127), stopping reaches
// a child that ignores SIGTERM, and a second launch of a run is refused while the first holds
// the lock and allowed once it is gone.

#include "sensornet/launcher/process_group.hpp"

#include <gtest/gtest.h>

#include <chrono>
#include <csignal>
#include <string>
#include <thread>

#include "../../support/scratch_dir.hpp"
#include "sensornet/core/input_error.hpp"
#include "sensornet/launcher/run_lock.hpp"

namespace sensornet::launcher {
namespace {

using namespace std::chrono_literals;
using testing::ScratchDir;

ChildSpec shell(const std::string& name, const std::string& script, const ScratchDir& dir) {
  return {name, {"/bin/sh", "-c", script}, dir.file(name + ".log")};
}

TEST(ProcessGroup, ReportsTheExitStatusAndTheLog) {
  ScratchDir dir;
  ProcessGroup group;
  group.start(shell("three", "echo hello; exit 3", dir));
  const std::optional<ChildExit> exit = group.waitFor("three", 10s);
  ASSERT_TRUE(exit.has_value());
  EXPECT_EQ(exit->exit_code, 3);
  EXPECT_EQ(exit->signal, 0);
  EXPECT_FALSE(exit->succeeded());
  EXPECT_FALSE(group.isRunning("three"));
  EXPECT_EQ(lastLines(*group.logOf("three"), 1), "hello\n");
}

// A program of ours says why it failed in an "error: " line; the last such line is the cause.
TEST(ProcessGroup, TheLastErrorLineOfALogIsItsCause) {
  ScratchDir dir;
  ProcessGroup group;
  group.start(shell("full",
                    "echo '[x] info: error: not at the start'; echo 'x: error: first' >&2; "
                    "echo 'fusion_center: error: cannot write r.json: No space left on device' "
                    ">&2; echo done; exit 1",
                    dir));
  ASSERT_TRUE(group.waitFor("full", 10s).has_value());
  EXPECT_EQ(lastErrorLine(*group.logOf("full")),
            std::optional<std::string>("cannot write r.json: No space left on device"));
  group.start(shell("fine", "echo all well", dir));
  ASSERT_TRUE(group.waitFor("fine", 10s).has_value());
  EXPECT_EQ(lastErrorLine(*group.logOf("fine")), std::nullopt);
  EXPECT_EQ(lastErrorLine(dir.file("no-such.log")), std::nullopt);
}

TEST(ProcessGroup, AProgramThatCannotStartExitsWith127) {
  ScratchDir dir;
  ProcessGroup group;
  group.start({"missing", {dir.file("no-such-program")}, dir.file("missing.log")});
  const std::optional<ChildExit> exit = group.waitFor("missing", 10s);
  ASSERT_TRUE(exit.has_value());
  EXPECT_EQ(exit->exit_code, 127);
  EXPECT_NE(lastLines(dir.file("missing.log"), 5).find("no-such-program"), std::string::npos);
}

TEST(ProcessGroup, StopReachesAChildThatIgnoresSigterm) {
  ScratchDir dir;
  ProcessGroup group;
  group.start(shell("stubborn", "trap '' TERM; echo ready; while :; do sleep 0.05; done", dir));
  group.start(shell("polite", "exec sleep 30", dir));
  EXPECT_EQ(group.runningNames().size(), 2U);
  // The shell must have set its trap before the stop begins.
  const auto ready_by = std::chrono::steady_clock::now() + 10s;
  while (lastLines(dir.file("stubborn.log"), 1) != "ready\n" &&
         std::chrono::steady_clock::now() < ready_by) {
    std::this_thread::sleep_for(10ms);
  }
  const auto started = std::chrono::steady_clock::now();
  const std::vector<ChildExit> ended = group.stopAll(300ms);
  EXPECT_LT(std::chrono::steady_clock::now() - started, 10s);
  ASSERT_EQ(ended.size(), 2U);
  for (const ChildExit& e : ended) {
    EXPECT_EQ(e.signal, e.name == "stubborn" ? SIGKILL : SIGTERM) << e.name << ": " << e.describe();
  }
  EXPECT_TRUE(group.runningNames().empty());
}

TEST(ProcessGroup, ReapReturnsEachEndOnce) {
  ScratchDir dir;
  ProcessGroup group;
  group.start(shell("quick", "exit 0", dir));
  std::vector<ChildExit> seen;
  const auto deadline = std::chrono::steady_clock::now() + 10s;
  while (seen.empty() && std::chrono::steady_clock::now() < deadline) {
    for (ChildExit& e : group.reap()) seen.push_back(std::move(e));
    std::this_thread::sleep_for(10ms);
  }
  ASSERT_EQ(seen.size(), 1U);
  EXPECT_TRUE(seen[0].succeeded());
  EXPECT_TRUE(group.reap().empty());
}

TEST(RunLock, ASecondLaunchOfTheRunIsRefusedUntilTheFirstEnds) {
  ScratchDir dir;
  {
    const RunLock first(dir.path(), "run-a");
    try {
      const RunLock second(dir.path(), "run-a");
      FAIL() << "a second lock of the same run was taken";
    } catch (const InputError& e) {
      const std::string message = e.what();
      EXPECT_NE(message.find("run-a"), std::string::npos) << message;
      EXPECT_NE(message.find(std::to_string(::getpid())), std::string::npos) << message;
    }
  }
  EXPECT_NO_THROW(RunLock(dir.path(), "run-a"));  // the first is gone: free again
}

}  // namespace
}  // namespace sensornet::launcher
