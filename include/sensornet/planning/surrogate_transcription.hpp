#pragma once
// The planner's transcription of the surrogate scheduling problem (eq. 12 with the information
// form, eq. 11, or the covariance form, eq. 15): single shooting with a fixed number of classical
// Runge-Kutta (RK4) steps per rate interval, the cost of eq. (6) accumulated by the same RK4
// stages, and the exact reverse (discrete adjoint) pass of that same scheme. The gradient is
// therefore the exact gradient of the discretized cost, to rounding, whatever the step.
//
//   SurrogateTranscription info(SurrogateForm::Information, scenario);
//   const CostGradient cg = info.costAndGradient(schedule.rates());
//   // cg.cost ≈ rollout(SurrogateForm::Information, scenario, schedule).cost (to O(h^4))
//   // cg.gradient(k, j) = ∂cost / ∂λ_kj
//
// Both forms share one mechanism (the RK4 step, its reverse pass, the interval loop); a form
// only supplies its right-hand side, its vector-Jacobian products and its costs. The asymmetry
// the first paper points out shows up here as cost per RK4 stage: in the information form the
// rates enter additively (Σ_j λ_j S_j), so ∂f/∂λ_j = S_j does not depend on the state and the
// rate gradient of a whole interval is M inner products <Σ_stages k̄, S_j>, once per interval;
// in the covariance form ∂f/∂λ_j = -g_j(P) depends on the state, so every stage of every step
// needs g_j(P_stage) paired with its adjoint for every sensor (O(M n²) per stage for
// single-row sensors, against O(n³) for the information form).

#include <Eigen/Core>
#include <memory>
#include <optional>

#include "sensornet/core/scenario.hpp"
#include "sensornet/core/surrogate.hpp"

namespace sensornet {

struct TranscriptionOptions {
  int substeps = 4;         // RK4 steps per rate interval (the partial first interval too)
  double start_time = 0.0;  // the cost is over [start_time, T] ...
  // ... from this covariance at start_time (P0 when absent; required when start_time > 0).
  std::optional<Eigen::MatrixXd> start_covariance;
  // Network-aware planning (PlanRequest::delivery): the surrogate is evaluated at the delivered
  // rates μ = delivery ⊙ λ (N x M, entries in [0, 1]), so the gradient in λ is
  // delivery ⊙ ∂cost/∂μ (chain rule). Absent: μ = λ.
  std::optional<Eigen::MatrixXd> delivery;
  // Threads of the information form's gradient products (one n x n adjoint per interval paired
  // with every S_j); 0 = the hardware concurrency, at most 2, and one thread for small problems
  // (below about 1e6 multiply-adds per gradient). The result does not depend on it.
  int threads = 0;
};

struct CostGradient {
  double cost = 0.0;         // +infinity when the discrete trajectory left the positive cone
  Eigen::MatrixXd gradient;  // N x M, ∂cost/∂λ_kj; rows before firstInterval() are zero
};

class SurrogateTranscription {
 public:
  // Throws InputError when the options are out of range (substeps < 1, start_time outside
  // [0, T], start_covariance not n x n symmetric positive definite).
  SurrogateTranscription(SurrogateForm form, const Scenario& scenario,
                         const TranscriptionOptions& options = {});
  ~SurrogateTranscription();
  SurrogateTranscription(SurrogateTranscription&&) noexcept;
  SurrogateTranscription& operator=(SurrogateTranscription&&) noexcept;

  [[nodiscard]] SurrogateForm form() const;
  // The first interval the cost depends on: the one containing start_time (or N when
  // start_time = T). A start time within 1e-12 T of a boundary starts the next interval, as in
  // the accurate rollout of surrogate.hpp.
  [[nodiscard]] int firstInterval() const;

  // rates is N x M (rows before firstInterval() are ignored), entries >= 0.
  [[nodiscard]] double cost(const Eigen::Ref<const Eigen::MatrixXd>& rates);
  [[nodiscard]] CostGradient costAndGradient(const Eigen::Ref<const Eigen::MatrixXd>& rates);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace sensornet
