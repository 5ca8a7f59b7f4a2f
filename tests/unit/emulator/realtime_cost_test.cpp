// The real-time cost of an episode (EpisodeFusion::finish, episode_fusion.hpp): the covariance of
// what had arrived by each instant, integrated. Checked against the hindsight cost it must equal
// without delay (the same floating-point number), the order it must keep with delay (fewer
// measurements known at each instant: a larger covariance), and a brute-force computation of a
// scalar example with the closed-form covariance flow and Simpson's rule.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include "sensornet/core/surrogate.hpp"
#include "sensornet/emulator/episode_fusion.hpp"
#include "sensornet/emulator/schedule_book.hpp"
#include "sensornet/emulator/sensor_timeline.hpp"

#include "emulator_test_support.hpp"

namespace sensornet::emulator {
namespace {

using test::versionOf;

// A random plant with a running weight, so that every instant's covariance counts.
Scenario weightedScenario() {
  RandomPlantSpec spec;
  spec.state_dim = 3;
  spec.sensor_count = 4;
  spec.seed = 9;
  spec.intervals = 6;
  spec.budget = 8.0;
  Scenario s = generateRandomScenario(spec);
  s.cost.W = Eigen::MatrixXd::Identity(3, 3);
  return s;
}

class RealtimeCostTest : public ::testing::Test {
 protected:
  RealtimeCostTest() : scenario_(weightedScenario()), plant_(scenario_, 5) {}

  // The book: one version, or a second one (sensor 0 out) from `switch_s` of every episode.
  ScheduleBook book(std::uint32_t episode, double switch_s) const {
    ScheduleBook b;
    (void)b.add(versionOf(1, uniformSchedule(scenario_)));
    if (switch_s > 0.0) {
      Eigen::MatrixXd rates = uniformSchedule(scenario_).rates();
      rates.col(0).setZero();
      (void)b.add(versionOf(2, RateSchedule(scenario_.horizon_s, rates), episode, switch_s));
    }
    return b;
  }

  // The episode's measurements, each held back by an exponential delay of the given mean.
  std::vector<FusedMeasurement> measurements(const ScheduleBook& b, std::uint32_t episode,
                                             double mean_delay_s) const {
    std::mt19937_64 random(episode + 100);
    std::exponential_distribution<double> delay(mean_delay_s > 0.0 ? 1.0 / mean_delay_s : 1.0);
    std::vector<FusedMeasurement> all;
    std::vector<std::uint64_t> seq(4, 0);
    for (const auto& a : sensorTimeline(b, plant_, 5, episode, {0, 1, 2, 3}, scenario_.horizon_s)) {
      FusedMeasurement m;
      m.sensor = a.sensor;
      m.seq = seq[static_cast<std::size_t>(a.sensor)]++;
      m.time_s = a.time_s;
      m.version = a.version;
      m.z = plant_.measure(plant_.stateAt(episode, a.tick), a.sensor, episode, m.seq);
      m.network_delay_s = mean_delay_s > 0.0 ? delay(random) : 0.0;
      all.push_back(m);
    }
    return all;
  }

  // Fuses them in a shuffled order with an online watermark on the way, as the fusion center may.
  EpisodeResult fuse(const ScheduleBook& b, std::uint32_t episode,
                     std::vector<FusedMeasurement> all) const {
    std::shuffle(all.begin(), all.end(), std::mt19937(episode));
    EpisodeFusion fusion(scenario_, plant_, b, episode, [this](const ScheduleVersion& v) {
      return computeBracket(scenario_, v.schedule);
    });
    const std::size_t half = all.size() / 2;
    for (std::size_t i = 0; i < half; ++i) EXPECT_FALSE(fusion.add(all[i]));
    fusion.fuseUpTo(1.2);
    for (std::size_t i = half; i < all.size(); ++i) EXPECT_FALSE(fusion.add(all[i]));
    return fusion.finish();
  }

