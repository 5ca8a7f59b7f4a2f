#include "sensornet/core/brownian_instants.hpp"

#include <Eigen/Core>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "sensornet/core/input_error.hpp"

namespace sensornet {
namespace {

// --- Forward-mode dual numbers: one directional derivative carried through the cost and its
// adjoint gives a Hessian column exactly (no finite-difference step to tune). ---------------

struct Dual {
  double v = 0.0;  // value
  double d = 0.0;  // derivative along the seeded direction
  Dual() = default;
  Dual(double value, double derivative = 0.0) : v(value), d(derivative) {}  // NOLINT: implicit
};
inline Dual operator+(Dual a, Dual b) { return {a.v + b.v, a.d + b.d}; }
inline Dual operator-(Dual a, Dual b) { return {a.v - b.v, a.d - b.d}; }
inline Dual operator*(Dual a, Dual b) { return {a.v * b.v, a.d * b.v + a.v * b.d}; }
inline Dual operator/(Dual a, Dual b) { return {a.v / b.v, (a.d * b.v - a.v * b.d) / (b.v * b.v)}; }
inline Dual& operator+=(Dual& a, Dual b) { return a = a + b; }

// --- Eq. (12) and its adjoint over the gaps Δ_1..Δ_{n+1} (Δ_{n+1} = T - t_n) -------------

// Fills posterior (Γ_0..Γ_n) and slope (r_k = dΓ_k/dP_k, k = 1..n at index k-1); returns J.
template <typename Real>
Real forwardSweep(double sigma2, double v0, const std::vector<double>& variances,
                  const std::vector<Real>& gaps, std::vector<Real>& posterior,
                  std::vector<Real>& slope) {
  const std::size_t n = variances.size();
  posterior[0] = Real(v0);
  Real cost = Real(0.0);
  for (std::size_t k = 1; k <= n; ++k) {
    const Real& gap = gaps[k - 1];
    cost += posterior[k - 1] * gap + Real(0.5 * sigma2) * gap * gap;  // eq. (12), one piece
    const Real prior = posterior[k - 1] + Real(sigma2) * gap;         // eq. (7)
    const Real denominator = Real(variances[k - 1]) + prior;
    posterior[k] = Real(variances[k - 1]) * prior / denominator;  // eq. (11)
    const Real ratio = Real(variances[k - 1]) / denominator;
    slope[k - 1] = ratio * ratio;
  }
  cost += posterior[n] * gaps[n] + Real(0.5 * sigma2) * gaps[n] * gaps[n];
  return cost;
}

// G_k = ∂J/∂Δ_k with every gap treated as independent (the adjoint recursion documented in the
// header). partials has n+1 entries.
template <typename Real>
void gapPartials(double sigma2, const std::vector<Real>& gaps, const std::vector<Real>& posterior,
                 const std::vector<Real>& slope, std::vector<Real>& partials) {
  const std::size_t n = slope.size();
  Real lambda = gaps[n];  // λ_n
  partials[n] = posterior[n] + Real(sigma2) * gaps[n];
  for (std::size_t k = n; k >= 1; --k) {
    partials[k - 1] =
        posterior[k - 1] + Real(sigma2) * gaps[k - 1] + Real(sigma2) * slope[k - 1] * lambda;
    lambda = gaps[k - 1] + slope[k - 1] * lambda;  // λ_{k-1}
  }
}

// The cost as a function of all n+1 gaps y = (Δ_1..Δ_{n+1}) taken as independent, with its
// partials G and Hessian; the refinement restricts them to Σ y = T. Buffers are reused.
class GapCost {
 public:
  explicit GapCost(const BrownianProblem& problem) : p_(problem), n_(problem.variances.size()) {
    gaps_.resize(n_ + 1);
    posterior_.resize(n_ + 1);
    slope_.resize(n_);
    partials_.resize(n_ + 1);
    dual_gaps_.resize(n_ + 1);
    dual_posterior_.resize(n_ + 1);
    dual_slope_.resize(n_);
    dual_partials_.resize(n_ + 1);
  }

  double cost(const Eigen::VectorXd& y) {
    for (std::size_t k = 0; k <= n_; ++k) gaps_[k] = y(static_cast<Eigen::Index>(k));
    return forwardSweep(p_.sigma2, p_.v0, p_.variances, gaps_, posterior_, slope_);
  }

  // Returns the cost and writes G_k = ∂J/∂Δ_k, k = 1..n+1.
  double costAndPartials(const Eigen::VectorXd& y, Eigen::VectorXd& partials) {
    const double value = cost(y);
    gapPartials(p_.sigma2, gaps_, posterior_, slope_, partials_);
    partials =
        Eigen::Map<const Eigen::VectorXd>(partials_.data(), static_cast<Eigen::Index>(n_ + 1));
    return value;
  }

  // Column j is the derivative of the partials along Δ_j.
  Eigen::MatrixXd hessian(const Eigen::VectorXd& y) {
    const auto size = static_cast<Eigen::Index>(n_ + 1);
    Eigen::MatrixXd h(size, size);
    for (Eigen::Index j = 0; j < size; ++j) {
      for (Eigen::Index k = 0; k < size; ++k) {
        dual_gaps_[static_cast<std::size_t>(k)] = Dual(y(k), k == j ? 1.0 : 0.0);
      }
      (void)forwardSweep(p_.sigma2, p_.v0, p_.variances, dual_gaps_, dual_posterior_, dual_slope_);
      gapPartials(p_.sigma2, dual_gaps_, dual_posterior_, dual_slope_, dual_partials_);
      for (Eigen::Index k = 0; k < size; ++k)
        h(k, j) = dual_partials_[static_cast<std::size_t>(k)].d;
    }
    return 0.5 * (h + h.transpose());  // exact up to rounding; symmetrised on purpose
  }

