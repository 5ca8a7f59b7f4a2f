// Planning for the realized cost: the acceptance sweep of the Monte Carlo planner
// (PlanSurrogate::MonteCarlo, mc_planner.hpp) on the first paper's Fig. 1 instances (sensor
// sweep n = 5, M = 30..100; state sweep M = 30, n = 2..20; generateRandomScenario with the seeds
// of planner_bench). Per instance: the info, cov, uniform and mc plans, each scored by an
// independent Monte Carlo run (evaluateSchedule, its own generator and seed, the same episodes
// for the four plans), and the verdict of mc against the best of the other three on those
// episodes: a paired two-sided 95% t interval of E[J_mc - J_best] entirely above 0 is
// "significantly worse", entirely below 0 "better", else "not significantly different".
//
//   mc_planner_bench [--sweep sensors|states|both] [--instances 10] [--eval-runs 4000]
//                    [--max-seconds 8] [--n N] [--m M] [--gradient-episodes G]
//                    [--screening-episodes S] [--gradient-sensors K] [--verbose] [--markdown]
//                    [--planner-seeds K] [--max-iterations I]
// --planner-seeds K plans each instance K times (planner seeds spec.seed + 0..K-1) and counts
// the accepted refinements ("improved") that the independent evaluation finds worse than the
// best of the other three (point estimate, and significantly at 95%). With --max-seconds 1e6
// and --max-iterations I the sample sizes do not depend on measured time, so runs repeat.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "sensornet/planning/mc_planner.hpp"
#include "sensornet/core/monte_carlo.hpp"
#include "sensornet/planning/planner.hpp"
#include "sensornet/core/rate_schedule.hpp"
#include "sensornet/core/scenario.hpp"
#include "sensornet/core/student_t.hpp"

namespace {

using sensornet::PlanSurrogate;

struct Options {
  std::string sweep = "both";
  int instances = 10;
  int eval_runs = 4000;
  double max_seconds = 8.0;
  int only_n = 0;
  int only_m = 0;
  bool verbose = false;
  bool markdown = false;
  int planner_seeds = 1;
  int max_iterations = sensornet::PlanRequest{}.max_iterations;
  sensornet::RealizedCostOptions realized;
};

double median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  const std::size_t h = v.size() / 2;
  return v.size() % 2 ? v[h] : 0.5 * (v[h - 1] + v[h]);
}

double mean(const std::vector<double>& v) {
  double s = 0.0;
  for (double x : v) s += x;
  return v.empty() ? 0.0 : s / static_cast<double>(v.size());
}

// One instance's paired comparison of mc with the best of the other three, kept for the verdict
// over the whole sweep: with K instances, K tests at 95% each would call about K / 40 instances
// "worse" by chance alone, so the sweep's own verdict holds the false-alarm rate of the whole
// family at 5% (Bonferroni: each interval at 1 - 0.05 / K).
struct Paired {
  double mean = 0.0;            // of J_mc - J_best per episode, / tr(P0)
  double standard_error = 0.0;  // of that mean
  double degrees_of_freedom = 0.0;
  double ratio = 0.0;  // mean J_mc / mean J_best
};

// The half-width of the two-sided (1 - alpha) t interval of E[J_mc - J_best], and the verdict:
// +1 entirely above 0 (mc significantly worse), -1 entirely below (better), 0 not significant.
double halfWidth(const Paired& p, double alpha) {
  return sensornet::studentTQuantile(1.0 - 0.5 * alpha, p.degrees_of_freedom) * p.standard_error;
}
int verdict(const Paired& p, double alpha) {
  const double half = halfWidth(p, alpha);
  return p.mean - half > 0.0 ? 1 : (p.mean + half < 0.0 ? -1 : 0);
}

// How many of `instances` the test at `alpha` calls better (-1), not significant (0), worse (+1).
int countVerdicts(const std::vector<Paired>& instances, double alpha, int which) {
  int count = 0;
  for (const Paired& p : instances) count += verdict(p, alpha) == which;
  return count;
}

