// Scheduling in closed loop against open-loop plans (issue 29): where does feedback pay, and how
// much? For each scenario: the open-loop info, cov, uniform and mc plans, and the closed loop of
// `--replan-every DT` (evaluation::simulateClosedLoop: the coordinator's Replanner, planning in no
// time) with the info and the cov surrogate at a few DT, every episode starting from the
// surrogate's own open-loop plan. All on common random numbers (the same unit-rate points per
// episode, TimeChangedArrivals), so each closed loop is compared with its open-loop plan episode
// by episode: mean and 95% interval of the paired difference.
//
//   closed_loop_bench [--runs 400] [--every 1,0.5] [--margin 0.3] [--seed 1] [--mc-seconds 20]
//                     [--scenarios default,paper-5-30,paper-5-60,paper-4-30,paper-8-30]
//                     [--markdown]
//
// Scenarios: "default" (scenarios/default.yaml), "paper-n-M" (the first paper's random family,
// generateRandomScenario with n states and M sensors, T = 3, N = 30, budget 5, seed 1), or a
// path to a scenario file.

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <sstream>
#include <string>
#include <vector>

#include "sensornet/planning/planner.hpp"
#include "sensornet/core/scenario.hpp"
#include "sensornet/core/student_t.hpp"
#include "sensornet/evaluation/closed_loop.hpp"
#include "sensornet/io/scenario_file.hpp"

namespace {

namespace evaluation = sensornet::evaluation;
using sensornet::PlanSurrogate;
using sensornet::RateSchedule;
using sensornet::Scenario;

struct Options {
  int runs = 400;
  std::vector<double> every{1.0, 0.5};
  double margin = 0.3;  // emulated seconds (the live default: 0.3 wall s at time scale 1)
  std::uint64_t seed = 1;
  double mc_seconds = 20.0;
  std::vector<std::string> scenarios{"default", "paper-5-30", "paper-5-60", "paper-4-30",
                                     "paper-8-30"};
  bool markdown = false;
};

[[noreturn]] void fail(const std::string& message) {
  std::fprintf(stderr, "closed_loop_bench: %s\n", message.c_str());
  std::exit(2);
}

std::vector<std::string> splitList(const std::string& text) {
  std::vector<std::string> items;
  std::stringstream in(text);
  for (std::string item; std::getline(in, item, ',');) {
    if (!item.empty()) items.push_back(item);
  }
  return items;
}

Scenario scenarioNamed(const std::string& name) {
  if (name == "default") {
    return sensornet::loadScenarioFile(std::string(SENSORNET_SOURCE_DIR) + "/scenarios/default.yaml");
  }
  int n = 0, m = 0;
  if (std::sscanf(name.c_str(), "paper-%d-%d", &n, &m) == 2 && n > 0 && m > 0) {
    sensornet::RandomPlantSpec spec;
    spec.state_dim = n;
    spec.sensor_count = m;
    spec.seed = 1;
    return sensornet::generateRandomScenario(spec);
  }
  return sensornet::loadScenarioFile(name);
}

using Stat = sensornet::SampleMean;
Stat statOf(const std::vector<double>& x) { return sensornet::sampleMean(x); }

double secondsSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

void row(const Options& o, const std::string& scenario, const std::string& policy, const Stat& s,
         double normalizer, const std::string& versus, const Stat* diff, double seconds) {
  const std::string diff_text =
      diff == nullptr ? "" : (std::to_string(diff->mean / normalizer).substr(0, 8) + " ± " +
                              std::to_string(diff->ci95 / normalizer).substr(0, 7) +
                              (diff->mean + diff->ci95 < 0   ? " (pays)"
                               : diff->mean - diff->ci95 > 0 ? " (costs)"
                                                             : " (no difference)"));
  const double relative = diff == nullptr ? 0.0 : 100.0 * diff->mean / (s.mean - diff->mean);
  if (o.markdown) {
    std::printf("| %s | %s | %.5f ± %.5f | %s | %s | %s | %.1f |\n", scenario.c_str(),
                policy.c_str(), s.mean / normalizer, s.ci95 / normalizer, versus.c_str(),
                diff_text.c_str(),
                diff == nullptr ? "" : (std::to_string(relative).substr(0, 6) + "%").c_str(),
                seconds);
  } else {
    std::printf("%-12s %-22s %9.5f ± %8.5f  %-10s %-34s %8s %7.1f s\n", scenario.c_str(),
                policy.c_str(), s.mean / normalizer, s.ci95 / normalizer, versus.c_str(),
                diff_text.c_str(),
                diff == nullptr ? "" : (std::to_string(relative).substr(0, 6) + "%").c_str(),
                seconds);
  }
  std::fflush(stdout);
}

void runScenario(const Options& o, const std::string& name) {
  const Scenario s = scenarioNamed(name);
  const double normalizer = s.plant.P0.trace();
  struct Open {
    std::string name;
    PlanSurrogate surrogate;
    RateSchedule schedule;
    std::vector<double> costs;
  };
  std::vector<Open> open;
  for (const PlanSurrogate surrogate : {PlanSurrogate::Information, PlanSurrogate::Covariance,
                                        PlanSurrogate::Uniform, PlanSurrogate::MonteCarlo}) {
    const auto start = std::chrono::steady_clock::now();
    sensornet::PlanRequest request;
    request.surrogate = surrogate;
    request.max_iterations = 3000;
    if (surrogate == PlanSurrogate::MonteCarlo) request.max_seconds = o.mc_seconds;
    const sensornet::PlanResult plan = sensornet::planSchedule(s, request);
    Open entry{std::string(sensornet::wordOf(surrogate)), surrogate, plan.schedule, {}};
    entry.costs = evaluation::openLoopCosts(s, plan.schedule, o.runs, o.seed, 0);
    row(o, name, "open " + entry.name + " (" + sensornet::statusText(plan.status, plan.failure) + ")", statOf(entry.costs), normalizer,
        "", nullptr, secondsSince(start));
    open.push_back(std::move(entry));
  }
  for (const Open& base : open) {
    if (base.surrogate != PlanSurrogate::Information && base.surrogate != PlanSurrogate::Covariance) {
      continue;
    }
    for (const double every : o.every) {
      const auto start = std::chrono::steady_clock::now();
      evaluation::ClosedLoopOptions loop;
      loop.replan_every_s = every;
      loop.surrogate = base.surrogate;
      loop.replanner.switch_margin_s = o.margin;
      loop.replanner.time_scale = 1.0;
      loop.runs = o.runs;
      loop.seed = o.seed;
      const evaluation::ClosedLoopResult closed =
          evaluation::simulateClosedLoop(s, base.schedule, loop);
      const Stat against_own = sensornet::pairedDifference(closed.episode_costs, base.costs);
      char policy[64];
      std::snprintf(policy, sizeof policy, "closed %s DT %g (%.1f tails%s)", base.name.c_str(),
                    every, closed.tails_mean, closed.refused > 0 ? ", refusals" : "");
      row(o, name, policy, statOf(closed.episode_costs), normalizer, "open " + base.name,
          &against_own, secondsSince(start));
      // Against the best open-loop plan by its sample mean.
      const Open* best = &open.front();
      for (const Open& other : open) {
        if (statOf(other.costs).mean < statOf(best->costs).mean) best = &other;
      }
      if (best != &base) {
        const Stat against_best = sensornet::pairedDifference(closed.episode_costs, best->costs);
        row(o, name, "", statOf(closed.episode_costs), normalizer, "open " + best->name,
            &against_best, 0.0);
      }
    }
  }
}

}  // namespace

