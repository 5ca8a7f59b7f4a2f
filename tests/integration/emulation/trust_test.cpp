// Trustworthy results (issue 10) with real processes over Cyclone DDS on loopback: stalls of any
// one process (SIGSTOP/SIGCONT) lose nothing and change no realized cost; a stall past the
// fusion center's limit is reported as degraded, naming the sensors and the episode; overload
// is either fully fused or reported; rogue samples on the wire are refused, counted by reason
// and never fused.
//
// What is checked is recomputed here, not taken from the report's verdict:
// - each sensor's sent count per episode against the exact Poisson timeline it must draw
//   (emulator::sensorTimeline from the run seed and the schedule file);
// - realized costs against a clean run of the same seed (bit for bit: the fusion takes the
//   same floating-point steps whatever the arrival timing);
// - sent = received + lost for every sensor and episode.
// Schedules vary in time and across sensors; the plant's A is not symmetric.

#include <gtest/gtest.h>
#include <signal.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <set>
#include <sstream>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <thread>

#include "emulation_fixture.hpp"
#include "sensornet/core/emulated_plant.hpp"
#include "sensornet/dds/participant.hpp"
#include "sensornet/dds/topics.hpp"
#include "sensornet/dds/wire.hpp"
#include "sensornet/dds/writer.hpp"
#include "sensornet/wire/messages.hpp"
#include "sensornet/wire/run_options.hpp"
#include "sensornet/emulator/run_partitions.hpp"
#include "sensornet/emulator/sensor_timeline.hpp"
#include "sensornet/io/scenario_file.hpp"
#include "support/in_order_cost.hpp"
#include "support/sanitizer.hpp"
#include "support/scratch_dir.hpp"

namespace sensornet {
namespace {

using namespace std::chrono_literals;
using nlohmann::json;
using testing::Emulation;
using testing::kDefaultScenario;
using testing::uniqueRunId;

constexpr std::uint64_t kSeed = 11;

// Rates that vary in time and across sensors, within the default scenario's budget
// (C = [1 1 1 1 1 1; 0 0 2 1 0 0], b = [12, 6]): the sensors' shares rotate every 10 intervals
// and the total breathes between 0.8 and 1.2 times 10 Hz.
json varyingSchedule() {
  const double shares[3][6] = {{3, 2, 1, 1, 2, 1}, {1, 3, 2, 1, 1, 2}, {2, 1, 1, 2, 3, 1}};
  json rates = json::array();
  for (int i = 0; i < 30; ++i) {
    const double factor = 0.8 + 0.2 * (i % 3);
    json row = json::array();
    for (const double share : shares[i / 10]) row.push_back(share * factor);
    rates.push_back(row);
  }
  return {{"horizon", 3.0}, {"intervals", 30}, {"rates", rates}};
}

std::string writeFile(const std::filesystem::path& path, const std::string& text) {
  std::ofstream(path) << text;
  return path.string();
}

// The measurements the sensors of a seeded run must draw in each episode, in time order: each
// sensor's exact timeline (the run seed and the schedule file), the emulated plant's state at
// each instant and the sensor's noise for its sequence number, as a sensor agent draws them.
std::vector<std::vector<emulator::FusedMeasurement>> drawnMeasurements(
    const Scenario& scenario, const std::string& schedule_path, std::uint64_t seed,
    int episodes) {
  emulator::ScheduleBook book;
  emulator::ScheduleVersion v;
  v.version = 1;
  v.schedule = loadScheduleFile(schedule_path, scenario);
  book.add(std::move(v));
  const EmulatedPlant plant(scenario, seed);
  std::vector<int> sensors(static_cast<std::size_t>(scenario.sensorCount()));
  for (std::size_t j = 0; j < sensors.size(); ++j) sensors[j] = static_cast<int>(j);
  std::vector<std::vector<emulator::FusedMeasurement>> drawn;
  for (int e = 0; e < episodes; ++e) {
    const auto episode = static_cast<std::uint32_t>(e);
    std::vector<std::uint64_t> seq(sensors.size(), 0);
    std::vector<emulator::FusedMeasurement> measurements;
    for (const auto& a :
         emulator::sensorTimeline(book, plant, seed, episode, sensors, scenario.horizon_s)) {
      emulator::FusedMeasurement m;
      m.sensor = a.sensor;
      m.seq = seq[static_cast<std::size_t>(a.sensor)]++;
      m.time_s = a.time_s;
      m.version = a.version;
      m.z = plant.measure(plant.stateAt(episode, a.tick), a.sensor, episode, m.seq);
      measurements.push_back(std::move(m));
    }
    drawn.push_back(std::move(measurements));
  }
  return drawn;
}

// How many measurements each sensor must send in each episode.
std::vector<std::vector<std::uint64_t>> timelineCounts(const std::string& scenario_path,
                                                       const std::string& schedule_path,
                                                       std::uint64_t seed, int episodes) {
  const Scenario scenario = loadScenarioFile(scenario_path);
  std::vector<std::vector<std::uint64_t>> counts;
  for (const auto& measurements : drawnMeasurements(scenario, schedule_path, seed, episodes)) {
    std::vector<std::uint64_t> per_sensor(static_cast<std::size_t>(scenario.sensorCount()), 0);
    for (const auto& m : measurements) ++per_sensor[static_cast<std::size_t>(m.sensor)];
    counts.push_back(per_sensor);
  }
  return counts;
}

class Trust : public ::testing::Test {
 protected:
  void SetUp() override {
    schedule_ = writeFile(dir_ / "varying.json", varyingSchedule().dump());
  }

