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
//
// Convergence mode (issue 29, "every plan converges, or says what it has"): every info and cov
// plan of the Fig. 1 instances (sensor sweep and state sweep, --instances per point, default 1)
// and of the scenario files given (run from the repository root: scenarios/*.yaml by default),
// from the default start and from --random-starts random feasible starts, with the planner's
// defaults (500 iterations, tolerance 1e-6); for the scenario files also without sensor 1,
// warm-started from their full info and cov plans (the live re-planning after a sensor fault).
// A plan passes when kkt_residual <= tolerance, or when it ends with another status and its
// accurate surrogate cost is no worse than its start's.
//   planner_bench --convergence [--instances 1] [--random-starts 2] [--max-iterations 500]
//                               [--scenarios a.yaml,b.yaml] [--each] [--markdown]

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <functional>
#include <map>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "sensornet/core/monte_carlo.hpp"
#include "sensornet/planning/planner.hpp"
#include "sensornet/core/random.hpp"
#include "sensornet/planning/rate_polytope.hpp"
#include "sensornet/core/scenario.hpp"
#include "sensornet/core/surrogate.hpp"
#include "sensornet/planning/surrogate_transcription.hpp"
#include "sensornet/io/scenario_file.hpp"

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
  bool each = false;          // scale and convergence modes: also one line per plan
  bool convergence = false;
  int random_starts = 2;      // convergence mode
  int max_iterations = sensornet::PlanRequest{}.max_iterations;  // convergence mode
  std::vector<std::string> scenario_files;  // convergence mode (empty: scenarios/*.yaml)
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
  if (plan.status != sensornet::PlanStatus::Optimal &&
      plan.status != sensornet::PlanStatus::Acceptable) {
    ++column.not_optimal;
  }
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
  if ((plan.status == sensornet::PlanStatus::Optimal ||
       plan.status == sensornet::PlanStatus::Acceptable) &&
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

// ---- Convergence mode -------------------------------------------------------------------------

// One planning problem of the sweep: a scenario, the sensors taken out, the starts to try.
struct ConvergenceCase {
  std::string group;  // the table row it counts in
  std::string name;
  sensornet::Scenario scenario;
  std::vector<int> excluded;
  std::vector<std::pair<std::string, std::optional<sensornet::RateSchedule>>> starts;
};

struct ConvergenceRow {  // one group and form, over its plans
  int plans = 0, converged = 0, stated_no_worse = 0, failed = 0;
  std::map<std::string, int> statuses;
  std::vector<double> iterations, seconds;
  double kkt_max = 0.0;
  int substeps_max = 0;
};

// Random feasible rates: each planned row uniform in [0, λ̄_j] per sensor, projected onto the
// admissible rates (so that some rows are tight, some not, some rates zero).
sensornet::RateSchedule randomFeasibleStart(const sensornet::Scenario& scenario,
                                            const std::vector<int>& excluded, std::uint64_t seed) {
  const sensornet::RatePolytope polytope(scenario.constraints, excluded);
  const Eigen::VectorXd max_rates = polytope.maxRates();
  sensornet::Rng rng = sensornet::Rng::keyed(seed, 29);
  Eigen::MatrixXd rates(scenario.intervals, scenario.sensorCount());
  for (int k = 0; k < scenario.intervals; ++k) {
    Eigen::VectorXd row(scenario.sensorCount());
    for (int j = 0; j < scenario.sensorCount(); ++j) {
      const double top = std::isfinite(max_rates(j)) ? max_rates(j) : 1.0;
      row(j) = rng.uniform() * top;
    }
    rates.row(k) = polytope.project(row).transpose();
  }
  return sensornet::RateSchedule(scenario.horizon_s, rates);
}

std::vector<ConvergenceCase> convergenceCases(const Options& options) {
  std::vector<ConvergenceCase> cases;
  const auto addStarts = [&options](ConvergenceCase& c, std::uint64_t seed) {
    c.starts.emplace_back("default", std::nullopt);
    for (int r = 0; r < options.random_starts; ++r) {
      c.starts.emplace_back("random " + std::to_string(r),
                            randomFeasibleStart(c.scenario, c.excluded, seed + 97u * (r + 1u)));
    }
  };
  const auto addInstances = [&](int n, int m) {
    for (int i = 0; i < options.instances; ++i) {
      sensornet::RandomPlantSpec spec;
      spec.state_dim = n;
      spec.sensor_count = m;
      spec.seed = 1000u * static_cast<std::uint64_t>(n) + 10u * static_cast<std::uint64_t>(m) +
                  static_cast<std::uint64_t>(i);
      ConvergenceCase c{"n=" + std::to_string(n) + " M=" + std::to_string(m),
                        "instance " + std::to_string(i),
                        sensornet::generateRandomScenario(spec),
                        {},
                        {}};
      addStarts(c, spec.seed);
      cases.push_back(std::move(c));
    }
  };
  for (int m = 30; m <= 100; m += 10) addInstances(5, m);
  for (int n = 2; n <= 20; n += 2) addInstances(n, 30);

  std::vector<std::string> files = options.scenario_files;
  if (files.empty()) {
    for (const auto& entry : std::filesystem::directory_iterator("scenarios")) {
      if (entry.path().extension() == ".yaml") files.push_back(entry.path().string());
    }
    std::sort(files.begin(), files.end());
  }
  for (const std::string& file : files) {
    const sensornet::Scenario scenario = sensornet::loadScenarioFile(file);
    const std::string base = std::filesystem::path(file).filename().string();
    ConvergenceCase full{base, base, scenario, {}, {}};
    addStarts(full, 4242u);
    cases.push_back(full);
    if (scenario.sensorCount() < 2) continue;
    // Sensor 1 out, warm-started from the schedules in force before (the full plans).
    ConvergenceCase without{base + " without sensor 1", base, scenario, {1}, {}};
    addStarts(without, 4343u);
    for (const PlanSurrogate s : {PlanSurrogate::Information, PlanSurrogate::Covariance}) {
      sensornet::PlanRequest request;
      request.surrogate = s;
      without.starts.emplace_back(std::string("warm ") + std::string(sensornet::describe(s)),
                                  sensornet::planSchedule(scenario, request).schedule);
    }
    cases.push_back(std::move(without));
  }
  return cases;
}

void runConvergence(const Options& options) {
  std::printf("planner_bench --convergence: %d instance(s) per Fig. 1 point, default start and %d "
              "random feasible starts, %d iterations, tolerance %.0e\n",
              options.instances, options.random_starts, options.max_iterations,
              options.tolerance);
  std::vector<std::string> order;
  std::map<std::string, ConvergenceRow> rows;
  for (const ConvergenceCase& c : convergenceCases(options)) {
    for (const PlanSurrogate surrogate : {PlanSurrogate::Information, PlanSurrogate::Covariance}) {
      const std::string key = c.group + " | " + std::string(sensornet::describe(surrogate));
      if (rows.find(key) == rows.end()) order.push_back(key);
      ConvergenceRow& row = rows[key];
      const auto form = sensornet::formOf(surrogate);
      for (const auto& [start_name, start] : c.starts) {
        sensornet::PlanRequest request;
        request.surrogate = surrogate;
        request.excluded_sensors = c.excluded;
        request.tolerance = options.tolerance;
        request.max_iterations = options.max_iterations;
        request.warm_start = start;
        const sensornet::PlanResult plan = sensornet::planSchedule(c.scenario, request);
        // The start as the planner sees it (the warm start projected, excluded sensors at 0;
        // the uniform rates without one): the plan of no iterations.
        sensornet::PlanRequest at_start = request;
        at_start.max_iterations = 0;
        const sensornet::PlanResult start_plan = sensornet::planSchedule(c.scenario, at_start);
        const double start_cost = sensornet::rollout(form, c.scenario, start_plan.schedule).cost;
        const bool converged = plan.kkt_residual <= options.tolerance;
        const bool no_worse = plan.objective <= start_cost * (1.0 + 1e-12);
        ++row.plans;
        ++row.statuses[sensornet::statusText(plan.status, plan.failure)];
        row.converged += converged ? 1 : 0;
        row.stated_no_worse += !converged && no_worse ? 1 : 0;
        row.failed += !converged && !no_worse ? 1 : 0;
        row.iterations.push_back(plan.iterations);
        row.seconds.push_back(plan.solve_seconds);
        row.kkt_max = std::max(row.kkt_max, plan.kkt_residual);
        row.substeps_max = std::max(row.substeps_max, plan.substeps);
        if (options.each || !converged) {
          std::printf("  %s %s %s from %s: %s, kkt %.2e, %d iterations, %d substeps, J %.10g "
                      "(start %.10g)%s\n",
                      c.group.c_str(), c.name.c_str(), std::string(sensornet::describe(surrogate)).c_str(),
                      start_name.c_str(), sensornet::statusText(plan.status, plan.failure).c_str(), plan.kkt_residual, plan.iterations,
                      plan.substeps, plan.objective, start_cost,
                      converged ? "" : (no_worse ? "  [not converged, no worse]" : "  [WORSE]"));
          std::fflush(stdout);
        }
      }
    }
  }
  if (options.markdown) {
    std::printf("\n| case | form | plans | converged | stated, no worse | worse | statuses | "
                "kkt max | it median | it max | s max | substeps max |\n"
                "|---|---|---|---|---|---|---|---|---|---|---|---|\n");
  } else {
    std::printf("\n%-34s %-4s | %5s %5s %5s %5s | %-28s | %8s %6s %6s %7s %4s\n", "case", "form",
                "plans", "conv", "nowrs", "worse", "statuses", "kkt max", "it med", "it max",
                "s max", "rk4");
  }
  int plans = 0, converged = 0, failed = 0;
  for (const std::string& key : order) {
    const ConvergenceRow& row = rows[key];
    std::ostringstream statuses;
    for (const auto& [status, count] : row.statuses) {
      statuses << (statuses.tellp() > 0 ? ", " : "") << status << " " << count;
    }
    const std::string group = key.substr(0, key.find(" | "));
    const std::string form = key.substr(key.find(" | ") + 3);
    const double it_max = *std::max_element(row.iterations.begin(), row.iterations.end());
    const double s_max = *std::max_element(row.seconds.begin(), row.seconds.end());
    if (options.markdown) {
      std::printf("| %s | %s | %d | %d | %d | %d | %s | %.1e | %.0f | %.0f | %.2f | %d |\n",
                  group.c_str(), form.c_str(), row.plans, row.converged, row.stated_no_worse,
                  row.failed, statuses.str().c_str(), row.kkt_max, median(row.iterations), it_max,
                  s_max, row.substeps_max);
    } else {
      std::printf("%-34s %-4s | %5d %5d %5d %5d | %-28s | %8.1e %6.0f %6.0f %7.2f %4d\n",
                  group.c_str(), form.c_str(), row.plans, row.converged, row.stated_no_worse,
                  row.failed, statuses.str().c_str(), row.kkt_max, median(row.iterations), it_max,
                  s_max, row.substeps_max);
    }
    plans += row.plans;
    converged += row.converged;
    failed += row.failed;
  }
  std::printf("\n%d plans: %d converged (kkt <= %.0e), %d ended otherwise no worse than their "
              "start, %d worse than their start\n",
              plans, converged, options.tolerance, plans - converged - failed, failed);
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
    } else if (arg == "--convergence") {
      options.convergence = true;
    } else if (arg == "--random-starts") {
      options.random_starts = std::max(0, std::atoi(value().c_str()));
    } else if (arg == "--max-iterations") {
      options.max_iterations = std::max(0, std::atoi(value().c_str()));
    } else if (arg == "--scenarios") {
      std::stringstream list(value());
      for (std::string file; std::getline(list, file, ',');) {
        if (!file.empty()) options.scenario_files.push_back(file);
      }
    } else {
      std::fprintf(stderr,
                   "usage: planner_bench [--sweep sensors|states|both] [--instances K] "
                   "[--mc-runs R] [--method pqn|ipopt] [--tolerance T] [--substeps S] [--n N] [--markdown]\n"
                   "       planner_bench --scale [--instances K] [--max-seconds S] "
                   "[--only pqn|ipopt] [--n N] [--m M] [--each] [--markdown]\n"
                   "       planner_bench --convergence [--instances K] [--random-starts R] "
                   "[--max-iterations I] [--scenarios a.yaml,b.yaml] [--each] [--markdown]\n");
      return arg == "--help" ? 0 : 2;
    }
  }
  if (options.sweep != "sensors" && options.sweep != "states" && options.sweep != "both") {
    std::fprintf(stderr, "planner_bench: --sweep expects sensors, states or both\n");
    return 2;
  }
  if (options.convergence) {
    if (options.instances == 0) options.instances = 1;
    runConvergence(options);
    return 0;
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
