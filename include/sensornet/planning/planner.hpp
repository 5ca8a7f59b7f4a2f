#pragma once
// The planner: the rate schedule λ(t), piecewise constant on the scenario's N intervals, that
// minimizes a surrogate cost (eq. 12 of the first paper) under C λ_k <= b, λ_k >= 0 (eq. 8) and
// the scenario's energy budgets Σ_k h λ_kj <= E_j (when it has them), for
// the information-form surrogate (eq. 11, the paper's Info-NLP) or the covariance-form surrogate
// (eq. 15, Cov-NLP), or the uniform baseline, or (PlanSurrogate::MonteCarlo, mc_planner.hpp)
// the expected realized cost E[J(P)] itself, by a stochastic method. It also plans the rest of a running episode, from
// the fused covariance at some time, with sensors taken out of service, warm-started from the
// schedule in force (the live re-planning of the coordinator).
//
//   PlanRequest request;
//   request.surrogate = PlanSurrogate::Information;
//   const PlanResult plan = planSchedule(scenario, request);
//   // plan.schedule: N x M rates; plan.bracket.info <= E[J] <= plan.bracket.cov
//
//   // Re-plan at t = 1.2 s from the fused covariance, without sensor 3:
//   request.start_time = 1.2;
//   request.start_covariance = fused_covariance;
//   request.excluded_sensors = {3};
//   request.warm_start = plan.schedule;
//   const PlanResult replanned = planSchedule(scenario, request);
//
// Method (bench/README.md has the measurements behind the choices): single shooting over the
// rates only; the surrogate is integrated by RK4 steps per interval with the exact discrete
// adjoint gradient (surrogate_transcription.hpp), as many steps as make the transcription's cost
// agree with the accurate rollout's within 1e-2 relative at the start point and at the solution
// (doubled from PlanRequest::substeps, at most 256; PlanResult::substeps says how many). The
// default optimizer is a projected quasi-Newton method (L-BFGS on the binding face, spectral
// projected gradient as the fallback) whose iterates are all feasible; IPOPT with a
// limited-memory Hessian is the alternative (PlanMethod::Ipopt). Energy budgets couple the
// intervals: the projection then runs over whole schedules (RatePolytope::projectSchedule),
// while the quasi-Newton steps' face stays per interval, so where budgets bind the solve
// proceeds mostly by projected gradient steps and may end at max_iterations a little short of
// the tolerance (docs/guide/math-and-planners.md). The returned schedule is projected onto the
// admissible set (rate_polytope.hpp), so it is feasible to rounding, and then scored with the
// ACCURATE rollouts of surrogate.hpp (relative tolerance 1e-10); `objective` and `bracket` are
// those numbers, not the planner's internal RK4 cost (`discretized_objective`, which differs by
// O(h^4)).

#include <Eigen/Core>
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "sensornet/core/plan_status.hpp"
#include "sensornet/core/rate_schedule.hpp"
#include "sensornet/core/scenario.hpp"
#include "sensornet/core/surrogate.hpp"
#include "sensornet/core/surrogate_kind.hpp"
#include "sensornet/core/words.hpp"

