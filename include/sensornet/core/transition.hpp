#pragma once
// The exact transition of the CD-KF between two arrivals. Between arrivals the covariance obeys
// the Lyapunov equation (3), Ṗ = A P + P A' + Q, and the running cost of eq. (6) accumulates
// ∫ <W, P(s)>_F ds. Both are linear in P, so one interval of length dt is summarized by four
// quantities that depend on (A, Q, W, dt) only:
//
//   P(dt)          = Phi P Phi' + Qd
//   ∫_0^dt <W,P>ds = <P, cost_gramian>_F + noise_cost
//
//   LtiTransition transition(A, Q, W);               // once per plant
//   IntervalTransition step = transition.over(0.25); // exact, any dt >= 0
//   double cost = P.cwiseProduct(step.cost_gramian).sum() + step.noise_cost;
//   P = step.Phi * P * step.Phi.transpose() + step.Qd;
//
// Three exact methods, none of which takes time steps. The modal one diagonalizes
// A = V Λ V^{-1} once, after which every quantity is a Hadamard product in the eigenbasis with
// scalar integrals of e^{(λ_i+λ_j)s}: n exponentials per call. It would lose accuracy when V is
// ill-conditioned (defective or nearly defective A). Nilpotent A (A^m = 0: the double
// integrator and other integrator chains, the common defective case) gives finite Taylor
// series, so all four quantities are polynomials in dt with precomputed coefficients. Any other
// defective A falls back to the Van Loan (1978) block exponential of one 3n x 3n matrix.

#include <Eigen/Core>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

namespace sensornet {

struct IntervalTransition {
  Eigen::MatrixXd Phi;           // e^{A dt}
  Eigen::MatrixXd Qd;            // ∫_0^dt e^{As} Q e^{A's} ds (process-noise covariance over dt)
  Eigen::MatrixXd cost_gramian;  // G = ∫_0^dt e^{A's} W e^{As} ds
  double noise_cost = 0.0;       // ∫_0^dt <W, Qd(s)>_F ds
  // so that for P(s) = Phi(s) P Phi(s)' + Qd(s):  ∫_0^dt <W, P(s)> ds = <P, G>_F + noise_cost
};

enum class TransitionMethod {
  kAutomatic,   // polynomial for nilpotent A, else modal when the eigenbasis is well
                // conditioned, else Van Loan
  kModal,       // eigen-decomposition of A; throws InputError when A is (numerically) defective
  kPolynomial,  // A^m = 0 exactly (integrator chains): finite polynomials in dt; throws
                // InputError for any other A
  kVanLoan,     // block matrix exponential; works for every A, slowest
};

// Precomputes what it can from (A, Q, W); over() is cheap and safe to call from several threads
// at once. Copies share the immutable precomputed data.
class LtiTransition {
 public:
  // Above this 2-norm condition number of the (unit-column) eigenvector matrix V the automatic
  // choice falls back to Van Loan. The modal path's relative error in Qd, G and noise_cost
  // grows like 0.1 cond(V)^2 ulps (V^{-1} Q V^{-T} and back): measured 2e-12 at cond 200,
  // 3e-10 at 2e3, 1e-8 at 2e4 on nearly defective 2 x 2 Jordan blocks. 100 keeps it < 1e-12.
  static constexpr double kMaxEigenvectorCondition = 100.0;
  // Past this the modal error (~eps cond^2) reaches order one: A counts as defective, and even
  // a forced kModal is refused.
  static constexpr double kDefectiveEigenvectorCondition = 1e8;

  // A, Q, W are n x n; Q and W are used through their symmetric parts (P is symmetric, so
  // that changes neither P(dt) nor the cost). Throws InputError on bad shapes or non-finite
  // entries.
  LtiTransition(const Eigen::MatrixXd& A, const Eigen::MatrixXd& Q, const Eigen::MatrixXd& W,
                TransitionMethod method = TransitionMethod::kAutomatic);

  // The exact transition over an interval of length dt >= 0 (throws InputError otherwise).
  [[nodiscard]] IntervalTransition over(double dt) const;
  // The same, written into `step` so that repeated calls reuse its storage.
  void over(double dt, IntervalTransition& step) const;

  [[nodiscard]] int stateDim() const;
  // The method in use: kModal, kPolynomial or kVanLoan, never kAutomatic.
  [[nodiscard]] TransitionMethod method() const;
  // cond_2(V) of the unit-column eigenvector matrix (about 1e15 or more for an exactly
  // defective A); infinity when the eigen-decomposition failed or V is singular.
  [[nodiscard]] double eigenvectorCondition() const;

 private:
  struct Impl;
  std::shared_ptr<const Impl> impl_;
};

// The steps over the interval lengths met last, found by their exact length. over() is a
// function of dt, so a step found here is, bit for bit, the one LtiTransition::over computes.
// It pays where lengths repeat: instants on a tick grid (the emulated plant's arrivals, whose
// gaps are whole ticks) and a filter that goes over the same intervals again (the fusion
// center's real-time cost). `slots` steps at most, direct-mapped by the bits of dt, so a
// look-up is a hash and one comparison; with 1 slot it remembers the last step only.
//
//   TransitionCache steps(transition, 256);
//   const IntervalTransition& step = steps.over(dt);  // valid until the next over()
class TransitionCache {
 public:
  TransitionCache(LtiTransition transition, std::size_t slots);

  // transition().over(dt), from the cache when a step of exactly this length is in it.
  [[nodiscard]] const IntervalTransition& over(double dt);

  [[nodiscard]] const LtiTransition& transition() const { return transition_; }
  [[nodiscard]] std::size_t slots() const { return steps_.size(); }
  [[nodiscard]] std::uint64_t hits() const { return hits_; }
  [[nodiscard]] std::uint64_t misses() const { return misses_; }

 private:
  LtiTransition transition_;
  std::vector<double> lengths_;  // of the step in each slot; NaN: empty
  std::vector<IntervalTransition> steps_;
  IntervalTransition computed_;  // a new step, swapped into its slot once over() succeeded
  int shift_ = 64;  // slot = (bits of dt * a Fibonacci constant) >> shift_
  std::uint64_t hits_ = 0;
  std::uint64_t misses_ = 0;
};

}  // namespace sensornet
