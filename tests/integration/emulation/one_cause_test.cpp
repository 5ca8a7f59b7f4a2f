// One cause, one fault (issue 23, "One cause, fourteen faults"), with `sensornet launch` and real
// processes over Cyclone DDS on loopback:
// - `--on-sensor-failure stop` with a sensor agent killed: the death is the run's one cause;
//   the coordinator's exit (it was told to stop) is no fault of its own, and what the fusion
//   center recorded because the run ended (a stall per healthy sensor, the coordinator's abort)
//   carries `caused_by` the death.
// - SIGINT to the launcher mid-run: the interrupt is the one cause; the children it stopped are
//   not faults, and the fusion center's entries about the cut-off episode are its consequences.
//
// Expectations are the outcome table's (DESIGN.md: failed and interrupted exit 1) and the
// scripted fault, recomputed from the report's entries, not taken from its verdict.
//
// What depends on the other sides (until their branches merge): the fusion center still writes
// a stall per healthy sensor and the coordinator still exits 1 when told to stop. Both are
// tolerated here (marked as consequences, or folded into the cause's detail); once they are
// fixed the consequences shrink and these tests still hold.

#include <gtest/gtest.h>
#include <signal.h>

#include <chrono>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <thread>
#include <vector>

#include "launch_fixture.hpp"

namespace sensornet::testing {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using namespace std::chrono_literals;

constexpr int kExitFailed = 1;  // DESIGN.md: failed / interrupted

// The entries that are causes (no caused_by), and every consequence's cause.
std::vector<json> causesIn(const json& faults) {
  std::vector<json> causes;
  for (const json& f : faults) {
    if (!f.contains("caused_by")) causes.push_back(f);
  }
  return causes;
}

// Every consequence names the one cause by its kind and process.
void expectConsequencesOf(const json& faults, const json& cause) {
  for (const json& f : faults) {
    if (!f.contains("caused_by")) continue;
    EXPECT_EQ(f["caused_by"]["kind"], cause["kind"]) << f.dump();
    EXPECT_EQ(f["caused_by"]["process"], cause["process"]) << f.dump();
  }
}

// No entry about the coordinator says it failed: it stopped because it was told to.
void expectNoCoordinatorFailure(const json& faults) {
  for (const json& f : faults) {
    if (f.value("process", "") != "coordinator") continue;
    EXPECT_NE(f.value("kind", ""), "process_failed") << f.dump();
    EXPECT_NE(f.value("kind", ""), "process_killed") << f.dump();
  }
}

class OneCause : public LaunchTest {
 protected:
  // The run in the background, once `episodes_before` episodes are in its log.
  void startAndWait(RunningProgram*& launcher, std::vector<std::string> extra,
                    std::size_t episodes_before) {
    std::vector<std::string> argv = launchArgs(20, "3");
    argv.insert(argv.end(), {"--seed", "5"});
    argv.insert(argv.end(), extra.begin(), extra.end());
    launcher_.emplace(argv, 180s);
    launcher = &*launcher_;
    ASSERT_TRUE(waitUntil(
        [&] { return readJsonLines(dir_ / "report.jsonl").size() >= episodes_before; }, 60s))
        << "the run never finished " << episodes_before << " episodes";
  }

  std::optional<RunningProgram> launcher_;
};

TEST_F(OneCause, SensorKilledUnderStopPolicyIsTheOnlyFault) {
  const LeftoverGuard guard(run_id_);
  RunningProgram* launcher = nullptr;
  startAndWait(launcher, {"--sensors-per-process", "3", "--on-sensor-failure", "stop"}, 1);
  if (HasFatalFailure()) return;
  std::this_thread::sleep_for(200ms);
  const std::optional<pid_t> victim = processOf(run_id_, SENSORNET_SENSOR_AGENT, "--sensors 0-2");
  ASSERT_TRUE(victim.has_value());
  ASSERT_EQ(::kill(*victim, SIGKILL), 0);
  const ProcessResult& r = launcher->result();

  EXPECT_EQ(r.exit_code, kExitFailed) << r.out << r.err;
  const json report = readJson(dir_ / "report.json");
  ASSERT_TRUE(report.is_object()) << r.err;
  EXPECT_EQ(report["status"], "failed");
  const json& faults = report["faults"];
  const std::vector<json> causes = causesIn(faults);
  ASSERT_EQ(causes.size(), 1u) << faults.dump(2);
  EXPECT_EQ(causes[0]["process"], "sensor_agent-0-2");
  EXPECT_EQ(causes[0]["kind"], "process_killed");
  EXPECT_EQ(causes[0]["sensors"], (json{0, 1, 2}));
  EXPECT_FALSE(causes[0]["survived"].get<bool>()) << "the stop policy ends the run";
  expectConsequencesOf(faults, causes[0]);
  expectNoCoordinatorFailure(faults);
  EXPECT_NE(r.out.find("failed (1 fault)"), std::string::npos) << r.out;
  EXPECT_TRUE(processesMentioning(run_id_).empty());
}

TEST_F(OneCause, SigintMidRunIsTheOnlyFault) {
  const LeftoverGuard guard(run_id_);
  RunningProgram* launcher = nullptr;
  startAndWait(launcher, {}, 1);
  if (HasFatalFailure()) return;
  std::this_thread::sleep_for(300ms);
  const std::optional<pid_t> self = processOf(run_id_, kLauncher, "launch");
  ASSERT_TRUE(self.has_value());
  ASSERT_EQ(::kill(*self, SIGINT), 0);
  const ProcessResult& r = launcher->result();

  EXPECT_EQ(r.exit_code, kExitFailed) << r.out << r.err;
  const json report = readJson(dir_ / "report.json");
  ASSERT_TRUE(report.is_object()) << r.err;
  EXPECT_EQ(report["status"], "interrupted");
  const json& faults = report["faults"];
  const std::vector<json> causes = causesIn(faults);
  ASSERT_EQ(causes.size(), 1u) << faults.dump(2);
  EXPECT_EQ(causes[0]["kind"], "interrupted");
  EXPECT_EQ(causes[0]["process"], "sensornet");
  EXPECT_EQ(causes[0]["detail"], "interrupted by SIGINT");
  expectConsequencesOf(faults, causes[0]);
  expectNoCoordinatorFailure(faults);
  EXPECT_NE(r.out.find("interrupted (1 fault)"), std::string::npos) << r.out;
  EXPECT_TRUE(processesMentioning(run_id_).empty());
}

}  // namespace
}  // namespace sensornet::testing