 private:
  const BrownianProblem& p_;
  std::size_t n_;
  std::vector<double> gaps_, posterior_, slope_, partials_;
  std::vector<Dual> dual_gaps_, dual_posterior_, dual_slope_, dual_partials_;
};

// Δ_1..Δ_{n+1} of a timetable (Δ_{n+1} = T - t_n).
Eigen::VectorXd gapsOf(const std::vector<double>& instants, double horizon_s) {
  Eigen::VectorXd y(static_cast<Eigen::Index>(instants.size() + 1));
  double previous = 0.0;
  for (std::size_t k = 0; k < instants.size(); ++k) {
    y(static_cast<Eigen::Index>(k)) = instants[k] - previous;
    previous = instants[k];
  }
  y(y.size() - 1) = horizon_s - previous;
  return y;
}

std::vector<double> instantsOf(const Eigen::VectorXd& gaps, double horizon_s) {
  std::vector<double> instants(static_cast<std::size_t>(gaps.size() - 1));
  double t = 0.0;
  for (std::size_t k = 0; k < instants.size(); ++k) {
    t += gaps(static_cast<Eigen::Index>(k));
    instants[k] = std::min(t, horizon_s);
  }
  return instants;
}

double costOfInstants(const BrownianProblem& problem, const std::vector<double>& instants) {
  GapCost cost(problem);
  return cost.cost(gapsOf(instants, problem.horizon_s));
}

// --- Input checks ---------------------------------------------------------------------------

bool isPositive(double x) { return std::isfinite(x) && x > 0.0; }
bool isNonNegative(double x) { return std::isfinite(x) && x >= 0.0; }

void requireSingleParameters(const std::string& source, double sigma2, double v0, double v1) {
  if (!isPositive(sigma2)) throw InputError(source, "sigma2", "a finite value > 0");
  if (!isNonNegative(v0)) throw InputError(source, "v0", "a finite value >= 0");
  if (!isPositive(v1)) throw InputError(source, "v1", "a finite value > 0");
}

void validateInstants(const BrownianProblem& problem, const std::vector<double>& instants,
                      const std::string& source) {
  validateBrownianProblem(problem, source);
  if (instants.size() != problem.variances.size()) {
    throw InputError(source, "instants",
                     std::to_string(problem.variances.size()) + " instants, one per variance");
  }
  double previous = 0.0;
  for (std::size_t k = 0; k < instants.size(); ++k) {
    const double t = instants[k];
    if (!std::isfinite(t) || t < previous || t > problem.horizon_s) {
      throw InputError(source, "instants[" + std::to_string(k) + "]",
                       "a finite instant in [previous instant, horizon]");
    }
    previous = t;
  }
}

// --- One measurement ---------------------------------------------------------------------

// Eq. (15) without cancellation: the numerator N = x - 3(v0 + v1) + sqrt(S), x = σ² T,
// S = (x + v0 + 5 v1)² - (4 v1)² = (x + v0 + v1)(x + v0 + 9 v1). When b = 3(v0 + v1) - x > 0,
// N = (S - b²) / (sqrt(S) + b) and S - b² = 8 (x (v0 + 2 v1) - v0 (v0 + v1)), whose sign is the
// regime test of eq. (17).
double singleInstant(double sigma2, double horizon_s, double v0, double v1) {
  const double x = sigma2 * horizon_s;
  const double root = std::sqrt((x + v0 + v1) * (x + v0 + 9.0 * v1));
  const double b = 3.0 * (v0 + v1) - x;
  const double numerator =
      b <= 0.0 ? root - b : 8.0 * (x * (v0 + 2.0 * v1) - v0 * (v0 + v1)) / (root + b);
  return std::clamp(numerator / (4.0 * sigma2), 0.0, horizon_s);
}

// T_crit^(1), eq. (17).
double singleCriticalDuration(double sigma2, double v0, double v1) {
  return v0 / (sigma2 * (v1 / (v0 + v1) + 1.0));
}

// Eq. (14) at t_1 = t_opt^(1): the optimal cost-to-go with one measurement left.
double singleMeasureCost(double sigma2, double horizon_s, double v0, double v1) {
  const double t = singleInstant(sigma2, horizon_s, v0, v1);
  const double rest = horizon_s - t;
  const double posterior = fusedVariance(v1, v0 + sigma2 * t);
  return v0 * t + 0.5 * sigma2 * t * t + posterior * rest + 0.5 * sigma2 * rest * rest;
}

// --- Two measurements --------------------------------------------------------------------

// The largest real root of a x³ + b x² + c x + d (a != 0): Cardano or the trigonometric form,
// then two Newton steps to clean up the rounding of the closed form.
double largestRealRootOfCubic(double a, double b, double c, double d) {
  const double p2 = b / a, p1 = c / a, p0 = d / a;
  const double shift = p2 / 3.0;
  const double p = p1 - p2 * shift;  // y³ + p y + q, x = y - p2/3
  const double q = 2.0 * shift * shift * shift - shift * p1 + p0;
  const double discriminant = 0.25 * q * q + p * p * p / 27.0;
  double y = 0.0;
  if (discriminant > 0.0) {
    const double u = std::cbrt(-0.5 * q - std::copysign(std::sqrt(discriminant), q));
    y = u != 0.0 ? u - p / (3.0 * u) : 0.0;
  } else if (p < 0.0) {
    const double r = std::sqrt(-p / 3.0);
    const double cosine = std::clamp(-0.5 * q / (r * r * r), -1.0, 1.0);
    y = 2.0 * r * std::cos(std::acos(cosine) / 3.0);
  }
  double x = y - shift;
  for (int step = 0; step < 2; ++step) {
    const double value = ((a * x + b) * x + c) * x + d;
    const double derivative = (3.0 * a * x + 2.0 * b) * x + c;
    if (derivative == 0.0) break;
    x -= value / derivative;
  }
  return x;
}

// σ² t_{2,1,crit}: largest real root of eq. (36) with the coefficients of eqs. (37)-(40).
double criticalGapVariance(double v0, double v1, double v2) {
  const double s01 = v0 + v1;
  const double a = -s01 * s01 * (v0 + 2.0 * v1);  // (37)
  const double b =
      s01 * (v0 * v0 * v0 - 3.0 * (s01 * (v0 + 2.0 * v1) * v2 + v0 * v1 * v1));  // (38)
  const double c =
      v2 * b + v0 * v0 * (2.0 * v0 + 3.0 * v1) * (v0 * v1 + v0 * v2 + v1 * v2);            // (39)
  const double d = v0 * v0 * (v1 + v2) * s01 * (v0 * v1 + 2.0 * v0 * v2 + 3.0 * v1 * v2);  // (40)
  return std::max(0.0, largestRealRootOfCubic(a, b, c, d));
}

// T_{t_1}, eq. (35): the horizon for which t_1 is the optimal single instant (inverse of 18).
double horizonForSingleInstant(double sigma2, double t, double v0, double v1) {
  return 2.0 * t + (v0 - v1) / sigma2 + 2.0 * v1 * v1 / (sigma2 * (v0 + sigma2 * t + 2.0 * v1));
}

TwoMeasureCriticalDurations twoCriticalDurations(double sigma2, double v0, double v1, double v2) {
  const double v01 = fusedVariance(v0, v1);
  TwoMeasureCriticalDurations durations;
  durations.regime1_end = singleCriticalDuration(sigma2, v01, v2);  // eq. (29)
  const double gap = criticalGapVariance(v0, v1, v2) / sigma2;
  durations.regime2_end = horizonForSingleInstant(sigma2, gap, v01, v2);  // eq. (34)
  // Both are continuous in the data and regime 2 may be empty; keep the order T2 <= T1.
  durations.regime2_end = std::max(durations.regime2_end, durations.regime1_end);
  return durations;
}

// The sign-carrying factor of ∂J/∂t_1 at (t_1, t_2), t_2 fixed, for n = 2. From the header's
// recursion, ∂J/∂t_k = G_k - G_{k+1} = P_k/(P_k + v_k) · [P_k - σ² λ_k (P_k + 2 v_k)/(P_k + v_k)]
// (eq. 16 for n = 1); the first factor only vanishes when P_1 = v0 + σ² t_1 = 0, which would
// make t_1 = 0 look stationary when v0 = 0, so the search works on the bracket. With
// Real = Dual seeded at t_1 it also gives the bracket's derivative.
template <typename Real>
Real firstInstantSlopeFactor(const BrownianProblem& p, Real t1, double t2) {
  const double sigma2 = p.sigma2, v1 = p.variances[0], v2 = p.variances[1];
  const Real gap2 = Real(t2) - t1;
  const double gap3 = p.horizon_s - t2;
  const Real prior1 = Real(p.v0) + Real(sigma2) * t1;
  const Real posterior1 = Real(v1) * prior1 / (Real(v1) + prior1);
  const Real ratio2 = Real(v2) / (Real(v2) + posterior1 + Real(sigma2) * gap2);
  const Real lambda1 = gap2 + ratio2 * ratio2 * Real(gap3);
  return prior1 - Real(sigma2) * lambda1 * (prior1 + Real(2.0 * v1)) / (prior1 + Real(v1));
}

// argmin over t_1 in [0, t_2] of J(t_1, t_2): the zero of ∂J/∂t_1, found by Newton's method
// kept inside a sign-change bracket (bisection when a step leaves it). Assumes, as the paper
// conjectures and our tests check, that J(·, t_2) is quasi-convex.
double bestFirstInstant(const BrownianProblem& p, double t2, double guess) {
  if (firstInstantSlopeFactor(p, 0.0, t2) >= 0.0) return 0.0;
  if (firstInstantSlopeFactor(p, t2, t2) <= 0.0) return t2;
  double low = 0.0, high = t2;
  double t = std::clamp(guess, low, high);
  if (t <= low || t >= high) t = 0.5 * (low + high);
  const double tolerance = 4.0 * std::numeric_limits<double>::epsilon() * t2;
  for (int iteration = 0; iteration < 100; ++iteration) {
    const Dual slope = firstInstantSlopeFactor(p, Dual(t, 1.0), t2);
    if (slope.v == 0.0) return t;
    (slope.v < 0.0 ? low : high) = t;
    double next = t - slope.v / slope.d;
    if (!(slope.d > 0.0) || !(next > low && next < high)) next = 0.5 * (low + high);
    const bool converged = std::abs(next - t) <= tolerance || high - low <= tolerance;
    t = next;
    if (converged) break;
  }
  return t;
}

BrownianSchedule solveOne(const BrownianProblem& p) {
  BrownianSchedule schedule;
  const double t = singleInstant(p.sigma2, p.horizon_s, p.v0, p.variances[0]);
  schedule.instants = {t};
  schedule.regime = t > 0.0 ? 2 : 1;
  return schedule;
}

// Section IV and the Appendix (Fig. 12).
BrownianSchedule solveTwo(const BrownianProblem& p) {
  const double sigma2 = p.sigma2, T = p.horizon_s, v0 = p.v0;
  const double v1 = p.variances[0], v2 = p.variances[1];
  BrownianSchedule schedule;
  const TwoMeasureCriticalDurations critical = twoCriticalDurations(sigma2, v0, v1, v2);
  if (T <= critical.regime1_end) {  // Theorem 5
    schedule.instants = {0.0, 0.0};
    schedule.regime = 1;
    return schedule;
  }
  double t2 = singleInstant(sigma2, T, fusedVariance(v0, v1), v2);  // eq. (41)
  if (T <= critical.regime2_end) {                                  // Theorem 6
    schedule.instants = {0.0, t2};
    schedule.regime = 2;
    return schedule;
  }
  // Regime 3: alternate the t_1 step and the closed-form t_2 step of eq. (28) until neither
  // moves by more than a few ulps of T.
  constexpr int kMaxSweeps = 500;
  const double tolerance = 1e-14 * T;
  double t1 = 0.0;
  int sweeps = 0;
  while (sweeps < kMaxSweeps) {
    ++sweeps;
    const double next_t1 = bestFirstInstant(p, t2, t1);
    const double posterior1 = fusedVariance(v0 + sigma2 * next_t1, v1);
    const double next_t2 = next_t1 + singleInstant(sigma2, T - next_t1, posterior1, v2);
    const double change = std::abs(next_t1 - t1) + std::abs(next_t2 - t2);
    t1 = next_t1;
    t2 = std::min(next_t2, T);
    if (change <= tolerance) break;
  }
  schedule.instants = {t1, t2};
  // T just above T_{1,crit} can round to a descent that never leaves t_1 = 0: that is the
  // boundary case of regime 2, and the regime reported must match which instants are zero.
  schedule.regime = t1 > 0.0 ? 3 : 2;
  schedule.iterations = sweeps;
  return schedule;
}

// --- Local refinement: projected Newton on the simplex of gaps ---------------------------

// A chart of the simplex {y >= 0, Σ y = T} of gaps: coordinates x = every gap but one, the
// pivot, which is T - Σ x. With the largest gap as pivot (it is >= T/(n+1)) the only
// constraints that can bind near y are the bounds x >= 0, the setting of Bertsekas' projected
// Newton method. (Keeping Δ_{n+1} as the dependent gap instead stalls when t_n reaches T.)
class SimplexChart {
 public:
  SimplexChart(const Eigen::VectorXd& y, double horizon_s) : horizon_s_(horizon_s) {
    y.maxCoeff(&pivot_);
    size_ = y.size();
  }

