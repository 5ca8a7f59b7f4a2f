#pragma once
// Deterministic surrogates of the expected CD-KF covariance under a rate schedule, and the cost
// bracket they give (paper 1, Section IV):
//   information form, eq. (11):  Ẏs = -Ys A - A' Ys - Ys Q Ys + Σ_j λ_j(t) S_j,  P_info = Ys^{-1}
//   covariance form,  eq. (15):  Ṗs = A Ps + Ps A' + Q - Σ_j λ_j(t) g_j(Ps)
// and, for any fixed admissible schedule, Corollary 1 (eq. 22):
//   J(P_info) <= E[J(P)] <= J(Ps),   J(P) = ∫ <W, P(t)>_F dt + <W_T, P(T)>_F   (eq. 6).
//
//   const CostBracket bracket = computeBracket(scenario, schedule);
//   // bracket.info <= expected cost <= bracket.cov
//
//   // The rest of an episode, from the fused covariance at the time a new schedule takes effect:
//   RolloutOptions from_now;
//   from_now.start_time = t_switch;
//   from_now.start_covariance = fused_covariance;
//   const SurrogateRollout rest = rolloutCovarianceForm(scenario, new_schedule, from_now);
//
// Both forms are integrated by the same mechanism: an adaptive Dormand-Prince 5(4) integrator
// (ode.hpp) on the symmetric matrix state augmented with the running-cost integral, restarted at
// every interval boundary of the schedule (the right-hand side jumps there). The local error of
// the matrix is measured relative to the matrix itself in every direction (Loewner sense), so the
// stated tolerance is a relative accuracy of every variance, however ill-conditioned P is.

#include <Eigen/Core>
#include <optional>
#include <vector>

#include "sensornet/core/rate_schedule.hpp"
#include "sensornet/core/scenario.hpp"

namespace sensornet {

enum class SurrogateForm { Information, Covariance };

struct RolloutOptions {
  double relative_tolerance = 1e-10;  // the bracket is a property of the model, not of the step
  double absolute_tolerance = 1e-12;
  double start_time = 0.0;  // roll out over [start_time, end_time] ...
  // ... from this covariance at start_time. Required when start_time > 0; P0 when absent.
  std::optional<Eigen::MatrixXd> start_covariance;
  // T when absent. A rollout that stops before T predicts covariances (its last one is the
  // covariance at end_time); its costs cover [start_time, end_time] without a terminal term.
  std::optional<double> end_time;
};

struct SurrogateRollout {
  std::vector<double> times;                 // start_time, the interval boundaries, end_time
  std::vector<Eigen::MatrixXd> covariances;  // P_info = Ys^{-1} or Ps at those times
  double running_cost = 0.0;                 // ∫ <W, P> dt over [start_time, end_time]
  double terminal_cost = 0.0;                // <W_T, P(T)> (0 if the rollout ends before T)
  double cost = 0.0;                         // the sum: J of eq. (6) over [start_time, end_time]
  int steps = 0;                             // accepted integrator steps
};

// Throw InputError when the schedule does not fit the scenario (sensor count, horizon), has a
// negative or non-finite rate, or the options are out of range (start_time outside [0, T],
// end_time outside [start_time, T], start_covariance not n x n symmetric positive definite).
// The scenario itself is assumed to have passed validateScenario. Throw std::runtime_error if
// the integrator cannot reach end_time.
[[nodiscard]] SurrogateRollout rolloutInformationForm(const Scenario& scenario,
                                                      const RateSchedule& schedule,
                                                      const RolloutOptions& options = {});
[[nodiscard]] SurrogateRollout rolloutCovarianceForm(const Scenario& scenario,
                                                     const RateSchedule& schedule,
                                                     const RolloutOptions& options = {});
[[nodiscard]] SurrogateRollout rollout(SurrogateForm form, const Scenario& scenario,
                                       const RateSchedule& schedule,
                                       const RolloutOptions& options = {});

// Corollary 1: J(P_info) <= E J <= J(P_cov) for the schedule, both over [start_time, T].
struct CostBracket {
  double info = 0.0;
  double cov = 0.0;
};
[[nodiscard]] CostBracket computeBracket(const Scenario& scenario, const RateSchedule& schedule,
                                         const RolloutOptions& options = {});

}  // namespace sensornet
