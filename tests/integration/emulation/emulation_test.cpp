// Whole emulation runs: the real coordinator, sensor agents and fusion center as separate
// processes over real Cyclone DDS on loopback, each run with its own run id (its own
// partition, and a domain id hashed from it). Every process is stopped by its
// BackgroundProcess guard whatever the outcome.
//
// Statistical checks, each at a stated false-alarm level with fixed seeds (so deterministic in
// what is drawn, up to which episode a live switch lands in):
// - counts per sensor against the schedule: Pearson's chi-square, level 0.001;
// - the realized mean against the in-process Monte Carlo: Welch's two-sample z, level 0.001;
// - the realized mean against the bracket: the 95% interval meets it (what the report says).

#include <gtest/gtest.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <optional>
#include <thread>

#include "sensornet/core/monte_carlo.hpp"
#include "sensornet/dds/participant.hpp"
#include "sensornet/dds/reader.hpp"
#include "sensornet/dds/topics.hpp"
#include "sensornet/dds/wire.hpp"
#include "sensornet/dds/writer.hpp"
#include "sensornet/wire/messages.hpp"
#include "sensornet/wire/run_options.hpp"
#include "sensornet/emulator/run_partitions.hpp"
#include "sensornet/io/scenario_file.hpp"
#include "emulation_fixture.hpp"
#include "support/background_process.hpp"
#include "support/sanitizer.hpp"