  // Starts a run of the default scenario under the varying schedule: fusion center, sensor
  // agents "0-2" and "3-5", coordinator.
  void start(Emulation& run, int episodes, double time_scale) const {
    run.startFusionCenter();
    run.startSensors("0-2");
    run.startSensors("3-5");
    std::ostringstream scale;
    scale << time_scale;
    run.startCoordinator({"--scenario", kDefaultScenario, "--schedule", schedule_, "--episodes",
                          std::to_string(episodes), "--time-scale", scale.str(), "--seed",
                          std::to_string(kSeed)});
  }

  // A clean run's realized cost per episode.
  std::vector<double> cleanCosts(const std::string& name, int episodes) const {
    Emulation run(uniqueRunId(name + "-clean"));
    start(run, episodes, 20.0);
    const json report = run.finish(90s);
    std::vector<double> costs;
    for (const json& e : report.value("per_episode", json::array())) {
      EXPECT_TRUE(e.at("complete").get<bool>());
      costs.push_back(e.at("realized_cost").get<double>());
    }
    EXPECT_EQ(costs.size(), static_cast<std::size_t>(episodes));
    return costs;
  }

  // Waits until the fusion center has logged `episodes` episodes, then `extra` more.
  static void waitForEpisodes(const Emulation& run, std::size_t episodes,
                              std::chrono::milliseconds extra) {
    const auto deadline = std::chrono::steady_clock::now() + 60s;
    while (run.episodesLogged() < episodes && std::chrono::steady_clock::now() < deadline) {
      std::this_thread::sleep_for(10ms);
    }
    ASSERT_GE(run.episodesLogged(), episodes);
    std::this_thread::sleep_for(extra);
  }

  static void stall(pid_t pid, std::chrono::milliseconds length) {
    ASSERT_EQ(::kill(pid, SIGSTOP), 0);
    std::this_thread::sleep_for(length);
    ASSERT_EQ(::kill(pid, SIGCONT), 0);
  }