std::vector<double> ratiosOf(const std::vector<Paired>& instances) {
  std::vector<double> ratios;
  for (const Paired& p : instances) ratios.push_back(p.ratio);
  return ratios;
}

struct Point {
  int n = 0, m = 0;
  int improved = 0;
  int improved_but_worse = 0;              // by the independent evaluation's point estimate
  int improved_but_significantly_worse = 0;  // its 95% interval entirely above 0
  std::vector<double> mc_seconds, episodes, info, cov, uniform, mc;
  std::vector<Paired> paired;
};

std::vector<double> evaluate(const sensornet::Scenario& scenario,
                             const sensornet::RateSchedule& schedule, int runs,
                             std::uint64_t seed) {
  sensornet::MonteCarloOptions options;
  options.runs = runs;
  options.seed = seed;
  options.threads = 0;
  options.simulate_plant = false;
  return sensornet::evaluateSchedule(scenario, schedule, options).episode_costs;
}

double secondsSince(std::chrono::steady_clock::time_point t) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
}

void runInstance(Point& point, int i, int planner_seed, const Options& options) {
  sensornet::RandomPlantSpec spec;
  spec.state_dim = point.n;
  spec.sensor_count = point.m;
  spec.seed = 1000u * static_cast<std::uint64_t>(point.n) +
              10u * static_cast<std::uint64_t>(point.m) + static_cast<std::uint64_t>(i);
  const sensornet::Scenario scenario = sensornet::generateRandomScenario(spec);
  const double normalizer = scenario.plant.P0.trace();
  std::vector<sensornet::RateSchedule> schedules;
  for (PlanSurrogate s :
       {PlanSurrogate::Information, PlanSurrogate::Covariance, PlanSurrogate::Uniform}) {
    sensornet::PlanRequest request;
    request.surrogate = s;
    request.max_iterations = 3000;
    schedules.push_back(sensornet::planSchedule(scenario, request).schedule);
  }
  sensornet::PlanRequest request;
  request.surrogate = PlanSurrogate::MonteCarlo;
  request.max_seconds = options.max_seconds;
  request.max_iterations = options.max_iterations;
  request.realized = options.realized;
  request.realized.seed = spec.seed + static_cast<std::uint64_t>(planner_seed);
  const auto start = std::chrono::steady_clock::now();
  const sensornet::PlanResult plan = sensornet::planSchedule(scenario, request);
  point.mc_seconds.push_back(secondsSince(start));
  point.episodes.push_back(static_cast<double>(plan.episodes));
  if (plan.status == sensornet::PlanStatus::Improved) ++point.improved;
  schedules.push_back(plan.schedule);

  // The independent evaluation: another generator (thinning, evaluateSchedule) and seed.
  const std::uint64_t eval_seed = spec.seed * 7919u + 12345u;
  std::vector<std::vector<double>> costs;
  std::vector<double> means;
  for (const auto& s : schedules) {
    costs.push_back(evaluate(scenario, s, options.eval_runs, eval_seed));
    means.push_back(mean(costs.back()) / normalizer);
  }
  const auto best =
      static_cast<std::size_t>(std::min_element(means.begin(), means.begin() + 3) - means.begin());
  std::vector<double> d(costs[3].size());
  for (std::size_t e = 0; e < d.size(); ++e) d[e] = (costs[3][e] - costs[best][e]) / normalizer;
  const double md = mean(d);
  double sq = 0.0;
  for (double x : d) sq += (x - md) * (x - md);
  const double runs = static_cast<double>(d.size());
  const Paired paired{md, std::sqrt(sq / (runs - 1.0) / runs), runs - 1.0, means[3] / means[best]};
  point.paired.push_back(paired);
  const int v = verdict(paired, 0.05);
  if (plan.status == sensornet::PlanStatus::Improved) {
    point.improved_but_worse += md > 0.0 ? 1 : 0;
    point.improved_but_significantly_worse += v > 0 ? 1 : 0;
  }
  point.info.push_back(means[0]);
  point.cov.push_back(means[1]);
  point.uniform.push_back(means[2]);
  point.mc.push_back(means[3]);
  if (options.verbose) {
    std::printf(
        "  n=%d M=%d #%d/%d: info %.4f cov %.4f unif %.4f mc %.4f (planner %.4f +- %.4f, %s, "
        "%lld episodes, %.1f s) mc-best %+.5f +- %.5f %s\n",
        point.n, point.m, i, planner_seed, means[0], means[1], means[2], means[3], plan.objective / normalizer,
        plan.objective_half_width / normalizer, std::string(wordOf(plan.status)).c_str(), plan.episodes,
        point.mc_seconds.back(), md, halfWidth(paired, 0.05),
        v > 0 ? "WORSE" : (v < 0 ? "better" : "n.s."));
    std::fflush(stdout);
  }
}

