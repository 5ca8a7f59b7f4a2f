// The first paper's Fig. 2: Corollary 1 over a noise sweep. One reference instance of the
// paper's family (the random form of a scenario file, scenarios/paper.yaml by default: n = 5,
// M = 30, p_j = 1, P0 = 100 I, Q = I, T = 3, N = 30, W = 0, W_T = I, 1'λ_k <= 5) is planned
// ONCE with the information form; that one schedule is then evaluated while every R_j is scaled
// by a common factor R_scale (the file's random.noise_scale) from 1e-2 to 1e2. Per point: the
// information-form cost J_info, the covariance-form cost J_cov and the Monte Carlo mean of the
// realized cost (exact CD-KF, Poisson arrivals) with its 95% interval, all divided by tr P(0) as
// in the paper; the normalized width (J_cov - J_info) / tr P(0); and the signed deviations
// (J_info - MC) / MC and (J_cov - MC) / MC that the paper's figure plots. Several seeds of the
// instance generator, each planned at R_scale = 1.
//
// Within one seed every point uses the same Monte Carlo seed, so the arrival realizations are
// the same at every R_scale (they depend on the schedule only): the sweep is paired.
//
//   bracket_sweep_bench [--scenario scenarios/paper.yaml] [--seeds 1,2,3,4,5]
//                       [--from 1e-2] [--to 1e2] [--per-two-decades 9] [--mc-runs 20000]
//                       [--threads 0] [--budget B] [--markdown] [--svg FILE]
//
// --budget replaces the file's budget (1'λ_k <= B): the width of the bracket is a Jensen gap,
// which shrinks as arrivals get denser.
//
// --svg writes the deviations of every seed against R_scale (the paper's Fig. 2 plot), with the
// 95% interval of the Monte Carlo mean of the first seed as a band.

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

#include "sensornet/core/input_error.hpp"
#include "sensornet/core/monte_carlo.hpp"
#include "sensornet/planning/planner.hpp"
#include "sensornet/core/scenario.hpp"
#include "sensornet/core/surrogate.hpp"
#include "sensornet/report/svg_plot.hpp"
#include "sensornet/io/scenario_file.hpp"