  Eigen::VectorXd reduce(const Eigen::VectorXd& full) const {
    Eigen::VectorXd x(size_ - 1);
    for (Eigen::Index k = 0, i = 0; k < size_; ++k) {
      if (k != pivot_) x(i++) = full(k);
    }
    return x;
  }

  Eigen::VectorXd lift(const Eigen::VectorXd& x) const {
    Eigen::VectorXd y(size_);
    for (Eigen::Index k = 0, i = 0; k < size_; ++k) {
      if (k != pivot_) y(k) = x(i++);
    }
    y(pivot_) = horizon_s_ - x.sum();
    return y;
  }

  // ∂J/∂x_i = G_k - G_pivot for the gap k that x_i stands for.
  Eigen::VectorXd gradient(const Eigen::VectorXd& partials) const {
    return (reduce(partials).array() - partials(pivot_)).matrix();
  }

  // H_xx = H_kl - H_k,pivot - H_pivot,l + H_pivot,pivot.
  Eigen::MatrixXd hessian(const Eigen::MatrixXd& full) const {
    const Eigen::VectorXd column = reduce(full.col(pivot_));
    Eigen::MatrixXd h(size_ - 1, size_ - 1);
    for (Eigen::Index j = 0, jj = 0; j < size_; ++j) {
      if (j != pivot_) h.col(jj++) = reduce(full.col(j));
    }
    h.colwise() -= column;
    h.rowwise() -= column.transpose();
    h.array() += full(pivot_, pivot_);
    return h;
  }

