#pragma once
// The chi-square distribution, for filter consistency: under a consistent filter the NEES at the
// horizon, e(T)' P(T)^{-1} e(T), is chi-square with n (the state dimension) degrees of freedom,
// and the sum over K independent episodes chi-square with n K. The run summary says whether the
// mean NEES lies in the two-sided band of that sum over K (nees_consistent).
//
//   const NeesBand band = neesBand(4, 20, 0.999);  // [chi2_{0.0005}(80) / 20, chi2_{0.9995}(80) / 20]
//   const bool consistent = band.holds(nees_mean);

namespace sensornet {

// P(X <= x) for X ~ chi-square(k), k > 0: the regularized lower incomplete gamma P(k/2, x/2)
// (its series below a + 1, its continued fraction above), to about 1e-14 absolute.
// Throws std::invalid_argument for k <= 0.
[[nodiscard]] double chiSquareCdf(double x, double k);

// The p-quantile (0 < p < 1) of chi-square(k): the CDF inverted by bisection on a bracket that
// doubles until it holds the root; relative accuracy about 1e-12.
// Throws std::invalid_argument for p outside (0, 1) or k <= 0.
[[nodiscard]] double chiSquareQuantile(double p, double k);

// The band of the mean NEES of `episodes` independent episodes of an n-state filter that holds
// with probability `confidence` when the filter is consistent: equal tails of chi-square(n K) / K.
struct NeesBand {
  double low = 0.0;
  double high = 0.0;
  [[nodiscard]] bool holds(double mean) const { return mean >= low && mean <= high; }
};
[[nodiscard]] NeesBand neesBand(int state_dim, unsigned episodes, double confidence);

// The confidence of the band the run summary reports (99.9%: a consistent run is called
// inconsistent once in a thousand).
inline constexpr double kNeesConfidence = 0.999;

}  // namespace sensornet
