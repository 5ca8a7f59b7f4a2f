#pragma once
// The exact continuous-discrete Kalman filter of the first paper: between arrivals the mean and
// covariance follow dm = A m dt and eq. (3) exactly (see transition.hpp), at an arrival from
// sensor j the covariance jumps by eq. (4), and the realized cost J(P) of eq. (6) is accumulated
// exactly along the way.
//
//   CdKalmanFilter filter(scenario);       // starts at t = 0 with m0, P0
//   filter.propagateTo(0.42);              // exact, adds ∫ <W, P> over [0, 0.42]
//   filter.update(/*sensor=*/3, z);        // eq. (4) and the mean update
//   filter.updateCovariance(7);            // a second arrival at the same instant, no value
//   filter.propagateTo(scenario.horizon_s);
//   double J = filter.cost();              // J(P) of eq. (6)
//
// Simultaneous arrivals are successive updates at one instant (propagateTo(time()) is a no-op);
// this equals one joint update with stacked H and block-diagonal R.
//
// Updates use the Joseph form (I - K H) P (I - K H)' + K R K', a sum of two positive
// semidefinite terms, so P stays symmetric positive definite over long runs; the covariance is
// symmetrized in one place, after every change.

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <cstddef>
#include <vector>

#include "sensornet/core/scenario.hpp"
#include "sensornet/core/transition.hpp"

namespace sensornet {

class CdKalmanFilter {
 public:
  // Copies what it needs from the scenario (which must be valid: see validateScenario; only
  // shapes are checked here) and builds the exact transition of its plant and running weight.
  explicit CdKalmanFilter(const Scenario& scenario,
                          TransitionMethod method = TransitionMethod::kAutomatic);

  // t = 0, mean m0 (zero if the scenario has none), covariance P0, cost 0.
  void reset();
  // Restarts at time t from the given mean and covariance, with cost 0 (so that runningCost()
  // is then ∫_t^... <W, P>).
  void reset(double t, const Eigen::VectorXd& mean, const Eigen::MatrixXd& covariance);

  // Exact propagation to t >= time(); adds ∫_{time()}^t <W, P(s)> ds to the running cost.
  // t == time() is a no-op; t < time() throws InputError.
  void propagateTo(double t);
  // The same with a precomputed step = transition().over(dt), for callers that reuse steps.
  void propagateBy(const IntervalTransition& step, double dt);
  // propagateTo keeps the steps of the last `slots` distinct interval lengths (1 by default;
  // see TransitionCache): the same numbers, fewer computed where lengths repeat.
  void cacheSteps(std::size_t slots) { steps_ = TransitionCache(transition_, slots); }
  [[nodiscard]] const TransitionCache& steps() const { return steps_; }

  // Eq. (4) and the mean update m += K (z - H_j m), for a measurement z (p_j values) of sensor j.
  void update(int sensor, const Eigen::Ref<const Eigen::VectorXd>& z);
  // Eq. (4) only: the covariance does not depend on the measured value.
  void updateCovariance(int sensor);

  [[nodiscard]] double time() const { return time_; }
  [[nodiscard]] const Eigen::VectorXd& mean() const { return mean_; }
  [[nodiscard]] const Eigen::MatrixXd& covariance() const { return covariance_; }
  // ∫ <W, P(s)> ds accumulated since the last reset.
  [[nodiscard]] double runningCost() const { return running_cost_; }
  // <W_T, P(time())>.
  [[nodiscard]] double terminalCost() const;
  // runningCost() + terminalCost(): J(P) of eq. (6) when time() = T.
  [[nodiscard]] double cost() const { return runningCost() + terminalCost(); }
  [[nodiscard]] const LtiTransition& transition() const { return transition_; }

  [[nodiscard]] int stateDim() const { return static_cast<int>(covariance_.rows()); }
  [[nodiscard]] int sensorCount() const { return static_cast<int>(sensors_.size()); }

 private:
  // Joseph-form covariance update for sensor j; with update_mean, also m += K (z - H m) of the
  // innovation update() put in its work space.
  void applyUpdate(int sensor, bool update_mean);
  [[nodiscard]] const SensorModel& sensorModel(int sensor) const;
  void symmetrizeCovariance();

  LtiTransition transition_;
  std::vector<SensorModel> sensors_;
  Eigen::VectorXd initial_mean_;
  Eigen::MatrixXd initial_covariance_;
  Eigen::MatrixXd terminal_weight_;

  double time_ = 0.0;
  Eigen::VectorXd mean_;
  Eigen::MatrixXd covariance_;
  double running_cost_ = 0.0;

  // Work space reused across calls so that the per-arrival path does not allocate.
  TransitionCache steps_;
  // An update's matrices for p measured values (sensors of different row counts each keep
  // theirs, instead of resizing one set at every change of sensor).
  struct UpdateWork {
    Eigen::MatrixXd PHt;             // P H', later K R
    Eigen::MatrixXd innovation_cov;  // H P H' + R
    Eigen::LLT<Eigen::MatrixXd> innovation_llt;
    Eigen::MatrixXd gain_t;      // K' (p x n)
    Eigen::VectorXd innovation;  // z - H m
  };
  std::vector<UpdateWork> update_work_;  // by p
  Eigen::MatrixXd IKH_;         // I - K H
  Eigen::MatrixXd work_;        // n x n products
  Eigen::VectorXd mean_work_;
};

}  // namespace sensornet
