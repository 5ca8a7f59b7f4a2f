#include "sensornet/core/brownian_instants.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <vector>

#include "sensornet/core/input_error.hpp"
#include "sensornet/core/random.hpp"

// Every reference below is written here from the paper's equations, independently of the code
// under test: the Kalman-gain form of the update (eqs. 5-7) instead of v // Γ⁻, the explicit
// two-measure cost eq. (26), fine Riemann sums, dense grids and a derivative-free compass search.

namespace sensornet {
namespace {

double logUniform(Rng& rng, double low, double high) {
  return std::exp(std::log(low) + (std::log(high) - std::log(low)) * rng.uniform());
}

BrownianProblem randomProblem(Rng& rng, int n) {
  BrownianProblem p;
  p.sigma2 = logUniform(rng, 0.2, 5.0);
  p.horizon_s = logUniform(rng, 0.2, 5.0);
  p.v0 = logUniform(rng, 0.05, 5.0);
  for (int k = 0; k < n; ++k) p.variances.push_back(logUniform(rng, 0.05, 5.0));
  return p;
}

std::vector<double> randomInstants(Rng& rng, int n, double horizon_s) {
  std::vector<double> t(static_cast<std::size_t>(n));
  for (double& x : t) x = horizon_s * rng.uniform();
  std::sort(t.begin(), t.end());
  return t;
}

// Posterior variances Γ_1..Γ_n by the Kalman gain, eqs. (5)-(7).
std::vector<double> referencePosteriors(const BrownianProblem& p, const std::vector<double>& t) {
  std::vector<double> posterior;
  double variance = p.v0, previous = 0.0;
  for (std::size_t k = 0; k < t.size(); ++k) {
    const double prior = variance + p.sigma2 * (t[k] - previous);  // (7)
    const double gain = prior / (prior + p.variances[k]);          // (6)
    variance = prior - gain * prior;                               // (5)
    posterior.push_back(variance);
    previous = t[k];
  }
  return posterior;
}

// ∫_0^T v(t) dt piece by piece (trapezoids of the piecewise-linear v of eq. 10).
double referenceCost(const BrownianProblem& p, const std::vector<double>& t) {
  const std::vector<double> posterior = referencePosteriors(p, t);
  double cost = 0.0, start = 0.0, level = p.v0;
  for (std::size_t k = 0; k <= t.size(); ++k) {
    const double end = k < t.size() ? t[k] : p.horizon_s;
    const double length = end - start;
    cost += length * (level + 0.5 * p.sigma2 * length);
    if (k < t.size()) level = posterior[k], start = end;
  }
  return cost;
}

// Eq. (14).
double singleCost(double sigma2, double T, double v0, double v1, double t1) {
  const double prior = sigma2 * t1 + v0;
  return 0.5 * sigma2 * t1 * t1 + v0 * t1 + 0.5 * sigma2 * (T - t1) * (T - t1) +
         prior * v1 * (T - t1) / (prior + v1);
}

// Eq. (26), third form.
double twoCost(const BrownianProblem& p, double t1, double t2) {
  const double s = p.sigma2, T = p.horizon_s, v0 = p.v0, v1 = p.variances[0], v2 = p.variances[1];
  const double d2 = t2 - t1, a = v0 + s * t1;
  return 0.5 * s * t1 * t1 + v0 * t1 + 0.5 * s * d2 * d2 + a * v1 * d2 / (a + v1) +
         0.5 * s * (T - t2) * (T - t2) +
         v2 * (T - t2) * (v1 * a + s * d2 * (v1 + a)) /
             ((v1 + v2) * a + v1 * v2 + s * d2 * (v1 + a));
}

// Derivative-free compass search over 0 <= t_1 <= ... <= t_n <= T (each trial point is sorted
// and clamped), from `start` with initial step `step`, halving the step until it is below
// `smallest`.
std::vector<double> compassSearch(const std::function<double(const std::vector<double>&)>& cost,
                                  std::vector<double> t, double T, double step, double smallest) {
  double best = cost(t);
  while (step > smallest) {
    bool improved = false;
    for (std::size_t k = 0; k < t.size(); ++k) {
      for (double sign : {1.0, -1.0}) {
        std::vector<double> trial = t;
        trial[k] = std::clamp(trial[k] + sign * step, 0.0, T);
        std::sort(trial.begin(), trial.end());
        const double c = cost(trial);
        if (c < best) best = c, t = trial, improved = true;
      }
    }
    if (!improved) step *= 0.5;
  }
  return t;
}

// ---------------------------------------------------------------------------------------------

TEST(BrownianCost, EqualsAFineRiemannSumOfTheVariancePath) {
  Rng rng(11);
  for (int trial = 0; trial < 20; ++trial) {
    const int n = 1 + trial % 5;
    const BrownianProblem p = randomProblem(rng, n);
    const std::vector<double> t = randomInstants(rng, n, p.horizon_s);
    const std::vector<double> posterior = referencePosteriors(p, t);
    // Midpoint sum of v(t) of eq. (10) on N cells. v is linear within a cell except where it
    // jumps down at a measurement, so the sum is exact up to (sum of jumps) x cell width.
    constexpr int kCells = 200000;
    const double h = p.horizon_s / kCells;
    double sum = 0.0, jumps = 0.0;
    std::size_t k = 0;
    double level = p.v0, since = 0.0;
    for (int i = 0; i < kCells; ++i) {
      const double mid = (i + 0.5) * h;
      while (k < t.size() && t[k] <= mid) {
        const double before = level + p.sigma2 * (t[k] - since);
        jumps += before - posterior[k];
        level = posterior[k], since = t[k];
        ++k;
      }
      sum += (level + p.sigma2 * (mid - since)) * h;
    }
    const double cost = timetableCost(p, t);
    EXPECT_NEAR(cost, sum, jumps * h + 1e-12 * cost) << "trial " << trial;
    EXPECT_NEAR(cost, referenceCost(p, t), 1e-12 * cost);
  }
}

TEST(BrownianCost, GradientMatchesCentralDifferences) {
  Rng rng(12);
  for (int trial = 0; trial < 30; ++trial) {
    const int n = 1 + trial % 6;
    const BrownianProblem p = randomProblem(rng, n);
    // Interior, distinct instants so that central differences stay feasible.
    std::vector<double> t = randomInstants(rng, n, 0.9 * p.horizon_s);
    for (int k = 0; k < n; ++k) t[static_cast<std::size_t>(k)] += 0.02 * p.horizon_s * (k + 1);
    const std::vector<double> gradient = timetableCostGradient(p, t);
    const double h = 1e-5 * p.horizon_s;
    const double scale = p.v0 + p.sigma2 * p.horizon_s;
    for (std::size_t k = 0; k < t.size(); ++k) {
      std::vector<double> up = t, down = t;
      up[k] += h, down[k] -= h;
      const double numeric = (referenceCost(p, up) - referenceCost(p, down)) / (2.0 * h);
      // Truncation O(h²) plus rounding ~ eps·J/h: far below 1e-7 of the gradient's scale.
      EXPECT_NEAR(gradient[k], numeric, 1e-7 * scale) << "trial " << trial << " k " << k;
    }
  }
}

TEST(BrownianCost, GradientOfOneMeasureIsEq16) {
  Rng rng(13);
  for (int trial = 0; trial < 20; ++trial) {
    const BrownianProblem p = randomProblem(rng, 1);
    const double t1 = p.horizon_s * rng.uniform();
    const double s = p.sigma2, v0 = p.v0, v1 = p.variances[0], T = p.horizon_s;
    const double a = v0 + s * t1;
    const double eq16 = a / (a + v1) * (a - s * (T - t1) * (v1 / (a + v1) + 1.0));
    EXPECT_NEAR(timetableCostGradient(p, {t1})[0], eq16, 1e-13 * (v0 + s * T));
  }
}

// ---------------------------------------------------------------------------------------------

TEST(BrownianOneMeasure, ClosedFormIsTheMinimumOfADenseGrid) {
  Rng rng(21);
  for (int trial = 0; trial < 40; ++trial) {
    const BrownianProblem p = randomProblem(rng, 1);
    const double s = p.sigma2, T = p.horizon_s, v0 = p.v0, v1 = p.variances[0];
    const double t = optimalSingleInstant(s, T, v0, v1);
    const double at_t = singleCost(s, T, v0, v1, t);
    constexpr int kPoints = 20000;
    double grid_best = std::numeric_limits<double>::infinity();
    for (int i = 0; i <= kPoints; ++i) {
      grid_best = std::min(grid_best, singleCost(s, T, v0, v1, T * i / kPoints));
    }
    // No grid point beats the closed form, and the grid gets within one Lipschitz step of it
    // (|dJ/dt_1| <= v0 + 2 σ² T).
    EXPECT_LE(at_t, grid_best * (1.0 + 1e-13)) << "trial " << trial;
    EXPECT_GE(at_t, grid_best - (v0 + 2.0 * s * T) * T / kPoints);
    EXPECT_EQ(optimalInstants(p).instants[0], t);
    EXPECT_EQ(optimalInstants(p).regime, t > 0.0 ? 2 : 1);
  }
}

TEST(BrownianOneMeasure, Fig2OptimumIsAtZeroExactlyWhenV0IsAtLeastSqrtTwo) {
  const double root2 = std::sqrt(2.0);
  EXPECT_NEAR(criticalDurationSingle(1.0, root2, 1.0), 1.0, 1e-15);
  EXPECT_GT(optimalSingleInstant(1.0, 1.0, root2 * (1.0 - 1e-6), 1.0), 0.0);
  EXPECT_EQ(optimalSingleInstant(1.0, 1.0, root2 * (1.0 + 1e-6), 1.0), 0.0);
  EXPECT_EQ(optimalSingleInstant(1.0, 1.0, 1.5, 1.0), 0.0);
  EXPECT_GT(optimalSingleInstant(1.0, 1.0, 1.3, 1.0), 0.0);
}

TEST(BrownianOneMeasure, Proposition2MonotonicityAndAsymptote) {
  const double s = 1.3;
  const std::vector<double> levels = {0.0, 0.1, 0.3, 0.7, 1.5, 3.0, 6.0};
  const std::vector<double> horizons = {0.05, 0.2, 0.5, 1.0, 2.0, 4.0, 8.0, 16.0};
  for (double v0 : levels) {
    for (double v1 : {0.1, 0.5, 1.0, 3.0}) {
      double previous = -1.0;
      for (double T : horizons) {  // increasing in T
        const double t = optimalSingleInstant(s, T, v0, v1);
        EXPECT_GE(t, previous) << v0 << " " << v1 << " " << T;
        if (previous > 0.0) {
          EXPECT_GT(t, previous);  // strictly, in regime 2
        }
        if (t > 0.0) {
          EXPECT_LT(t, (s * T + v1 - v0) / (2.0 * s));  // eq. (21)
        }
        previous = t;
      }
    }
  }
  for (double T : horizons) {
    for (double v1 : {0.1, 0.5, 1.0, 3.0}) {
      double previous = std::numeric_limits<double>::infinity();
      for (double v0 : levels) {  // decreasing in v0
        const double t = optimalSingleInstant(s, T, v0, v1);
        EXPECT_LE(t, previous);
        previous = t;
      }
    }
    for (double v0 : levels) {
      double previous = -1.0;
      for (double v1 : {0.05, 0.1, 0.5, 1.0, 3.0, 10.0}) {  // increasing in v1
        const double t = optimalSingleInstant(s, T, v0, v1);
        EXPECT_GE(t, previous);
        previous = t;
      }
      // Eq. (22): the limit v1 -> ∞.
      EXPECT_NEAR(optimalSingleInstant(s, T, v0, 1e9),
                  std::max(0.0, (2.0 * s * T - v0) / (3.0 * s)), 1e-6 * (1.0 + T));
    }
  }
  // Eq. (20) prints the remainder as o(1/T); expanding the square root of eq. (18) gives
  // t_opt = asymptote - 2 v1² / (σ⁴ T) + O(1/T²), so the remainder is of order exactly 1/T.
  const double T = 1e4, v0 = 0.7, v1 = 2.0;
  const double asymptote = (s * T + v1 - v0) / (2.0 * s);
  EXPECT_NEAR(T * (asymptote - optimalSingleInstant(s, T, v0, v1)), 2.0 * v1 * v1 / (s * s),
              1e-2 * 2.0 * v1 * v1 / (s * s));
}

TEST(BrownianOneMeasure, Theorem3LowerBoundHoldsAtTheOptimumAndElsewhere) {
  Rng rng(23);
  for (int trial = 0; trial < 50; ++trial) {
    const BrownianProblem p = randomProblem(rng, 1);
    const double s = p.sigma2, T = p.horizon_s, v0 = p.v0, v1 = p.variances[0];
    const double bound = lowerBoundSingle(s, T, v0, v1);
    EXPECT_NEAR(bound, std::sqrt(s * (v0 * v1 / (v0 + v1)) * T * T * T), 1e-14 * bound);
    EXPECT_GT(singleCost(s, T, v0, v1, optimalSingleInstant(s, T, v0, v1)), bound);
    for (int i = 0; i < 10; ++i) EXPECT_GT(singleCost(s, T, v0, v1, T * rng.uniform()), bound);
  }
}

// ---------------------------------------------------------------------------------------------

BrownianProblem twoProblem(double T, double v0, double v1, double v2) {
  BrownianProblem p;
  p.sigma2 = 1.0;
  p.horizon_s = T;
  p.v0 = v0;
  p.variances = {v1, v2};
  return p;
}

TEST(BrownianTwoMeasures, Fig9CriticalDurations) {
  const TwoMeasureCriticalDurations critical = criticalDurationsTwo(1.0, 1.0, 1.0, 1.0);
  EXPECT_NEAR(critical.regime1_end, 0.3, 1e-14);
  EXPECT_NEAR(critical.regime2_end, 7.0 / 6.0, 1e-14);
  const BrownianSchedule at_critical = optimalInstants(twoProblem(7.0 / 6.0, 1, 1, 1));
  EXPECT_NEAR(at_critical.instants[0], 0.0, 1e-9);
  EXPECT_NEAR(at_critical.instants[1], 0.5, 1e-9);

  const BrownianSchedule short_horizon = optimalInstants(twoProblem(0.29, 1, 1, 1));
  EXPECT_EQ(short_horizon.regime, 1);
  EXPECT_EQ(short_horizon.instants, (std::vector<double>{0.0, 0.0}));
  const BrownianSchedule middle = optimalInstants(twoProblem(0.31, 1, 1, 1));
  EXPECT_EQ(middle.regime, 2);
  EXPECT_EQ(middle.instants[0], 0.0);
  EXPECT_GT(middle.instants[1], 0.0);
  const BrownianSchedule long_horizon = optimalInstants(twoProblem(1.2, 1, 1, 1));
  EXPECT_EQ(long_horizon.regime, 3);
  EXPECT_GT(long_horizon.instants[0], 0.0);
}

// Fig. 7, rows b-f (σ² = 1): v0, v1, v2, T, printed t_1^(1), T_{1,crit}, t_1,opt, t_2,opt.
struct Fig7Row {
  double v0, v1, v2, T, first_step_t1, critical, t1, t2;
  int regime;
};

// The table mixes rounding (rows d, e) and truncation (row b: 1.04016 prints as 1.0401), so the
// printed digits are matched to within one unit of the last one.
TEST(BrownianTwoMeasures, Fig7TableToThePrintedDigits) {
  // Row d prints t_2,opt = 2.985; 2.2985 is meant (a dropped digit): (1.1211, 2.985) costs more
  // than (1.1211, 2.2985), which also satisfies eq. (44) (checked in the next test).
  const std::vector<Fig7Row> rows = {
      {1, 1, 1, 71.0 / 18.0, 0.8668, 7.0 / 6.0, 1.0401, 2.4092, 3},
      {3, 1, 1, 317.0 / 76.0, 0.0, 4.6500, 0.0, 2.0, 2},
      {1, 3, 1, 317.0 / 76.0, 0.9768, 1.1878, 1.1211, 2.2985, 3},
      {1, 1, 3, 123.0 / 34.0, 1.1044, 0.8630, 1.1968, 2.4269, 3},
      {0, 1, 1, 3.5, 1.3538, 0.0, 1.5107, 2.4196, 3},
  };
  for (const Fig7Row& row : rows) {
    SCOPED_TRACE("v = (" + std::to_string(row.v0) + ", " + std::to_string(row.v1) + ", " +
                 std::to_string(row.v2) + ")");
    const BrownianProblem p = twoProblem(row.T, row.v0, row.v1, row.v2);
    // t_2^(1) = 2 in every row: eq. (15) inverts eq. (19), which fixed T.
    const double v01 = row.v0 * row.v1 / (row.v0 + row.v1);
    EXPECT_NEAR(optimalSingleInstant(1.0, row.T, v01, row.v2), 2.0, 1e-12);
    // t_1^(1): argmin of J(·, 2) by a dense grid and compass search on eq. (26).
    const auto along_t1 = [&](const std::vector<double>& t) { return twoCost(p, t[0], 2.0); };
    double grid_t1 = 0.0;
    for (int i = 0; i <= 2000; ++i) {
      if (along_t1({2.0 * i / 2000}) < along_t1({grid_t1})) grid_t1 = 2.0 * i / 2000;
    }
    const double first_step = compassSearch(along_t1, {grid_t1}, 2.0, 1e-3, 1e-12)[0];
    EXPECT_NEAR(first_step, row.first_step_t1, 1e-4);
    EXPECT_NEAR(criticalDurationsTwo(1.0, row.v0, row.v1, row.v2).regime2_end, row.critical, 1e-4);
    const BrownianSchedule best = optimalInstants(p);
    EXPECT_EQ(best.regime, row.regime);
    EXPECT_NEAR(best.instants[0], row.t1, 1e-4);
    EXPECT_NEAR(best.instants[1], row.t2, 1e-4);
  }
  const BrownianProblem d = twoProblem(317.0 / 76.0, 1, 3, 1);
  EXPECT_GT(twoCost(d, 1.1211, 2.985), twoCost(d, 1.1211, 2.2985));
}

TEST(BrownianTwoMeasures, Regime3SolutionSatisfiesTheorem7) {
  Rng rng(31);
  int regime3 = 0;
  for (int trial = 0; trial < 60; ++trial) {
    const BrownianProblem p = randomProblem(rng, 2);
    const BrownianSchedule best = optimalInstants(p);
    if (best.regime != 3) continue;
    ++regime3;
    const double s = p.sigma2, v1 = p.variances[0], v2 = p.variances[1];
    const double t1 = best.instants[0], t2 = best.instants[1];
    const double posterior1 = (p.v0 + s * t1) * v1 / (p.v0 + s * t1 + v1);
    // Eq. (43) (eq. 28 at the optimum) and eq. (44), whose right side comes from the cubic (36).
    EXPECT_NEAR(t2 - t1, optimalSingleInstant(s, p.horizon_s - t1, posterior1, v2),
                1e-12 * p.horizon_s);
    EXPECT_NEAR(t2 - t1, criticalGapTwo(s, p.v0 + s * t1, v1, v2), 1e-8 * p.horizon_s)
        << "trial " << trial;
  }
  EXPECT_GE(regime3, 20);
}

TEST(BrownianTwoMeasures, ReportedRegimeMatchesInstantsAndCriticalDurations) {
  Rng rng(32);
  int seen[4] = {0, 0, 0, 0};
  for (int trial = 0; trial < 300; ++trial) {
    BrownianProblem p = randomProblem(rng, 2);
    p.horizon_s = logUniform(rng, 0.02, 5.0);  // reach regime 1 often enough
    const BrownianSchedule best = optimalInstants(p);
    const TwoMeasureCriticalDurations critical =
        criticalDurationsTwo(p.sigma2, p.v0, p.variances[0], p.variances[1]);
    ASSERT_GE(best.regime, 1);
    ASSERT_LE(best.regime, 3);
    ++seen[best.regime];
    const double t1 = best.instants[0], t2 = best.instants[1];
    switch (best.regime) {
      case 1:
        EXPECT_EQ(t1, 0.0);
        EXPECT_EQ(t2, 0.0);
        EXPECT_LE(p.horizon_s, critical.regime1_end);
        break;
      case 2:
        EXPECT_EQ(t1, 0.0);
        EXPECT_GT(t2, 0.0);
        EXPECT_GT(p.horizon_s, critical.regime1_end);
        EXPECT_LE(p.horizon_s, critical.regime2_end * (1.0 + 1e-12));
        break;
      default:
        EXPECT_GT(t1, 0.0);
        EXPECT_GT(t2, t1);
        EXPECT_GT(p.horizon_s, critical.regime2_end);
    }
    EXPECT_NEAR(best.cost, twoCost(p, t1, t2), 1e-12 * best.cost);
    EXPECT_NEAR(best.regular_cost, twoCost(p, p.horizon_s / 3, 2 * p.horizon_s / 3),
                1e-12 * best.regular_cost);
  }
  EXPECT_GE(seen[1], 10);
  EXPECT_GE(seen[2], 10);
  EXPECT_GE(seen[3], 10);
}

TEST(BrownianTwoMeasures, MatchesBruteForceGridSearchWithRefinement) {
  Rng rng(33);
  for (int trial = 0; trial < 25; ++trial) {
    BrownianProblem p = randomProblem(rng, 2);
    if (trial % 5 == 0) p.v0 = 0.0;  // the paper's row f) kind
    const double T = p.horizon_s;
    const auto cost = [&](const std::vector<double>& t) { return twoCost(p, t[0], t[1]); };
    constexpr int kSteps = 300;
    std::vector<double> grid_best = {0.0, 0.0};
    for (int i = 0; i <= kSteps; ++i) {
      for (int j = i; j <= kSteps; ++j) {
        const std::vector<double> t = {T * i / kSteps, T * j / kSteps};
        if (cost(t) < cost(grid_best)) grid_best = t;
      }
    }
    const std::vector<double> reference = compassSearch(cost, grid_best, T, T / kSteps, 1e-11 * T);
    const BrownianSchedule best = optimalInstants(p);
    SCOPED_TRACE("trial " + std::to_string(trial));
    EXPECT_LE(best.cost, cost(reference) * (1.0 + 1e-12));
    EXPECT_NEAR(best.cost, cost(reference), 1e-10 * best.cost);
    EXPECT_NEAR(best.instants[0], reference[0], 1e-5 * T);
    EXPECT_NEAR(best.instants[1], reference[1], 1e-5 * T);
  }
}

TEST(BrownianTwoMeasures, GeneralSearchAgreesWithTheClosedForms) {
  Rng rng(34);
  for (int trial = 0; trial < 40; ++trial) {
    BrownianProblem p = randomProblem(rng, 1 + trial % 2);
    p.horizon_s = logUniform(rng, 0.05, 5.0);
    const BrownianSchedule exact = optimalInstants(p);
    const BrownianSchedule searched = optimalInstantsBySearch(p);
    EXPECT_NEAR(searched.cost, exact.cost, 1e-12 * exact.cost) << "trial " << trial;
    for (std::size_t k = 0; k < exact.instants.size(); ++k) {
      EXPECT_NEAR(searched.instants[k], exact.instants[k], 1e-6 * p.horizon_s);
    }
  }
}

// ---------------------------------------------------------------------------------------------

TEST(BrownianManyMeasures, ThreeMeasuresMatchBruteForceSearch) {
  Rng rng(41);
  for (int trial = 0; trial < 6; ++trial) {
    BrownianProblem p = randomProblem(rng, 3);
    if (trial == 5) p.v0 = 0.0;  // wasted measurements at t = 0 make saddles there
    const double T = p.horizon_s;
    const auto cost = [&](const std::vector<double>& t) { return referenceCost(p, t); };
    constexpr int kSteps = 48;  // the ordered 3-D grid: about 20,000 points
    std::vector<double> grid_best = {0.0, 0.0, 0.0};
    double grid_cost = cost(grid_best);
    for (int i = 0; i <= kSteps; ++i) {
      for (int j = i; j <= kSteps; ++j) {
        for (int k = j; k <= kSteps; ++k) {
          const std::vector<double> t = {T * i / kSteps, T * j / kSteps, T * k / kSteps};
          const double c = cost(t);
          if (c < grid_cost) grid_cost = c, grid_best = t;
        }
      }
    }
    const std::vector<double> reference = compassSearch(cost, grid_best, T, T / kSteps, 1e-11 * T);
    const BrownianSchedule best = optimalInstants(p);
    SCOPED_TRACE("trial " + std::to_string(trial));
    EXPECT_EQ(best.regime, 0);
    EXPECT_LE(best.cost, cost(reference) * (1.0 + 1e-12));
    EXPECT_NEAR(best.cost, cost(reference), 1e-9 * best.cost);
    for (std::size_t k = 0; k < 3; ++k) EXPECT_NEAR(best.instants[k], reference[k], 1e-5 * T);
  }
}

TEST(BrownianManyMeasures, OptimumIsStationaryAndNoRandomStartDoesBetter) {
  Rng rng(42);
  for (int trial = 0; trial < 10; ++trial) {
    const int n = 4 + trial % 5;  // 4..8
    BrownianProblem p = randomProblem(rng, n);
    if (trial % 4 == 3) p.v0 = 0.0;
    const BrownianSchedule best = optimalInstants(p);
    SCOPED_TRACE("trial " + std::to_string(trial) + ", n = " + std::to_string(n));
    ASSERT_EQ(best.instants.size(), static_cast<std::size_t>(n));
    EXPECT_TRUE(std::is_sorted(best.instants.begin(), best.instants.end()));
    EXPECT_GE(best.instants.front(), 0.0);
    EXPECT_LE(best.instants.back(), p.horizon_s);
    EXPECT_NEAR(best.cost, referenceCost(p, best.instants), 1e-12 * best.cost);
    EXPECT_LE(best.cost, best.regular_cost);
    // First-order conditions in time coordinates: ∂J/∂t_k = 0 for an instant strictly between
    // its neighbours; a group of equal instants can only be pushed apart without gain.
    const std::vector<double> gradient = timetableCostGradient(p, best.instants);
    const double scale = p.v0 + p.sigma2 * p.horizon_s;
    for (std::size_t k = 0; k < gradient.size(); ++k) {
      const double before = k == 0 ? 0.0 : best.instants[k - 1];
      const double after = k + 1 == gradient.size() ? p.horizon_s : best.instants[k + 1];
      if (best.instants[k] > before + 1e-9 && best.instants[k] < after - 1e-9) {
        EXPECT_NEAR(gradient[k], 0.0, 1e-9 * scale) << "k " << k;
      }
    }
    // The last instant given the others is the one-measure closed form (eq. 28 generalised).
    const std::vector<double> posterior = referencePosteriors(p, best.instants);
    const double previous = best.instants[static_cast<std::size_t>(n - 2)];
    EXPECT_NEAR(
        best.instants.back() - previous,
        optimalSingleInstant(p.sigma2, p.horizon_s - previous,
                             posterior[static_cast<std::size_t>(n - 2)], p.variances.back()),
        1e-7 * p.horizon_s);
    // The empirical claim behind "global": local refinement from random starts never wins.
    for (int start = 0; start < 8; ++start) {
      const BrownianSchedule local = refineInstants(p, randomInstants(rng, n, p.horizon_s));
      EXPECT_GE(local.cost, best.cost * (1.0 - 1e-12));
    }
  }
}

TEST(BrownianManyMeasures, RefinementNeverRaisesTheCost) {
  Rng rng(43);
  for (int trial = 0; trial < 20; ++trial) {
    const int n = 1 + trial % 6;
    const BrownianProblem p = randomProblem(rng, n);
    const std::vector<double> start = randomInstants(rng, n, p.horizon_s);
    const BrownianSchedule refined = refineInstants(p, start);
    EXPECT_LE(refined.cost, referenceCost(p, start) * (1.0 + 1e-15));
    EXPECT_NEAR(refined.cost, referenceCost(p, refined.instants), 1e-12 * refined.cost);
  }
}

// With v0 = 0 a measurement at t = 0 is wasted and ∂J/∂t vanishes there (the factor
// P/(P + v) of eq. 16), so a start with instants at 0 sits on a saddle that plain projected
// Newton never leaves. For n = 2 the reference is the closed-form/coordinate-descent solution,
// which the brute-force test above checks.
TEST(BrownianManyMeasures, RefinementLeavesWastedMeasurementSaddlesAtZero) {
  Rng rng(44);
  for (int trial = 0; trial < 12; ++trial) {
    const int n = 2 + trial % 3;
    BrownianProblem p = randomProblem(rng, n);
    p.v0 = 0.0;
    const BrownianSchedule best = optimalInstants(p);
    for (int at_zero = 1; at_zero < n; ++at_zero) {
      std::vector<double> start = regularInstants(p.horizon_s, n);
      for (int k = 0; k < at_zero; ++k) start[static_cast<std::size_t>(k)] = 0.0;
      const BrownianSchedule refined = refineInstants(p, start);
      EXPECT_NEAR(refined.cost, best.cost, 1e-10 * best.cost)
          << "trial " << trial << ", n = " << n << ", " << at_zero << " at zero";
      EXPECT_GT(refined.instants[0], 0.0);
    }
  }
}

// ---------------------------------------------------------------------------------------------

std::string fieldOfError(const std::function<void()>& call) {
  try {
    call();
  } catch (const InputError& e) {
    return e.field();
  }
  return "(no InputError)";
}

TEST(BrownianInput, BadProblemsThrowInputErrorNamingTheField) {
  const BrownianProblem good = twoProblem(1.0, 1.0, 1.0, 1.0);
  const auto field = [](const BrownianProblem& p) {
    return fieldOfError([&] { (void)optimalInstants(p); });
  };
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  struct Case {
    std::function<void(BrownianProblem&)> spoil;
    std::string field;
  };
  const std::vector<Case> cases = {
      {[](BrownianProblem&) {}, "(no InputError)"},
      {[](BrownianProblem& p) { p.sigma2 = 0.0; }, "sigma2"},
      {[](BrownianProblem& p) { p.sigma2 = -1.0; }, "sigma2"},
      {[&](BrownianProblem& p) { p.sigma2 = nan; }, "sigma2"},
      {[](BrownianProblem& p) { p.horizon_s = 0.0; }, "horizon"},
      {[](BrownianProblem& p) { p.horizon_s = -2.0; }, "horizon"},
      {[&](BrownianProblem& p) { p.horizon_s = inf; }, "horizon"},
      {[](BrownianProblem& p) { p.v0 = -1e-9; }, "v0"},
      {[&](BrownianProblem& p) { p.v0 = nan; }, "v0"},
      {[](BrownianProblem& p) { p.variances = {}; }, "variances"},
      {[](BrownianProblem& p) {
         p.variances = {1.0, 0.0};
       },
       "variances[1]"},
      {[](BrownianProblem& p) {
         p.variances = {-1.0, 1.0};
       },
       "variances[0]"},
      {[&](BrownianProblem& p) {
         p.variances = {1.0, 1.0, inf};
       },
       "variances[2]"},
      {[&](BrownianProblem& p) { p.variances = {nan}; }, "variances[0]"},
  };
  for (const Case& c : cases) {
    BrownianProblem p = good;
    c.spoil(p);
    EXPECT_EQ(field(p), c.field);
  }

  BrownianProblem p = good;
  p.v0 = -1.0;
  EXPECT_EQ(fieldOfError([&] { validateBrownianProblem(p, "test"); }), "v0");
  EXPECT_EQ(fieldOfError([&] { (void)timetableCost(good, {0.5, 0.2}); }), "instants[1]");
  EXPECT_EQ(fieldOfError([&] { (void)timetableCost(good, {0.5, 1.5}); }), "instants[1]");
  EXPECT_EQ(fieldOfError([&] { (void)timetableCost(good, {0.5}); }), "instants");
  EXPECT_EQ(fieldOfError([&] { (void)optimalSingleInstant(0.0, 1.0, 1.0, 1.0); }), "sigma2");
  EXPECT_EQ(fieldOfError([&] { (void)criticalDurationSingle(1.0, 1.0, 0.0); }), "v1");
  EXPECT_EQ(fieldOfError([&] { (void)lowerBoundSingle(1.0, -1.0, 1.0, 1.0); }), "horizon");
  EXPECT_EQ(fieldOfError([&] { (void)criticalDurationsTwo(1.0, 1.0, 1.0, -1.0); }), "v2");
  try {
    BrownianProblem bad = good;
    bad.variances = {1.0, -3.0};
    (void)optimalInstants(bad);
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("variances[1]"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace sensornet