void printHeader(bool markdown) {
  if (markdown) {
    std::printf(
        "| n | M | info MC/trP0 | cov MC/trP0 | uniform MC/trP0 | mc MC/trP0 | mc / best "
        "(median) | mc / best (mean) | better / n.s. / worse | refined kept | mc s | "
        "episodes |\n");
    std::printf("|---|---|---|---|---|---|---|---|---|---|---|---|\n");
  } else {
    std::printf("%3s %4s | %8s %8s %8s %8s | %7s %7s | %8s | %4s | %6s %9s\n", "n", "M", "info",
                "cov", "unif", "mc", "mc/best", "mean", "b/ns/w", "kept", "mc s", "episodes");
  }
}

void printPoint(const Point& p, bool markdown) {
  const char* format = markdown
                           ? "| %d | %d | %.4f | %.4f | %.4f | %.4f | %.3f | %.3f | %d / %d / %d "
                             "| %d | %.1f | %.0f |\n"
                           : "%3d %4d | %8.4f %8.4f %8.4f %8.4f | %7.3f %7.3f | %2d/%2d/%2d | %4d "
                             "| %6.1f %9.0f\n";
  std::printf(format, p.n, p.m, median(p.info), median(p.cov), median(p.uniform), median(p.mc),
              median(ratiosOf(p.paired)), mean(ratiosOf(p.paired)),
              countVerdicts(p.paired, 0.05, -1), countVerdicts(p.paired, 0.05, 0),
              countVerdicts(p.paired, 0.05, 1), p.improved, median(p.mc_seconds),
              median(p.episodes));
  std::fflush(stdout);
}

// The verdict over every instance run: per instance at 95% and with the family-wise 5%, and the
// mean of mc / best over instances with its 95% t interval.
void printSweepVerdict(const std::vector<Paired>& all_instances) {
  const auto k = static_cast<double>(all_instances.size());
  if (all_instances.size() < 2) return;
  const int worse = countVerdicts(all_instances, 0.05, 1);
  const int better = countVerdicts(all_instances, 0.05, -1);
  const int family_worse = countVerdicts(all_instances, 0.05 / k, 1);
  const int family_better = countVerdicts(all_instances, 0.05 / k, -1);
  const std::vector<double> ratios = ratiosOf(all_instances);
  const double m = mean(ratios);
  double sq = 0.0;
  for (double r : ratios) sq += (r - m) * (r - m);
  const double half = sensornet::studentTQuantile(0.975, k - 1.0) * std::sqrt(sq / (k - 1.0) / k);
  std::printf(
      "\nall %.0f instances: mc significantly worse than the best of info, cov and "
      "uniform on %d at 95%% per instance (about %.1f expected by chance if mc equalled "
      "the best everywhere), on %d with the family-wise false-alarm rate held at 5%% "
      "(Bonferroni); better on %d (%d family-wise); mean mc / best %.4f, 95%% interval "
      "[%.4f, %.4f], median %.4f\n",
      k, worse, 0.025 * k, family_worse, better, family_better, m, m - half, m + half,
      median(ratios));
}