namespace sensornet {

// The surrogate form a plan of this kind rolls out (uniform and mc plans use the information
// form: their bracket is still [info, cov] of the schedule).
[[nodiscard]] SurrogateForm formOf(PlanSurrogate surrogate);

// The optimizer: a spectral projected gradient method of our own (the default, see
// bench/README.md for why), or IPOPT with a limited-memory Hessian.
enum class PlanMethod { ProjectedGradient, Ipopt };

template <>
struct Words<PlanMethod> {
  static constexpr std::array<WordOf<PlanMethod>, 2> kTable{
      {{PlanMethod::ProjectedGradient, "pqn"}, {PlanMethod::Ipopt, "ipopt"}}};
};

struct PlanProgress {
  int iteration = 0;
  double objective = 0.0;       // the discretized surrogate cost at the current iterate
  double elapsed_seconds = 0.0;
};

// Options of the Monte Carlo planner (PlanSurrogate::MonteCarlo; mc_planner.hpp describes the
// method). Episode counts are per stage; the plan stops refining at max_seconds (wall time of
// the whole plan, warm starts included) or when the next stage would exceed max_episodes.
struct RealizedCostOptions {
  std::uint64_t seed = 1;
  int threads = 0;                   // 0 = std::thread::hardware_concurrency()
  int screening_episodes = 2000;     // the common-random-number sample that compares candidates
  int gradient_episodes = 64;        // episodes per gradient estimate
  int gradient_sensors = 8;          // sensors sampled per interval and episode (0 = all)
  int acceptance_episodes = 10000;   // fresh paired tests: refined schedule vs its warm start
  int report_episodes = 10000;       // fresh episodes that score the returned schedule
  long long max_episodes = 2000000;  // all stages together
};

struct PlanRequest {
  PlanSurrogate surrogate = PlanSurrogate::Information;
  // Plan over [start_time, T] from P(start_time) = start_covariance (P0 when absent; required
  // when start_time > 0). The interval k0 containing start_time is re-planned as a whole, and the
  // cost counts only its part after start_time (a start time within 1e-12 T of the next
  // boundary starts the next interval). Intervals before k0 keep warm_start's rates (or 0).
  double start_time = 0.0;
  std::optional<Eigen::MatrixXd> start_covariance;
  std::vector<int> excluded_sensors;  // forced to rate 0 in the planned intervals
  // Network-aware planning: the surrogate sees the delivered rates delivery(k, j) * λ_kj (N x M,
  // entries in [0, 1]; deliveryFactors() in network.hpp) while C λ <= b binds the planned ones.
  // Absent: every factor is 1.
  std::optional<Eigen::MatrixXd> delivery;
  std::optional<RateSchedule> warm_start;  // initial guess (projected onto the admissible set)
  // Start from the uniform rates of the sensors in service even with a warm start, whose rows
  // before start_time still stay and still count as spent against the energy budgets.
  bool cold_start = false;
  // Expected measurements each sensor has sent before start_time in this episode, against its
  // energy budget (Scenario::constraints.energy). Absent: what warm_start's rates (or 0) sent
  // before it. A re-plan of a running episode passes what the versions in force sent, which
  // warm_start's rows alone do not say when an earlier version took over inside an interval.
  std::optional<Eigen::VectorXd> energy_spent;
  // Stop when kkt_residual (below) <= tolerance; for IPOPT, its scaled KKT tolerance.
  double tolerance = 1e-6;
  int max_iterations = 500;
  double max_seconds = 120.0;  // wall time of the solve (mc: of the whole plan)
  // RK4 steps per interval of the transcription to start from (2 suffice on the paper's
  // family); the planner doubles them until its cost agrees with the accurate rollout's within
  // 1e-2 relative at the start point and at the solution, up to 256 (bench/README.md).
  int substeps = 2;
  PlanMethod method = PlanMethod::ProjectedGradient;
  // Optional; called after every solver iteration from the calling thread. Returning false
  // stops the solve (PlanStatus::Stopped). An exception it throws propagates.
  std::function<bool(const PlanProgress&)> progress;
  RealizedCostOptions realized;  // used by PlanSurrogate::MonteCarlo only
};

struct PlanResult {
  // Full N x M: intervals before start_time keep warm_start's rates (or 0).
  RateSchedule schedule;
  // The planned surrogate's accurate cost of `schedule` over [start_time, T] (for Uniform, the
  // information-form cost, the lower end of the bracket); with `delivery`, of the delivered
  // rates delivery ⊙ λ that it minimized (the bracket below stays that of `schedule`).
  // For MonteCarlo: the Monte Carlo mean of J(P) over fresh episodes (not those that chose the
  // schedule), with its 95% half-width below.
  double objective = 0.0;
  double objective_half_width = 0.0;  // MonteCarlo only (0 otherwise)
  long long episodes = 0;             // MonteCarlo only: episodes simulated in all stages
  CostBracket bracket;                  // info and cov of `schedule` over [start_time, T]
  double discretized_objective = 0.0;   // the same cost under the planner's RK4 transcription
  // RK4 steps per interval of that transcription (PlanRequest::substeps, doubled as needed). If
  // it is 256, discretized_objective may still differ from objective by more than 1e-2.
  // MonteCarlo: 0 (no transcription is solved).
  int substeps = 0;
  int iterations = 0;
  int evaluations = 0;  // cost-and-gradient evaluations of the transcription
  double solve_seconds = 0.0;
  // How the solve ended (plan_status.hpp; solved() says whether the plan is what its method
  // promises). Failed (IPOPT, or no finite cost at the start point) still returns the best point
  // found, projected and scored, and `failure` says why; statusText(status, failure) is the text.
  // MonteCarlo: Improved (the refined schedule passed the paired test against its warm start,
  // and again on fresh episodes) or KeptStart (it did not, or no refinement was found: the warm
  // start is returned).
  PlanStatus status = PlanStatus::NotOptimized;
  std::string failure{};  // Failed only: the solver's reason
  // First-order optimality at the returned point, scale-free: with rates measured in units of
  // the largest λ̄_j and the cost in units of the cost itself, the largest change of a planned
  // rate under a unit projected-gradient step, max |x - Π(x - ∇f(x))| (0 exactly at a KKT point
  // of the discretized problem). NaN for "not_optimized".
  double kkt_residual = 0.0;
};

// Throws InputError for a request that does not fit the scenario (excluded index out of range,
// warm start of the wrong shape or horizon, start time or covariance out of range, non-positive
// tolerance, max_iterations or max_seconds). The scenario is assumed validated.
[[nodiscard]] PlanResult planSchedule(const Scenario& scenario, const PlanRequest& request);

// The first-order measure of PlanResult::kkt_residual for any schedule, computed with the
// discretized gradient of `form` at request.substeps RK4 steps per interval, as given (pass a
// plan's PlanResult::substeps to reproduce its kkt_residual). Exposed for tests and diagnostics.
[[nodiscard]] double kktResidual(const Scenario& scenario, const RateSchedule& schedule,
                                 SurrogateForm form, const PlanRequest& request);

[[nodiscard]] std::string_view describe(PlanSurrogate surrogate);  // "info", "cov", "uniform", "mc"

}  // namespace sensornet
