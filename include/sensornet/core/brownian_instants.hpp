#pragma once
// Optimal deterministic measurement instants for a scalar Brownian motion observed n times over
// a finite horizon (the second paper, "Optimal Measurement Times for a Small Number of Measures
// of a Brownian Motion over a Finite Period"). θ has variance rate σ², the prior variance at
// t = 0 is v0, and n measurements, taken in a FIXED order with noise variances v_1..v_n, are
// placed at 0 <= t_1 <= ... <= t_n <= T so as to minimise the mean estimation variance
// J = ∫_0^T v(t) dt (eq. 12). Between measurements v grows with slope σ²; a measurement of
// noise variance v_k maps the prior variance Γ⁻ to v_k // Γ⁻ = v_k Γ⁻ / (v_k + Γ⁻) (eqs. 7-11).
//
//   BrownianProblem problem;
//   problem.sigma2 = 1.0;
//   problem.horizon_s = 71.0 / 18.0;
//   problem.v0 = 1.0;
//   problem.variances = {1.0, 1.0};
//   BrownianSchedule best = optimalInstants(problem);  // (1.04016, 2.40925), regime 3
//   double gain = 1.0 - best.cost / best.regular_cost;
//
// How each case is solved, and what is proven:
//
// n = 1: the closed form eq. (15) (Proposition 1, proven in the paper), evaluated without the
//   cancellation of eq. (18) near the regime boundary.
//
// n = 2: the paper's three regimes. T <= T_{2,crit} (eq. 29) gives (0, 0) (Theorem 5);
//   T <= T_{1,crit} (eqs. 34-40, largest real root of the cubic 36) gives (0, t_opt^(1)(σ², T,
//   v0 // v1, v2)) (Theorem 6); otherwise the coordinate descent of the Appendix (Fig. 12):
//   t_2 given t_1 by eq. (28) in closed form, t_1 given t_2 by a safeguarded Newton search for
//   the zero of ∂J/∂t_1 on [0, t_2] (exact first and second derivatives), warm-started from the
//   previous sweep; it works on the factor of ∂J/∂t_1 that carries its sign, since the other
//   factor, P_1/(P_1 + v_1), makes t_1 = 0 look stationary when v0 = 0. The paper proves the
//   minimiser and the coordinatewise local minimum are unique (Theorems 8, 9), so the descent can
//   only converge to the global optimum. That the t_1 step finds the minimum of J(·, t_2) rests on
//   the paper's conjecture that this function is quasi-convex (Section IV-F), which our tests
//   confirm against dense grids.
//
// n >= 3 (left open by the paper): optimalInstantsBySearch, in two steps.
//   1. Starts from a dynamic programme. After k measurements the state is (time left τ,
//      posterior variance g) and the optimal cost-to-go obeys the Bellman recursion
//        W_k(τ, g) = min_{0 <= s <= τ} [g s + σ² s²/2 + W_{k+1}(τ - s, v_{k+1} // (g + σ² s))],
//      W_n(τ, g) = g τ + σ² τ²/2, and W_{n-1} is the one-measure optimum in closed form (eq. 28
//      generalised: given the past, placing the last instant is a one-measure problem, eq. 15).
//      W_1..W_{n-2} are tabulated on 64 time steps x 33 values of g (linear in g between
//      them). The grid path out of each of the 3 lowest local minima of the first-instant
//      profile is a start; so is the regular timetable.
//   2. Each start is refined by projected Newton (Bertsekas) on the simplex of gaps
//      Δ_1..Δ_{n+1} >= 0, Σ Δ_k = T, charted at each iteration by all gaps but the largest, with
//      the exact gradient (the adjoint recursion of timetableCostGradient) and the exact Hessian
//      (forward-mode dual numbers through that recursion), and with a negative-curvature step
//      out of saddle points: notably, when v0 = 0, instants at t = 0 are wasted and ∂J/∂t
//      vanishes there although moving them forward lowers J. The lowest refined cost wins.
//   Proven: the result satisfies the first-order (KKT) conditions to rounding, admits none of
//   the feasible negative-curvature directions checked, and costs no more than any start (so no
//   more than the regular timetable or the DP's grid schedules).
//   Empirical, not proven: that it is the global minimum. For 1,800 random problems (n = 3..8;
//   σ² T and the variances log-uniform over up to six decades, v0 over three, a tenth with
//   v0 = 0), refining from 30 random starts each never found a second local minimum or a lower
//   cost. The tests compare n = 3 with an independent brute-force search and n = 1, 2 with the
//   paper's results. So the minimiser looks unique for every n, as the paper proves for
//   n <= 2; if it is, every converged start is global and the DP only saves Newton iterations,
//   and if it is not, the DP still picks the basin that is best at grid resolution T/64.
//   Cost: about 1 ms for n = 3 to 2.5 ms for n = 8 (median, bench/brownian_bench.cpp).

#include <string>
#include <vector>