  // Every episode complete, nothing lost, sent as the timelines say, costs as the clean run.
  // `slow_delivery_allowed`: the one fault accepted is `overload` (everything arrived, more than
  // the keep-up limit after the last tally), which is what retransmission under heavy packet
  // loss looks like from the fusion center.
  void expectLosslessAndEqual(const json& report, const std::vector<double>& clean,
                              bool slow_delivery_allowed = false) const {
    ASSERT_TRUE(report.is_object());
    json faults = report.at("faults");
    if (slow_delivery_allowed) {
      faults.erase(std::remove_if(faults.begin(), faults.end(),
                                  [](const json& f) { return f.at("kind") == "overload"; }),
                   faults.end());
    }
    if (faults.empty() == report.at("faults").empty()) {
      EXPECT_EQ(report.at("status"), "completed") << report.at("faults").dump();
    }
    const auto expected = timelineCounts(kDefaultScenario, schedule_, kSeed,
                                         static_cast<int>(clean.size()));
    const json& per_episode = report.at("per_episode");
    ASSERT_EQ(per_episode.size(), clean.size());
    for (std::size_t k = 0; k < clean.size(); ++k) {
      const json& e = per_episode[k];
      EXPECT_TRUE(e.at("complete").get<bool>()) << "episode " << k;
      EXPECT_EQ(e.at("realized_cost").get<double>(), clean[k]) << "episode " << k;
      for (std::size_t j = 0; j < 6; ++j) {
        EXPECT_EQ(e.at("sent")[j].get<std::uint64_t>(), expected[k][j]) << k << "/" << j;
        EXPECT_EQ(e.at("received")[j].get<std::uint64_t>(), expected[k][j]) << k << "/" << j;
        EXPECT_EQ(e.at("lost")[j].get<std::uint64_t>(), 0u) << k << "/" << j;
      }
    }
    EXPECT_EQ(report.at("summary").at("lost"), 0);
    EXPECT_EQ(report.at("summary").at("rejected"), 0);
    EXPECT_TRUE(faults.empty()) << report.at("faults").dump();
  }