namespace {

using sensornet::Scenario;

struct Options {
  std::string scenario = std::string(SENSORNET_SOURCE_DIR) + "/scenarios/paper.yaml";
  std::vector<std::uint64_t> seeds{1, 2, 3, 4, 5};
  double from = 1e-2;
  double to = 1e2;
  int per_two_decades = 9;  // points per factor 100, both ends included
  int mc_runs = 20000;
  int threads = 0;
  double budget = 0.0;  // > 0: replaces the file's random.budget (1'λ <= budget)
  bool markdown = false;
  std::string svg;
};

struct Row {
  double r_scale = 0.0;
  double info = 0.0, cov = 0.0, mc = 0.0, ci95 = 0.0, std_dev = 0.0;  // all / tr P(0)
  [[nodiscard]] double width() const { return cov - info; }
  [[nodiscard]] double infoDeviation() const { return (info - mc) / mc; }
  [[nodiscard]] double covDeviation() const { return (cov - mc) / mc; }
  // Corollary 1 at the 95% level: the interval of the MC mean meets [info, cov].
  [[nodiscard]] bool inside() const { return mc + ci95 >= info && mc - ci95 <= cov; }
};

struct SeedSweep {
  std::uint64_t seed = 0;
  std::string plan_status;
  double plan_kkt = 0.0;
  std::vector<Row> rows;
};

[[noreturn]] void usage(int code) {
  std::fprintf(code == 0 ? stdout : stderr,
               "usage: bracket_sweep_bench [--scenario FILE] [--seeds 1,2,3] [--from 1e-2] "
               "[--to 1e2]\n"
               "                           [--per-two-decades 9] [--mc-runs 20000] "
               "[--threads 0] [--budget B] [--markdown] [--svg FILE]\n"
               "The first paper's Fig. 2: the Info-NLP schedule of each seed's instance (planned "
               "at R_scale = 1)\nevaluated by both surrogates and Monte Carlo while every R_j is "
               "scaled by R_scale.\nFILE must use the random form (random: states, sensors, "
               "seed, ...); its seed is replaced by each of --seeds, its budget by --budget.\n");
  std::exit(code);
}

[[noreturn]] void fail(const std::string& message) {
  std::fprintf(stderr, "bracket_sweep_bench: %s\n", message.c_str());
  std::exit(2);
}

// The scenario file with random.seed and random.noise_scale replaced, parsed as a file.
Scenario instance(const YAML::Node& file, const Options& options, std::uint64_t seed,
                  double r_scale) {
  YAML::Node node = YAML::Clone(file);
  node["random"]["seed"] = seed;
  node["random"]["noise_scale"] = r_scale;
  if (options.budget > 0.0) node["random"]["budget"] = options.budget;
  YAML::Emitter out;
  out.SetDoublePrecision(17);
  out << node;
  return sensornet::parseScenarioYaml(out.c_str(), options.scenario);
}

std::vector<double> sweepPoints(const Options& options) {
  const double step = 2.0 / (options.per_two_decades - 1);  // in decades
  const double first = std::log10(options.from);
  const double last = std::log10(options.to);
  std::vector<double> points;
  for (int i = 0; first + i * step <= last + 1e-9; ++i) points.push_back(std::pow(10.0, first + i * step));
  return points;
}

void printHeader(const Options& options) {
  if (options.markdown) {
    std::printf(
        "| seed | R_scale | info/trP0 | cov/trP0 | MC/trP0 | MC 95%% +- | width/trP0 | "
        "(info-MC)/MC | (cov-MC)/MC | in bracket |\n");
    std::printf("|---|---|---|---|---|---|---|---|---|---|\n");
  } else {
    std::printf("%4s %9s | %10s %10s %10s %9s | %10s | %12s %12s | %s\n", "seed", "R_scale",
                "info/trP0", "cov/trP0", "MC/trP0", "95% +-", "width/trP0", "(info-MC)/MC",
                "(cov-MC)/MC", "in");
  }
}

void printRow(std::uint64_t seed, const Row& r, const Options& options) {
  const char* format =
      options.markdown
          ? "| %llu | %.3g | %.5f | %.5f | %.5f | %.5f | %.5f | %+.3f | %+.3f | %s |\n"
          : "%4llu %9.3g | %10.5f %10.5f %10.5f %9.5f | %10.5f | %+12.3f %+12.3f | %s\n";
  std::printf(format, static_cast<unsigned long long>(seed), r.r_scale, r.info, r.cov, r.mc,
              r.ci95, r.width(), r.infoDeviation(), r.covDeviation(), r.inside() ? "yes" : "NO");
  std::fflush(stdout);
}

SeedSweep sweepSeed(const YAML::Node& file, const Options& options, std::uint64_t seed) {
  SeedSweep sweep;
  sweep.seed = seed;
  const Scenario reference = instance(file, options, seed, 1.0);
  sensornet::PlanRequest request;
  request.surrogate = sensornet::PlanSurrogate::Information;
  request.max_iterations = 3000;
  const sensornet::PlanResult plan = sensornet::planSchedule(reference, request);
  sweep.plan_status = sensornet::statusText(plan.status, plan.failure);
  sweep.plan_kkt = plan.kkt_residual;
  const double normalizer = reference.plant.P0.trace();

  for (const double r_scale : sweepPoints(options)) {
    const Scenario s = instance(file, options, seed, r_scale);
    // The generator draws the same plant and sensors whatever the noise scale: only R moves.
    if (s.plant.A != reference.plant.A || s.sensors[0].H != reference.sensors[0].H ||
        !s.sensors[0].R.isApprox(r_scale * reference.sensors[0].R, 1e-12)) {
      fail("the generator did not keep A and H fixed across the noise sweep");
    }
    const sensornet::CostBracket bracket = sensornet::computeBracket(s, plan.schedule);
    sensornet::MonteCarloOptions mc_options;
    mc_options.runs = options.mc_runs;
    mc_options.seed = 1000 * seed + 1;  // the same arrivals at every point of the sweep
    mc_options.threads = options.threads;
    mc_options.simulate_plant = false;
    const sensornet::MonteCarloResult mc = sensornet::evaluateSchedule(s, plan.schedule, mc_options);
    Row row;
    row.r_scale = r_scale;
    row.info = bracket.info / normalizer;
    row.cov = bracket.cov / normalizer;
    row.mc = mc.mean / normalizer;
    row.ci95 = mc.ci95 / normalizer;
    row.std_dev = mc.std_dev / normalizer;
    sweep.rows.push_back(row);
    printRow(seed, row, options);  // as it comes: a seed takes minutes
  }
  return sweep;
}

void printSummary(const std::vector<SeedSweep>& sweeps, const Options& options) {
  std::printf("\nsummary per seed (over the sweep)\n");
  if (options.markdown) {
    std::printf(
        "| seed | plan | KKT | in bracket | max width/trP0 | at R_scale | min width/trP0 | "
        "(info-MC)/MC range | (cov-MC)/MC range |\n|---|---|---|---|---|---|---|---|---|\n");
  }
  for (const SeedSweep& sweep : sweeps) {
    int inside = 0;
    double max_width = 0.0, min_width = std::numeric_limits<double>::infinity(), at = 0.0;
    double info_lo = 1e300, info_hi = -1e300, cov_lo = 1e300, cov_hi = -1e300;
    for (const Row& r : sweep.rows) {
      inside += r.inside() ? 1 : 0;
      if (r.width() > max_width) {
        max_width = r.width();
        at = r.r_scale;
      }
      min_width = std::min(min_width, r.width());
      info_lo = std::min(info_lo, r.infoDeviation());
      info_hi = std::max(info_hi, r.infoDeviation());
      cov_lo = std::min(cov_lo, r.covDeviation());
      cov_hi = std::max(cov_hi, r.covDeviation());
    }
    const char* format =
        options.markdown
            ? "| %llu | %s | %.1e | %d of %zu | %.4f | %.3g | %.5f | %+.3f .. %+.3f | %+.3f .. "
              "%+.3f |\n"
            : "seed %llu: plan %s (KKT %.1e); MC inside the bracket at %d of %zu points; width "
              "max %.4f (at R_scale %.3g), min %.5f; (info-MC)/MC %+.3f .. %+.3f; (cov-MC)/MC "
              "%+.3f .. %+.3f\n";
    std::printf(format, static_cast<unsigned long long>(sweep.seed), sweep.plan_status.c_str(),
                sweep.plan_kkt, inside, sweep.rows.size(), max_width, at, min_width, info_lo,
                info_hi, cov_lo, cov_hi);
  }
}

void writeSvg(const std::vector<SeedSweep>& sweeps, const Options& options) {
  namespace plot = sensornet::report;
  double lo = 0.0, hi = 0.0;
  for (const SeedSweep& sweep : sweeps) {
    for (const Row& r : sweep.rows) {
      lo = std::min({lo, r.infoDeviation(), -r.ci95 / r.mc});
      hi = std::max({hi, r.covDeviation(), r.ci95 / r.mc});
    }
  }
  plot::SvgPlot::Frame frame;
  frame.height = 380.0;
  frame.top = 34.0 + plot::kLegendRow;
  plot::SvgPlot svg(frame, plot::Axis({options.from, options.to}, "noise scale R_scale", true),
                    plot::Axis(plot::niceRange({lo, hi}, 8), "deviation from the MC mean, (J - MC) / MC"));
  const std::vector<std::string> colours{"#1f3b73", "#b2182b", "#4d9221", "#8c510a", "#762a83",
                                         "#01665e", "#c51b7d", "#555555"};
  std::vector<plot::LegendEntry> legend;
  const SeedSweep& first = sweeps.front();
  std::vector<double> xs, band_lo, band_hi, zero;
  for (const Row& r : first.rows) {
    xs.push_back(r.r_scale);
    band_lo.push_back(-r.ci95 / r.mc);
    band_hi.push_back(r.ci95 / r.mc);
    zero.push_back(0.0);
  }
  const plot::Style band = plot::Style::area("#d9d9d9");
  svg.band(xs, band_lo, band_hi, band, "95% interval of the MC mean, seed " + std::to_string(first.seed));
  legend.push_back({"MC 95% interval (seed " + std::to_string(first.seed) + ")", band});
  svg.polyline(xs, zero, plot::Style::line("#000000", 0.8), "MC mean");
  for (std::size_t i = 0; i < sweeps.size(); ++i) {
    const std::string colour = colours[i % colours.size()];
    std::vector<double> x, info, cov;
    for (const Row& r : sweeps[i].rows) {
      x.push_back(r.r_scale);
      info.push_back(r.infoDeviation());
      cov.push_back(r.covDeviation());
    }
    const std::string seed = std::to_string(sweeps[i].seed);
    const plot::Style cov_style = plot::Style::line(colour, 1.5);
    const plot::Style info_style = plot::Style::line(colour, 1.5, "5,3");
    svg.polyline(x, cov, cov_style, "(J_cov - MC)/MC, seed " + seed);
    svg.polyline(x, info, info_style, "(J_info - MC)/MC, seed " + seed);
    legend.push_back({"seed " + seed, cov_style});
  }
  legend.insert(legend.begin() + 1, {{"J_cov (solid)", plot::Style::line("#000000")},
                                     {"J_info (dashed)", plot::Style::line("#000000", 1.5, "5,3")}});
  svg.legend(legend);
  // Standalone (bench/README.md shows the file itself): the report page's plot styles inline.
  std::string text = svg.svg(
      "bracket-sweep", "Corollary 1 over the noise sweep: surrogate deviations from the Monte Carlo mean");
  const std::string style =
      "<style>svg.plot { background: #ffffff; font-family: sans-serif; } svg.plot text { "
      "font-size: 12px; fill: #1a1a1a; } svg.plot .tick { font-size: 11px; } svg.plot .grid { "
      "stroke: #e4e4e4; stroke-width: 1; } svg.plot .frame { fill: none; stroke: #555; }</style>";
  text.insert(text.find('>') + 1, "\n" + style);
  std::ofstream out(options.svg);
  out << text << "\n";
  if (!out) fail("cannot write " + options.svg);
}

std::vector<std::uint64_t> parseSeeds(const std::string& text) {
  std::vector<std::uint64_t> seeds;
  std::stringstream in(text);
  std::string item;
  while (std::getline(in, item, ',')) {
    char* end = nullptr;
    const unsigned long long seed = std::strtoull(item.c_str(), &end, 10);
    if (item.empty() || *end != '\0') fail("--seeds expects integers separated by commas, got " + text);
    seeds.push_back(seed);
  }
  if (seeds.empty()) fail("--seeds expects at least one seed");
  return seeds;
}

double parsePositive(const std::string& flag, const std::string& text) {
  char* end = nullptr;
  const double value = std::strtod(text.c_str(), &end);
  if (text.empty() || *end != '\0' || !(value > 0.0) || !std::isfinite(value)) {
    fail(flag + " expects a number > 0, got " + text);
  }
  return value;
}

}  // namespace

