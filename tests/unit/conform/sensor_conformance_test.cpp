// The conformance rules of a sensor (sensornet/conform/sensor_conformance.hpp) on made-up runs:
// a sensor that does what the page says, drawn by our own timeline, passes every rule; each way
// of breaking one rule fails that rule and no other. The Kolmogorov-Smirnov p-value is checked
// against Kolmogorov's tabulated critical values.

#include "sensornet/conform/sensor_conformance.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "sensornet/core/emulated_plant.hpp"
#include "sensornet/core/scenario.hpp"
#include "sensornet/emulator/sensor_timeline.hpp"

namespace sensornet::conform {
namespace {

using emulator::SensorState;

constexpr std::uint64_t kSeed = 5;
constexpr int kSensor = 1;
constexpr std::int64_t kSecond = 1'000'000'000;
constexpr std::int64_t kT0 = 1'700'000'000LL * kSecond;
constexpr std::uint32_t kEpisodes = 3;

Scenario scenario() {
  RandomPlantSpec spec;
  spec.state_dim = 3;
  spec.sensor_count = 3;
  spec.seed = 17;
  spec.intervals = 5;
  spec.budget = 30.0;  // rates of several Hz: enough arrivals for the law's tests to have power
  return generateRandomScenario(spec);
}

// Rates that differ across sensors and intervals.
RateSchedule varyingRates(const Scenario& s) {
  Eigen::MatrixXd rates(s.intervals, s.sensorCount());
  for (int i = 0; i < s.intervals; ++i) {
    for (int j = 0; j < s.sensorCount(); ++j) rates(i, j) = 2.0 + 3.0 * ((i + 2 * j) % 4);
  }
  return RateSchedule(s.horizon_s, rates);
}

emulator::ScheduleVersion version(std::uint32_t number, const RateSchedule& rates,
                                  std::uint32_t episode, double at) {
  emulator::ScheduleVersion v;
  v.version = number;
  v.effective_episode = episode;
  v.effective_time_s = at;
  v.schedule = rates;
  return v;
}

// A run of kEpisodes episodes at time scale 1 in which sensor kSensor does everything right:
// READY before the first start, a status every 0.5 s, each episode's arrivals drawn as our agents
// draw them (version 2 switches in at 40% of episode 1), written at their instants, a finished
// tally after each episode, STOPPED after the shutdown.
class SensorConformanceTest : public ::testing::Test {
 protected:
  SensorConformanceTest() : scenario_(scenario()) {
    emulator::RunInputState::Update update;
    run_.inputs.onScenario({scenario_, "digest", "yaml", kSeed}, update);
    const RateSchedule rates = varyingRates(scenario_);
    run_.inputs.onSchedule(version(1, rates, 0, 0.0), update);
    RateSchedule doubled(scenario_.horizon_s, 2.0 * rates.rates());
    run_.inputs.onSchedule(version(2, doubled, 1, 0.4 * scenario_.horizon_s), update);
    run_.run_id = "made-up";
    run_.first_ns = kT0;
    const std::int64_t period =
        static_cast<std::int64_t>(scenario_.horizon_s * kSecond) + kSecond / 10;
    for (std::uint32_t k = 0; k < kEpisodes; ++k) run_.starts_ns[k] = kT0 + kSecond + k * period;
    run_.time_scale = 1.0;
    run_.shutdown_ns = kT0 + kSecond + kEpisodes * period;
    run_.shutdown_written_ns = *run_.shutdown_ns;

    SensorTrace& trace = run_.sensors[kSensor];
    trace.statuses.push_back({SensorState::Starting, 0, kT0 + kSecond / 10, kT0 + kSecond / 10});
    trace.statuses.push_back({SensorState::Ready, 1, kT0 + kSecond / 2, kT0 + kSecond / 2});
    for (std::int64_t at = kT0 + kSecond; at < *run_.shutdown_ns; at += kSecond / 2) {
      trace.statuses.push_back({SensorState::Running, 1, at, at});
    }
    trace.statuses.push_back({SensorState::Stopped, 2, *run_.shutdown_ns + kSecond / 100,
                              *run_.shutdown_ns + kSecond / 100});
    for (std::uint32_t k = 0; k < kEpisodes; ++k) {
      std::uint64_t seq = 0;
      for (const emulator::TimedArrival& a : emulator::sensorTimeline(
               run_.inputs.book(), run_.inputs.plant(), kSeed, k, {kSensor}, scenario_.horizon_s)) {
        const Eigen::VectorXd z =
            run_.inputs.plant().measure(run_.inputs.plant().stateAt(k, a.tick), kSensor, k, seq);
        ticks_.push_back(a.tick);
        trace.samples.push_back({k, seq++, a.time_s, a.version,
                                 std::vector<double>(z.data(), z.data() + z.size()),
                                 wallOf(k, a.time_s)});
      }
      trace.tallies.push_back({k, seq, true, wallOf(k, scenario_.horizon_s) + 1000});
    }
    report::RunRecord record;
    record.status = emulator::RunStatus::Completed;
    report::SensorRecord line;
    line.sensor_id = kSensor;
    line.sent = line.received = trace.samples.size();
    record.sensors = {line};
    facts_.launcher_exit = 0;
    facts_.report = record;
    facts_.program_exit = 0;
  }