int main(int argc, char** argv) {
  Options o;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    const auto value = [&]() -> std::string {
      if (i + 1 >= argc) fail(arg + " needs a value");
      return argv[++i];
    };
    if (arg == "--runs") {
      o.runs = std::atoi(value().c_str());
    } else if (arg == "--every") {
      o.every.clear();
      for (const std::string& item : splitList(value())) o.every.push_back(std::atof(item.c_str()));
    } else if (arg == "--margin") {
      o.margin = std::atof(value().c_str());
    } else if (arg == "--seed") {
      o.seed = std::strtoull(value().c_str(), nullptr, 10);
    } else if (arg == "--mc-seconds") {
      o.mc_seconds = std::atof(value().c_str());
    } else if (arg == "--scenarios") {
      o.scenarios = splitList(value());
    } else if (arg == "--markdown") {
      o.markdown = true;
    } else {
      std::fprintf(arg == "--help" ? stdout : stderr,
                   "usage: closed_loop_bench [--runs 400] [--every 1,0.5] [--margin 0.3] "
                   "[--seed 1] [--mc-seconds 20]\n"
                   "                         [--scenarios default,paper-5-30,...] [--markdown]\n");
      return arg == "--help" ? 0 : 2;
    }
  }
  if (o.runs < 2 || o.every.empty() || !(o.margin > 0.0)) {
    fail("--runs expects >= 2, --every at least one DT > 0, --margin > 0");
  }
  for (const double every : o.every) {
    if (!(every > 0.0)) fail("--every expects numbers > 0");
  }
  std::printf("closed_loop_bench: %d episodes per policy, common random numbers, switch margin "
              "%g emulated s; costs / tr P(0); differences are paired, 95%%\n\n",
              o.runs, o.margin);
  if (o.markdown) {
    std::printf("| scenario | policy | mean J/trP0 ± 95%% | against | difference ± 95%% | "
                "relative | s |\n|---|---|---|---|---|---|---|\n");
  }
  for (const std::string& name : o.scenarios) runScenario(o, name);
  return 0;
}
