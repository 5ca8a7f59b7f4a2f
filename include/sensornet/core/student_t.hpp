#pragma once
// Student's t distribution: its CDF and quantiles, for confidence intervals of a mean from few
// samples (the run summary's 95% interval over K episodes uses t_{0.975, K-1}, not 1.96, which
// is too narrow for small K: 12.7 for K = 2, 2.78 for K = 5, 2.09 for K = 20).
//
//   const double h = studentTQuantile(0.975, k - 1) * s / std::sqrt(k);

#include <span>

namespace sensornet {

// P(T <= t) for T ~ t(df), df > 0: through the regularized incomplete beta function,
// 1 - I_{df/(df+t^2)}(df/2, 1/2) / 2 for t >= 0, to about 1e-14 absolute.
[[nodiscard]] double studentTCdf(double t, double df);

// The p-quantile (0 < p < 1) of t(df), df > 0: the CDF inverted by bisection on a bracket that
// doubles until it holds the root, then Newton steps; relative accuracy about 1e-12.
// Throws std::invalid_argument for p outside (0, 1) or df <= 0.
[[nodiscard]] double studentTQuantile(double p, double df);

// The mean of a sample, its standard deviation (n - 1) and the half-width of its 95% interval,
// t_{0.975, n-1} s / sqrt(n) (0 and infinity for n < 2; all 0 for an empty sample).
struct SampleMean {
  double mean = 0.0;
  double std_dev = 0.0;
  double ci95 = 0.0;
};
[[nodiscard]] SampleMean sampleMean(std::span<const double> sample);
// The same of the differences a[i] - b[i] (a paired comparison; the sizes must agree).
[[nodiscard]] SampleMean pairedDifference(std::span<const double> a, std::span<const double> b);

}  // namespace sensornet
