#include "sensornet/core/poisson_arrivals.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include "sensornet/core/input_error.hpp"

namespace sensornet {
namespace {

// Statistical checks here fix their seeds and reject at a false-alarm rate of 0.1% each; with
// the 26 goodness-of-fit checks below the family-wise false-alarm rate is at most 2.6%, and as
// the seeds are fixed a pass is reproducible.
constexpr double kFalseAlarm = 1e-3;

// --- Reference distributions, written out here so the tests do not lean on the code under test.

// Regularized lower incomplete gamma P(a, x): the power series for x < a + 1, else the
// continued fraction of Q = 1 - P (modified Lentz), both to full double precision.
double regularizedGammaP(double a, double x) {
  if (x <= 0.0) return 0.0;
  const double log_prefactor = -x + a * std::log(x) - std::lgamma(a);
  if (x < a + 1.0) {
    double term = 1.0 / a;
    double sum = term;
    for (int n = 1; n < 1000 && std::abs(term) > 1e-17 * std::abs(sum); ++n) {
      term *= x / (a + n);
      sum += term;
    }
    return sum * std::exp(log_prefactor);
  }
  constexpr double kTiny = 1e-300;
  double b = x + 1.0 - a;
  double c = 1.0 / kTiny;
  double d = 1.0 / b;
  double h = d;
  for (int i = 1; i < 1000; ++i) {
    const double an = -i * (i - a);
    b += 2.0;
    d = an * d + b;
    if (std::abs(d) < kTiny) d = kTiny;
    c = b + an / c;
    if (std::abs(c) < kTiny) c = kTiny;
    d = 1.0 / d;
    const double delta = d * c;
    h *= delta;
    if (std::abs(delta - 1.0) < 1e-16) break;
  }
  return 1.0 - std::exp(log_prefactor) * h;
}

// Quantile of χ²(dof) at probability p, by bisection on the CDF P(dof/2, x/2).
double chiSquareQuantile(double dof, double p) {
  double lo = 0.0;
  double hi = dof + 100.0 * std::sqrt(dof) + 100.0;
  for (int i = 0; i < 200; ++i) {
    const double mid = 0.5 * (lo + hi);
    (regularizedGammaP(0.5 * dof, 0.5 * mid) < p ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

double poissonPmf(int k, double mean) {
  return std::exp(-mean + k * std::log(mean) - std::lgamma(k + 1.0));
}

struct ChiSquare {
  double statistic = 0.0;
  int dof = 0;
  [[nodiscard]] double critical() const { return chiSquareQuantile(dof, 1.0 - kFalseAlarm); }
};

// Pearson's goodness of fit of observed counts (one per episode) against Poisson(mean). Bins
// are fixed from the law alone: consecutive values merged until each bin expects >= 5
// episodes, the upper tail in the last bin.
ChiSquare poissonGoodnessOfFit(const std::vector<int>& counts, double mean) {
  const double episodes = static_cast<double>(counts.size());
  std::vector<int> bin_upper;  // bin b holds values in (bin_upper[b-1], bin_upper[b]]
  std::vector<double> bin_probability;
  double tail = 1.0;
  double current = 0.0;
  for (int k = 0; episodes * tail >= 10.0; ++k) {
    const double p = poissonPmf(k, mean);
    current += p;
    tail -= p;
    if (episodes * current >= 5.0) {
      bin_upper.push_back(k);
      bin_probability.push_back(current);
      current = 0.0;
    }
  }
  // Whatever is left (the partial bin and the tail) goes to the last bin.
  bin_probability.back() += current + std::max(tail, 0.0);
  bin_upper.back() = std::numeric_limits<int>::max();

  std::vector<double> observed(bin_upper.size(), 0.0);
  for (int c : counts) {
    const auto bin = std::lower_bound(bin_upper.begin(), bin_upper.end(), c) - bin_upper.begin();
    observed[bin] += 1.0;
  }
  ChiSquare result;
  for (std::size_t b = 0; b < observed.size(); ++b) {
    const double expected = episodes * bin_probability[b];
    result.statistic += (observed[b] - expected) * (observed[b] - expected) / expected;
  }
  result.dof = static_cast<int>(observed.size()) - 1;
  return result;
}

// Kolmogorov-Smirnov distance between a sample and the exponential law of rate `rate`.
double ksDistanceToExponential(std::vector<double> sample, double rate) {
  std::sort(sample.begin(), sample.end());
  const double n = static_cast<double>(sample.size());
  double distance = 0.0;
  for (std::size_t i = 0; i < sample.size(); ++i) {
    const double cdf = 1.0 - std::exp(-rate * sample[i]);
    const double rank = static_cast<double>(i);
    distance = std::max({distance, (rank + 1.0) / n - cdf, cdf - rank / n});
  }
  return distance;
}

// Critical KS distance at level `alpha`: the Kolmogorov law Q(x) = 2 Σ (-1)^(k-1) e^(-2 k² x²)
// inverted by bisection, with Stephens' finite-sample scaling √n + 0.12 + 0.11/√n.
double ksCritical(double n, double alpha) {
  auto survival = [](double x) {
    double sum = 0.0;
    for (int k = 1; k <= 100; ++k) {
      sum += ((k % 2 == 1) ? 2.0 : -2.0) * std::exp(-2.0 * k * k * x * x);
    }
    return sum;
  };
  double lo = 0.3;
  double hi = 3.0;
  for (int i = 0; i < 100; ++i) {
    const double mid = 0.5 * (lo + hi);
    (survival(mid) > alpha ? lo : hi) = mid;
  }
  const double root_n = std::sqrt(n);
  return 0.5 * (lo + hi) / (root_n + 0.12 + 0.11 / root_n);
}

// --- Fixture: a schedule with varying rates, zero-rate intervals and a sensor that is silent
// for the first two intervals.

class PoissonArrivals : public ::testing::Test {
 protected:
  static constexpr int kEpisodes = 20000;
  static constexpr std::uint64_t kSeed = 20240611;
  static constexpr std::uint64_t kStream = 0xa771;

  PoissonArrivals()
      : schedule_(2.5, (Eigen::MatrixXd(5, 3) << 1.0, 0.0, 3.0,  //
                        0.0, 0.0, 0.0,                            //
                        2.0, 4.0, 0.0,                            //
                        6.0, 1.0, 0.5,                            //
                        0.0, 2.0, 2.0)
                           .finished()) {}

  // counts[j][k][episode]: arrivals of sensor j in interval k.
  using Counts = std::vector<std::vector<std::vector<int>>>;
  [[nodiscard]] Counts emptyCounts() const {
    return Counts(3, std::vector<std::vector<int>>(5, std::vector<int>(kEpisodes, 0)));
  }

  void expectPoissonCounts(const Counts& counts, const char* what) const {
    for (int j = 0; j < 3; ++j) {
      for (int k = 0; k < 5; ++k) {
        const double mean = schedule_.rate(k, j) * schedule_.intervalLength();
        const auto& cell = counts[j][k];
        if (mean == 0.0) {
          EXPECT_EQ(*std::max_element(cell.begin(), cell.end()), 0)
              << what << ": sensor " << j << " drew arrivals in zero-rate interval " << k;
          continue;
        }
        const ChiSquare fit = poissonGoodnessOfFit(cell, mean);
        EXPECT_LT(fit.statistic, fit.critical())
            << what << ": sensor " << j << ", interval " << k << ", mean " << mean
            << ", dof " << fit.dof;
      }
    }
  }

  RateSchedule schedule_;
};

TEST_F(PoissonArrivals, MergedDrawHasPoissonCountsPerSensorAndInterval) {
  Counts counts = emptyCounts();
  std::vector<int> totals(kEpisodes, 0);
  for (int e = 0; e < kEpisodes; ++e) {
    Rng rng = Rng::keyed(kSeed, kStream, e);
    for (const Arrival& a : drawArrivals(schedule_, rng, 0.0, schedule_.horizon())) {
      ++counts[a.sensor][schedule_.intervalAt(a.time)][e];
      ++totals[e];
    }
  }
  expectPoissonCounts(counts, "drawArrivals");
  // The episode total is Poisson(∫ Σ λ) only if the intervals are independent.
  const ChiSquare fit = poissonGoodnessOfFit(totals, schedule_.rates().sum() * 0.5);
  EXPECT_LT(fit.statistic, fit.critical()) << "episode totals, dof " << fit.dof;
}

TEST_F(PoissonArrivals, PerSensorDrawHasPoissonCountsPerInterval) {
  Counts counts = emptyCounts();
  for (int e = 0; e < kEpisodes; ++e) {
    for (int j = 0; j < 3; ++j) {
      Rng rng = Rng::keyed(kSeed, kStream, j, e);
      for (double t : drawSensorArrivals(schedule_, j, rng, 0.0, schedule_.horizon())) {
        ++counts[j][schedule_.intervalAt(t)][e];
      }
    }
  }
  expectPoissonCounts(counts, "drawSensorArrivals");
}

TEST_F(PoissonArrivals, WindowNotOnIntervalBoundariesHasCountsOfTheIntegratedRate) {
  // [0.3, 1.7) cuts intervals 0 and 3: expected counts 0.2 λ_0 + 0.5 λ_1 + 0.5 λ_2 + 0.2 λ_3.
  const double t0 = 0.3;
  const double t1 = 1.7;
  std::vector<std::vector<int>> merged(3, std::vector<int>(kEpisodes, 0));
  std::vector<std::vector<int>> single(3, std::vector<int>(kEpisodes, 0));
  for (int e = 0; e < kEpisodes; ++e) {
    Rng rng = Rng::keyed(kSeed + 1, kStream, e);
    for (const Arrival& a : drawArrivals(schedule_, rng, t0, t1)) ++merged[a.sensor][e];
    for (int j = 0; j < 3; ++j) {
      Rng own = Rng::keyed(kSeed + 1, kStream, j, e);
      single[j][e] = static_cast<int>(drawSensorArrivals(schedule_, j, own, t0, t1).size());
    }
  }
  for (int j = 0; j < 3; ++j) {
    const double mean = 0.2 * schedule_.rate(0, j) + 0.5 * schedule_.rate(1, j) +
                        0.5 * schedule_.rate(2, j) + 0.2 * schedule_.rate(3, j);
    const ChiSquare fit_merged = poissonGoodnessOfFit(merged[j], mean);
    EXPECT_LT(fit_merged.statistic, fit_merged.critical()) << "merged, sensor " << j;
    const ChiSquare fit_single = poissonGoodnessOfFit(single[j], mean);
    EXPECT_LT(fit_single.statistic, fit_single.critical()) << "single, sensor " << j;
  }
}

// Time change, drawn in pieces as a closed loop does: [0, 0.3) and [0.3, 1.7) under the
// fixture's schedule, then [1.7, 2.5) under a second schedule (the "re-planned tail"). Counts
// per sensor and interval must be Poisson with the rates in force, the piece boundaries
// (0.3 and 1.7 cut intervals 0 and 3) included.
TEST_F(PoissonArrivals, TimeChangedArrivalsDrawnInPiecesHavePoissonCounts) {
  const RateSchedule tail(2.5, (Eigen::MatrixXd(5, 3) << 9.0, 9.0, 9.0,  //
                                9.0, 9.0, 9.0,                           //
                                9.0, 9.0, 9.0,                           //
                                0.5, 3.0, 5.0,                           //
                                4.0, 0.0, 1.0)
                                   .finished());
  // Expected counts per sensor in [1.5, 2.0) (0.2 s of interval 3 before the switch, 0.3 s
  // after) and in [2.0, 2.5) under the tail.
  std::vector<std::vector<int>> interval3(3, std::vector<int>(kEpisodes, 0));
  std::vector<std::vector<int>> interval4(3, std::vector<int>(kEpisodes, 0));
  std::vector<std::vector<int>> interval0(3, std::vector<int>(kEpisodes, 0));
  std::vector<Arrival> piece;
  for (int e = 0; e < kEpisodes; ++e) {
    TimeChangedArrivals arrivals(3, kSeed, static_cast<std::uint64_t>(e));
    const std::pair<const RateSchedule*, double> pieces[] = {
        {&schedule_, 0.3}, {&schedule_, 1.7}, {&tail, 2.5}};
    double from = 0.0;
    for (const auto& [schedule, to] : pieces) {
      arrivals.drawUntil(*schedule, to, piece);
      EXPECT_EQ(arrivals.now(), to);
      for (std::size_t i = 0; i < piece.size(); ++i) {
        ASSERT_GE(piece[i].time, from);
        ASSERT_LT(piece[i].time, to);
        if (i > 0) {
          ASSERT_LE(piece[i - 1].time, piece[i].time);
        }
        const int k = schedule_.intervalAt(piece[i].time);
        if (k == 0) ++interval0[piece[i].sensor][e];
        if (k == 3) ++interval3[piece[i].sensor][e];
        if (k == 4) ++interval4[piece[i].sensor][e];
      }
      from = to;
    }
  }
  // Poisson(mean) counts, or none at all where the mean is zero.
  const auto expectPoisson = [](const std::vector<int>& counts, double mean, const char* what,
                                int j) {
    if (mean == 0.0) {
      EXPECT_EQ(*std::max_element(counts.begin(), counts.end()), 0) << what << ", sensor " << j;
      return;
    }
    const ChiSquare fit = poissonGoodnessOfFit(counts, mean);
    EXPECT_LT(fit.statistic, fit.critical()) << what << ", sensor " << j << ", mean " << mean;
  };
  for (int j = 0; j < 3; ++j) {
    expectPoisson(interval0[j], 0.5 * schedule_.rate(0, j), "interval 0", j);
    expectPoisson(interval3[j], 0.2 * schedule_.rate(3, j) + 0.3 * tail.rate(3, j), "interval 3", j);
    expectPoisson(interval4[j], 0.5 * tail.rate(4, j), "interval 4", j);
  }
}

// Common random numbers: drawn in pieces under one schedule, the points are those of one draw
// over the whole window (the same unit-rate points, the same map), to rounding.
TEST_F(PoissonArrivals, TimeChangedArrivalsInPiecesEqualOneDrawOfTheWhole) {
  for (int e = 0; e < 50; ++e) {
    TimeChangedArrivals whole(3, kSeed, static_cast<std::uint64_t>(e));
    TimeChangedArrivals pieces(3, kSeed, static_cast<std::uint64_t>(e));
    std::vector<Arrival> all, part, joined;
    whole.drawUntil(schedule_, 2.5, all);
    for (const double to : {0.13, 0.5, 1.61, 2.5}) {
      pieces.drawUntil(schedule_, to, part);
      joined.insert(joined.end(), part.begin(), part.end());
    }
    ASSERT_EQ(joined.size(), all.size()) << "episode " << e;
    for (std::size_t i = 0; i < all.size(); ++i) {
      EXPECT_EQ(joined[i].sensor, all[i].sensor);
      EXPECT_NEAR(joined[i].time, all[i].time, 1e-12);
    }
  }
}

TEST_F(PoissonArrivals, ArrivalsAreSortedAndInsideTheHalfOpenWindow) {
  const double windows[][2] = {{0.0, 2.5}, {0.3, 1.7}, {1.0, 1.5}, {2.2, 2.5}, {0.7, 0.7}};
  for (const auto& w : windows) {
    for (int e = 0; e < 2000; ++e) {
      Rng rng = Rng::keyed(kSeed + 2, e);
      const std::vector<Arrival> all = drawArrivals(schedule_, rng, w[0], w[1]);
      for (std::size_t i = 0; i < all.size(); ++i) {
        ASSERT_GE(all[i].time, w[0]);
        ASSERT_LT(all[i].time, w[1]);
        ASSERT_GE(all[i].sensor, 0);
        ASSERT_LT(all[i].sensor, 3);
        ASSERT_GT(schedule_.rateAt(all[i].time, all[i].sensor), 0.0);
        if (i > 0) {
          ASSERT_LE(all[i - 1].time, all[i].time);
        }
      }
      for (int j = 0; j < 3; ++j) {
        const std::vector<double> mine = drawSensorArrivals(schedule_, j, rng, w[0], w[1]);
        ASSERT_TRUE(std::is_sorted(mine.begin(), mine.end()));
        for (double t : mine) {
          ASSERT_GE(t, w[0]);
          ASSERT_LT(t, w[1]);
          ASSERT_GT(schedule_.rateAt(t, j), 0.0);
        }
      }
    }
  }
}

TEST_F(PoissonArrivals, ZeroRatesGiveNoArrivals) {
  const RateSchedule silent(3.0, Eigen::MatrixXd::Zero(30, 4));
  for (int e = 0; e < 100; ++e) {
    Rng rng = Rng::keyed(kSeed + 3, e);
    EXPECT_TRUE(drawArrivals(silent, rng, 0.0, 3.0).empty());
    EXPECT_TRUE(drawSensorArrivals(silent, 2, rng, 0.0, 3.0).empty());
    // Interval 1 of the fixture is silent for every sensor.
    EXPECT_TRUE(drawArrivals(schedule_, rng, 0.5, 1.0).empty());
    EXPECT_TRUE(drawSensorArrivals(schedule_, 1, rng, 0.0, 1.0).empty());
  }
}

// Gaps of a homogeneous Poisson process are i.i.d. exponential. The schedule below keeps the
// rate constant over 200 intervals, so the gaps also cross 199 restarts of the clock. Only
// gaps between two observed arrivals are used; the end of the window biases them by a factor
// (1 - s/T) ~ 1 - 2e-4 at typical s, far below the KS resolution (~0.03 here).
TEST(PoissonArrivalGaps, InterArrivalTimesAtConstantRateAreExponential) {
  const double horizon = 1000.0;
  Eigen::MatrixXd rates(200, 2);
  rates.col(0).setConstant(2.0);
  rates.col(1).setConstant(3.0);
  const RateSchedule schedule(horizon, rates);

  Rng rng = Rng::keyed(7, 0x9a95);
  const std::vector<Arrival> merged = drawArrivals(schedule, rng, 0.0, horizon);
  std::vector<double> merged_gaps;
  std::vector<double> sensor1_gaps;  // sensor 1 alone, thinned out of the merged stream
  double last_sensor1 = -1.0;
  for (std::size_t i = 0; i < merged.size(); ++i) {
    if (i > 0) merged_gaps.push_back(merged[i].time - merged[i - 1].time);
    if (merged[i].sensor == 1) {
      if (last_sensor1 >= 0.0) sensor1_gaps.push_back(merged[i].time - last_sensor1);
      last_sensor1 = merged[i].time;
    }
  }
  const std::vector<double> own = drawSensorArrivals(schedule, 0, rng, 0.0, horizon);
  std::vector<double> own_gaps;
  for (std::size_t i = 1; i < own.size(); ++i) own_gaps.push_back(own[i] - own[i - 1]);

  ASSERT_GT(merged_gaps.size(), 4000u);
  EXPECT_LT(ksDistanceToExponential(merged_gaps, 5.0),
            ksCritical(static_cast<double>(merged_gaps.size()), kFalseAlarm));
  EXPECT_LT(ksDistanceToExponential(sensor1_gaps, 3.0),
            ksCritical(static_cast<double>(sensor1_gaps.size()), kFalseAlarm));
  EXPECT_LT(ksDistanceToExponential(own_gaps, 2.0),
            ksCritical(static_cast<double>(own_gaps.size()), kFalseAlarm));
  // The test can fail: the same gaps against a 10% faster law are rejected.
  EXPECT_GT(ksDistanceToExponential(merged_gaps, 5.5),
            ksCritical(static_cast<double>(merged_gaps.size()), kFalseAlarm));
}

TEST(PoissonArrivalStatistics, ReferenceQuantilesMatchTables) {
  // χ² table values (Abramowitz & Stegun 26.8) and the Kolmogorov 0.1% point 1.9495.
  EXPECT_NEAR(chiSquareQuantile(1, 0.95), 3.841459, 1e-5);
  EXPECT_NEAR(chiSquareQuantile(3, 0.999), 16.26624, 1e-4);
  EXPECT_NEAR(chiSquareQuantile(10, 0.999), 29.5883, 1e-3);
  EXPECT_NEAR(chiSquareQuantile(100, 0.999), 149.449, 1e-2);
  EXPECT_NEAR(ksCritical(1e12, 1e-3) * 1e6, 1.94947, 1e-4);
}

TEST(PoissonArrivalInput, BadWindowsSensorsAndRatesThrowInputError) {
  const RateSchedule schedule(1.0, Eigen::MatrixXd::Ones(2, 2));
  Rng rng(1);
  EXPECT_THROW((void)drawArrivals(schedule, rng, 0.5, 0.4), InputError);
  EXPECT_THROW((void)drawArrivals(schedule, rng, -0.1, 0.4), InputError);
  EXPECT_THROW((void)drawArrivals(schedule, rng, 0.0, 1.5), InputError);
  EXPECT_THROW((void)drawSensorArrivals(schedule, 2, rng, 0.0, 1.0), InputError);
  EXPECT_THROW((void)drawSensorArrivals(schedule, -1, rng, 0.0, 1.0), InputError);
  Eigen::MatrixXd negative = Eigen::MatrixXd::Ones(2, 2);
  negative(1, 0) = -1.0;
  EXPECT_THROW((void)drawArrivals(RateSchedule(1.0, negative), rng, 0.0, 1.0), InputError);
  EXPECT_THROW((void)drawSensorArrivals(RateSchedule(1.0, negative), 0, rng, 0.0, 1.0),
               InputError);
}

}  // namespace
}  // namespace sensornet