  Scenario scenario_;
  EmulatedPlant plant_;
};

// The computation itself (EpisodeFusion takes the hindsight cost without delay, so it is called
// here directly), in the arrival order the fusion center saw.
TEST_F(RealtimeCostTest, EqualsTheHindsightCostBitForBitWithoutDelay) {
  for (std::uint32_t episode = 0; episode < 4; ++episode) {
    for (const double switch_s : {0.0, plant_.timeOf(plant_.tickAt(1.37))}) {
      const ScheduleBook b = book(episode, switch_s);
      std::vector<FusedMeasurement> all = measurements(b, episode, 0.0);
      ASSERT_GT(all.size(), 10u);
      const EpisodeResult r = fuse(b, episode, all);
      std::shuffle(all.begin(), all.end(), std::mt19937(episode));
      EXPECT_EQ(realtimeCost(scenario_, switch_s, all), r.realized_cost)
          << "episode " << episode << " switch " << switch_s;
      EXPECT_EQ(r.realtime_cost, r.realized_cost);
    }
  }
}

// With delay, at every instant the filter knows a subset of what hindsight knows, so its
// covariance is larger in the Loewner order and, with W = I, the cost strictly larger. The
// hindsight cost does not depend on the delays at all.
TEST_F(RealtimeCostTest, IsAboveTheHindsightCostWithDelayWhichLeavesHindsightUnchanged) {
  for (std::uint32_t episode = 0; episode < 4; ++episode) {
    for (const double switch_s : {0.0, plant_.timeOf(plant_.tickAt(1.37))}) {
      const ScheduleBook b = book(episode, switch_s);
      const EpisodeResult prompt = fuse(b, episode, measurements(b, episode, 0.0));
      const EpisodeResult delayed = fuse(b, episode, measurements(b, episode, 0.05));
      EXPECT_EQ(delayed.realized_cost, prompt.realized_cost);
      EXPECT_GT(delayed.realtime_cost, delayed.realized_cost * (1.0 + 1e-6)) << episode;
      // A longer delay costs more still.
      const EpisodeResult later = fuse(b, episode, measurements(b, episode, 0.3));
      EXPECT_GT(later.realtime_cost, delayed.realtime_cost) << episode;
    }
  }
}

// Arrivals far out of timestamp order make every late one re-fuse what follows it: past the
// given bound the computation gives up (NaN) instead of holding the fusion center's loop.
TEST_F(RealtimeCostTest, GivesUpPastItsBoundOnMeasurementsFusedAgain) {
  const ScheduleBook b = book(1, 0.0);
  const std::vector<FusedMeasurement> all = measurements(b, 1, 0.3);
  EXPECT_TRUE(std::isfinite(realtimeCost(scenario_, 0.0, all)));
  EXPECT_TRUE(std::isnan(realtimeCost(scenario_, 0.0, all, 0)));
}

// The scalar plant dx = a x dt + sqrt(q) dW, z = x + v with v ~ N(0, r), W = W_T = 1, T = 1.
// Measurement 1 taken at 0.2 arrives at 0.7, measurement 2 taken at 0.4 arrives at 0.5, and
// measurement 3 taken at 0.9 arrives at 1.1, after T. The covariance known at time t is:
//   [0, 0.5): no measurement;  [0.5, 0.7): measurement 2;  [0.7, 1]: measurements 1 and 2.
// Each piece by the closed-form flow P(t) = e^{2a(t-s)} P(s) + q (e^{2a(t-s)} - 1) / (2a) and the
// update P r / (P + r), integrated by composite Simpson on 20000 panels per piece.
class ScalarExample {
 public:
  static constexpr double a = -0.7, q = 1.3, p0 = 2.0, r = 0.4, horizon = 1.0;

  static double flow(double p, double dt) {
    const double e = std::exp(2.0 * a * dt);
    return e * p + q * (e - 1.0) / (2.0 * a);
  }