  std::int64_t wallOf(std::uint32_t episode, double t) const {
    return run_.starts_ns.at(episode) + static_cast<std::int64_t>(t * kSecond) + 200'000;
  }

  SensorTrace& trace() { return run_.sensors[kSensor]; }

  // The rules that fail, by name.
  std::vector<std::string> failing() const {
    std::vector<std::string> names;
    for (const RuleCheck& r : checkSensor(run_, kSensor, facts_)) {
      if (!r.pass) names.push_back(r.rule + ": " + r.evidence);
    }
    return names;
  }

  void expectOnlyFails(const std::string& rule) const {
    const std::vector<std::string> names = failing();
    ASSERT_EQ(names.size(), 1u) << ::testing::PrintToString(names);
    EXPECT_EQ(names[0].substr(0, rule.size() + 1), rule + ":") << names[0];
  }

  Scenario scenario_;
  RecordedRun run_;
  std::vector<std::int64_t> ticks_;  // each sample's tick, as drawn
  RunFacts facts_;
};

TEST_F(SensorConformanceTest, ASensorThatKeepsTheProtocolPassesEveryRule) {
  const std::vector<RuleCheck> rules = checkSensor(run_, kSensor, facts_);
  EXPECT_EQ(rules.size(), 10u);
  for (const RuleCheck& r : rules) {
    EXPECT_TRUE(r.pass) << r.rule << ": " << r.evidence;
    EXPECT_EQ(r.section.rfind("docs/wire-protocol.md#", 0), 0u) << r.section;
  }
  const auto arrivals = std::find_if(rules.begin(), rules.end(),
                                     [](const RuleCheck& r) { return r.rule == "arrivals"; });
  ASSERT_NE(arrivals, rules.end());
  EXPECT_NE(arrivals->evidence.find("3 of 3 drawn exactly as our agents draw"), std::string::npos)
      << arrivals->evidence;
  // Both versions were drawn under: the switch inside episode 1 is there.
  std::set<std::uint32_t> versions;
  for (const SensorTrace::Sample& s : trace().samples) versions.insert(s.version);
  EXPECT_EQ(versions, (std::set<std::uint32_t>{1, 2}));
}

// Arrivals on an even grid at the right rate: the count is right, the law is not.
TEST_F(SensorConformanceTest, EvenlySpacedArrivalsFailTheArrivalLaw) {
  std::map<std::uint32_t, std::vector<SensorTrace::Sample*>> by_episode;
  for (SensorTrace::Sample& s : trace().samples) by_episode[s.episode].push_back(&s);
  for (auto& [k, samples] : by_episode) {
    // Keep each sample's version stretch: spread the instants evenly within it.
    std::map<std::uint32_t, std::vector<SensorTrace::Sample*>> by_version;
    for (SensorTrace::Sample* s : samples) by_version[s->version].push_back(s);
    for (auto& [v, list] : by_version) {
      const double from = list.front()->time_s, to = list.back()->time_s;
      for (std::size_t i = 0; i < list.size(); ++i) {
        list[i]->time_s =
            from + (to - from) * static_cast<double>(i) / static_cast<double>(list.size());
        list[i]->received_ns = wallOf(k, list[i]->time_s);
      }
    }
  }
  expectOnlyFails("arrivals");
}

TEST_F(SensorConformanceTest, ATimeOutsideTheHorizonFailsTheMeasurementTimes) {
  trace().samples.back().time_s = scenario_.horizon_s * 1.01;
  expectOnlyFails("measurement-times");
}

TEST_F(SensorConformanceTest, AMeasurementWrittenBeforeItsInstantFailsTheMeasurementTimes) {
  trace().samples[5].received_ns -= kSecond / 2;
  expectOnlyFails("measurement-times");
}

TEST_F(SensorConformanceTest, ASkippedSeqFailsTheSeqRule) {
  for (SensorTrace::Sample& s : trace().samples) {
    if (s.episode == 1 && s.seq >= 4) ++s.seq;  // seq 4 never written, the tally still says n
  }
  expectOnlyFails("seq");
}

TEST_F(SensorConformanceTest, TheWrongScheduleVersionFailsTheVersionRule) {
  for (SensorTrace::Sample& s : trace().samples) {
    if (s.version == 2) {
      s.version = 1;  // the switch ignored in the label (the instants are still right)
      break;
    }
  }
  expectOnlyFails("schedule-version");
}

TEST_F(SensorConformanceTest, AMissingTallyFailsTheTallyRuleAndTheSeqRule) {
  trace().tallies.erase(trace().tallies.begin() + 1);
  const std::vector<std::string> names = failing();
  ASSERT_EQ(names.size(), 2u) << ::testing::PrintToString(names);
  EXPECT_EQ(names[0],
            "seq: episode 1: " +
                std::to_string(std::count_if(trace().samples.begin(), trace().samples.end(),
                                             [](const auto& s) { return s.episode == 1; })) +
                " samples without a tally");
  EXPECT_EQ(names[1], "tally: episode 1: no tally");
}

TEST_F(SensorConformanceTest, ReadinessAfterTheFirstStartFailsTheReadinessRule) {
  trace().statuses[1].received_ns = run_.starts_ns.at(0) + 1;
  trace().statuses[2].state = SensorState::Starting;  // the first RUNNING came with it
  expectOnlyFails("readiness");
}

TEST_F(SensorConformanceTest, ASilenceLongerThanTheStatusPeriodFailsTheStatusRule) {
  auto& statuses = trace().statuses;
  statuses.erase(statuses.begin() + 5, statuses.begin() + 9);  // 2.5 s without a status
  expectOnlyFails("status-period");
}

// The recorder got the sensor's STOPPED before the RUN_SHUTDOWN it answers (two writers, two
// deliveries): written after it, it is in order.
TEST_F(SensorConformanceTest, AStoppedReceivedBeforeTheShutdownButWrittenAfterItLeaves) {
  trace().statuses.back().received_ns = *run_.shutdown_ns - kSecond / 100;
  for (const RuleCheck& r : checkSensor(run_, kSensor, facts_)) {
    EXPECT_TRUE(r.pass) << r.rule << ": " << r.evidence;
  }
}

TEST_F(SensorConformanceTest, LeavingWithoutStoppedOrBeingKilledFailsTheLeavingRule) {
  trace().statuses.pop_back();
  expectOnlyFails("leaving");
  trace().statuses.push_back(
      {SensorState::Stopped, 2, *run_.shutdown_ns + 1, *run_.shutdown_ns + 1});
  facts_.program_exit.reset();
  expectOnlyFails("leaving");
}

TEST_F(SensorConformanceTest, ALossInTheReportFailsTheAccountingRule) {
  facts_.report->sensors[0].received -= 1;
  facts_.report->sensors[0].lost = 1;
  expectOnlyFails("accounted");
}

// z judged against the truth: our agents' z (truth + R-noise) pass; the truth without noise,
// noise twice too large, and z = 0 fail.
TEST_F(SensorConformanceTest, MeasurementsAreJudgedAgainstTheTruthWhenClaimed) {
  facts_.measures_truth = true;
  facts_.report->summary.nees_mean = 3.0;
  facts_.report->summary.nees_band_low = 2.5;
  facts_.report->summary.nees_band_high = 3.6;
  facts_.report->summary.nees_consistent = true;
  EXPECT_TRUE(failing().empty()) << ::testing::PrintToString(failing());
  const EmulatedPlant& plant = run_.inputs.plant();
  const SensorModel& model = scenario_.sensors[kSensor];
  const std::vector<SensorTrace::Sample> ours = trace().samples;
  const auto remake = [&](double noise_scale) {
    for (std::size_t i = 0; i < ours.size(); ++i) {
      const SensorTrace::Sample& s = ours[i];
      const Eigen::VectorXd truth = model.H * plant.stateAt(s.episode, ticks_[i]);
      const Eigen::Map<const Eigen::VectorXd> z(s.z.data(), static_cast<Eigen::Index>(s.z.size()));
      const Eigen::VectorXd scaled = truth + noise_scale * (z - truth);
      trace().samples[i].z.assign(scaled.data(), scaled.data() + scaled.size());
    }
  };
  remake(0.0);
  expectOnlyFails("measurement-noise");
  remake(2.0);
  expectOnlyFails("measurement-noise");
  for (SensorTrace::Sample& s : trace().samples) std::fill(s.z.begin(), s.z.end(), 0.0);
  expectOnlyFails("measurement-noise");
}

TEST_F(SensorConformanceTest, TruthIsCheckedOnlyWhenClaimed) {
  facts_.measures_truth = true;
  facts_.report->summary.nees_mean = 9.0;
  facts_.report->summary.nees_band_low = 2.5;
  facts_.report->summary.nees_band_high = 3.6;
  facts_.report->summary.nees_confidence = 0.999;
  facts_.report->summary.nees_consistent = false;
  expectOnlyFails("truth");
  facts_.measures_truth = false;
  EXPECT_TRUE(failing().empty());
}

// Kolmogorov's limiting law: P(√n D > 1.3581) = 0.05 and P(√n D > 1.9495) = 0.001 (the
// tabulated critical values); with n = 10^6 Stephens' correction is negligible.
TEST(KsUniform, MatchesKolmogorovsCriticalValues) {
  const std::size_t n = 1'000'000;
  for (const auto& [lambda, p] : {std::pair{1.3581, 0.05}, std::pair{1.9495, 0.001}}) {
    const double d = lambda / std::sqrt(static_cast<double>(n));
    std::vector<double> values(n);
    // An even grid shifted up by d - 1/n: its largest distance to the uniform law is d.
    for (std::size_t i = 0; i < n; ++i) {
      values[i] = std::min(1.0, (static_cast<double>(i) + 1.0) / static_cast<double>(n) + d -
                                    1.0 / static_cast<double>(n));
    }
    const KsTest test = ksUniform(values);
    EXPECT_NEAR(test.d, d, 1e-9);
    EXPECT_NEAR(test.p_value, p, 0.02 * p) << lambda;
  }
  EXPECT_NEAR(ksUniform({0.1, 0.3, 0.5, 0.7, 0.9}).d, 0.1, 1e-12);
  EXPECT_LT(ksUniform(std::vector<double>(50, 0.2)).p_value, 1e-10);
}

}  // namespace
}  // namespace sensornet::conform
