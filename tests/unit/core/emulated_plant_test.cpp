// The emulated plant against closed forms: for the scalar Ornstein-Uhlenbeck plant
// dx = -a x dt + dw, E[dw²] = q dt, x(0) ~ N(m0, p0), the exact moments are
//   E x(t) = e^{-at} m0,   Var x(t) = e^{-2at} p0 + q (1 - e^{-2at}) / (2a),
//   Cov(x(s), x(t)) = e^{-a(t-s)} Var x(s)   (s <= t).
// Sample moments over 4000 episodes are compared with them at 4.5 standard errors (a false
// alarm rate below 1e-5 per comparison); the seeds are fixed, so the test is deterministic.

#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <vector>

#include "sensornet/core/emulated_plant.hpp"
#include "sensornet/core/input_error.hpp"
#include "sensornet/core/random.hpp"
#include "sensornet/core/scenario.hpp"

namespace sensornet {
namespace {

using Eigen::MatrixXd;
using Eigen::VectorXd;

constexpr double kA = 0.8, kQ = 1.5, kP0 = 2.0, kM0 = 1.0, kT = 3.0;

Scenario scalarPlant() {
  Scenario s;
  s.horizon_s = kT;
  s.intervals = 3;
  s.plant.A = MatrixXd::Constant(1, 1, -kA);
  s.plant.Q = MatrixXd::Constant(1, 1, kQ);
  s.plant.P0 = MatrixXd::Constant(1, 1, kP0);
  s.plant.m0 = VectorXd::Constant(1, kM0);
  s.sensors.push_back({MatrixXd::Constant(1, 1, 2.0), MatrixXd::Constant(1, 1, 0.5)});
  s.cost.W = MatrixXd::Zero(1, 1);
  s.cost.WT = MatrixXd::Identity(1, 1);
  s.constraints.C = MatrixXd::Ones(1, 1);
  s.constraints.b = VectorXd::Ones(1);
  return s;
}

double exactVariance(double t) {
  return std::exp(-2 * kA * t) * kP0 + kQ * (1 - std::exp(-2 * kA * t)) / (2 * kA);
}

TEST(EmulatedPlant, MomentsAtAnyTicksMatchTheOrnsteinUhlenbeckClosedForm) {
  const EmulatedPlant plant(scalarPlant(), 11, /*tick_levels=*/12);
  // Ticks that are not dyadic midpoints of one another, and the two ends.
  const std::vector<std::int64_t> ticks = {0, 37, 1234, 2049, 4095, plant.tickCount()};
  const int episodes = 4000;
  std::vector<std::vector<double>> samples(ticks.size());
  for (std::uint32_t e = 0; e < episodes; ++e) {
    for (std::size_t i = 0; i < ticks.size(); ++i) {
      samples[i].push_back(plant.stateAt(e, ticks[i])(0));
    }
  }
  const auto mean = [&](std::size_t i) {
    double sum = 0;
    for (double x : samples[i]) sum += x;
    return sum / episodes;
  };
  const auto covariance = [&](std::size_t i, std::size_t j) {
    const double mi = mean(i), mj = mean(j);
    double sum = 0;
    for (int k = 0; k < episodes; ++k) sum += (samples[i][k] - mi) * (samples[j][k] - mj);
    return sum / (episodes - 1);
  };
  for (std::size_t i = 0; i < ticks.size(); ++i) {
    const double t = plant.timeOf(ticks[i]);
    const double var = exactVariance(t);
    EXPECT_NEAR(mean(i), std::exp(-kA * t) * kM0, 4.5 * std::sqrt(var / episodes)) << "t " << t;
    EXPECT_NEAR(covariance(i, i), var, 4.5 * var * std::sqrt(2.0 / episodes)) << "t " << t;
    for (std::size_t j = i + 1; j < ticks.size(); ++j) {
      const double s = t, u = plant.timeOf(ticks[j]);
      const double exact = std::exp(-kA * (u - s)) * var;
      // Standard error of a sample covariance: sqrt((σ_ss σ_uu + σ_su²) / N).
      const double se = std::sqrt((var * exactVariance(u) + exact * exact) / episodes);
      EXPECT_NEAR(covariance(i, j), exact, 4.5 * se) << "ticks " << ticks[i] << ", " << ticks[j];
    }
  }
}

TEST(EmulatedPlant, EveryProcessGetsTheSameTruthWhateverItAsksFirst) {
  const Scenario s = scalarPlant();
  const EmulatedPlant one(s, 5), other(s, 5);
  const double x_late = other.stateAt(3, 700001)(0);  // asked in another order
  const double x_early = one.stateAt(3, 12345)(0);
  EXPECT_EQ(one.stateAt(3, 700001)(0), x_late);
  EXPECT_EQ(other.stateAt(3, 12345)(0), x_early);
  EXPECT_NE(one.stateAt(4, 12345)(0), x_early);            // another episode
  EXPECT_NE(EmulatedPlant(s, 6).stateAt(3, 12345)(0), x_early);  // another run seed
  EXPECT_EQ(one.tickAt(one.timeOf(777)), 777);
  EXPECT_EQ(one.tickAt(-1.0), 0);
  EXPECT_EQ(one.tickAt(10 * kT), one.tickCount());
}

// A Path only saves work: whatever it went through before (sorted ticks as a sensor asks them,
// a tick asked twice, the ends, ticks out of order, another episode, another plant), each state
// is bit for bit that of a descent from the top. A non-symmetric n = 4 plant, so that every
// bridge matrix has all its entries.
TEST(EmulatedPlant, APathGivesTheSameStatesBitForBitAsADescentFromTheTop) {
  RandomPlantSpec spec;
  spec.state_dim = 4;
  spec.sensor_count = 3;
  spec.seed = 21;
  Scenario scenario = generateRandomScenario(spec);  // the family's A is symmetric
  scenario.plant.A(0, 1) += 0.7;
  scenario.plant.A(3, 2) -= 0.4;
  ASSERT_FALSE(scenario.plant.A.isApprox(scenario.plant.A.transpose()));
  const EmulatedPlant plant(scenario, 7);
  const EmulatedPlant other(scenario, 8);
  Rng rng(3);
  std::vector<std::int64_t> sorted;
  for (int i = 0; i < 2000; ++i) {
    sorted.push_back(static_cast<std::int64_t>(rng.uniform() * static_cast<double>(plant.tickCount())));
  }
  std::sort(sorted.begin(), sorted.end());
  std::vector<std::int64_t> asked = sorted;  // then the same tick twice, the ends, neighbours
  asked.insert(asked.end(), {sorted.back(), plant.tickCount(), 0, 1, plant.tickCount() - 1,
                             plant.tickCount() / 2, plant.tickCount() / 2 - 1});
  for (int i = 0; i < 500; ++i) {  // and out of order
    asked.push_back(static_cast<std::int64_t>(rng.uniform() * static_cast<double>(plant.tickCount())));
  }
  EmulatedPlant::Path path;
  int compared = 0;
  for (const std::uint32_t episode : {2u, 3u, 2u}) {
    for (const std::int64_t tick : asked) {
      const Eigen::VectorXd fresh = plant.stateAt(episode, tick);
      const Eigen::VectorXd reused = plant.stateAt(episode, tick, path);
      ASSERT_EQ(fresh.size(), 4);
      for (Eigen::Index i = 0; i < fresh.size(); ++i) {
        ASSERT_EQ(std::bit_cast<std::uint64_t>(reused(i)), std::bit_cast<std::uint64_t>(fresh(i)))
            << "episode " << episode << ", tick " << tick << ", component " << i;
      }
      ++compared;
    }
  }
  EXPECT_EQ(compared, 3 * static_cast<int>(asked.size()));
  // The same Path on another plant (another seed) starts over.
  EXPECT_EQ(other.stateAt(2, sorted[7], path), other.stateAt(2, sorted[7]));
  EXPECT_EQ(plant.stateAt(2, sorted[7], path), plant.stateAt(2, sorted[7]));
}

TEST(EmulatedPlant, MeasurementNoiseHasTheSensorsCovariance) {
  const EmulatedPlant plant(scalarPlant(), 2);
  const VectorXd x = VectorXd::Constant(1, 0.25);
  const int count = 20000;
  double sum = 0, sum2 = 0;
  for (int k = 0; k < count; ++k) {
    const double v = plant.measure(x, 0, 1, static_cast<std::uint64_t>(k))(0) - 2.0 * 0.25;
    sum += v;
    sum2 += v * v;
  }
  const double mean = sum / count, var = sum2 / count - mean * mean;
  EXPECT_NEAR(mean, 0.0, 4.5 * std::sqrt(0.5 / count));
  EXPECT_NEAR(var, 0.5, 4.5 * 0.5 * std::sqrt(2.0 / count));
  EXPECT_EQ(plant.measure(x, 0, 1, 7)(0), plant.measure(x, 0, 1, 7)(0));
}

TEST(EmulatedPlant, RejectsBadTicksSensorsAndLevels) {
  const Scenario s = scalarPlant();
  const EmulatedPlant plant(s, 1, 4);
  EXPECT_THROW((void)plant.stateAt(0, -1), InputError);
  EXPECT_THROW((void)plant.stateAt(0, 17), InputError);
  EXPECT_THROW((void)plant.measure(VectorXd::Zero(1), 1, 0, 0), InputError);
  EXPECT_THROW(EmulatedPlant(s, 1, 0), InputError);
  EXPECT_THROW(EmulatedPlant(s, 1, 41), InputError);
}

}  // namespace
}  // namespace sensornet