namespace sensornet {
namespace {

using namespace std::chrono_literals;
using testing::BackgroundProcess;

using testing::Emulation;
using testing::kDefaultScenario;
using testing::uniqueRunId;

// Upper 1 - α quantile of χ²(df), Wilson-Hilferty, with z the standard normal quantile.
double chiSquareQuantile(double df, double z) {
  const double a = 2.0 / (9.0 * df);
  return df * std::pow(1.0 - a + z * std::sqrt(a), 3.0);
}
constexpr double kZ999 = 3.090;  // one-sided 0.001

// Pearson's statistic of the per-sensor totals against their expectations (sensors with a
// positive expectation), and its degrees of freedom.
std::pair<double, int> countStatistic(const nlohmann::json& report) {
  double statistic = 0.0;
  int df = 0;
  for (const auto& sensor : report.at("sensors")) {
    const double expected = sensor.at("expected").get<double>();
    const double received = sensor.at("received").get<double>();
    if (expected <= 0.0) {
      EXPECT_EQ(received, 0.0) << "sensor " << sensor.at("sensor_id") << " has no rate";
      continue;
    }
    statistic += (received - expected) * (received - expected) / expected;
    ++df;
  }
  return {statistic, df};
}

void expectCompleteAndLossless(const nlohmann::json& report, int episodes) {
  ASSERT_FALSE(report.is_null());
  EXPECT_EQ(report.at("status"), "completed");
  EXPECT_EQ(report.at("episodes").get<int>(), episodes);
  const auto& summary = report.at("summary");
  EXPECT_EQ(summary.at("lost").get<int>(), 0);
  EXPECT_EQ(summary.at("rejected").get<int>(), 0);
  for (const auto& e : report.at("per_episode")) EXPECT_TRUE(e.at("complete").get<bool>());
  const auto [statistic, df] = countStatistic(report);
  ASSERT_GT(df, 0);
  EXPECT_LT(statistic, chiSquareQuantile(df, kZ999)) << "counts do not match the schedule";
}

TEST(Emulation, DefaultScenarioRunMatchesBracketScheduleAndInProcessMonteCarlo) {
  const int episodes = 60;
  Emulation run(uniqueRunId("default"));
  run.startFusionCenter();
  run.startSensors("0-2");
  run.startSensors("3-5");
  run.startCoordinator({"--scenario", kDefaultScenario, "--surrogate", "uniform", "--episodes",
                        std::to_string(episodes), "--time-scale", "30", "--seed", "5"});
  const nlohmann::json report = run.finish(120s);
  expectCompleteAndLossless(report, episodes);
  if (HasFailure()) return;
  const auto& summary = report.at("summary");
  EXPECT_TRUE(summary.at("meets_bracket").get<bool>()) << summary.dump();
  EXPECT_LE(summary.at("bracket").at("info").get<double>(),
            summary.at("bracket").at("cov").get<double>());

  // The same scenario and schedule in process (independent draws).
  const Scenario scenario = loadScenarioFile(kDefaultScenario);
  MonteCarloOptions options;
  options.runs = 4000;
  options.seed = 77;
  options.simulate_plant = false;
  const MonteCarloResult mc = evaluateSchedule(scenario, uniformSchedule(scenario), options);
  const double emulated = summary.at("mean").get<double>();
  const double emulated_sd = summary.at("std").get<double>();
  const double z = (emulated - mc.mean) / std::sqrt(emulated_sd * emulated_sd / episodes +
                                                    mc.std_dev * mc.std_dev / options.runs);
  EXPECT_LT(std::abs(z), 3.29) << "emulated " << emulated << " vs in-process " << mc.mean;
  // Mean NEES at T: χ²(n)/K has mean n and standard deviation sqrt(2n/K).
  const double n = scenario.stateDim();
  EXPECT_NEAR(summary.at("nees_mean").get<double>(), n, 3.29 * std::sqrt(2.0 * n / episodes));
}

// A live change: sensor 0 taken out of service while episode 1 runs. The switch must happen at
// the announced time in every sensor: no measurement is drawn under the wrong version, sensor 0
// sends nothing after it, and the counts match the two schedules.
TEST(Emulation, LiveScheduleChangeTakesEffectAtItsEffectiveTimeEverywhere) {
  const int episodes = 4;
  Emulation run(uniqueRunId("live"));
  run.startFusionCenter();
  run.startSensors("0-2");
  run.startSensors("3-5");
  // The whole time axis stretched by the sanitizer build's factor (1 in the release build): the
  // episodes, the margin and the waits below, so the switch lands at the same emulated moment.
  constexpr int kSlow = sensornet::testing::kTimeFactor;
  run.startCoordinator({"--scenario", kDefaultScenario, "--surrogate", "uniform", "--episodes",
                        std::to_string(episodes), "--time-scale", std::to_string(1.0 / kSlow),
                        "--switch-margin", std::to_string(1.0 * kSlow)});

  wire::RunOptions options;
  options.run_id = run.runId();
  dds::Domain domain(options.domainConfig());
  dds::Participant participant(domain);
  dds::Topic<sensornet_Report> report_topic(participant);
  dds::Topic<sensornet_Command> command_topic(participant);
  dds::Topic<sensornet_CommandReply> reply_topic(participant);
  dds::Reader<sensornet_Report> reports(participant, report_topic);
  // An operator's commands come in the operator's partition; statuses in each sensor process's
  // (run_partitions.hpp).
  dds::Writer<sensornet_Command> commands(
      participant, command_topic,
      dds::endpointQosIn<sensornet_Command>(emulator::commandPartition(
          participant.partition(), emulator::CommandSender::Operator)));
  dds::Reader<sensornet_CommandReply> replies(participant, reply_topic);
  dds::Topic<sensornet_SensorStatus> status_topic(participant);
  dds::Reader<sensornet_SensorStatus> statuses(
      participant, status_topic,
      dds::readerQosMatching<sensornet_SensorStatus>(
          emulator::sensorPartitionPattern(participant.partition())));

  // Wait for episode 0's report: episode 1 is then about to start.
  const auto deadline = std::chrono::steady_clock::now() + kSlow * 60s;
  bool first_report = false;
  while (!first_report && std::chrono::steady_clock::now() < deadline) {
    for (auto& r : reports.take(8).samples) first_report |= r.sample->episode == 0;
    std::this_thread::sleep_for(20ms);
  }
  ASSERT_TRUE(first_report);
  // Into episode 1 (3 s of wall time long; it starts 0.2 s after the report), so that the
  // fusion center has published a covariance of it: the switch lands about 1.8 s into it, with
  // a second of wall time for planning and for every process to hear of it.
  std::this_thread::sleep_for(kSlow * 1000ms);

  ASSERT_TRUE(commands.waitForReaders(1, 5s));
  const std::vector<std::uint32_t> excluded = {0};
  const std::string issuer = "emulation test";
  const std::string empty;
  sensornet_Command command{};
  command.run_id = dds::borrowString(run.runId());
  command.command_id = static_cast<std::uint64_t>(emulator::wallNowNs());
  command.kind = sensornet_COMMAND_EXCLUDE_SENSORS;
  command.surrogate = dds::borrowString(empty);
  dds::borrowSequence(command.sensor_ids, excluded);
  command.schedule_json = dds::borrowString(empty);
  command.issuer = dds::borrowString(issuer);
  command.issued_wall_time_ns = emulator::wallNowNs();
  ASSERT_EQ(commands.write(command), dds::WriteResult::Written);
  std::optional<std::uint32_t> version;
  while (!version && std::chrono::steady_clock::now() < deadline) {
    for (auto& r : replies.take(8).samples) {
      if (r.sample->command_id == command.command_id) {
        EXPECT_TRUE(r.sample->accepted) << dds::viewString(r.sample->reason);
        version = r.sample->schedule_version;
      }
    }
    std::this_thread::sleep_for(20ms);
  }
  ASSERT_TRUE(version.has_value()) << "no reply from the coordinator";
  EXPECT_EQ(*version, 2u);
  // Once version 2 is in force (the rest of the running episode), `status` shows sensor 0 as
  // excluded, and only it.
  bool zero_excluded = false;
  const auto status_deadline = std::chrono::steady_clock::now() + kSlow * 6s;
  while (!zero_excluded && std::chrono::steady_clock::now() < status_deadline) {
    for (auto& s : statuses.take(32).samples) {
      const bool says_excluded = s.sample->state == sensornet_SENSOR_EXCLUDED;
      if (s.sample->sensor_id == 0) {
        zero_excluded |= says_excluded && s.sample->schedule_version == *version;
      } else {
        EXPECT_FALSE(says_excluded) << "sensor " << s.sample->sensor_id << " under version "
                               << s.sample->schedule_version;
      }
    }
    std::this_thread::sleep_for(20ms);
  }
  EXPECT_TRUE(zero_excluded) << "sensor 0 never reported itself excluded";

  const nlohmann::json report = run.finish(60s);
  expectCompleteAndLossless(report, episodes);
  if (HasFailure()) return;
  // Version 2 for the rest of the running episode, version 3 for the episodes after it.
  ASSERT_EQ(report.at("schedule_versions").size(), 3u);
  const auto& v2 = report.at("schedule_versions")[1];
  const auto& v3 = report.at("schedule_versions")[2];
  const int switch_episode = v2.at("effective_episode").get<int>();
  const double switch_time = v2.at("effective_time_s").get<double>();
  EXPECT_GE(switch_episode, 1);
  EXPECT_GT(switch_time, 0.0);
  EXPECT_EQ(v3.at("effective_episode").get<int>(), switch_episode + 1);
  EXPECT_EQ(v3.at("effective_time_s").get<double>(), 0.0);
  for (const auto& sensor : report.at("sensors")) {
    EXPECT_EQ(sensor.at("wrong_version").get<int>(), 0) << "sensor " << sensor.at("sensor_id");
  }
  for (const auto& e : report.at("per_episode")) {
    const int number = e.at("episode").get<int>();
    const auto versions = e.at("schedule_versions").get<std::vector<int>>();
    if (number < switch_episode) {
      EXPECT_EQ(versions, std::vector<int>{1});
    } else if (number == switch_episode) {
      EXPECT_EQ(versions, (std::vector<int>{1, 2}));
    } else {
      EXPECT_EQ(versions, std::vector<int>{3});
      EXPECT_EQ(e.at("received")[0].get<int>(), 0) << "episode " << number;
    }
  }
}

// Two runs on the same domain id at once: only their partitions keep them apart.
TEST(Emulation, TwoRunsAtOnceDoNotSeeEachOthersData) {
  const int episodes = 6;
  std::vector<std::unique_ptr<Emulation>> runs;
  for (const std::string name : {"pair-a", "pair-b"}) {
    runs.push_back(std::make_unique<Emulation>(uniqueRunId(name)));
    Emulation& run = *runs.back();
    const std::vector<std::string> domain = {"--domain-id", "17"};
    run.startFusionCenter(domain);
    run.startSensors("0-5", domain);
    std::vector<std::string> args = {"--scenario",   kDefaultScenario,
                                     "--surrogate",  "uniform",
                                     "--episodes",   std::to_string(episodes),
                                     "--time-scale", "20",
                                     "--seed",       name == "pair-a" ? "1" : "2"};
    args.insert(args.end(), domain.begin(), domain.end());
    run.startCoordinator(args);
  }
  for (auto& run : runs) {
    const nlohmann::json report = run->finish(90s);
    expectCompleteAndLossless(report, episodes);
    EXPECT_EQ(report.at("run_id"), run->runId());
  }
}

// A sensor process started after the scenario and the schedule were published still gets both
// (transient-local durability) and the run completes with it.
TEST(Emulation, ASensorStartedLateStillJoinsTheRun) {
  const int episodes = 3;
  Emulation run(uniqueRunId("late"));
  run.startFusionCenter();
  run.startSensors("0-4");
  run.startCoordinator({"--scenario", kDefaultScenario, "--surrogate", "uniform", "--episodes",
                        std::to_string(episodes), "--time-scale", "20"});
  std::this_thread::sleep_for(2s);  // scenario and schedule are out; the run waits for sensor 5
  run.startSensors("5");
  const nlohmann::json report = run.finish(60s);
  expectCompleteAndLossless(report, episodes);
  if (HasFailure()) return;
  EXPECT_GT(report.at("sensors")[5].at("expected").get<double>(), 0.0);
}

}  // namespace
}  // namespace sensornet
