// Faults as part of the emulation (issue 11), with `sensornet launch` and real processes over
// Cyclone DDS on loopback: a run survives the death of any of its processes.
// - A sensor agent killed mid-run: the coordinator applies --on-sensor-failure. replan: a new
//   version gives the dead sensor rate zero from a switch within seconds of the death, every
//   later episode is complete, the run ends degraded (exit 3) with a fault naming the process,
//   its sensor, when, and the version that followed. continue: no new version, the dead sensor
//   is still expected (the bracket shows the damage) but sends nothing. stop: failed (exit 1).
// - A scripted crash (the scenario's faults:) is the same death, named as scripted.
// - A killed fusion center or coordinator is restarted with --resume: the run completes
//   degraded and every episode but the one the fusion center died in equals a clean run of the
//   same seed.
//
// What is checked is recomputed from the report's per-episode lists (sent = received + lost +
// dropped, no loss) and from a clean run, not taken from the report's verdict; exit codes are
// docs/ARCHITECTURE.md's.

#include <gtest/gtest.h>
#include <signal.h>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <set>
#include <string>
#include <thread>
#include <vector>

#include "launch_fixture.hpp"
#include "support/sanitizer.hpp"

namespace sensornet::testing {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using namespace std::chrono_literals;

constexpr int kExitFailed = 1;
constexpr int kExitDegraded = 3;
constexpr int kSensors = 6;  // the default scenario's

// The launcher's fault about `process`, or null.
json faultOf(const json& report, const std::string& process) {
  for (const json& fault : report.value("faults", json::array())) {
    if (fault.value("process", "") == process) return fault;
  }
  return nullptr;
}

std::uint64_t at(const json& list, int j) { return list.at(static_cast<std::size_t>(j)).get<std::uint64_t>(); }

// Every sensor of every episode accounted for, nothing lost by the middleware.
void expectAccounted(const json& report) {
  for (const json& e : report["per_episode"]) {
    for (int j = 0; j < kSensors; ++j) {
      const std::uint64_t dropped =
          e.contains("dropped_by_network") ? at(e["dropped_by_network"], j) : 0;
      EXPECT_EQ(at(e["sent"], j), at(e["received"], j) + at(e["lost"], j) + dropped)
          << "episode " << e["episode"] << " sensor " << j;
      EXPECT_EQ(at(e["lost"], j), 0u) << "episode " << e["episode"] << " sensor " << j;
    }
  }
}

class Faults : public LaunchTest {
 protected:
  // Launches `episodes` of the default scenario at `time_scale` with seed 5 and `extra` flags,
  // waits until `episodes_before` episodes are in the episode log, waits `delay` more, kills
  // the process whose command line starts with `program` and contains `token`, and returns the
  // launcher's result with the report.
  std::pair<ProcessResult, json> killMidRun(int episodes, const std::string& time_scale,
                                            std::vector<std::string> extra,
                                            std::size_t episodes_before,
                                            std::chrono::milliseconds delay,
                                            const std::string& program,
                                            const std::string& token = "") {
    std::vector<std::string> argv = launchArgs(episodes, time_scale);
    argv.insert(argv.end(), {"--seed", "5"});
    argv.insert(argv.end(), extra.begin(), extra.end());
    RunningProgram launcher(argv, 180s);
    const fs::path log = dir_ / "report.jsonl";
    EXPECT_TRUE(waitUntil([&] { return readJsonLines(log).size() >= episodes_before; },
                          scaledLimit(60s)))
        << "the run never finished " << episodes_before << " episodes";
    std::this_thread::sleep_for(delay);
    const std::optional<pid_t> victim = processOf(run_id_, program, token);
    EXPECT_TRUE(victim.has_value()) << program << " " << token;
    if (victim) {
      EXPECT_EQ(::kill(*victim, SIGKILL), 0);
    }
    ProcessResult result = launcher.result();
    return {result, readJson(dir_ / "report.json")};
  }