namespace sensornet {

struct BrownianProblem {
  double sigma2 = 1.0;            // σ² > 0, variance rate of θ
  double horizon_s = 1.0;         // T > 0
  double v0 = 1.0;                // prior variance of θ(0), >= 0
  std::vector<double> variances;  // v_1..v_n > 0 in measurement order, n >= 1
};

// Throws InputError(source, field, ...) naming sigma2, horizon, v0, variances or variances[k].
void validateBrownianProblem(const BrownianProblem& problem, const std::string& source);

// a // b = ab / (a + b) (Section II-B): the variance after fusing two independent estimates.
// Requires a, b >= 0 and a + b > 0.
[[nodiscard]] double fusedVariance(double a, double b);

// The cost eq. (12), ∫_0^T v(t) dt, of a timetable. `instants` holds t_1..t_n, sorted, in
// [0, T]; throws InputError ("instants" or "instants[k]") otherwise.
[[nodiscard]] double timetableCost(const BrownianProblem& problem,
                                   const std::vector<double>& instants);

// The exact gradient (∂J/∂t_1, ..., ∂J/∂t_n) of eq. (12), by one backward (adjoint) sweep.
// With Δ_k = t_k - t_{k-1} (t_0 = 0, t_{n+1} = T), P_k = Γ_{k-1} + σ² Δ_k the prior and
// Γ_k = v_k // P_k the posterior variance at t_k (eqs. 7, 11), and r_k = (v_k / (v_k + P_k))²
// = dΓ_k/dP_k:
//   λ_n = Δ_{n+1},  λ_k = Δ_{k+1} + r_{k+1} λ_{k+1}          (λ_k = ∂J/∂Γ_k)
//   G_k = Γ_{k-1} + σ² Δ_k + σ² r_k λ_k (k <= n),  G_{n+1} = Γ_n + σ² Δ_{n+1}   (G_k = ∂J/∂Δ_k)
//   ∂J/∂t_k = G_k - G_{k+1}.
// For n = 1 this is eq. (16). Same input checks as timetableCost.
[[nodiscard]] std::vector<double> timetableCostGradient(const BrownianProblem& problem,
                                                        const std::vector<double>& instants);

// k T / (n + 1), k = 1..n: the regular timetable the paper compares against.
[[nodiscard]] std::vector<double> regularInstants(double horizon_s, int count);

// --- One measurement (Section III) --------------------------------------------------------
// All four throw InputError unless σ² > 0, T > 0 (T >= 0 for optimalSingleInstant), v0 >= 0
// and v1 > 0.

// t_opt^(1), eq. (15).
[[nodiscard]] double optimalSingleInstant(double sigma2, double horizon_s, double v0, double v1);
// T_crit^(1), eq. (17): t_opt^(1) = 0 iff T <= T_crit^(1).
[[nodiscard]] double criticalDurationSingle(double sigma2, double v0, double v1);
// The lower bound sqrt(σ² v_{0,1} T³) of Theorem 3, eq. (25), on J over every t_1.
[[nodiscard]] double lowerBoundSingle(double sigma2, double horizon_s, double v0, double v1);

// --- Two measurements (Section IV) --------------------------------------------------------

struct TwoMeasureCriticalDurations {
  double regime1_end = 0.0;  // T^(2)_{2,crit}, eq. (29): (0, 0) is optimal iff T <= this
  double regime2_end = 0.0;  // T^(2)_{1,crit}, eqs. (34)-(40): t_1,opt = 0 iff T <= this
};

// Throws InputError unless σ² > 0, v0 >= 0, v1 > 0, v2 > 0.
[[nodiscard]] TwoMeasureCriticalDurations criticalDurationsTwo(double sigma2, double v0, double v1,
                                                               double v2);

// t_{2,1,crit}: (the largest real root of the cubic eq. (36), coefficients eqs. (37)-(40)) / σ².
// At T = T^(2)_{1,crit} the optimal timetable is (0, t_{2,1,crit}); in regime 3 it is the gap
// t_2 - t_1 of eq. (44) with v0 replaced by v0 + σ² t_1. Same checks as criticalDurationsTwo.
[[nodiscard]] double criticalGapTwo(double sigma2, double v0, double v1, double v2);

// --- Any number of measurements -----------------------------------------------------------

struct BrownianSchedule {
  std::vector<double> instants;  // t_1..t_n, sorted, in [0, T]
  double cost = 0.0;             // eq. (12) at instants
  double regular_cost = 0.0;     // eq. (12) at kT/(n+1), k = 1..n
  int regime = 0;                // n = 1: 1 or 2; n = 2: 1, 2 or 3 as the paper numbers them;
                                 // 0 for n >= 3
  int iterations = 0;            // n = 2: coordinate-descent sweeps (0 when the critical
                                 // durations decide the regime); n >= 3: Newton iterations of
                                 // the winning local refinement; n = 1: 0
};

// The optimal timetable: closed forms for n = 1, the three regimes and coordinate descent for
// n = 2, optimalInstantsBySearch for n >= 3. Throws InputError on a bad problem.
[[nodiscard]] BrownianSchedule optimalInstants(const BrownianProblem& problem);

// The general method used for n >= 3 (described at the top of this header). It works for any
// n >= 1, which lets the tests compare it with the closed forms at n = 1, 2. regime = 0.
[[nodiscard]] BrownianSchedule optimalInstantsBySearch(const BrownianProblem& problem);

// Local refinement from a start timetable (step 2 above). Returns a point that satisfies the
// first-order (KKT) conditions to rounding, with a cost no larger than the start's. Throws
// InputError like timetableCost. regime = 0; iterations = Newton iterations.
[[nodiscard]] BrownianSchedule refineInstants(const BrownianProblem& problem,
                                              const std::vector<double>& start);

}  // namespace sensornet
