// One cause, one fault (issue 23, "One cause, fourteen faults"), with `sensornet launch` and real
// processes over Cyclone DDS on loopback:
// - `--on-sensor-failure stop` with a sensor agent killed: the death is the run's one cause;
//   the coordinator's exit (it was told to stop) is no fault of its own, and what the fusion
//   center recorded because the run ended (a stall per healthy sensor, the coordinator's abort)
//   carries `caused_by` the death.
// - SIGINT to the launcher mid-run: the interrupt is the one cause; the children it stopped are
//   not faults, and the fusion center's entries about the cut-off episode are its consequences.
//
// Expectations are the outcome table's (docs/ARCHITECTURE.md: failed and interrupted exit 1) and the
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

constexpr int kExitFailed = 1;  // docs/ARCHITECTURE.md: failed / interrupted

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
  // Starts a run of 20 episodes with `extra` flags, waits until one episode is in its log and
  // `delay` more, sends `signal` to the process whose command line starts with `program` and
  // contains `token`, and returns the launcher's result.
  ProcessResult faultMidRun(std::vector<std::string> extra, std::chrono::milliseconds delay,
                            const std::string& program, const std::string& token, int signal) {
    std::vector<std::string> argv = launchArgs(20, "3");
    argv.insert(argv.end(), {"--seed", "5"});
    argv.insert(argv.end(), extra.begin(), extra.end());
    RunningProgram launcher(argv, 180s);
    EXPECT_TRUE(waitUntil([&] { return !readJsonLines(dir_ / "report.jsonl").empty(); }, 60s))
        << "the run never finished an episode";
    std::this_thread::sleep_for(delay);
    const std::optional<pid_t> target = processOf(run_id_, program, token);
    EXPECT_TRUE(target.has_value()) << program << " " << token;
    if (target) {
      EXPECT_EQ(::kill(*target, signal), 0);
    }
    return launcher.result();
  }

  // The run's report, with the expectations every one-cause run shares: exit 1 and `status`,
  // exactly one cause (returned), every consequence naming it, no coordinator failure, and the
  // summary line counting the one cause.
  json expectOneCause(const ProcessResult& r, const std::string& status) {
    EXPECT_EQ(r.exit_code, kExitFailed) << r.out << r.err;
    const json report = readJson(dir_ / "report.json");
    if (!report.is_object()) {
      ADD_FAILURE() << "no report: " << r.err;
      return nullptr;
    }
    EXPECT_EQ(report["status"], status);
    const json& faults = report["faults"];
    const std::vector<json> causes = causesIn(faults);
    if (causes.size() != 1) {
      ADD_FAILURE() << "expected one cause: " << faults.dump(2);
      return nullptr;
    }
    expectConsequencesOf(faults, causes[0]);
    expectNoCoordinatorFailure(faults);
    EXPECT_NE(r.out.find(status + " (1 fault)"), std::string::npos) << r.out;
    return causes[0];
  }
};

TEST_F(OneCause, SensorKilledUnderStopPolicyIsTheOnlyFault) {
  const LeftoverGuard guard(run_id_);
  const ProcessResult r = faultMidRun({"--sensors-per-process", "3", "--on-sensor-failure", "stop"},
                                      200ms, SENSORNET_SENSOR_AGENT, "--sensors 0-2", SIGKILL);
  const json cause = expectOneCause(r, "failed");
  ASSERT_TRUE(cause.is_object());
  EXPECT_EQ(cause["process"], "sensor_agent-0-2");
  EXPECT_EQ(cause["kind"], "process_killed");
  EXPECT_EQ(cause["sensors"], (json{0, 1, 2}));
  EXPECT_FALSE(cause["survived"].get<bool>()) << "the stop policy ends the run";
  EXPECT_TRUE(processesMentioning(run_id_).empty());
}

TEST_F(OneCause, SigintMidRunIsTheOnlyFault) {
  const LeftoverGuard guard(run_id_);
  const ProcessResult r = faultMidRun({}, 300ms, kLauncher, "launch", SIGINT);
  const json cause = expectOneCause(r, "interrupted");
  ASSERT_TRUE(cause.is_object());
  EXPECT_EQ(cause["kind"], "interrupted");
  EXPECT_EQ(cause["process"], "sensornet");
  EXPECT_EQ(cause["detail"], "interrupted by SIGINT");
  EXPECT_TRUE(processesMentioning(run_id_).empty());
}

}  // namespace
}  // namespace sensornet::testing