Point runPoint(int n, int m, const Options& options) {
  Point point;
  point.n = n;
  point.m = m;
  for (int i = 0; i < options.instances; ++i) {
    for (int r = 0; r < options.planner_seeds; ++r) runInstance(point, i, r, options);
  }
  if (point.improved > 0) {
    std::printf("  n=%d M=%d: %d of %zu plans improved; of those, %d worse than the best of the "
                "others by the independent evaluation, %d significantly (95%%)\n",
                n, m, point.improved, point.paired.size(), point.improved_but_worse,
                point.improved_but_significantly_worse);
  }
  return point;
}

}  // namespace

int main(int argc, char** argv) {
  Options options;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    const auto value = [&]() -> std::string {
      if (i + 1 >= argc) {
        std::fprintf(stderr, "mc_planner_bench: %s needs a value\n", arg.c_str());
        std::exit(2);
      }
      return argv[++i];
    };
    if (arg == "--sweep") {
      options.sweep = value();
    } else if (arg == "--instances") {
      options.instances = std::max(1, std::atoi(value().c_str()));
    } else if (arg == "--eval-runs") {
      options.eval_runs = std::max(2, std::atoi(value().c_str()));
    } else if (arg == "--max-seconds") {
      options.max_seconds = std::max(0.1, std::atof(value().c_str()));
    } else if (arg == "--n") {
      options.only_n = std::atoi(value().c_str());
    } else if (arg == "--m") {
      options.only_m = std::atoi(value().c_str());
    } else if (arg == "--gradient-episodes") {
      options.realized.gradient_episodes = std::atoi(value().c_str());
    } else if (arg == "--screening-episodes") {
      options.realized.screening_episodes = std::atoi(value().c_str());
    } else if (arg == "--gradient-sensors") {
      options.realized.gradient_sensors = std::atoi(value().c_str());
    } else if (arg == "--planner-seeds") {
      options.planner_seeds = std::max(1, std::atoi(value().c_str()));
    } else if (arg == "--max-iterations") {
      options.max_iterations = std::max(0, std::atoi(value().c_str()));
    } else if (arg == "--verbose") {
      options.verbose = true;
    } else if (arg == "--markdown") {
      options.markdown = true;
    } else {
      std::fprintf(stderr,
                   "usage: mc_planner_bench [--sweep sensors|states|both] [--instances K] "
                   "[--eval-runs R] [--max-seconds S] [--n N] [--m M] [--gradient-episodes G] "
                   "[--screening-episodes S] "
                   "[--gradient-sensors K] [--verbose] [--markdown] [--planner-seeds K] "
                   "[--max-iterations I]\n");
      return arg == "--help" ? 0 : 2;
    }
  }
  if (options.sweep != "sensors" && options.sweep != "states" && options.sweep != "both") {
    std::fprintf(stderr, "mc_planner_bench: --sweep expects sensors, states or both\n");
    return 2;
  }
  std::printf(
      "mc_planner_bench: %d instances per point, independent evaluation %d episodes, mc "
      "planner max %.1f s; costs / tr(P0), medians over instances\n",
      options.instances, options.eval_runs, options.max_seconds);
  const auto start = std::chrono::steady_clock::now();
  std::vector<Paired> all_instances;
  const auto run = [&](int n, int m) {
    const Point point = runPoint(n, m, options);
    printPoint(point, options.markdown);
    all_instances.insert(all_instances.end(), point.paired.begin(), point.paired.end());
  };
  if (options.sweep != "states") {
    std::printf("\nsensor sweep (n = 5)\n");
    printHeader(options.markdown);
    for (int m = 30; m <= 100; m += 10) {
      if (options.only_m == 0 || options.only_m == m) run(5, m);
    }
  }
  if (options.sweep != "sensors") {
    std::printf("\nstate sweep (M = 30)\n");
    printHeader(options.markdown);
    for (int n = 2; n <= 20; n += 2) {
      if (options.only_n == 0 || options.only_n == n) run(n, 30);
    }
  }
  printSweepVerdict(all_instances);
  std::printf("\ntotal %.0f s\n", secondsSince(start));
  return 0;
}