  double horizon() const { return horizon_s_; }

 private:
  double horizon_s_;
  Eigen::Index pivot_ = 0;
  Eigen::Index size_ = 0;
};

struct Refinement {
  Eigen::VectorXd gaps;  // Δ_1..Δ_{n+1}
  double cost = 0.0;
  int iterations = 0;
};

// Coordinates held at their bound 0 this iteration: at (or within `hold` of) 0 and pushed below
// it by more than the rounding noise of the gradient (a coordinate at 0 with a zero gradient
// stays free, so that a direction of negative curvature through it can still be found).
std::vector<bool> heldGaps(const Eigen::VectorXd& x, const Eigen::VectorXd& gradient, double hold,
                           double gradient_noise) {
  std::vector<bool> held(static_cast<std::size_t>(x.size()));
  for (Eigen::Index k = 0; k < x.size(); ++k) {
    held[static_cast<std::size_t>(k)] = x(k) <= hold && gradient(k) > gradient_noise;
  }
  return held;
}

std::vector<Eigen::Index> freeIndices(const std::vector<bool>& held) {
  std::vector<Eigen::Index> free;
  for (std::size_t k = 0; k < held.size(); ++k) {
    if (!held[k]) free.push_back(static_cast<Eigen::Index>(k));
  }
  return free;
}

Eigen::MatrixXd freeBlock(const Eigen::MatrixXd& hessian, const std::vector<Eigen::Index>& free) {
  const auto m = static_cast<Eigen::Index>(free.size());
  Eigen::MatrixXd block(m, m);
  for (Eigen::Index i = 0; i < m; ++i) {
    for (Eigen::Index j = 0; j < m; ++j) {
      block(i, j) = hessian(free[static_cast<std::size_t>(i)], free[static_cast<std::size_t>(j)]);
    }
  }
  return block;
}

// Bertsekas' projected Newton direction: Newton on the free coordinates, a diagonally scaled
// gradient step on the held ones.
Eigen::VectorXd newtonDirection(const Eigen::MatrixXd& hessian, const Eigen::VectorXd& gradient,
                                const std::vector<bool>& held, double time_per_variance) {
  const auto n = gradient.size();
  Eigen::VectorXd direction = Eigen::VectorXd::Zero(n);
  const std::vector<Eigen::Index> free = freeIndices(held);
  if (!free.empty()) {
    const Eigen::MatrixXd h = freeBlock(hessian, free);
    Eigen::VectorXd g(h.rows());
    for (std::size_t i = 0; i < free.size(); ++i) {
      g(static_cast<Eigen::Index>(i)) = gradient(free[i]);
    }
    // Eigenvalues replaced by their absolute values (floored): positive definite, so a descent
    // direction, and unlike a uniform shift it keeps the full Newton step along every direction
    // of positive curvature; negative curvature is dealt with at stationary points.
    const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eigen(h);
    const double largest = std::max(eigen.eigenvalues().cwiseAbs().maxCoeff(), 1e-300);
    const Eigen::VectorXd inverse =
        eigen.eigenvalues().cwiseAbs().cwiseMax(1e-10 * largest).cwiseInverse();
    Eigen::VectorXd step =
        -(eigen.eigenvectors() * (inverse.asDiagonal() * (eigen.eigenvectors().transpose() * g)));
    if (!step.allFinite()) step = -g * time_per_variance;
    for (std::size_t i = 0; i < free.size(); ++i) {
      direction(free[i]) = step(static_cast<Eigen::Index>(i));
    }
  }
  for (Eigen::Index k = 0; k < n; ++k) {
    if (held[static_cast<std::size_t>(k)]) {
      direction(k) = -gradient(k) / std::max(hessian(k, k), 1e-12 / time_per_variance);
    }
  }
  return direction;
}

struct CurvatureStep {
  Eigen::VectorXd direction;  // unit length; empty when there is none worth following
  bool both_signs = false;    // false when only +direction keeps the gaps feasible
};

// A feasible direction of negative curvature at a stationary point, if there is one worth
// following: the lowest eigenvector of the Hessian block of the coordinates away from 0 (both
// signs feasible), or, for a coordinate at 0 that the gradient does not press against its
// bound, e_k or e_k - e_j. In gap terms the second kind moves a group of instants forward
// together, which leaves the saddles where measurements are wasted: when v0 = 0, instants at
// t = 0 have P = 0, so ∂J/∂t = 0 there (the factor P/(P + v) of the gradient vanishes) although
// moving them forward lowers J.
CurvatureStep negativeCurvatureStep(const Eigen::MatrixXd& hessian, const Eigen::VectorXd& x,
                                    const Eigen::VectorXd& gradient, double hold,
                                    double gradient_noise) {
  const auto n = x.size();
  CurvatureStep best;
  double lowest = -1e-9 * hessian.cwiseAbs().maxCoeff();
  std::vector<bool> at_bound(static_cast<std::size_t>(n));
  for (Eigen::Index k = 0; k < n; ++k) at_bound[static_cast<std::size_t>(k)] = x(k) <= hold;
  const std::vector<Eigen::Index> interior = freeIndices(at_bound);
  if (!interior.empty()) {
    const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eigen(freeBlock(hessian, interior));
    if (eigen.eigenvalues()(0) < lowest) {
      lowest = eigen.eigenvalues()(0);
      best.direction = Eigen::VectorXd::Zero(n);
      for (std::size_t i = 0; i < interior.size(); ++i) {
        best.direction(interior[i]) = eigen.eigenvectors()(static_cast<Eigen::Index>(i), 0);
      }
      best.both_signs = true;
    }
  }
  for (Eigen::Index k = 0; k < n; ++k) {
    if (!at_bound[static_cast<std::size_t>(k)] || gradient(k) > gradient_noise) continue;
    for (Eigen::Index j = k; j < n; ++j) {
      Eigen::VectorXd d = Eigen::VectorXd::Zero(n);
      d(k) = 1.0;
      if (j != k) d(j) = -1.0;
      d.normalize();
      const double curvature = d.dot(hessian * d);
      if (curvature < lowest) {
        lowest = curvature;
        best.direction = d;
        best.both_signs = false;
      }
    }
  }
  return best;
}

// Armijo search along the projection arc x(α) = max(x + α d, 0), α = α0, α0/2, ..., skipping
// the α that would make the pivot gap negative: the first point with sufficient decrease.
bool searchArc(GapCost& objective, const SimplexChart& chart, const Eigen::VectorXd& x, double cost,
               const Eigen::VectorXd& gradient, const Eigen::VectorXd& direction, double alpha,
               Eigen::VectorXd& next_gaps, double& next_cost) {
  for (int halving = 0; halving < 60; ++halving, alpha *= 0.5) {
    const Eigen::VectorXd trial = (x + alpha * direction).cwiseMax(0.0);
    if (trial.sum() > chart.horizon()) continue;
    next_gaps = chart.lift(trial);
    next_cost = objective.cost(next_gaps);
    const double predicted = gradient.dot(trial - x);
    if (next_cost <= cost + 1e-4 * std::min(predicted, 0.0) && next_cost < cost) return true;
  }
  return false;
}

// Projected Newton (Bertsekas 1982) on the simplex of gaps with exact gradient and Hessian, a
// projected-gradient step when Newton does not descend, and a negative-curvature step at
// stationary points that are not local minima. Stops when the projected gradient vanishes to
// rounding and no feasible direction checked has negative curvature, or when no step lowers
// the cost any more.
Refinement refineGaps(const BrownianProblem& p, Eigen::VectorXd y) {
  const double T = p.horizon_s;
  GapCost objective(p);
  y = y.cwiseMax(0.0);
  Eigen::VectorXd partials;
  double cost = objective.costAndPartials(y, partials);
  // Gradients are variances; this turns them into times for the stationarity test.
  const double time_per_variance = T / (p.v0 + p.sigma2 * T);
  const double gradient_noise = 1e-13 * T / time_per_variance;
  constexpr int kMaxIterations = 200;
  int iteration = 0;
  for (; iteration < kMaxIterations; ++iteration) {
    const SimplexChart chart(y, T);
    const Eigen::VectorXd x = chart.reduce(y);
    const Eigen::VectorXd gradient = chart.gradient(partials);
    const double residual =
        (x - (x - time_per_variance * gradient).cwiseMax(0.0)).cwiseAbs().maxCoeff();
    const double hold = std::min(1e-9 * T, residual);
    const Eigen::MatrixXd hessian = chart.hessian(objective.hessian(y));
    Eigen::VectorXd next;
    double next_cost = cost;
    bool moved = false;
    if (residual > 1e-13 * T) {
      const Eigen::VectorXd newton = newtonDirection(
          hessian, gradient, heldGaps(x, gradient, hold, gradient_noise), time_per_variance);
      moved = searchArc(objective, chart, x, cost, gradient, newton, 1.0, next, next_cost) ||
              searchArc(objective, chart, x, cost, gradient, -time_per_variance * gradient, 1.0,
                        next, next_cost);
    }
    if (!moved) {
      // Stationary to rounding: a second-order check, treating as pressed against 0 only the
      // coordinates whose gradient clearly pushes them there.
      const CurvatureStep curve = negativeCurvatureStep(
          hessian, x, gradient, std::max(hold, 1e-9 * T), 1e-6 * T / time_per_variance);
      if (curve.direction.size() == 0) break;
      moved = searchArc(objective, chart, x, cost, gradient, curve.direction, 0.5 * T, next,
                        next_cost) ||
              (curve.both_signs && searchArc(objective, chart, x, cost, gradient, -curve.direction,
                                             0.5 * T, next, next_cost));
      if (!moved) break;
    }
    y = next;
    cost = objective.costAndPartials(y, partials);
  }
  return {y, cost, iteration};
}

// --- Global search for n >= 3 ------------------------------------------------------------

// Optimal cost-to-go W_k(τ, g) after k measurements, with τ = i h left and posterior variance
// g: W_n = g τ + σ² τ²/2, W_{n-1} is the one-measure optimum (eq. 15 at prior g), and W_k for
// 1 <= k <= n-2 is tabulated on τ_i = i h and a uniform grid of g over the posterior variances
// reachable after measurement k, linear in g between nodes.
class CostToGoTable {
 public:
  CostToGoTable(const BrownianProblem& problem, int time_steps, int variance_nodes)
      : p_(problem),
        n_(static_cast<int>(problem.variances.size())),
        steps_(time_steps),
        nodes_(variance_nodes),
        h_(problem.horizon_s / time_steps) {
    const int tables = std::max(n_ - 2, 0);
    low_.assign(static_cast<std::size_t>(tables) + 1, 0.0);
    high_.assign(static_cast<std::size_t>(tables) + 1, 0.0);
    values_.resize(static_cast<std::size_t>(tables) + 1);
    double all_at_zero = p_.v0;
    const double largest_prior = p_.v0 + p_.sigma2 * p_.horizon_s;  // v(t) <= v0 + σ² t
    for (int k = 1; k <= tables; ++k) {
      all_at_zero = fusedVariance(all_at_zero, variance(k));
      low_[static_cast<std::size_t>(k)] = all_at_zero;
      high_[static_cast<std::size_t>(k)] = fusedVariance(variance(k), largest_prior);
    }
    for (int k = tables; k >= 1; --k) fill(k);
  }

