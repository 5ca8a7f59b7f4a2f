#include "sensornet/core/student_t.hpp"

#include <cmath>
#include <limits>
#include <numbers>
#include <stdexcept>
#include <string>
#include <vector>

namespace sensornet {
namespace {

// Continued fraction of the incomplete beta function (modified Lentz), valid for
// x < (a + 1) / (a + b + 2); the caller uses the symmetry I_x(a, b) = 1 - I_{1-x}(b, a) otherwise.
double betaContinuedFraction(double a, double b, double x) {
  constexpr double kTiny = 1e-300;
  constexpr double kEpsilon = 1e-16;
  double c = 1.0;
  double d = 1.0 - (a + b) * x / (a + 1.0);
  if (std::abs(d) < kTiny) d = kTiny;
  d = 1.0 / d;
  double h = d;
  for (int m = 1; m <= 10'000; ++m) {
    const double md = m;
    const double even = md * (b - md) * x / ((a + 2.0 * md - 1.0) * (a + 2.0 * md));
    d = 1.0 + even * d;
    if (std::abs(d) < kTiny) d = kTiny;
    c = 1.0 + even / c;
    if (std::abs(c) < kTiny) c = kTiny;
    d = 1.0 / d;
    h *= d * c;
    const double odd = -(a + md) * (a + b + md) * x / ((a + 2.0 * md) * (a + 2.0 * md + 1.0));
    d = 1.0 + odd * d;
    if (std::abs(d) < kTiny) d = kTiny;
    c = 1.0 + odd / c;
    if (std::abs(c) < kTiny) c = kTiny;
    d = 1.0 / d;
    const double step = d * c;
    h *= step;
    if (std::abs(step - 1.0) < kEpsilon) break;
  }
  return h;
}

// The regularized incomplete beta function I_x(a, b), 0 <= x <= 1.
double regularizedBeta(double a, double b, double x) {
  if (x <= 0.0) return 0.0;
  if (x >= 1.0) return 1.0;
  const double log_front = std::lgamma(a + b) - std::lgamma(a) - std::lgamma(b) +
                           a * std::log(x) + b * std::log1p(-x);
  const double front = std::exp(log_front);
  if (x < (a + 1.0) / (a + b + 2.0)) return front * betaContinuedFraction(a, b, x) / a;
  return 1.0 - front * betaContinuedFraction(b, a, 1.0 - x) / b;
}

// The t density, for Newton steps.
double studentTDensity(double t, double df) {
  const double log_density = std::lgamma(0.5 * (df + 1.0)) - std::lgamma(0.5 * df) -
                             0.5 * std::log(df * std::numbers::pi) -
                             0.5 * (df + 1.0) * std::log1p(t * t / df);
  return std::exp(log_density);
}

}  // namespace

double studentTCdf(double t, double df) {
  if (!(df > 0.0)) throw std::invalid_argument("studentTCdf: df must be > 0");
  if (std::isnan(t)) return t;
  const double tail = 0.5 * regularizedBeta(0.5 * df, 0.5, df / (df + t * t));
  return t >= 0.0 ? 1.0 - tail : tail;
}

double studentTQuantile(double p, double df) {
  if (!(p > 0.0 && p < 1.0)) throw std::invalid_argument("studentTQuantile: p must be in (0, 1)");
  if (!(df > 0.0)) throw std::invalid_argument("studentTQuantile: df must be > 0");
  if (p == 0.5) return 0.0;
  // Solve for the upper half and mirror: the t distribution is symmetric.
  const double upper = p > 0.5 ? p : 1.0 - p;
  double low = 0.0;
  double high = 1.0;
  while (studentTCdf(high, df) < upper) {
    low = high;
    high *= 2.0;
    if (!std::isfinite(high)) return p > 0.5 ? high : -high;
  }
  double t = 0.5 * (low + high);
  for (int i = 0; i < 200 && (high - low) > 1e-13 * high; ++i) {
    const double f = studentTCdf(t, df) - upper;
    if (f < 0.0) {
      low = t;
    } else {
      high = t;
    }
    // A Newton step when it stays inside the bracket, else bisection.
    const double newton = t - f / studentTDensity(t, df);
    const double next = newton > low && newton < high ? newton : 0.5 * (low + high);
    if (f == 0.0 || std::abs(next - t) <= 1e-14 * t) break;
    t = next;
  }
  return p > 0.5 ? t : -t;
}

SampleMean sampleMean(std::span<const double> sample) {
  SampleMean s;
  if (sample.empty()) return s;
  const double n = static_cast<double>(sample.size());
  for (const double x : sample) s.mean += x / n;
  if (sample.size() < 2) {
    s.ci95 = std::numeric_limits<double>::infinity();
    return s;
  }
  double squares = 0.0;
  for (const double x : sample) squares += (x - s.mean) * (x - s.mean);
  s.std_dev = std::sqrt(squares / (n - 1.0));
  s.ci95 = studentTQuantile(0.975, n - 1.0) * s.std_dev / std::sqrt(n);
  return s;
}

SampleMean pairedDifference(std::span<const double> a, std::span<const double> b) {
  if (a.size() != b.size()) {
    throw std::invalid_argument("pairedDifference: samples of " + std::to_string(a.size()) +
                                " and " + std::to_string(b.size()) + " values");
  }
  std::vector<double> d(a.size());
  for (std::size_t i = 0; i < a.size(); ++i) d[i] = a[i] - b[i];
  return sampleMean(d);
}

}  // namespace sensornet