int main(int argc, char** argv) {
  Options options;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    const auto value = [&]() -> std::string {
      if (i + 1 >= argc) fail(arg + " needs a value");
      return argv[++i];
    };
    if (arg == "--scenario") {
      options.scenario = value();
    } else if (arg == "--seeds") {
      options.seeds = parseSeeds(value());
    } else if (arg == "--from") {
      options.from = parsePositive(arg, value());
    } else if (arg == "--to") {
      options.to = parsePositive(arg, value());
    } else if (arg == "--per-two-decades") {
      options.per_two_decades = static_cast<int>(parsePositive(arg, value()));
    } else if (arg == "--mc-runs") {
      options.mc_runs = static_cast<int>(parsePositive(arg, value()));
    } else if (arg == "--threads") {
      options.threads = std::atoi(value().c_str());
    } else if (arg == "--budget") {
      options.budget = parsePositive(arg, value());
    } else if (arg == "--markdown") {
      options.markdown = true;
    } else if (arg == "--svg") {
      options.svg = value();
    } else if (arg == "--help" || arg == "-h") {
      usage(0);
    } else {
      std::fprintf(stderr, "bracket_sweep_bench: unknown option %s\n", arg.c_str());
      usage(2);
    }
  }
  if (options.per_two_decades < 2) fail("--per-two-decades expects an integer >= 2");
  if (options.to < options.from) fail("--to must not be below --from");
  if (options.mc_runs < 2) fail("--mc-runs expects at least 2 episodes");

  YAML::Node file;
  try {
    file = YAML::Load(sensornet::readTextFile(options.scenario, "scenario"));
    if (!file["random"]) fail(options.scenario + ": expected the random form (a `random:` map)");
    (void)instance(file, options, options.seeds.front(), 1.0);  // the file is valid
  } catch (const sensornet::InputError& error) {
    fail(error.what());
  } catch (const YAML::Exception& error) {
    fail(options.scenario + ": " + error.what());
  }

  const std::vector<double> points = sweepPoints(options);
  std::printf(
      "bracket_sweep_bench: %s%s, Info-NLP schedule planned once per seed at R_scale = 1; %zu "
      "points from %.3g to %.3g; Monte Carlo %d episodes per point (same arrivals at every "
      "point); costs / tr P(0)\n\n",
      options.scenario.c_str(),
      options.budget > 0.0 ? (" with budget " + std::to_string(options.budget)).c_str() : "",
      points.size(), options.from, options.to, options.mc_runs);
  printHeader(options);
  std::vector<SeedSweep> sweeps;
  for (const std::uint64_t seed : options.seeds) {
    sweeps.push_back(sweepSeed(file, options, seed));
  }
  printSummary(sweeps, options);
  if (!options.svg.empty()) writeSvg(sweeps, options);
  return 0;
}
