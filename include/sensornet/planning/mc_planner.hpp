#pragma once
// Planning for the realized cost: the rate schedule that minimizes E[J(P)] of the exact CD-KF
// (eq. 6) under Poisson arrivals over {λ >= 0, C λ <= b} (eq. 8), by Monte Carlo, rather than a
// surrogate of it. Reached through planSchedule with PlanSurrogate::MonteCarlo ("mc").
//
//   PlanRequest request;
//   request.surrogate = PlanSurrogate::MonteCarlo;
//   request.max_seconds = 45;
//   const PlanResult plan = planSchedule(scenario, request);   // or planForRealizedCost
//   // plan.objective +- plan.objective_half_width: E[J] of plan.schedule (95%, fresh episodes)
//
// Method:
//  - Common random numbers by time change: in episode e, sensor j's arrivals are the points of
//    one unit-rate Poisson process (keyed by seed, e, j) mapped through the inverse of its
//    integrated rate Λ_j(t) = ∫_{t0}^t λ_j. This is the exact Poisson law for every schedule, and
//    two schedules compared on the same episodes see the same underlying randomness.
//  - Warm start: the info, cov and uniform plans (and the request's warm start) and convex
//    mixtures of cov with info and with uniform, compared on one screening sample; the best is
//    the start of the refinement.
//  - Gradient: the Poisson "add one point" (Mecke) identity, unbiased also at λ_kj = 0:
//    dE[J]/dλ_kj = Δ_k E[J(N + one arrival of j at U ~ U(interval k)) - J(N)]. One U per
//    interval and episode, a random subset of the sensors per interval (weighted so the
//    estimate stays unbiased), each a partial re-run from U that reuses the stored forward path.
//  - Steps: projected gradient steps (rate_polytope.hpp) whose length is a fraction of the
//    largest λ̄_j; a step is taken when it lowers the screening sample's mean (same episodes, so
//    the comparison is paired); the fraction doubles on success and shrinks by 4 on failure.
//    Refinement stops after 3 failures in a row, at max_iterations, at the time or episode
//    budget, or when progress returns false.
//  - Honesty: on fresh episodes (acceptance_episodes, another seed) the starts are scored again
//    and raced: a start leaves when a paired test says it is worse than the leader (one-sided
//    2.5%) or equal within 0.5%; while two remain the sample doubles (up to 8x, as time allows).
//    The winner becomes the reference; the refined schedule replaces it only if a paired
//    one-sided t-test on the same episodes says it is better at level 5%, and the same test
//    says so again on those episodes and as many fresh ones together (the confirmation: J(P)
//    is heavy-tailed where a mode is unstable, and one sample can miss the refined schedule's
//    rare disasters; bench/README.md). The returned
//    schedule is then scored on yet another fresh sample (report_episodes): mean and 95%
//    half-width t_{0.975, E-1} s / √E.
//  - Time: the screening sample shrinks (to >= 200 episodes, measured on a pilot) so that it
//    takes <= 30% of max_seconds, the acceptance, confirmation and report samples (to >= 1000)
//    so that they take <= 25%, and refinement stops in time for them.
// Deterministic for a fixed seed and any thread count (per-episode results reduced in order)
// when the time budget does not bind (the sample sizes above depend on measured time).

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "sensornet/planning/planner.hpp"
#include "sensornet/core/scenario.hpp"

namespace sensornet {

// The realized cost J(P) over [t0, T] of a request (start time and covariance, delivery
// factors), sampled with common random numbers. Thread-safe for concurrent const calls.
class RealizedCostSampler {
 public:
  // request supplies start_time, start_covariance and delivery (validated by the caller).
  RealizedCostSampler(const Scenario& scenario, const PlanRequest& request, int threads);

  // J(P) of episodes first..first+count-1 of `seed` under the planned rates (N x M).
  [[nodiscard]] std::vector<double> episodeCosts(const Eigen::MatrixXd& rates,
                                                 std::uint64_t seed, long long first,
                                                 int count) const;

  struct Gradient {
    Eigen::MatrixXd gradient;  // N x M estimate of dE[J]/dλ (zero rows before firstInterval)
    double cost = 0.0;         // mean J(P) of the same episodes
  };
  // The add-one-point estimate over `count` episodes of `seed`. `sensors` is the number of
  // sensors of `in_service` sampled per interval and episode (0 or >= their number: all).
  [[nodiscard]] Gradient gradient(const Eigen::MatrixXd& rates, std::uint64_t seed, int count,
                                  const std::vector<int>& in_service, int sensors) const;

  [[nodiscard]] int firstInterval() const { return first_interval_; }
  [[nodiscard]] int threads() const { return threads_; }

 private:
  const Scenario& scenario_;
  double start_time_;
  Eigen::MatrixXd start_covariance_;
  Eigen::MatrixXd delivery_;  // N x M (ones when the request has none)
  int first_interval_;
  int threads_;
};

// The Monte Carlo planner (see above). Throws InputError for bad options (episode counts < 2,
// negative threads or gradient_sensors, max_episodes smaller than the fixed stages) and for
// whatever planSchedule refuses in the request.
[[nodiscard]] PlanResult planForRealizedCost(const Scenario& scenario,
                                             const PlanRequest& request);

}  // namespace sensornet