  double step() const { return h_; }

  // Cost of measuring next after `wait` steps, from stage k with `left` steps and posterior g,
  // plus the cost-to-go after that measurement.
  double stageCost(int k, int left, double g, int wait) const {
    const double s = wait * h_;
    const double next_g = fusedVariance(variance(k + 1), g + p_.sigma2 * s);
    return g * s + 0.5 * p_.sigma2 * s * s + value(k + 1, left - wait, next_g);
  }

  double value(int k, int left, double g) const {
    const double tau = left * h_;
    if (k == n_) return g * tau + 0.5 * p_.sigma2 * tau * tau;
    if (k == n_ - 1) return singleMeasureCost(p_.sigma2, tau, g, variance(n_));
    const auto kk = static_cast<std::size_t>(k);
    const double position =
        std::clamp((g - low_[kk]) / (high_[kk] - low_[kk]), 0.0, 1.0) * (nodes_ - 1);
    const int j = std::min(static_cast<int>(position), nodes_ - 2);
    const double weight = position - j;
    const std::vector<double>& row = values_[kk];
    const std::size_t at = static_cast<std::size_t>(left) * static_cast<std::size_t>(nodes_) +
                           static_cast<std::size_t>(j);
    return (1.0 - weight) * row[at] + weight * row[at + 1];
  }