  // The covariance at t of the filter over the measurements taken at `times` (all <= t).
  static double covarianceAt(std::vector<double> times, double t) {
    std::sort(times.begin(), times.end());
    double p = p0, at = 0.0;
    for (const double s : times) {
      p = flow(p, s - at);
      p = p * r / (p + r);
      at = s;
    }
    return flow(p, t - at);
  }

  static double integral(const std::vector<double>& times, double from, double to) {
    const int panels = 20000;
    const double h = (to - from) / panels;
    double sum = covarianceAt(times, from) + covarianceAt(times, to);
    for (int i = 1; i < panels; ++i) {
      sum += (i % 2 == 1 ? 4.0 : 2.0) * covarianceAt(times, from + i * h);
    }
    return sum * h / 3.0;
  }

  static double realtimeCost() {
    return integral({}, 0.0, 0.5) + integral({0.4}, 0.5, 0.7) + integral({0.2, 0.4}, 0.7, 1.0) +
           covarianceAt({0.2, 0.4}, horizon);
  }
  static double hindsightCost() {
    return integral({}, 0.0, 0.2) + integral({0.2}, 0.2, 0.4) + integral({0.2, 0.4}, 0.4, 0.9) +
           integral({0.2, 0.4, 0.9}, 0.9, 1.0) + covarianceAt({0.2, 0.4, 0.9}, horizon);
  }

  // Measurement `seq` of the one sensor, taken at time_s, held back delay_s by the emulated
  // network and received at received_s (0: when due).
  static FusedMeasurement measurement(std::uint64_t seq, double time_s, double delay_s,
                                      double received_s = 0.0) {
    FusedMeasurement m;
    m.sensor = 0;
    m.seq = seq;
    m.time_s = time_s;
    m.version = 1;
    m.z = Eigen::VectorXd::Constant(1, 0.25);
    m.network_delay_s = delay_s;
    m.received_s = received_s;
    return m;
  }

  static ScheduleBook book() {
    ScheduleBook b;
    (void)b.add(versionOf(1, RateSchedule(1.0, Eigen::MatrixXd::Constant(1, 1, 3.0))));
    return b;
  }

