// Timetable arrivals in the emulation (issue 14, part 3): a sensor agent's timeline in
// ArrivalMode::Timetable across a live schedule switch, checked against instants computed here
// by hand from the rates (the composed intensity, continued across the switch), and the arrival
// mode as it travels on the wire (the Scenario's appended `arrivals`).

#include <gtest/gtest.h>

#include <algorithm>
#include <iterator>
#include <string>
#include <vector>

#include "emulator_test_support.hpp"
#include "sensornet/core/input_error.hpp"
#include "sensornet/dds/wire.hpp"
#include "sensornet/wire/messages.hpp"
#include "sensornet/emulator/schedule_book.hpp"
#include "sensornet/emulator/sensor_timeline.hpp"
#include "sensornet/io/scenario_file.hpp"

namespace sensornet::emulator {
namespace {

using namespace sensornet::wire;  // the samples a run carries, fed to the core as live

using test::smallScenario;
using test::versionOf;

constexpr double kSwitchS = 1.2;
constexpr std::uint32_t kSwitchEpisode = 2;

// Horizon 3 s in 6 intervals of 0.5 s, sensors 2 and 3 silent. Version 1: sensor 0 at 2 Hz,
// sensor 1 at 0.6, 0.6, 4, 4, 0, 0 Hz. Version 2 (from episode 2 at 1.2 s): sensor 0 at 5 Hz,
// sensor 1 at 1 Hz.
RateSchedule firstVersion(double horizon_s) {
  Eigen::MatrixXd rates = Eigen::MatrixXd::Zero(6, 4);
  rates.col(0).setConstant(2.0);
  rates.col(1) << 0.6, 0.6, 4.0, 4.0, 0.0, 0.0;
  return RateSchedule(horizon_s, rates);
}

RateSchedule secondVersion(double horizon_s) {
  Eigen::MatrixXd rates = Eigen::MatrixXd::Zero(6, 4);
  rates.col(0).setConstant(5.0);
  rates.col(1).setConstant(1.0);
  return RateSchedule(horizon_s, rates);
}

struct Expected {
  double time_s;
  int sensor;
  std::uint32_t version;
};

// Each sensor's instants in the timeline, in order, are the exact ones floored to the plant's
// tick (per sensor: instants of two sensors at the same exact time may floor differently).
void expectInstants(const std::vector<TimedArrival>& timeline, std::vector<Expected> expected,
                    double tick_s) {
  std::sort(expected.begin(), expected.end(),
            [](const Expected& a, const Expected& b) { return a.time_s < b.time_s; });
  ASSERT_EQ(timeline.size(), expected.size());
  for (int sensor = 0; sensor < 4; ++sensor) {
    std::vector<TimedArrival> got;
    std::vector<Expected> want;
    std::copy_if(timeline.begin(), timeline.end(), std::back_inserter(got),
                 [&](const TimedArrival& a) { return a.sensor == sensor; });
    std::copy_if(expected.begin(), expected.end(), std::back_inserter(want),
                 [&](const Expected& e) { return e.sensor == sensor; });
    ASSERT_EQ(got.size(), want.size()) << "sensor " << sensor;
    for (std::size_t i = 0; i < want.size(); ++i) {
      EXPECT_EQ(got[i].version, want[i].version) << "sensor " << sensor << ", instant " << i;
      EXPECT_LE(got[i].time_s, want[i].time_s + 1e-12) << "sensor " << sensor << ", instant " << i;
      EXPECT_GT(got[i].time_s, want[i].time_s - tick_s - 1e-12)
          << "sensor " << sensor << ", instant " << i;
    }
  }
}

class TimetableTimeline : public ::testing::Test {
 protected:
  TimetableTimeline() : scenario_(smallScenario()), plant_(scenario_, 5) {
    (void)book_.add(versionOf(1, firstVersion(scenario_.horizon_s)));
    (void)book_.add(versionOf(2, secondVersion(scenario_.horizon_s), kSwitchEpisode, kSwitchS));
  }

  [[nodiscard]] std::vector<TimedArrival> timeline(std::uint32_t episode,
                                                   std::uint64_t seed = 7) const {
    return sensorTimeline(book_, plant_, seed, episode, {0, 1, 2, 3}, scenario_.horizon_s,
                          ArrivalMode::Timetable);
  }