  // Best number of steps to wait before measurement k+1 from (k, left, g).
  int bestWait(int k, int left, double g) const {
    int best = 0;
    double best_cost = std::numeric_limits<double>::infinity();
    for (int wait = 0; wait <= left; ++wait) {
      const double c = stageCost(k, left, g, wait);
      if (c < best_cost) best_cost = c, best = wait;
    }
    return best;
  }

 private:
  double variance(int k) const { return p_.variances[static_cast<std::size_t>(k - 1)]; }

  void fill(int k) {
    const auto kk = static_cast<std::size_t>(k);
    std::vector<double>& row = values_[kk];
    row.assign(static_cast<std::size_t>(steps_ + 1) * static_cast<std::size_t>(nodes_), 0.0);
    for (int left = 0; left <= steps_; ++left) {
      for (int j = 0; j < nodes_; ++j) {
        const double g = low_[kk] + (high_[kk] - low_[kk]) * j / (nodes_ - 1);
        double best = std::numeric_limits<double>::infinity();
        for (int wait = 0; wait <= left; ++wait) best = std::min(best, stageCost(k, left, g, wait));
        row[static_cast<std::size_t>(left) * static_cast<std::size_t>(nodes_) +
            static_cast<std::size_t>(j)] = best;
      }
    }
  }

