#pragma once
// The admissible rates of one interval, {λ ∈ R^M : λ >= 0, C λ <= b, λ_j = 0 for excluded j}
// (eq. 8 of the first paper, with sensors taken out of service), and the Euclidean projection
// onto it, or onto the schedules of several intervals under per-sensor energy budgets. The
// planner uses the projection to return exactly feasible schedules and to measure first-order
// optimality (the projected gradient).
//
//   const RatePolytope polytope(scenario.constraints, /*excluded=*/{3});
//   const Eigen::VectorXd lambda = polytope.project(proposal);   // nearest admissible rates
//   assert(polytope.contains(lambda, 1e-12));

#include <Eigen/Core>
#include <vector>

#include "sensornet/core/scenario.hpp"

namespace sensornet {

class RatePolytope {
 public:
  // Throws InputError when an excluded index is not a sensor of C.
  RatePolytope(ResourceConstraints constraints, const std::vector<int>& excluded_sensors = {});

  [[nodiscard]] const ResourceConstraints& constraints() const { return constraints_; }
  [[nodiscard]] int sensorCount() const { return static_cast<int>(constraints_.C.cols()); }
  [[nodiscard]] bool isExcluded(int sensor) const { return excluded_[static_cast<std::size_t>(sensor)]; }
  // λ̄_j = min_{i: C_ij > 0} b_i / C_ij, and 0 for an excluded sensor.
  [[nodiscard]] Eigen::VectorXd maxRates() const;
  // The largest rate r, equal for every sensor in service, with C λ <= b (0 for excluded ones).
  [[nodiscard]] Eigen::VectorXd uniformRates() const;
  [[nodiscard]] bool contains(const Eigen::Ref<const Eigen::VectorXd>& rates, double tol) const;

  // argmin ||λ - y|| over the polytope. The dual of the projection, max over μ >= 0 of
  // min_{λ >= 0} ½||λ - y||² + μ'(C λ - b), is solved by exact coordinate ascent on μ
  // (Hildreth's method): each coordinate is the root of a monotone piecewise-linear function.
  // With one constraint row (the paper's budget 1'λ <= b) one sweep is exact; with several rows
  // the sweeps stop when C λ <= b holds and every row with μ_i > 0 is tight, both to 1e-13
  // relative (or after 10000 sweeps), and the result is then scaled into the polytope, so it is
  // always admissible.
  [[nodiscard]] Eigen::VectorXd project(const Eigen::Ref<const Eigen::VectorXd>& rates) const;

  // The same projection for consecutive intervals of length h under per-sensor energy budgets,
  // which couple them: argmin ||Λ - Y||_F over K x M schedules Λ whose every row is in the
  // polytope and whose columns meet Σ_k h Λ_kj <= energy_j (+infinity: no budget). Hildreth's
  // coordinate ascent runs over all K n_c interval rows and the M energy rows, until every row
  // holds and every row with a positive multiplier is tight, both to 1e-12 relative (or after
  // kMaxScheduleSweeps sweeps), and the result is then scaled into the set (each interval into
  // its rows, then each sensor into its budget), so it is always admissible.
  //
  // `budget_multipliers`, when given, starts the ascent on the budgets' multipliers from those
  // it holds (the last projection's, when it has M of them: the optimizer projects nearby
  // points one after another) and receives the new ones.
  [[nodiscard]] Eigen::MatrixXd projectSchedule(const Eigen::Ref<const Eigen::MatrixXd>& rates,
                                                double interval_length,
                                                const Eigen::VectorXd& energy,
                                                Eigen::VectorXd* budget_multipliers =
                                                    nullptr) const;
  // The uniform rates of every interval, each sensor's capped so that its column meets its
  // budget: min(uniformRates()_j, energy_j / (K h)).
  [[nodiscard]] Eigen::MatrixXd uniformSchedule(int intervals, double interval_length,
                                                const Eigen::VectorXd& energy) const;

  static constexpr int kMaxDualSteps = 2000;
  static constexpr int kMaxScheduleSweeps = 20000;

 private:
  ResourceConstraints constraints_;
  std::vector<bool> excluded_;
};

}  // namespace sensornet