  Scenario scenario_;
  EmulatedPlant plant_;
  ScheduleBook book_;
};

// Λ_0 = 2t: 0.5 and 1.5 at 0.25 and 0.75 s; Λ_0(1.2) = 2.4, then 5 Hz: 2.5 at 1.2 + 0.1 / 5.
// Λ_1: 0.3 at 0.5 s, 0.6 at 1 s (0.5 at 0.5 + 0.2 / 0.6), 1.4 at 1.2 s; then 1 Hz: 1.5 at 1.3 s,
// 2.5 at 2.3 s. Restarting the count at the switch would put sensor 1 at 1.7 and 2.7 s, taking
// version 2's own Λ_1(1.2) = 1.2 at 1.5 and 2.5 s.
TEST_F(TimetableTimeline, ContinuesTheComposedIntensityAcrossASwitch) {
  ASSERT_EQ(scenario_.horizon_s, 3.0);
  std::vector<Expected> expected = {
      {0.25, 0, 1}, {0.75, 0, 1}, {0.5 + 0.2 / 0.6, 1, 1}, {1.3, 1, 2}, {2.3, 1, 2}};
  for (int k = 0; k < 9; ++k) expected.push_back({1.22 + 0.2 * k, 0, 2});  // 1.22 .. 2.82
  expectInstants(timeline(kSwitchEpisode), expected, plant_.tickSeconds());
}

// Before the switch's episode, version 1 alone: sensor 0 every 0.5 s from 0.25 s; sensor 1 at
// Λ_1 = 0.5 (0.8333 s), then at 4 Hz from Λ_1(1) = 0.6 to 4.6 at 2 s: 1.5, 2.5, 3.5, 4.5 at
// 1 + 0.9 / 4, 1 + 1.9 / 4, 1 + 2.9 / 4, 1 + 3.9 / 4. After it,
// version 2 from 0: sensor 0 every 0.2 s from 0.1 s, sensor 1 at 0.5, 1.5 and 2.5 s.
TEST_F(TimetableTimeline, UsesTheVersionInForceAloneInTheOtherEpisodes) {
  std::vector<Expected> before = {
      {0.5 + 0.2 / 0.6, 1, 1}, {1.225, 1, 1}, {1.475, 1, 1}, {1.725, 1, 1}, {1.975, 1, 1}};
  for (int k = 0; k < 6; ++k) before.push_back({0.25 + 0.5 * k, 0, 1});
  expectInstants(timeline(kSwitchEpisode - 1), before, plant_.tickSeconds());

  std::vector<Expected> after = {{0.5, 1, 2}, {1.5, 1, 2}, {2.5, 1, 2}};
  for (int k = 0; k < 15; ++k) after.push_back({0.1 + 0.2 * k, 0, 2});
  expectInstants(timeline(kSwitchEpisode + 1), after, plant_.tickSeconds());
}

// No randomness: the seed and the episode number change nothing, and the version arriving
// mid-episode leaves the instants before its effective time as they were.
TEST_F(TimetableTimeline, IsTheSameForEverySeedAndEpisodeAndKeepsItsHeadAtASwitch) {
  const auto same = [](const std::vector<TimedArrival>& a, const std::vector<TimedArrival>& b) {
    if (a.size() != b.size()) return false;
    for (std::size_t i = 0; i < a.size(); ++i) {
      if (a[i].tick != b[i].tick || a[i].sensor != b[i].sensor) return false;
    }
    return true;
  };
  EXPECT_TRUE(same(timeline(0, 1), timeline(1, 99)));
  EXPECT_TRUE(same(timeline(5, 3), timeline(9, 4)));

  ScheduleBook first_only;
  (void)first_only.add(versionOf(1, firstVersion(scenario_.horizon_s)));
  const auto planned = sensorTimeline(first_only, plant_, 7, kSwitchEpisode, {0, 1, 2, 3},
                                      scenario_.horizon_s, ArrivalMode::Timetable);
  const auto head = [](const std::vector<TimedArrival>& all) {
    std::vector<TimedArrival> before_switch;
    for (const auto& a : all) {
      if (a.time_s < kSwitchS) before_switch.push_back(a);
    }
    return before_switch;
  };
  const std::vector<TimedArrival> head_planned = head(planned);
  EXPECT_FALSE(head_planned.empty());
  EXPECT_TRUE(same(head_planned, head(timeline(kSwitchEpisode))));
}

// The Scenario sample carries the mode in force; empty (a writer that does not set it) is
// Poisson whatever the YAML says, and anything else is refused naming the field.
class ScenarioOnTheWire : public ::testing::Test {
 protected:
  ScenarioOnTheWire() {
    run_.yaml =
        "horizon: 1.0\nintervals: 2\narrivals: timetable\nplant:\n  A: [[0]]\n  Q: [[1]]\n"
        "  P0: [[1]]\nsensors:\n  - H: [[1]]\n    R: [[1]]\nconstraints:\n  C: [[1]]\n"
        "  b: [10]\n";
    run_.scenario = parseScenarioYaml(run_.yaml, "test");
    run_.digest = digestOf(run_.yaml);
    sample_.run_id = dds::borrowString(run_id_);
    sample_.digest = dds::borrowString(run_.digest);
    sample_.yaml = dds::borrowString(run_.yaml);
    sample_.horizon_s = 1.0;
    sample_.intervals = 2;
    sample_.sensor_count = 1;
    sample_.state_dim = 1;
  }

  std::string run_id_ = "wire";
  RunScenario run_;
  sensornet_Scenario sample_{};
};

TEST_F(ScenarioOnTheWire, TakesTheAnnouncedModeOverTheYamls) {
  ASSERT_EQ(run_.scenario.arrivals, ArrivalMode::Timetable);
  const std::string poisson = "poisson";
  const std::string timetable = "timetable";
  sample_.arrivals = dds::borrowString(poisson);
  EXPECT_EQ(scenarioFromWire(sample_).scenario.arrivals, ArrivalMode::Poisson);
  sample_.arrivals = dds::borrowString(timetable);
  EXPECT_EQ(scenarioFromWire(sample_).scenario.arrivals, ArrivalMode::Timetable);
}

TEST_F(ScenarioOnTheWire, AnEmptyModeIsPoissonAndAnUnknownOneIsRefused) {
  sample_.arrivals = nullptr;
  EXPECT_EQ(scenarioFromWire(sample_).scenario.arrivals, ArrivalMode::Poisson);
  const std::string empty;
  sample_.arrivals = dds::borrowString(empty);
  EXPECT_EQ(scenarioFromWire(sample_).scenario.arrivals, ArrivalMode::Poisson);
  const std::string periodic = "periodic";
  sample_.arrivals = dds::borrowString(periodic);
  try {
    (void)scenarioFromWire(sample_);
    ADD_FAILURE() << "an unknown arrival mode was taken";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("arrivals"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("periodic"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace sensornet::emulator