  const BrownianProblem& p_;
  int n_, steps_, nodes_;
  double h_;
  std::vector<double> low_, high_;
  std::vector<std::vector<double>> values_;  // [k][left * nodes + j]
};

// Starts for the local refinement: for each of the best few local minima (over the grid) of
// the stage-0 profile t_1 -> v0 t_1 + σ² t_1²/2 + W_1(T - t_1, v_1 // (v0 + σ² t_1)), the DP
// path on the grid for t_1..t_{n-1} and the closed-form t_n.
std::vector<std::vector<double>> gridStarts(const BrownianProblem& p, int time_steps,
                                            int variance_nodes, int basins) {
  const int n = static_cast<int>(p.variances.size());
  if (n == 1) return {{singleInstant(p.sigma2, p.horizon_s, p.v0, p.variances[0])}};
  const CostToGoTable table(p, time_steps, variance_nodes);
  std::vector<double> profile(static_cast<std::size_t>(time_steps) + 1);
  for (int wait = 0; wait <= time_steps; ++wait) {
    profile[static_cast<std::size_t>(wait)] = table.stageCost(0, time_steps, p.v0, wait);
  }
  std::vector<std::pair<double, int>> minima;
  for (int a = 0; a <= time_steps; ++a) {
    const auto i = static_cast<std::size_t>(a);
    const bool left_ok = a == 0 || profile[i] <= profile[i - 1];
    const bool right_ok = a == time_steps || profile[i] < profile[i + 1];
    if (left_ok && right_ok) minima.emplace_back(profile[i], a);
  }
  std::sort(minima.begin(), minima.end());
  if (static_cast<int>(minima.size()) > basins) minima.resize(static_cast<std::size_t>(basins));

  std::vector<std::vector<double>> starts;
  for (const auto& [unused, first_wait] : minima) {
    std::vector<double> instants;
    double t = first_wait * table.step();
    double g = fusedVariance(p.variances[0], p.v0 + p.sigma2 * t);
    int left = time_steps - first_wait;
    instants.push_back(t);
    for (int k = 1; k <= n - 2; ++k) {
      const int wait = table.bestWait(k, left, g);
      const double s = wait * table.step();
      g = fusedVariance(p.variances[static_cast<std::size_t>(k)], g + p.sigma2 * s);
      t += s;
      left -= wait;
      instants.push_back(t);
    }
    const double tau = p.horizon_s - t;
    instants.push_back(t + singleInstant(p.sigma2, tau, g, p.variances.back()));
    starts.push_back(std::move(instants));
  }
  return starts;
}

void fillCosts(const BrownianProblem& p, BrownianSchedule& schedule) {
  schedule.cost = costOfInstants(p, schedule.instants);
  schedule.regular_cost =
      costOfInstants(p, regularInstants(p.horizon_s, static_cast<int>(p.variances.size())));
}

}  // namespace

// --- Public API ---------------------------------------------------------------------------

void validateBrownianProblem(const BrownianProblem& problem, const std::string& source) {
  if (!isPositive(problem.sigma2)) throw InputError(source, "sigma2", "a finite value > 0");
  if (!isPositive(problem.horizon_s)) throw InputError(source, "horizon", "a finite value > 0");
  if (!isNonNegative(problem.v0)) throw InputError(source, "v0", "a finite value >= 0");
  if (problem.variances.empty()) {
    throw InputError(source, "variances", "at least one measurement variance");
  }
  for (std::size_t k = 0; k < problem.variances.size(); ++k) {
    if (!isPositive(problem.variances[k])) {
      throw InputError(source, "variances[" + std::to_string(k) + "]", "a finite value > 0");
    }
  }
}

double fusedVariance(double a, double b) { return a * b / (a + b); }

double timetableCost(const BrownianProblem& problem, const std::vector<double>& instants) {
  validateInstants(problem, instants, "timetableCost");
  return costOfInstants(problem, instants);
}

std::vector<double> timetableCostGradient(const BrownianProblem& problem,
                                          const std::vector<double>& instants) {
  validateInstants(problem, instants, "timetableCostGradient");
  const std::size_t n = instants.size();
  std::vector<double> gaps(n + 1), posterior(n + 1), slope(n), partials(n + 1);
  double previous = 0.0;
  for (std::size_t k = 0; k < n; ++k) {
    gaps[k] = instants[k] - previous;
    previous = instants[k];
  }
  gaps[n] = problem.horizon_s - previous;
  (void)forwardSweep(problem.sigma2, problem.v0, problem.variances, gaps, posterior, slope);
  gapPartials(problem.sigma2, gaps, posterior, slope, partials);
  std::vector<double> gradient(n);
  for (std::size_t k = 0; k < n; ++k) gradient[k] = partials[k] - partials[k + 1];
  return gradient;
}

std::vector<double> regularInstants(double horizon_s, int count) {
  std::vector<double> instants(static_cast<std::size_t>(std::max(count, 0)));
  for (int k = 1; k <= count; ++k) {
    instants[static_cast<std::size_t>(k - 1)] = k * horizon_s / (count + 1);
  }
  return instants;
}

double optimalSingleInstant(double sigma2, double horizon_s, double v0, double v1) {
  requireSingleParameters("optimalSingleInstant", sigma2, v0, v1);
  if (!isNonNegative(horizon_s)) {
    throw InputError("optimalSingleInstant", "horizon", "a finite value >= 0");
  }
  return singleInstant(sigma2, horizon_s, v0, v1);
}

double criticalDurationSingle(double sigma2, double v0, double v1) {
  requireSingleParameters("criticalDurationSingle", sigma2, v0, v1);
  return singleCriticalDuration(sigma2, v0, v1);
}

double lowerBoundSingle(double sigma2, double horizon_s, double v0, double v1) {
  requireSingleParameters("lowerBoundSingle", sigma2, v0, v1);
  if (!isPositive(horizon_s)) throw InputError("lowerBoundSingle", "horizon", "a finite value > 0");
  return std::sqrt(sigma2 * fusedVariance(v0, v1) * horizon_s * horizon_s * horizon_s);
}

TwoMeasureCriticalDurations criticalDurationsTwo(double sigma2, double v0, double v1, double v2) {
  requireSingleParameters("criticalDurationsTwo", sigma2, v0, v1);
  if (!isPositive(v2)) throw InputError("criticalDurationsTwo", "v2", "a finite value > 0");
  return twoCriticalDurations(sigma2, v0, v1, v2);
}

double criticalGapTwo(double sigma2, double v0, double v1, double v2) {
  requireSingleParameters("criticalGapTwo", sigma2, v0, v1);
  if (!isPositive(v2)) throw InputError("criticalGapTwo", "v2", "a finite value > 0");
  return criticalGapVariance(v0, v1, v2) / sigma2;
}

BrownianSchedule refineInstants(const BrownianProblem& problem, const std::vector<double>& start) {
  validateInstants(problem, start, "refineInstants");
  const Refinement refined = refineGaps(problem, gapsOf(start, problem.horizon_s));
  BrownianSchedule schedule;
  schedule.instants = instantsOf(refined.gaps, problem.horizon_s);
  schedule.iterations = refined.iterations;
  fillCosts(problem, schedule);
  return schedule;
}

BrownianSchedule optimalInstantsBySearch(const BrownianProblem& problem) {
  validateBrownianProblem(problem, "optimalInstantsBySearch");
  constexpr int kTimeSteps = 64, kVarianceNodes = 33, kBasins = 3;
  std::vector<std::vector<double>> starts =
      gridStarts(problem, kTimeSteps, kVarianceNodes, kBasins);
  starts.push_back(regularInstants(problem.horizon_s, static_cast<int>(problem.variances.size())));
  Refinement best;
  best.cost = std::numeric_limits<double>::infinity();
  for (const std::vector<double>& start : starts) {
    Refinement refined = refineGaps(problem, gapsOf(start, problem.horizon_s));
    if (refined.cost < best.cost) best = std::move(refined);
  }
  BrownianSchedule schedule;
  schedule.instants = instantsOf(best.gaps, problem.horizon_s);
  schedule.iterations = best.iterations;
  fillCosts(problem, schedule);
  return schedule;
}

BrownianSchedule optimalInstants(const BrownianProblem& problem) {
  validateBrownianProblem(problem, "optimalInstants");
  BrownianSchedule schedule;
  switch (problem.variances.size()) {
    case 1:
      schedule = solveOne(problem);
      break;
    case 2:
      schedule = solveTwo(problem);
      break;
    default:
      return optimalInstantsBySearch(problem);
  }
  fillCosts(problem, schedule);
  return schedule;
}

}  // namespace sensornet
