// The coordinator's exit status, with real processes (issue 23, "one cause, fourteen faults"): a
// coordinator that ends a run because it was told to (the stop policy, a signal) exits 0, so the
// launcher's report names the cause once and no `process_failed in coordinator` follows from it;
// one that could not carry the run (its peers never came) exits 1.

#include <gtest/gtest.h>
#include <signal.h>

#include <chrono>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <thread>
#include <vector>

#include "launch_fixture.hpp"
#include "support/scratch_dir.hpp"

namespace sensornet::testing {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using namespace std::chrono_literals;

// The launcher's faults of `report` that say the coordinator process ended badly (the fusion
// center's run_aborted names the coordinator too: it is the cause, said once).
std::vector<json> coordinatorFaults(const json& report) {
  std::vector<json> found;
  for (const json& fault : report.value("faults", json::array())) {
    const std::string kind = fault.value("kind", "");
    const bool process_fault = kind == "process_failed" || kind == "process_killed";
    if (fault.value("process", "") == "coordinator" && process_fault) found.push_back(fault);
  }
  return found;
}

TEST(CoordinatorExit, ASignalWhileWaitingForPeersEndsTheRunAndExitsZero) {
  const std::string id = uniqueRunId("coord-exit-signal");
  const LeftoverGuard guard(id);
  const sensornet::testing::ScratchDir dir;
  BackgroundProcess coordinator({kCoordinator, "serve", "--run-id", id, "--scenario",
                                 kDefaultScenario, "--surrogate", "uniform"},
                                dir.file("coordinator.log"));
  ASSERT_TRUE(waitUntil([&] { return coordinator.log().find("waiting for") != std::string::npos; },
                        30s))
      << coordinator.log();
  ASSERT_EQ(::kill(coordinator.pid(), SIGTERM), 0);
  const std::optional<int> code = coordinator.waitForExit(30s);
  ASSERT_TRUE(code.has_value()) << coordinator.log();
  EXPECT_EQ(*code, 0) << "it stopped because it was told to:\n" << coordinator.log();
  EXPECT_NE(coordinator.log().find("the coordinator was stopped by a signal"), std::string::npos)
      << "the others hear why the run ended:\n" << coordinator.log();
}

TEST(CoordinatorExit, PeersThatNeverComeAreItsOwnFailure) {
  const std::string id = uniqueRunId("coord-exit-alone");
  const LeftoverGuard guard(id);
  const sensornet::testing::ScratchDir dir;
  BackgroundProcess coordinator({kCoordinator, "serve", "--run-id", id, "--scenario",
                                 kDefaultScenario, "--surrogate", "uniform", "--ready-timeout",
                                 "1"},
                                dir.file("coordinator.log"));
  const std::optional<int> code = coordinator.waitForExit(30s);
  ASSERT_TRUE(code.has_value()) << coordinator.log();
  EXPECT_EQ(*code, 1) << coordinator.log();
  EXPECT_NE(coordinator.log().find("not ready after 1 s"), std::string::npos) << coordinator.log();
}

class CoordinatorExitInALaunch : public LaunchTest {};

TEST_F(CoordinatorExitInALaunch, StopPolicyFailsTheRunWithoutFaultingTheCoordinator) {
  const LeftoverGuard guard(run_id_);
  std::vector<std::string> argv = launchArgs(20, "3");
  argv.insert(argv.end(), {"--seed", "5", "--sensors-per-process", "3", "--on-sensor-failure",
                           "stop"});
  RunningProgram launcher(argv, 180s);
  ASSERT_TRUE(waitUntil([&] { return readJsonLines(dir_ / "report.jsonl").size() >= 1; }, 60s));
  std::this_thread::sleep_for(200ms);
  const std::optional<pid_t> victim = processOf(run_id_, SENSORNET_SENSOR_AGENT, "--sensors 0-2");
  ASSERT_TRUE(victim.has_value());
  ASSERT_EQ(::kill(*victim, SIGKILL), 0);
  const ProcessResult& r = launcher.result();
  EXPECT_EQ(r.exit_code, 1) << r.out << r.err;
  const json report = readJson(dir_ / "report.json");
  ASSERT_TRUE(report.is_object()) << r.out << r.err;
  EXPECT_EQ(report["status"], "failed");
  EXPECT_EQ(coordinatorFaults(report), std::vector<json>{}) << report["faults"].dump();
  EXPECT_EQ(r.err.find("coordinator exited with status"), std::string::npos) << r.err;
  EXPECT_TRUE(processesMentioning(run_id_).empty());
}

TEST_F(CoordinatorExitInALaunch, InterruptedRunDoesNotFaultTheCoordinator) {
  const LeftoverGuard guard(run_id_);
  RunningProgram launcher(launchArgs(50, "3"), 120s);
  ASSERT_TRUE(waitUntil([&] { return readJsonLines(dir_ / "report.jsonl").size() >= 1; }, 60s));
  const std::optional<pid_t> pid = processOf(run_id_, kLauncher, "launch");
  ASSERT_TRUE(pid.has_value());
  ASSERT_EQ(::kill(*pid, SIGINT), 0);
  const ProcessResult& r = launcher.result();
  EXPECT_EQ(r.exit_code, 1) << r.err;
  const json report = readJson(dir_ / "report.json");
  ASSERT_TRUE(report.is_object()) << r.out << r.err;
  EXPECT_EQ(report["status"], "interrupted");
  EXPECT_EQ(coordinatorFaults(report), std::vector<json>{}) << report["faults"].dump();
  EXPECT_TRUE(processesMentioning(run_id_).empty());
}

}  // namespace
}  // namespace sensornet::testing
