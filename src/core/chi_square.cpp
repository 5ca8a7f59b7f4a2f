#include "sensornet/core/chi_square.hpp"

#include <cmath>
#include <stdexcept>

namespace sensornet {
namespace {

// The regularized lower incomplete gamma function P(a, x), a > 0, x >= 0: its power series
// converges fast for x < a + 1, the continued fraction of Q = 1 - P (modified Lentz) above.
double regularizedGammaP(double a, double x) {
  if (x <= 0.0) return 0.0;
  const double log_front = a * std::log(x) - x - std::lgamma(a);
  if (x < a + 1.0) {
    double term = 1.0 / a;
    double sum = term;
    for (int n = 1; n <= 100'000; ++n) {
      term *= x / (a + n);
      sum += term;
      if (term < sum * 1e-17) break;
    }
    return sum * std::exp(log_front);
  }
  constexpr double kTiny = 1e-300;
  double b = x + 1.0 - a;
  double c = 1.0 / kTiny;
  double d = 1.0 / b;
  double h = d;
  for (int n = 1; n <= 100'000; ++n) {
    const double an = -n * (n - a);
    b += 2.0;
    d = an * d + b;
    if (std::abs(d) < kTiny) d = kTiny;
    c = b + an / c;
    if (std::abs(c) < kTiny) c = kTiny;
    d = 1.0 / d;
    const double step = d * c;
    h *= step;
    if (std::abs(step - 1.0) < 1e-16) break;
  }
  return 1.0 - std::exp(log_front) * h;
}

}  // namespace

double chiSquareCdf(double x, double k) {
  if (!(k > 0.0)) throw std::invalid_argument("chiSquareCdf: k must be > 0");
  if (std::isnan(x)) return x;
  return regularizedGammaP(0.5 * k, 0.5 * x);
}

double chiSquareQuantile(double p, double k) {
  if (!(p > 0.0 && p < 1.0)) throw std::invalid_argument("chiSquareQuantile: p must be in (0, 1)");
  if (!(k > 0.0)) throw std::invalid_argument("chiSquareQuantile: k must be > 0");
  double low = 0.0;
  double high = k + 1.0;
  while (chiSquareCdf(high, k) < p) {
    low = high;
    high *= 2.0;
  }
  for (int i = 0; i < 400 && high - low > 1e-13 * high; ++i) {
    const double mid = 0.5 * (low + high);
    if (chiSquareCdf(mid, k) < p) {
      low = mid;
    } else {
      high = mid;
    }
  }
  return 0.5 * (low + high);
}

NeesBand neesBand(int state_dim, unsigned episodes, double confidence) {
  if (state_dim < 1 || episodes < 1 || !(confidence > 0.0 && confidence < 1.0)) {
    throw std::invalid_argument("neesBand: needs n >= 1, K >= 1 and a confidence in (0, 1)");
  }
  const double dof = static_cast<double>(state_dim) * episodes;
  const double tail = 0.5 * (1.0 - confidence);
  return {chiSquareQuantile(tail, dof) / episodes, chiSquareQuantile(1.0 - tail, dof) / episodes};
}

}  // namespace sensornet
