// The first paper's Fig. 2 in small (bench/bracket_sweep_bench.cpp is the full one): the
// Info-NLP schedule of one instance of the paper's family, planned once at R_scale = 1, stays
// inside its Corollary 1 bracket J_info <= E J <= J_cov while every R_j is scaled by R_scale from
// 1e-2 to 1e2. Both ends of the bracket are recomputed here, independently of src/core (the
// exact Hamiltonian solution of eq. 11 and a brute-force RK4 of eq. 15,
// support/surrogate_references.hpp), and computeBracket must agree with them.
//
// Statistics: each Monte Carlo check asks the 99.9% interval of the mean (normal approximation,
// z = 3.29) to meet its end of the bracket, so a correct evaluator fails one check with
// probability at most 0.1%: two checks at each of 5 points, a family-wise false-alarm rate of
// at most 1%. The seeds are fixed, so the test is deterministic.

#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "sensornet/core/monte_carlo.hpp"
#include "sensornet/planning/planner.hpp"
#include "sensornet/core/scenario.hpp"
#include "sensornet/core/surrogate.hpp"
#include "support/surrogate_references.hpp"

namespace sensornet {
namespace {

constexpr double kZ999 = 3.2905;  // two-sided 99.9% quantile of the standard normal

Scenario sweepInstance(double r_scale) {
  RandomPlantSpec spec;  // the paper's family, made smaller so that the test is quick
  spec.state_dim = 4;
  spec.sensor_count = 12;
  spec.horizon_s = 2.0;
  spec.intervals = 10;
  spec.seed = 5;
  spec.noise_scale = r_scale;
  return generateRandomScenario(spec);
}

// W = 0 and W_T = I in the paper's family: J = tr P(T).
double terminalTrace(const std::vector<Eigen::MatrixXd>& boundaries) {
  return boundaries.back().trace();
}

TEST(Corollary1Sweep, TheInfoPlanStaysInsideItsBracketFromRScale1eMinus2To1e2) {
  const Scenario reference_instance = sweepInstance(1.0);
  PlanRequest request;
  request.surrogate = PlanSurrogate::Information;
  const PlanResult plan = planSchedule(reference_instance, request);
  ASSERT_EQ(plan.status, PlanStatus::Optimal) << "kkt " << plan.kkt_residual;
  // A plan that varies in time and across sensors, where ordering bugs would show.
  const Eigen::MatrixXd& rates = plan.schedule.rates();
  ASSERT_GT((rates.rowwise() - rates.colwise().mean()).cwiseAbs().maxCoeff(), 1e-3);
  ASSERT_GT((rates.colwise() - rates.rowwise().mean()).cwiseAbs().maxCoeff(), 1e-3);

  for (const double r_scale : {1e-2, 1e-1, 1.0, 1e1, 1e2}) {
    const std::string label = "R_scale " + std::to_string(r_scale);
    const Scenario s = sweepInstance(r_scale);
    const double info = terminalTrace(reference::informationFormExact(s, plan.schedule));
    const double cov = terminalTrace(reference::covarianceFormByRk4(s, plan.schedule, 4000).boundaries);
    ASSERT_LT(info, cov) << label;

    const CostBracket bracket = computeBracket(s, plan.schedule);
    EXPECT_NEAR(bracket.info, info, 1e-7 * info) << label;
    EXPECT_NEAR(bracket.cov, cov, 1e-7 * cov) << label;

    MonteCarloOptions options;
    options.runs = 4000;
    options.seed = 77;
    options.threads = 2;
    options.simulate_plant = false;
    const MonteCarloResult mc = evaluateSchedule(s, plan.schedule, options);
    const double half_width = kZ999 * mc.std_dev / std::sqrt(static_cast<double>(mc.runs));
    EXPECT_GE(mc.mean + half_width, info)
        << label << ": MC " << mc.mean << " +- " << half_width << ", bracket [" << info << ", "
        << cov << "]";
    EXPECT_LE(mc.mean - half_width, cov)
        << label << ": MC " << mc.mean << " +- " << half_width << ", bracket [" << info << ", "
        << cov << "]";
  }
}

}  // namespace
}  // namespace sensornet
