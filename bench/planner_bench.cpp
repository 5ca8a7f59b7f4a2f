// The first paper's Fig. 1 sweeps for the planner: T = 3, N = 30, budget 1'λ <= 5, W = 0,
// W_T = I, P0 = 100 I, Q = I, random instances of the paper's family (generateRandomScenario).
//   sensor sweep: n = 5, M = 30, 40, ..., 100;   state sweep: M = 30, n = 2, 4, ..., 20.
// For each point and each surrogate (info, cov): the median over the instances of the solve's
// wall time, iterations, one cost-and-gradient evaluation ("assembly") at the solution, the
// surrogate objective, and the Monte Carlo cost of the returned schedule (no plant, fixed seed),
// costs normalized by tr(P0) as in the paper. Then the Cov/Info ratios of the medians.
//
//   planner_bench [--sweep sensors|states|both] [--instances 10] [--mc-runs 200]
//                 [--method pqn|ipopt] [--tolerance 1e-6] [--substeps 2] [--n N] [--markdown]
//
// Scale mode (issue 14, "plan at scale"): time, iterations, status and KKT residual against n
// and M for the default optimizer and IPOPT in the same run, medians over the instances.
//   planner_bench --scale [--instances 3] [--max-seconds 60] [--only pqn|ipopt] [--n N] [--m M]
//                         [--each] [--markdown]
// --each adds one line per instance (J/trP0 to 10 digits, residual, iterations, time).

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <string>
#include <vector>

#include "sensornet/core/monte_carlo.hpp"
#include "sensornet/core/planner.hpp"
#include "sensornet/core/scenario.hpp"
#include "sensornet/core/surrogate_transcription.hpp"