  static Scenario scenario() {
    Scenario s;
    s.horizon_s = horizon;
    s.intervals = 1;
    s.plant.A = Eigen::MatrixXd::Constant(1, 1, a);
    s.plant.Q = Eigen::MatrixXd::Constant(1, 1, q);
    s.plant.P0 = Eigen::MatrixXd::Constant(1, 1, p0);
    s.sensors.push_back({Eigen::MatrixXd::Ones(1, 1), Eigen::MatrixXd::Constant(1, 1, r)});
    s.cost.W = Eigen::MatrixXd::Ones(1, 1);
    s.cost.WT = Eigen::MatrixXd::Ones(1, 1);
    s.constraints.C = Eigen::MatrixXd::Ones(1, 1);
    s.constraints.b = Eigen::VectorXd::Constant(1, 10.0);
    return s;
  }
};

TEST(RealtimeCost, MatchesABruteForceScalarComputation) {
  const Scenario s = ScalarExample::scenario();
  const EmulatedPlant plant(s, 1, 8);
  const ScheduleBook b = ScalarExample::book();
  EpisodeFusion fusion(s, plant, b, 0, [](const ScheduleVersion&) { return CostBracket{}; });
  // In arrival order, as the network delivers them.
  EXPECT_FALSE(fusion.add(ScalarExample::measurement(1, 0.4, 0.1)));
  EXPECT_FALSE(fusion.add(ScalarExample::measurement(0, 0.2, 0.5)));
  EXPECT_FALSE(fusion.add(ScalarExample::measurement(2, 0.9, 0.2)));
  fusion.setTally(0, {3});
  const EpisodeResult result = fusion.finish();
  const double realtime = ScalarExample::realtimeCost();
  const double hindsight = ScalarExample::hindsightCost();
  EXPECT_NEAR(result.realized_cost, hindsight, 1e-11 * hindsight);
  EXPECT_NEAR(result.realtime_cost, realtime, 1e-11 * realtime);
  EXPECT_GT(realtime - hindsight, 0.05);  // the example tells the two apart
}

// The cost of what was received by each instant: the same example, but the late arrivals come
// from the real network (received_s) rather than the emulated one, and one measurement the
// emulated network held back is received "earlier" than it was due (clock skew between hosts):
// it counts from when it was due. The emulated real-time cost sees only the emulated delay:
//   [0, 0.2): none;  [0.2, 0.5): measurement 1;  [0.5, 0.9): 1 and 2;  [0.9, 1]: all three.
// A receipt counts from the plant's next tick (1/256 s here): 0.7 s from 180/256 = 0.703125 s.
TEST(RealtimeCost, OfWhatWasReceivedMatchesABruteForceScalarComputation) {
  const Scenario s = ScalarExample::scenario();
  const EmulatedPlant plant(s, 1, 8);
  const ScheduleBook b = ScalarExample::book();
  EpisodeFusion fusion(s, plant, b, 0, [](const ScheduleVersion&) { return CostBracket{}; });
  EXPECT_FALSE(fusion.add(ScalarExample::measurement(1, 0.4, 0.1, 0.45)));  // due at 0.5: counts from 0.5
  EXPECT_FALSE(fusion.add(ScalarExample::measurement(0, 0.2, 0.0, 0.7)));
  EXPECT_FALSE(fusion.add(ScalarExample::measurement(2, 0.9, 0.0, 1.1)));   // received after T
  fusion.setTally(0, {3});
  const EpisodeResult result = fusion.finish();
  using X = ScalarExample;
  const double emulated = X::integral({}, 0.0, 0.2) + X::integral({0.2}, 0.2, 0.5) +
                          X::integral({0.2, 0.4}, 0.5, 0.9) +
                          X::integral({0.2, 0.4, 0.9}, 0.9, 1.0) +
                          X::covarianceAt({0.2, 0.4, 0.9}, X::horizon);
  const double tick = std::ceil(0.7 * 256.0) / 256.0;
  const double received = X::integral({}, 0.0, 0.5) + X::integral({0.4}, 0.5, tick) +
                          X::integral({0.2, 0.4}, tick, 1.0) +
                          X::covarianceAt({0.2, 0.4}, X::horizon);
  EXPECT_NEAR(result.realtime_cost, emulated, 1e-11 * emulated);
  EXPECT_NEAR(result.received_realtime_cost, received, 1e-11 * received);
  EXPECT_GT(received - emulated, 0.05);  // the example tells the two apart
}

// Nothing received later than it was due: the received cost is the real-time cost itself.
TEST_F(RealtimeCostTest, OfWhatWasReceivedEqualsTheRealtimeCostWhenNothingCameLate) {
  const ScheduleBook b = book(2, 0.0);
  std::vector<FusedMeasurement> all = measurements(b, 2, 0.05);
  for (FusedMeasurement& m : all) m.received_s = m.time_s + 0.5 * m.network_delay_s;
  const EpisodeResult r = fuse(b, 2, all);
  EXPECT_GT(r.realtime_cost, r.realized_cost);
  EXPECT_EQ(r.received_realtime_cost, r.realtime_cost);
}

TEST(RealtimeCost, RefusesANegativeOrNonFiniteDelay) {
  const Scenario s = ScalarExample::scenario();
  const EmulatedPlant plant(s, 1, 8);
  const ScheduleBook b = ScalarExample::book();
  EpisodeFusion fusion(s, plant, b, 0, [](const ScheduleVersion&) { return CostBracket{}; });
  FusedMeasurement m;
  m.time_s = 0.5;
  m.z = Eigen::VectorXd::Zero(1);
  for (const double delay : {-0.1, std::nan(""), HUGE_VAL}) {
    m.network_delay_s = delay;
    const auto rejection = fusion.add(m);
    ASSERT_TRUE(rejection);
    EXPECT_EQ(rejection->reason, "malformed");
  }
}

}  // namespace
}  // namespace sensornet::emulator