  sensornet::testing::ScratchDir scratch_;
  std::filesystem::path dir_ = scratch_.path();
  std::string schedule_;
};

// The whole measurement path changes no result (issue 28): the realized cost of every episode of
// a seeded run of real processes is, bit for bit, the in-order CD-KF over the measurements
// recomputed here in-process from the seed (timelines, plant states, noise). A change to how the
// agents sample, send or the fusion center orders and fuses that alters a single rounding fails.
TEST_F(Trust, ASeededRunsCostsAreTheInProcessComputationBitForBit) {
  constexpr int kEpisodes = 3;
  const std::vector<double> costs = cleanCosts("in-process", kEpisodes);
  ASSERT_EQ(costs.size(), static_cast<std::size_t>(kEpisodes));
  const Scenario scenario = loadScenarioFile(kDefaultScenario);
  const auto drawn = drawnMeasurements(scenario, schedule_, kSeed, kEpisodes);
  for (int e = 0; e < kEpisodes; ++e) {
    const auto& measurements = drawn[static_cast<std::size_t>(e)];
    ASSERT_GT(measurements.size(), 10u) << "episode " << e;  // a real episode, not an empty one
    EXPECT_EQ(costs[static_cast<std::size_t>(e)],
              sensornet::testing::inOrderCost(scenario, measurements))
        << "episode " << e;
  }
}

// A 3 s stall (SIGSTOP, SIGCONT) of one process in episode 1 of 3, at real time (an episode is
// 3 s of wall time): shorter than the 10 s a run absorbs.
class TrustStall : public Trust, public ::testing::WithParamInterface<const char*> {};

TEST_P(TrustStall, ThreeSecondStallLosesNothingAndChangesNoCost) {
  const std::string process = GetParam();
  const std::vector<double> clean = cleanCosts(process, 3);
  Emulation run(uniqueRunId("stall-" + process));
  start(run, 3, 1.0);
  waitForEpisodes(run, 1, 500ms);
  stall(run.pidOf(process), 3s);
  expectLosslessAndEqual(run.finish(90s), clean);
}

INSTANTIATE_TEST_SUITE_P(OfEachProcess, TrustStall,
                         ::testing::Values("fusion_center", "sensors-0-2", "coordinator"),
                         [](const ::testing::TestParamInfo<const char*>& param) {
                           std::string name = param.param;
                           std::erase_if(name, [](char c) { return c == '-' || c == '_'; });
                           return name;
                         });

// The middleware under loss (issue 11, item 3): Cyclone's own fault injection drops 10% and 30%
// of every packet each process sends (Internal/Test/XmitLossiness, per thousand), discovery
// included. Reliability must still deliver every measurement and count: nothing lost, every
// episode complete, costs bit-equal to the clean run's. (Before the shipped configuration set
// SPDPInterval to 1 s, a participant whose first discovery packets were dropped stayed unknown
// for Cyclone's default 30 s, and the run never started; a capped heartbeat interval keeps
// retransmissions prompt.) At 30%, a retransmission round (heartbeat, acknack, sample) fails
// two times in three, so the last measurement of an episode can take more than the fusion
// center's 1 s keep-up limit to arrive: an `overload` fault is accepted there, nothing else.
class TrustUnderLoss : public Trust, public ::testing::WithParamInterface<int> {
 protected:
  // The shipped loopback configuration with XmitLossiness added.
  static std::string lossyConfig(int per_thousand) {
    std::string xml = testing::readText(std::string(SENSORNET_SOURCE_DIR) +
                                        "/config/cyclonedds-loopback.xml");
    const std::string test = "<Test><XmitLossiness>" + std::to_string(per_thousand) +
                             "</XmitLossiness></Test>";
    const std::size_t internal = xml.find("<Internal>");
    if (internal != std::string::npos) {
      xml.insert(internal + std::string("<Internal>").size(), test);
    } else {
      xml.insert(xml.find("</Domain>"), "<Internal>" + test + "</Internal>");
    }
    return xml;
  }
};

TEST_P(TrustUnderLoss, NothingIsLostAndCostsEqualACleanRun) {
  const int loss = GetParam();
  const std::vector<double> clean = cleanCosts("loss" + std::to_string(loss), 3);
  Emulation run(uniqueRunId("loss" + std::to_string(loss)));
  const std::vector<std::string> config = {"--cyclone-config", lossyConfig(loss)};
  run.startFusionCenter(config);
  run.startSensors("0-2", config);
  run.startSensors("3-5", config);
  std::vector<std::string> coordinator = {"--scenario", kDefaultScenario, "--schedule", schedule_,
                                          "--episodes", "3", "--time-scale", "5", "--seed",
                                          std::to_string(kSeed)};
  coordinator.insert(coordinator.end(), config.begin(), config.end());
  run.startCoordinator(coordinator);
  expectLosslessAndEqual(run.finish(120s), clean, /*slow_delivery_allowed=*/loss >= 300);
}

INSTANTIATE_TEST_SUITE_P(XmitLossiness, TrustUnderLoss, ::testing::Values(100, 300),
                         [](const ::testing::TestParamInfo<int>& param) {
                           return "PerThousand" + std::to_string(param.param);
                         });

// Past the fusion center's stall limit (12 s of silence after the episode's end) the episode
// is closed without the stalled sensors: incomplete, named in the faults, left out of the
// statistics; the run goes on and its other episodes are exact.
TEST_F(Trust, SixteenSecondStallIsReportedAsDegradedWithExactCounts) {
  const std::vector<double> clean = cleanCosts("long", 3);
  Emulation run(uniqueRunId("stall-long"));
  start(run, 3, 1.0);
  waitForEpisodes(run, 1, 500ms);
  stall(run.pidOf("sensors-3-5"), 16s);
  const json report = run.finish(90s);
  ASSERT_TRUE(report.is_object());
  EXPECT_EQ(report.at("status"), "degraded");
  const auto expected = timelineCounts(kDefaultScenario, schedule_, kSeed, 3);
  const json& per_episode = report.at("per_episode");
  ASSERT_EQ(per_episode.size(), 3u);
  for (std::size_t k = 0; k < 3; ++k) {
    const json& e = per_episode[k];
    for (std::size_t j = 0; j < 6; ++j) {
      const auto sent = e.at("sent")[j].get<std::uint64_t>();
      EXPECT_EQ(sent, e.at("received")[j].get<std::uint64_t>() + e.at("lost")[j].get<std::uint64_t>());
      if (k != 1 || j < 3) {
        EXPECT_EQ(sent, expected[k][j]) << k << "/" << j;
        EXPECT_EQ(e.at("received")[j].get<std::uint64_t>(), expected[k][j]) << k << "/" << j;
      } else {
        EXPECT_LE(e.at("received")[j].get<std::uint64_t>(), expected[k][j]) << k << "/" << j;
      }
    }
    EXPECT_EQ(e.at("complete").get<bool>(), k != 1) << "episode " << k;
    if (k != 1) {
      EXPECT_EQ(e.at("realized_cost").get<double>(), clean[k]) << "episode " << k;
    }
  }
  // The faults name each stalled sensor in episode 1.
  std::set<int> named;
  for (const json& f : report.at("faults")) {
    if (f.at("kind") == "stall" && f.at("episode") == 1) named.insert(f.at("sensor").get<int>());
  }
  EXPECT_EQ(named, (std::set<int>{3, 4, 5})) << report.at("faults").dump();
  const json& summary = report.at("summary");
  EXPECT_EQ(summary.at("episodes_complete"), 2);
  EXPECT_EQ(summary.at("episodes_incomplete"), 1);
  EXPECT_DOUBLE_EQ(summary.at("mean").get<double>(), 0.5 * (clean[0] + clean[2]));
}

// Far more measurements than the fusion center may keep up with on two cores: whatever
// happens, every measurement a sensor sent is accounted for, and the run is never "completed"
// with anything lost, rejected or incomplete.
TEST_F(Trust, OverloadIsFullyFusedOrReportedNeverCompletedWithLosses) {
  if (sensornet::testing::kAddressSanitizer) GTEST_SKIP() << sensornet::testing::kNoCapacity;
  std::string yaml = testing::readText(kDefaultScenario);
  const auto at = yaml.find("constraints:");
  ASSERT_NE(at, std::string::npos);
  yaml = yaml.substr(0, at) + "constraints:\n  C: [[1, 1, 1, 1, 1, 1]]\n  b: [60000]\n";
  const std::string scenario = writeFile(dir_ / "loud.yaml", yaml);
  json uniform = varyingSchedule();
  for (json& row : uniform["rates"]) {
    for (json& rate : row) rate = 10000.0;
  }
  const std::string schedule = writeFile(dir_ / "loud.json", uniform.dump());

  Emulation run(uniqueRunId("overload"));
  run.startFusionCenter();
  run.startSensors("0-2");
  run.startSensors("3-5");
  run.startCoordinator({"--scenario", scenario, "--schedule", schedule, "--episodes", "1",
                        "--time-scale", "1", "--seed", std::to_string(kSeed)});
  const json report = run.finish(180s);
  ASSERT_TRUE(report.is_object());
  const auto expected = timelineCounts(scenario, schedule, kSeed, 1);
  const json& e = report.at("per_episode").at(0);
  std::uint64_t lost = 0;
  for (std::size_t j = 0; j < 6; ++j) {
    const auto sent = e.at("sent")[j].get<std::uint64_t>();
    EXPECT_EQ(sent, expected[0][j]) << "sensor " << j;
    EXPECT_EQ(sent, e.at("received")[j].get<std::uint64_t>() + e.at("lost")[j].get<std::uint64_t>());
    lost += e.at("lost")[j].get<std::uint64_t>();
  }
  EXPECT_TRUE(e.contains("drain_s") && e.contains("backlog"));
  const std::string status = report.at("status");
  std::printf("[ measured ] overload: %s, %llu measurements, drain %.3f s, backlog %llu\n",
              status.c_str(),
              static_cast<unsigned long long>(report.at("summary").at("received").get<std::uint64_t>()),
              e.at("drain_s").get<double>(),
              static_cast<unsigned long long>(e.at("backlog").get<std::uint64_t>()));
  if (status == "completed") {
    EXPECT_EQ(lost, 0u);
    EXPECT_EQ(report.at("summary").at("rejected"), 0);
    EXPECT_TRUE(e.at("complete").get<bool>());
    EXPECT_LE(e.at("drain_s").get<double>(), 1.0);
  } else {
    EXPECT_EQ(status, "degraded");
    EXPECT_FALSE(report.at("faults").empty());
  }
}

// Samples on the wire that do not belong are refused and counted by reason, never fused: the
// realized costs are those of a clean run.
TEST_F(Trust, RogueMeasurementsAreRefusedCountedAndNeverFused) {
  const std::vector<double> clean = cleanCosts("rogue", 3);
  Emulation run(uniqueRunId("rogue"));
  run.startFusionCenter();

  wire::RunOptions options;
  options.run_id = run.runId();
  dds::Domain domain(options.domainConfig());
  dds::Participant participant(domain);
  dds::Topic<sensornet_Measurement> topic(participant);
  // In the partition of sensors 0 and 1 (run_partitions.hpp): what it writes for them is
  // refused for what it is, not for its identity.
  dds::Writer<sensornet_Measurement> rogue(
      participant, topic,
      dds::endpointQosIn<sensornet_Measurement>(
          emulator::sensorPartition(participant.partition(), {0, 1})));
  ASSERT_TRUE(rogue.waitForReaders(1, 10s));
  const std::vector<double> wrong_size = {1.0, 2.0, 3.0};
  const std::vector<double> one = {1.0};
  const std::string this_run = run.runId(), other_run = "someone-else";
  const auto send = [&](std::uint32_t sensor, const std::string& run_id, std::uint32_t episode,
                        const std::vector<double>& z) {
    sensornet_Measurement m{};
    m.sensor_id = sensor;
    m.run_id = dds::borrowString(run_id);
    m.episode = episode;
    m.seq = 1000;
    m.emulated_time_s = 1.0;
    m.schedule_version = 1;
    m.publish_wall_time_ns = emulator::wallNowNs();
    dds::borrowSequence(m.z, z);
    ASSERT_EQ(rogue.write(m), dds::WriteResult::Written);
  };
  // Episode 1 has not started: they wait for it, then are refused.
  for (int i = 0; i < 3; ++i) send(0, this_run, 1, wrong_size);  // sensor 0 measures 1 value
  for (int i = 0; i < 2; ++i) send(99, this_run, 1, one);         // no sensor 99
  for (int i = 0; i < 4; ++i) send(1, other_run, 1, one);         // another run
  send(1, this_run, 500, one);                                     // an episode that never runs
  ASSERT_TRUE(rogue.waitForAcks(5s));

  run.startSensors("0-2");
  run.startSensors("3-5");
  run.startCoordinator({"--scenario", kDefaultScenario, "--schedule", schedule_, "--episodes",
                        "3", "--time-scale", "20", "--seed", std::to_string(kSeed)});
  const json report = run.finish(90s);
  ASSERT_TRUE(report.is_object());
  EXPECT_EQ(report.at("status"), "degraded");
  const json& by_reason = report.at("summary").at("rejected_by_reason");
  EXPECT_EQ(by_reason.value("malformed", 0), 3) << by_reason.dump();
  EXPECT_EQ(by_reason.value("unknown_sensor", 0), 2) << by_reason.dump();
  EXPECT_EQ(by_reason.value("other_run", 0), 4) << by_reason.dump();
  EXPECT_EQ(by_reason.value("unknown_episode", 0), 1) << by_reason.dump();
  EXPECT_EQ(report.at("summary").at("rejected"), 10);
  const json& per_episode = report.at("per_episode");
  ASSERT_EQ(per_episode.size(), 3u);
  const auto expected = timelineCounts(kDefaultScenario, schedule_, kSeed, 3);
  for (std::size_t k = 0; k < 3; ++k) {
    EXPECT_EQ(per_episode[k].at("realized_cost").get<double>(), clean[k]) << "episode " << k;
    for (std::size_t j = 0; j < 6; ++j) {
      EXPECT_EQ(per_episode[k].at("received")[j].get<std::uint64_t>(), expected[k][j]);
    }
  }
  bool named = false;
  for (const json& f : report.at("faults")) named |= f.at("kind") == "rejected";
  EXPECT_TRUE(named) << report.at("faults").dump();
}

}  // namespace
}  // namespace sensornet