namespace {

using sensornet::PlanSurrogate;

double median(std::vector<double> values) {
  if (values.empty()) return 0.0;
  std::sort(values.begin(), values.end());
  const std::size_t mid = values.size() / 2;
  return values.size() % 2 == 1 ? values[mid] : 0.5 * (values[mid - 1] + values[mid]);
}

double secondsOf(const std::function<void()>& work) {
  const auto start = std::chrono::steady_clock::now();
  work();
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

struct Options {
  std::string sweep = "both";
  int instances = 0;  // 0: 10 for the sweeps, 3 for --scale
  int mc_runs = 200;
  sensornet::PlanMethod method = sensornet::PlanMethod::ProjectedGradient;
  bool markdown = false;
  double tolerance = sensornet::PlanRequest{}.tolerance;
  int substeps = sensornet::PlanRequest{}.substeps;
  int only_n = 0;  // run just this state dimension of the state sweep (0: all)
  bool scale = false;
  double max_seconds = 60.0;  // per solve, scale mode
  std::string only_method;    // scale mode: "pqn" or "ipopt" alone (empty: both)
  int only_m = 0;             // scale mode: just the rows with this M (0: all)
  bool each = false;          // scale mode: also one line per instance (J to 10 digits)
};

struct Column {  // one surrogate at one sweep point, over the instances
  std::vector<double> seconds, iterations, assembly_ms, objective, mc_cost;
  int not_optimal = 0;
};

struct Point {
  int n = 0, m = 0;
  Column info, cov;
  std::vector<double> uniform_mc;
};

// Median time of one cost-and-gradient evaluation of the planner's transcription at `rates`.
double assemblyMilliseconds(sensornet::SurrogateForm form, const sensornet::Scenario& scenario,
                            const Eigen::MatrixXd& rates, int substeps) {
  sensornet::TranscriptionOptions transcription_options;
  transcription_options.substeps = substeps;
  sensornet::SurrogateTranscription transcription(form, scenario, transcription_options);
  std::vector<double> times;
  for (int r = 0; r < 15; ++r) {
    times.push_back(1e3 * secondsOf([&] { (void)transcription.costAndGradient(rates); }));
  }
  return median(times);
}

double monteCarloCost(const sensornet::Scenario& scenario, const sensornet::RateSchedule& schedule,
                      int runs, std::uint64_t seed) {
  sensornet::MonteCarloOptions options;
  options.runs = runs;
  options.seed = seed;
  options.threads = 1;
  options.simulate_plant = false;
  return sensornet::evaluateSchedule(scenario, schedule, options).mean;
}

void solveInto(Column& column, PlanSurrogate surrogate, const sensornet::Scenario& scenario,
               const Options& options, double normalizer, std::uint64_t seed) {
  sensornet::PlanRequest request;
  request.surrogate = surrogate;
  request.method = options.method;
  request.max_iterations = 3000;
  request.tolerance = options.tolerance;
  request.substeps = options.substeps;
  const sensornet::PlanResult plan = sensornet::planSchedule(scenario, request);
  if (plan.status != "optimal" && plan.status != "acceptable") ++column.not_optimal;
  column.seconds.push_back(plan.solve_seconds);
  column.iterations.push_back(plan.iterations);
  const auto form = surrogate == PlanSurrogate::Covariance ? sensornet::SurrogateForm::Covariance
                                                           : sensornet::SurrogateForm::Information;
  column.assembly_ms.push_back(assemblyMilliseconds(form, scenario, plan.schedule.rates(), options.substeps));
  column.objective.push_back(plan.objective / normalizer);
  column.mc_cost.push_back(monteCarloCost(scenario, plan.schedule, options.mc_runs, seed) /
                           normalizer);
}

Point runPoint(int n, int m, const Options& options) {
  Point point{n, m, {}, {}, {}};
  for (int i = 0; i < options.instances; ++i) {
    sensornet::RandomPlantSpec spec;
    spec.state_dim = n;
    spec.sensor_count = m;
    spec.seed = 1000u * static_cast<std::uint64_t>(n) + 10u * static_cast<std::uint64_t>(m) +
                static_cast<std::uint64_t>(i);
    const sensornet::Scenario scenario = sensornet::generateRandomScenario(spec);
    const double normalizer = scenario.plant.P0.trace();
    const std::uint64_t mc_seed = spec.seed + 7;
    solveInto(point.info, PlanSurrogate::Information, scenario, options, normalizer, mc_seed);
    solveInto(point.cov, PlanSurrogate::Covariance, scenario, options, normalizer, mc_seed);
    point.uniform_mc.push_back(
        monteCarloCost(scenario, sensornet::uniformSchedule(scenario), options.mc_runs, mc_seed) /
        normalizer);
  }
  return point;
}

void printHeader(bool markdown) {
  if (markdown) {
    std::printf(
        "| n | M | info s | info it | info eval ms | info J/trP0 | info MC/trP0 | cov s | cov it "
        "| cov eval ms | cov J/trP0 | cov MC/trP0 | uniform MC/trP0 | time cov/info | it "
        "cov/info | eval cov/info |\n");
    std::printf("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
  } else {
    std::printf("%3s %4s | %8s %6s %8s %8s %8s | %8s %6s %8s %8s %8s | %8s | %6s %6s %6s\n", "n",
                "M", "info s", "it", "eval ms", "J/trP0", "MC", "cov s", "it", "eval ms",
                "J/trP0", "MC", "unif MC", "t c/i", "it c/i", "ev c/i");
  }
}

void printPoint(const Point& p, bool markdown) {
  const double ti = median(p.info.seconds), tc = median(p.cov.seconds);
  const double ii = median(p.info.iterations), ic = median(p.cov.iterations);
  const double ei = median(p.info.assembly_ms), ec = median(p.cov.assembly_ms);
  const char* format =
      markdown ? "| %d | %d | %.3f | %.0f | %.3f | %.4f | %.4f | %.3f | %.0f | %.3f | %.4f | %.4f "
                 "| %.4f | %.1fx | %.1fx | %.1fx |\n"
               : "%3d %4d | %8.3f %6.0f %8.3f %8.4f %8.4f | %8.3f %6.0f %8.3f %8.4f %8.4f | "
                 "%8.4f | %5.1fx %5.1fx %5.1fx\n";
  std::printf(format, p.n, p.m, ti, ii, ei, median(p.info.objective), median(p.info.mc_cost), tc,
              ic, ec, median(p.cov.objective), median(p.cov.mc_cost), median(p.uniform_mc),
              tc / ti, ic / ii, ec / ei);
  if (p.info.not_optimal + p.cov.not_optimal > 0) {
    std::printf("%s  (not optimal within 3000 iterations: info %d, cov %d of %zu)\n",
                markdown ? "" : "   ", p.info.not_optimal, p.cov.not_optimal,
                p.info.seconds.size());
  }
  std::fflush(stdout);
}


// ---- Scale mode -------------------------------------------------------------------------------

struct ScaleCase {
  PlanSurrogate surrogate;
  int n, m;
};

struct ScaleColumn {  // one method at one case, over the instances
  std::vector<double> seconds, iterations, evaluations, eval_ms, kkt, objective;
  int optimal = 0;
};

ScaleColumn& scaleSolve(ScaleColumn& column, const sensornet::Scenario& scenario,
                        PlanSurrogate surrogate, sensornet::PlanMethod method,
                        const Options& options) {
  sensornet::PlanRequest request;
  request.surrogate = surrogate;
  request.method = method;
  request.max_iterations = 3000;
  request.max_seconds = options.max_seconds;
  request.tolerance = options.tolerance;
  request.substeps = options.substeps;
  const sensornet::PlanResult plan = sensornet::planSchedule(scenario, request);
  // "acceptable" is IPOPT's looser tolerance: counted as converged only when the residual of
  // the returned schedule meets the tolerance.
  if ((plan.status == "optimal" || plan.status == "acceptable") &&
      plan.kkt_residual <= options.tolerance) {
    ++column.optimal;
  }
  column.seconds.push_back(plan.solve_seconds);
  column.iterations.push_back(plan.iterations);
  column.evaluations.push_back(plan.evaluations);
  column.kkt.push_back(plan.kkt_residual);
  column.objective.push_back(plan.objective / scenario.plant.P0.trace());
  return column;
}

void printScaleHeader(bool markdown) {
  if (markdown) {
    std::printf(
        "| form | n | M | method | s | it | evals | eval ms | optimal | kkt (max) | J/trP0 | "
        "time vs ipopt |\n|---|---|---|---|---|---|---|---|---|---|---|---|\n");
  } else {
    std::printf("%-4s %3s %5s %-6s | %8s %6s %6s %8s %8s %9s %9s | %8s\n", "form", "n", "M",
                "method", "s", "it", "evals", "eval ms", "optimal", "kkt max", "J/trP0",
                "t/ipopt");
  }
}

void printScaleRow(const ScaleCase& c, const char* method, const ScaleColumn& col,
                   double ipopt_seconds, bool markdown) {
  const double kkt_max = *std::max_element(col.kkt.begin(), col.kkt.end());
  const double t = median(col.seconds);
  char ratio[32] = "-";
  if (ipopt_seconds > 0.0) std::snprintf(ratio, sizeof ratio, "%.2fx", t / ipopt_seconds);
  const char* form = c.surrogate == PlanSurrogate::Covariance ? "cov" : "info";
  if (markdown) {
    std::printf("| %s | %d | %d | %s | %.3f | %.0f | %.0f | %.2f | %d/%zu | %.1e | %.5f | %s |\n",
                form, c.n, c.m, method, t, median(col.iterations), median(col.evaluations),
                median(col.eval_ms), col.optimal, col.seconds.size(), kkt_max,
                median(col.objective), ratio);
  } else {
    std::printf("%-4s %3d %5d %-6s | %8.3f %6.0f %6.0f %8.2f %6d/%zu %9.1e %9.5f | %8s\n", form,
                c.n, c.m, method, t, median(col.iterations), median(col.evaluations),
                median(col.eval_ms), col.optimal, col.seconds.size(), kkt_max,
                median(col.objective), ratio);
  }
  std::fflush(stdout);
}

// One line per instance, to compare optima between versions of the planner.
void printInstances(const char* method, const ScaleColumn& col) {
  for (std::size_t i = 0; i < col.seconds.size(); ++i) {
    std::printf("    %s instance %zu: J/trP0 %.10g, kkt %.2e, it %.0f, evals %.0f, %.3f s\n", method,
                i, col.objective[i], col.kkt[i], col.iterations[i], col.evaluations[i],
                col.seconds[i]);
  }
}

void runScale(const Options& options) {
  const std::vector<ScaleCase> cases = {
      {PlanSurrogate::Information, 20, 30},   {PlanSurrogate::Information, 20, 100},
      {PlanSurrogate::Information, 20, 300},  {PlanSurrogate::Information, 20, 1000},
      {PlanSurrogate::Information, 50, 1000}, {PlanSurrogate::Covariance, 20, 30},
      {PlanSurrogate::Covariance, 20, 100}};
  std::printf("planner_bench --scale: T = 3, N = 30, budget 1'λ <= 5, %d instances per row, "
              "medians; limit %.0f s and 3000 iterations per solve\n",
              options.instances, options.max_seconds);
  printScaleHeader(options.markdown);
  for (const ScaleCase& c : cases) {
    if ((options.only_n != 0 && c.n != options.only_n) ||
        (options.only_m != 0 && c.m != options.only_m)) {
      continue;
    }
    ScaleColumn pqn, ipopt;
    for (int i = 0; i < options.instances; ++i) {
      sensornet::RandomPlantSpec spec;
      spec.state_dim = c.n;
      spec.sensor_count = c.m;
      spec.seed = 1000u * static_cast<std::uint64_t>(c.n) + 10u * static_cast<std::uint64_t>(c.m) +
                  static_cast<std::uint64_t>(i);
      const sensornet::Scenario scenario = sensornet::generateRandomScenario(spec);
      const auto form = sensornet::formOf(c.surrogate);
      const double eval_ms = assemblyMilliseconds(form, scenario,
                                                  sensornet::uniformSchedule(scenario).rates(),
                                                  options.substeps);
      if (options.only_method != "ipopt") {
        scaleSolve(pqn, scenario, c.surrogate, sensornet::PlanMethod::ProjectedGradient, options)
            .eval_ms.push_back(eval_ms);
      }
      if (options.only_method != "pqn") {
        scaleSolve(ipopt, scenario, c.surrogate, sensornet::PlanMethod::Ipopt, options)
            .eval_ms.push_back(eval_ms);
      }
    }
    const double ipopt_seconds = ipopt.seconds.empty() ? 0.0 : median(ipopt.seconds);
    if (!pqn.seconds.empty()) printScaleRow(c, "pqn", pqn, ipopt_seconds, options.markdown);
    if (!ipopt.seconds.empty()) printScaleRow(c, "ipopt", ipopt, 0.0, options.markdown);
    if (options.each) {
      printInstances("pqn", pqn);
      printInstances("ipopt", ipopt);
    }
  }
}

}  // namespace

int main(int argc, char** argv) {
  Options options;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    const auto value = [&]() -> std::string {
      if (i + 1 >= argc) {
        std::fprintf(stderr, "planner_bench: %s needs a value\n", arg.c_str());
        std::exit(2);
      }
      return argv[++i];
    };
    if (arg == "--sweep") {
      options.sweep = value();
    } else if (arg == "--instances") {
      options.instances = std::max(1, std::atoi(value().c_str()));
    } else if (arg == "--mc-runs") {
      options.mc_runs = std::max(2, std::atoi(value().c_str()));
    } else if (arg == "--method") {
      options.method = value() == "ipopt" ? sensornet::PlanMethod::Ipopt
                                          : sensornet::PlanMethod::ProjectedGradient;
    } else if (arg == "--tolerance") {
      options.tolerance = std::atof(value().c_str());
    } else if (arg == "--substeps") {
      options.substeps = std::max(1, std::atoi(value().c_str()));
    } else if (arg == "--n") {
      options.only_n = std::atoi(value().c_str());
    } else if (arg == "--markdown") {
      options.markdown = true;
    } else if (arg == "--scale") {
      options.scale = true;
    } else if (arg == "--max-seconds") {
      options.max_seconds = std::atof(value().c_str());
    } else if (arg == "--m") {
      options.only_m = std::atoi(value().c_str());
    } else if (arg == "--only") {
      options.only_method = value();
    } else if (arg == "--each") {
      options.each = true;
    } else {
      std::fprintf(stderr,
                   "usage: planner_bench [--sweep sensors|states|both] [--instances K] "
                   "[--mc-runs R] [--method pqn|ipopt] [--tolerance T] [--substeps S] [--n N] [--markdown]\n"
                   "       planner_bench --scale [--instances K] [--max-seconds S] "
                   "[--only pqn|ipopt] [--n N] [--m M] [--each] [--markdown]\n");
      return arg == "--help" ? 0 : 2;
    }
  }
  if (options.sweep != "sensors" && options.sweep != "states" && options.sweep != "both") {
    std::fprintf(stderr, "planner_bench: --sweep expects sensors, states or both\n");
    return 2;
  }
  if (options.scale) {
    if (options.instances == 0) options.instances = 3;
    if (!(options.max_seconds > 0.0) ||
        (!options.only_method.empty() && options.only_method != "pqn" &&
         options.only_method != "ipopt")) {
      std::fprintf(stderr, "planner_bench: --max-seconds expects S > 0, --only pqn or ipopt\n");
      return 2;
    }
    runScale(options);
    return 0;
  }
  if (options.instances == 0) options.instances = 10;
  std::printf("planner_bench: %d instances per point, Monte Carlo %d episodes, medians\n",
              options.instances, options.mc_runs);
  if (options.sweep != "states") {
    std::printf("\nsensor sweep (n = 5)\n");
    printHeader(options.markdown);
    for (int m = 30; m <= 100; m += 10) printPoint(runPoint(5, m, options), options.markdown);
  }
  if (options.sweep != "sensors") {
    std::printf("\nstate sweep (M = 30)\n");
    printHeader(options.markdown);
    for (int n = 2; n <= 20; n += 2) {
      if (options.only_n == 0 || options.only_n == n) printPoint(runPoint(n, 30, options), options.markdown);
    }
  }
  return 0;
}