  // A clean run of the same seed in a folder of its own: the reference costs.
  json cleanRun(int episodes, const std::string& time_scale) {
    const std::string id = run_id_ + "-clean";
    const LeftoverGuard guard(id);
    const ProcessResult r = runProcess(
        {kLauncher, "launch", kDefaultScenario, "--episodes", std::to_string(episodes),
         "--time-scale", time_scale, "--seed", "5", "--run-id", id, "--report",
         (dir_ / "clean.json").string(), "--log-dir", (dir_ / "clean-logs").string()},
        120s);
    EXPECT_EQ(r.exit_code, 0) << r.out << r.err;
    return readJson(dir_ / "clean.json");
  }
};

TEST_F(Faults, KilledSensorIsReplannedAroundAndLaterEpisodesAreComplete) {
  const LeftoverGuard guard(run_id_);
  const auto [r, report] = killMidRun(5, "1", {"--sensors-per-process", "1"}, 1, 1000ms,
                                      SENSORNET_SENSOR_AGENT, "--sensors 3 ");
  EXPECT_EQ(r.exit_code, kExitDegraded) << r.out << r.err;
  ASSERT_TRUE(report.is_object()) << r.out << r.err;
  EXPECT_EQ(report["status"], "degraded");
  ASSERT_EQ(report["per_episode"].size(), 5u) << "every episode ran";

  const json fault = faultOf(report, "sensor_agent-3");
  ASSERT_TRUE(fault.is_object()) << report["faults"].dump();
  EXPECT_EQ(fault["kind"], "process_killed");
  EXPECT_EQ(fault["sensor"], 3);
  EXPECT_EQ(fault["survived"], true);
  ASSERT_TRUE(fault["episode"].is_number()) << fault.dump();
  ASSERT_TRUE(fault["schedule_version"].is_number()) << fault.dump();
  EXPECT_NE(fault["detail"].get<std::string>().find("policy replan"), std::string::npos)
      << fault.dump();
  const auto failed_in = fault["episode"].get<std::uint32_t>();
  const auto version = fault["schedule_version"].get<std::uint32_t>();

  // The version that followed: mid-episode, from a switch soon after the death (the launcher
  // sees it at once; planning and the 0.3 s switch margin come on top).
  const json versions = report["schedule_versions"];
  json followed;
  for (const json& v : versions) {
    if (v["version"] == version) followed = v;
  }
  ASSERT_TRUE(followed.is_object()) << versions.dump();
  if (followed["effective_episode"] == failed_in && fault["emulated_time_s"].is_number()) {
    const double reaction =
        followed["effective_time_s"].get<double>() - fault["emulated_time_s"].get<double>();
    std::printf("death at %.3f s of episode %u, re-planned version from %.3f s (%.3f s later)\n",
                fault["emulated_time_s"].get<double>(), failed_in,
                followed["effective_time_s"].get<double>(), reaction);
    EXPECT_GT(reaction, 0.0);
    EXPECT_LT(reaction, 3.0);
  }

  expectAccounted(report);
  for (const json& e : report["per_episode"]) {
    const auto k = e["episode"].get<std::uint32_t>();
    if (k <= failed_in) continue;
    // After the failure: complete, and the dead sensor is neither expected nor heard from.
    EXPECT_TRUE(e["complete"].get<bool>()) << e.dump();
    EXPECT_EQ(e["expected"][3].get<double>(), 0.0) << "episode " << k;
    EXPECT_EQ(at(e["sent"], 3), 0u);
    EXPECT_GT(e["schedule_versions"].back().get<std::uint32_t>(), 1u);
  }
  EXPECT_NE(r.out.find("run " + run_id_ + ": degraded"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("exit code 3"), std::string::npos) << r.out;
  EXPECT_TRUE(processesMentioning(run_id_).empty());
}

TEST_F(Faults, KilledSensorUnderContinueKeepsTheScheduleAndShowsTheDamage) {
  const LeftoverGuard guard(run_id_);
  const auto [r, report] =
      killMidRun(5, "3", {"--sensors-per-process", "3", "--on-sensor-failure", "continue"}, 1,
                 200ms, SENSORNET_SENSOR_AGENT, "--sensors 3-5");
  EXPECT_EQ(r.exit_code, kExitDegraded) << r.out << r.err;
  ASSERT_TRUE(report.is_object());
  EXPECT_EQ(report["status"], "degraded");
  const json fault = faultOf(report, "sensor_agent-3-5");
  ASSERT_TRUE(fault.is_object()) << report["faults"].dump();
  EXPECT_EQ(fault["sensors"], json({3, 4, 5}));
  EXPECT_FALSE(fault.contains("schedule_version")) << fault.dump();
  EXPECT_NE(fault["detail"].get<std::string>().find("policy continue"), std::string::npos);
  EXPECT_EQ(report["schedule_versions"].size(), 1u) << "continue publishes no version";
  const auto failed_in = fault["episode"].get<std::uint32_t>();
  expectAccounted(report);
  // The schedule is unchanged, so every episode expects what episode 0 did of every sensor,
  // the dead ones included (the info plan of the default scenario gives sensor 3 a rate).
  const json expected_before = report["per_episode"][0]["expected"];
  EXPECT_GT(expected_before[3].get<double>(), 0.0);
  for (const json& e : report["per_episode"]) {
    EXPECT_EQ(e["expected"], expected_before) << "episode " << e["episode"];
    if (e["episode"].get<std::uint32_t>() <= failed_in) continue;
    EXPECT_TRUE(e["complete"].get<bool>()) << e.dump();
    for (const int j : {3, 4, 5}) EXPECT_EQ(at(e["sent"], j), 0u) << "episode " << e["episode"];
  }
  EXPECT_TRUE(processesMentioning(run_id_).empty());
}

TEST_F(Faults, KilledSensorUnderStopFailsTheRun) {
  const LeftoverGuard guard(run_id_);
  const auto [r, report] =
      killMidRun(20, "3", {"--sensors-per-process", "3", "--on-sensor-failure", "stop"}, 1,
                 200ms, SENSORNET_SENSOR_AGENT, "--sensors 0-2");
  EXPECT_EQ(r.exit_code, kExitFailed) << r.out << r.err;
  ASSERT_TRUE(report.is_object());
  EXPECT_EQ(report["status"], "failed");
  EXPECT_LT(report["per_episode"].size(), 20u) << "the run stopped early";
  EXPECT_TRUE(faultOf(report, "sensor_agent-0-2").is_object()) << report["faults"].dump();
  EXPECT_TRUE(processesMentioning(run_id_).empty());
}

TEST_F(Faults, ScriptedCrashIsSurvivedAndNamedAsScripted) {
  const LeftoverGuard guard(run_id_);
  // The default scenario with one scripted crash: sensor 4's process exits at 1.5 s of
  // episode 1.
  const fs::path scenario = dir_ / "crash.yaml";
  std::ofstream(scenario) << readText(kDefaultScenario)
                          << "\nfaults:\n  - {kind: crash, sensor: 4, episode: 1, at: 1.5}\n";
  std::vector<std::string> argv =
      launchArgs(4, "3", dir_ / "report.json", dir_ / "logs", scenario.string());
  argv.insert(argv.end(), {"--sensors-per-process", "2"});
  const ProcessResult r = runProcess(argv, 120s);
  EXPECT_EQ(r.exit_code, kExitDegraded) << r.out << r.err;
  const json report = readJson(dir_ / "report.json");
  ASSERT_TRUE(report.is_object()) << r.out << r.err;
  const json fault = faultOf(report, "sensor_agent-4-5");
  ASSERT_TRUE(fault.is_object()) << report["faults"].dump();
  EXPECT_EQ(fault["kind"], "crash");
  EXPECT_EQ(fault["episode"], 1);
  EXPECT_EQ(fault["survived"], true);
  expectAccounted(report);
  for (const json& e : report["per_episode"]) {
    const auto k = e["episode"].get<int>();
    if (k != 1) {
      EXPECT_TRUE(e["complete"].get<bool>()) << "episode " << k << ", not the crash's";
    }
  }
  EXPECT_TRUE(processesMentioning(run_id_).empty());
}

// The per-episode realized costs of `report` by episode (null for an episode not fused).
std::map<int, json> costsOf(const json& report) {
  std::map<int, json> costs;
  for (const json& e : report["per_episode"]) costs[e["episode"].get<int>()] = e["realized_cost"];
  return costs;
}

TEST_F(Faults, KilledFusionCenterIsRestartedAndOtherEpisodesEqualACleanRun) {
  const LeftoverGuard guard(run_id_);
  constexpr int kEpisodes = 6;
  // Time scale 2, the kill 0.3 s into episode 2. In the sanitizer build the time axis is
  // stretched by its factor: a restarted fusion center that needs 2 s there to hear every
  // sensor would otherwise miss the start of the next episode as well (and says so).
  const std::string time_scale = std::to_string(2.0 / kTimeFactor);
  const auto [r, report] =
      killMidRun(kEpisodes, time_scale, {}, 2, kTimeFactor * 300ms, SENSORNET_FUSION_CENTER);
  EXPECT_EQ(r.exit_code, kExitDegraded) << r.out << r.err;
  ASSERT_TRUE(report.is_object()) << r.out << r.err;
  EXPECT_EQ(report["status"], "degraded");
  const json fault = faultOf(report, "fusion_center");
  ASSERT_TRUE(fault.is_object()) << report["faults"].dump();
  EXPECT_EQ(fault["survived"], true);
  EXPECT_NE(fault["detail"].get<std::string>().find("restarted"), std::string::npos);

  const json clean = cleanRun(kEpisodes, time_scale);
  ASSERT_TRUE(clean.is_object());
  const std::map<int, json> costs = costsOf(report);
  const std::map<int, json> clean_costs = costsOf(clean);
  ASSERT_EQ(costs.size(), static_cast<std::size_t>(kEpisodes)) << "every episode is reported";
  int incomplete = 0;
  for (const json& e : report["per_episode"]) {
    const int k = e["episode"].get<int>();
    if (!e["complete"].get<bool>()) {
      ++incomplete;  // the episode it died in: not fused
      continue;
    }
    EXPECT_EQ(e["realized_cost"], clean_costs.at(k)) << "episode " << k;
  }
  EXPECT_LE(incomplete, 1) << report["faults"].dump(2);
  EXPECT_TRUE(processesMentioning(run_id_).empty());
}

TEST_F(Faults, KilledCoordinatorIsRestartedAndTheRunCarriesOn) {
  const LeftoverGuard guard(run_id_);
  constexpr int kEpisodes = 6;
  const auto [r, report] = killMidRun(kEpisodes, "2", {}, 2, 300ms, SENSORNET_COORDINATOR);
  EXPECT_EQ(r.exit_code, kExitDegraded) << r.out << r.err;
  ASSERT_TRUE(report.is_object()) << r.out << r.err;
  EXPECT_EQ(report["status"], "degraded");
  const json fault = faultOf(report, "coordinator");
  ASSERT_TRUE(fault.is_object()) << report["faults"].dump();
  EXPECT_EQ(fault["survived"], true);
  const json clean = cleanRun(kEpisodes, "2");
  ASSERT_TRUE(clean.is_object());
  const std::map<int, json> clean_costs = costsOf(clean);
  ASSERT_EQ(report["per_episode"].size(), static_cast<std::size_t>(kEpisodes));
  for (const json& e : report["per_episode"]) {
    const int k = e["episode"].get<int>();
    EXPECT_TRUE(e["complete"].get<bool>()) << e.dump();
    EXPECT_EQ(e["realized_cost"], clean_costs.at(k)) << "episode " << k;
  }
  EXPECT_EQ(report["schedule_versions"].size(), 1u) << "the resumed run keeps its version";
  expectAccounted(report);
  EXPECT_TRUE(processesMentioning(run_id_).empty());
}

}  // namespace
}  // namespace sensornet::testing
