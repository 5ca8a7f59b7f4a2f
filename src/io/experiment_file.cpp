#include "sensornet/io/experiment_file.hpp"

#include <yaml-cpp/yaml.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "sensornet/core/digest.hpp"
#include "sensornet/core/input_error.hpp"
#include "sensornet/core/words.hpp"
#include "sensornet/emulator/vocabulary.hpp"
#include "sensornet/io/scenario_file.hpp"
#include "sensornet/io/yaml_text.hpp"
#include "yaml_reader.hpp"

namespace sensornet {
namespace {

namespace fs = std::filesystem;

// A number written so that reading it back gives the same double.
std::string exact(double value) {
  char text[32];
  std::snprintf(text, sizeof text, "%.17g", value);
  return text;
}

std::string flowYaml(const YAML::Node& node) {
  YAML::Emitter out;
  out.SetMapFormat(YAML::Flow);
  out.SetSeqFormat(YAML::Flow);
  out << node;
  return out.c_str();
}

// The values of an axis: a list, or one value.
std::vector<YAML::Node> axisValues(const YamlReader& in, const YAML::Node& node,
                                   const std::string& field) {
  if (!node.IsSequence()) return {node};
  if (node.size() == 0) in.fail(node, field, "a value or a non-empty list of values");
  std::vector<YAML::Node> values;
  for (const YAML::Node& v : node) values.push_back(v);
  return values;
}

// Every combination of the axes, the first axis slowest.
template <class Value>
void cartesian(const std::vector<std::vector<Value>>& axes,
               const std::function<void(const std::vector<Value>&)>& visit) {
  std::vector<Value> chosen;
  std::function<void(std::size_t)> go = [&](std::size_t a) {
    if (a == axes.size()) {
      visit(chosen);
      return;
    }
    for (const Value& v : axes[a]) {
      chosen.push_back(v);
      go(a + 1);
      chosen.pop_back();
    }
  };
  go(0);
}

std::vector<SweepScenario> readScenario(const YamlReader& in, const YAML::Node& entry,
                                        const std::string& field, const fs::path& folder) {
  in.rejectUnknownKeys(entry, field,
                       {"file", "random", "budget", "energy", "horizon", "intervals"});
  const bool file = entry["file"].IsDefined();
  const bool random = entry["random"].IsDefined();
  if (file == random)
    in.fail(entry, field, "either file: (a scenario file) or random: (a random plant)");
  std::vector<std::optional<double>> budgets = {std::nullopt};
  if (entry["budget"]) {
    budgets.clear();
    for (const YAML::Node& b : axisValues(in, entry["budget"], field + ".budget")) {
      const double value = in.number(b, field + ".budget");
      if (value <= 0.0) in.fail(b, field + ".budget", "a number > 0");
      budgets.emplace_back(value);
    }
  }
  // Every sensor's energy budget, beside budget: or (random plants) inside random: too.
  const bool inside = random && entry["random"].IsMap() && entry["random"]["energy"];
  if (inside && entry["energy"]) {
    in.fail(entry["random"]["energy"], field + ".random.energy", "the energy in one place only");
  }
  const YAML::Node energy_node = inside ? entry["random"]["energy"] : entry["energy"];
  const std::string energy_field = field + (inside ? ".random.energy" : ".energy");
  std::vector<std::optional<double>> energies = {std::nullopt};
  if (energy_node) {
    energies.clear();
    for (const YAML::Node& e : axisValues(in, energy_node, energy_field)) {
      const double value = in.number(e, energy_field);
      if (value <= 0.0) {
        in.fail(e, energy_field, "a number > 0 (expected measurements of each sensor)");
      }
      energies.emplace_back(value);
    }
  }
  std::vector<SweepScenario> out;
  if (file) {
    if (entry["horizon"] || entry["intervals"]) {
      in.fail(entry, field, "horizon and intervals only with random: (a file has its own)");
    }
    if (!entry["file"].IsScalar())
      in.fail(entry["file"], field + ".file", "the path of a scenario file");
    fs::path path = entry["file"].Scalar();
    if (path.is_relative()) path = folder / path;
    for (const auto& budget : budgets) {
      for (const auto& energy : energies) {
        out.push_back({path.lexically_normal().string(), std::nullopt, budget, energy});
      }
    }
    return out;
  }
  const YAML::Node r = entry["random"];
  const std::string rf = field + ".random";
  in.rejectUnknownKeys(
      r, rf, {"states", "sensors", "rows_per_sensor", "seed", "budget", "noise_scale", "energy"});
  if (r["budget"] && entry["budget"])
    in.fail(r["budget"], rf + ".budget", "the budget in one place only");
  RandomPlantSpec base;
  if (entry["horizon"]) base.horizon_s = in.number(entry["horizon"], field + ".horizon");
  if (entry["intervals"])
    base.intervals = static_cast<int>(in.integer(entry["intervals"], field + ".intervals"));
  if (!(base.horizon_s > 0.0)) in.fail(entry["horizon"], field + ".horizon", "a number > 0");
  if (base.intervals < 1 || base.intervals > 100000) {
    in.fail(entry["intervals"], field + ".intervals", "an integer from 1 to 100000");
  }
  // Each key of random: is an axis (a list) or one value.
  const std::vector<std::pair<const char*, bool>> keys = {
      {"states", true}, {"sensors", true}, {"rows_per_sensor", false},
      {"seed", true},   {"budget", false}, {"noise_scale", false}};
  std::vector<std::vector<YAML::Node>> axes;
  for (const auto& [key, required] : keys) {
    if (required) in.required(r, key, rf + "." + key);
    axes.push_back(r[key] ? axisValues(in, r[key], rf + "." + key)
                          : std::vector<YAML::Node>{YAML::Node()});
  }
  cartesian<YAML::Node>(axes, [&](const std::vector<YAML::Node>& v) {
    RandomPlantSpec spec = base;
    const auto integer = [&](const YAML::Node& n, const char* key, long low) {
      const long value = in.integer(n, rf + "." + key);
      if (value < low) in.fail(n, rf + "." + key, "an integer >= " + std::to_string(low));
      return value;
    };
    spec.state_dim = static_cast<int>(integer(v[0], "states", 1));
    spec.sensor_count = static_cast<int>(integer(v[1], "sensors", 1));
    if (v[2].IsDefined() && !v[2].IsNull())
      spec.rows_per_sensor = static_cast<int>(integer(v[2], "rows_per_sensor", 1));
    spec.seed = static_cast<std::uint64_t>(integer(v[3], "seed", 0));
    if (v[4].IsDefined() && !v[4].IsNull()) {
      spec.budget = in.number(v[4], rf + ".budget");
      if (spec.budget <= 0.0) in.fail(v[4], rf + ".budget", "a number > 0");
    }
    if (v[5].IsDefined() && !v[5].IsNull()) {
      spec.noise_scale = in.number(v[5], rf + ".noise_scale");
      if (spec.noise_scale <= 0.0) in.fail(v[5], rf + ".noise_scale", "a number > 0");
    }
    if (spec.rows_per_sensor > spec.state_dim) {
      in.fail(r, rf + ".rows_per_sensor", "an integer between 1 and random.states");
    }
    for (const auto& budget : budgets) {
      for (const auto& energy : energies) out.push_back({"", spec, budget, energy});
    }
  });
  return out;
}

struct PlannerChoice {
  std::string name;
  PlanSurrogate surrogate = PlanSurrogate::Information;
  double replan_every_s = 0.0;
  std::string schedule_file{};
};

PlannerChoice readPlanner(const YamlReader& in, const YAML::Node& node, const std::string& field,
                          const fs::path& folder) {
  if (node.IsScalar()) {
    const std::string& word = node.Scalar();
    for (const WordOf<PlanSurrogate>& w : Words<PlanSurrogate>::kTable) {
      if (word == w.text) return {word, w.value, 0.0};
    }
    // The default surrogate's plan, measured with deterministic instants.
    if (word == "timetable") return {word, PlanSurrogate::Covariance, 0.0};
    in.fail(node, field,
            "info, cov, uniform, mc, timetable, {timetable: info|cov|uniform|mc}, "
            "{closed_loop: info|cov, replan_every: DT} or {schedule: FILE}, got '" + word + "'");
  }
  if (node.IsMap() && node["schedule"]) {
    in.rejectUnknownKeys(node, field, {"schedule"});
    if (!node["schedule"].IsScalar()) {
      in.fail(node["schedule"], field + ".schedule", "the path of a schedule file (JSON)");
    }
    fs::path path = node["schedule"].Scalar();
    if (path.is_relative()) path = folder / path;
    return {"schedule", PlanSurrogate::Information, 0.0, path.lexically_normal().string()};
  }
  if (node.IsMap() && node["timetable"]) {
    in.rejectUnknownKeys(node, field, {"timetable"});
    const YAML::Node form = node["timetable"];
    for (const WordOf<PlanSurrogate>& w : Words<PlanSurrogate>::kTable) {
      if (form.IsScalar() && form.Scalar() == w.text) return {"timetable", w.value, 0.0};
    }
    in.fail(form, field + ".timetable", "info, cov, uniform or mc (the plan the instants follow)");
  }
  in.rejectUnknownKeys(node, field, {"closed_loop", "replan_every"});
  const YAML::Node form = in.required(node, "closed_loop", field + ".closed_loop");
  PlannerChoice p{"closed_loop", PlanSurrogate::Information, 0.0};
  if (!form.IsScalar() || (form.Scalar() != "info" && form.Scalar() != "cov")) {
    in.fail(form, field + ".closed_loop", "info or cov (the surrogate the tails are planned with)");
  }
  p.surrogate = form.Scalar() == "info" ? PlanSurrogate::Information : PlanSurrogate::Covariance;
  p.replan_every_s = in.number(in.required(node, "replan_every", field + ".replan_every"),
                               field + ".replan_every");
  if (p.replan_every_s <= 0.0)
    in.fail(node["replan_every"], field + ".replan_every", "a number > 0 (emulated seconds)");
  return p;
}

// An emulated cell's scenario file is a scenario (its network and faults sections fit the plant):
// bad input names the experiment's section, not the file the sweep writes.
void checkEmulatedScenario(const SweepCell& cell, const YAML::Node& emulate,
                           const std::string& source) {
  try {
    (void)parseScenarioYaml(cell.scenarioYaml(), "the scenario");
  } catch (const InputError& e) {
    const YamlReader in(source);
    const EmulatedRuns& m = *cell.emulate;
    const bool network = e.field().rfind("network", 0) == 0;
    const std::string& name = network ? m.network_name : m.faults_name;
    const char* section = network ? "network" : "faults";
    const YAML::Node at = name.empty() ? emulate : emulate[section][name];
    const std::string field =
        name.empty() ? e.field() : std::string(section) + "." + name + " (" + e.field() + ")";
    in.fail(at, "emulate." + field,
            e.expected() + (cell.scenario.file.empty() ? "" : " for " + cell.scenario.file));
  }
}

// `emulate:`: the emulated runs' settings, one EmulatedRuns per value of its axes (time_scale,
// network, faults).
std::vector<EmulatedRuns> readEmulate(const YamlReader& in, const YAML::Node& node) {
  in.rejectUnknownKeys(node, "emulate",
                       {"episodes", "time_scale", "network", "faults", "on_sensor_failure"});
  EmulatedRuns base;
  if (node["episodes"]) {
    base.episodes = static_cast<int>(in.integer(node["episodes"], "emulate.episodes"));
    if (base.episodes < 1 || base.episodes > 100000) {
      in.fail(node["episodes"], "emulate.episodes", "an integer from 1 to 100000");
    }
  }
  if (const YAML::Node p = node["on_sensor_failure"]) {
    using emulator::FailurePolicy;
    if (!p.IsScalar()) in.fail(p, "emulate.on_sensor_failure", wordChoices<FailurePolicy>());
    try {
      base.on_sensor_failure = wordOf(parseWord<FailurePolicy>(p.Scalar(), "", ""));
    } catch (const InputError& e) {
      in.fail(p, "emulate.on_sensor_failure", e.expected());
    }
  }
  std::vector<double> scales;
  if (node["time_scale"]) {
    for (const YAML::Node& v : axisValues(in, node["time_scale"], "emulate.time_scale")) {
      const double scale = in.number(v, "emulate.time_scale");
      if (scale < 0.001 || scale > 10000) {
        in.fail(v, "emulate.time_scale", "a number from 0.001 to 10000 (emulated s per wall s)");
      }
      scales.push_back(scale);
    }
  } else {
    scales.push_back(base.time_scale);
  }
  // network: and faults: map a name (the results' column) to a section; absent: the scenario's.
  using Named = std::pair<std::string, std::string>;
  const auto sections = [&](const char* key, const char* what) {
    std::vector<Named> out;
    const YAML::Node map = node[key];
    if (!map) return std::vector<Named>{{"", ""}};
    const std::string field = std::string("emulate.") + key;
    if (!map.IsMap() || map.size() == 0) {
      in.fail(map, field, std::string("names, each with ") + what + " (or ~ for none)");
    }
    for (const auto& entry : map) {
      const std::string name = entry.first.Scalar();
      if (name.empty() || name.find_first_of(",;()#") != std::string::npos) {
        in.fail(entry.first, field, "a name without , ; ( ) #, got '" + name + "'");
      }
      out.emplace_back(name, entry.second.IsNull() ? "~" : flowYaml(entry.second));
    }
    return out;
  };
  const std::vector<Named> networks = sections("network", "a scenario's network: section");
  const std::vector<Named> faults = sections("faults", "a scenario's faults: list");
  std::vector<EmulatedRuns> out;
  for (const double scale : scales) {
    for (const auto& [network_name, network_yaml] : networks) {
      for (const auto& [faults_name, faults_yaml] : faults) {
        EmulatedRuns e = base;
        e.time_scale = scale;
        e.network_name = network_name;
        e.network_yaml = network_yaml;
        e.faults_name = faults_name;
        e.faults_yaml = faults_yaml;
        out.push_back(std::move(e));
      }
    }
  }
  return out;
}

}  // namespace

Scenario SweepScenario::load(const std::string& source) const {
  Scenario s;
  if (random) {
    s = generateRandomScenario(*random);
    validateScenario(s, source);
  } else {
    s = loadScenarioFile(file);
  }
  if (budget) s = withBudget(std::move(s), *budget, source);
  if (energy) s = withEnergy(std::move(s), Eigen::VectorXd::Constant(1, *energy), source);
  return s;
}

std::string SweepCell::key() const {
  std::string k = "scenario=";
  if (scenario.random) {
    const RandomPlantSpec& r = *scenario.random;
    k += "random(states=" + std::to_string(r.state_dim) +
         ",sensors=" + std::to_string(r.sensor_count) +
         ",rows_per_sensor=" + std::to_string(r.rows_per_sensor) +
         ",seed=" + std::to_string(r.seed) + ",budget=" + exact(r.budget) +
         ",noise_scale=" + exact(r.noise_scale) + ",horizon=" + exact(r.horizon_s) +
         ",intervals=" + std::to_string(r.intervals) + ")";
  } else {
    k += scenario.file;
  }
  if (scenario.budget) k += ";budget=" + exact(*scenario.budget);
  if (scenario.energy) k += ";energy=" + exact(*scenario.energy);
  k += ";planner=" + planner;
  if (planner == "closed_loop") {
    k += "(" + std::string(wordOf(surrogate)) + ",every=" + exact(replan_every_s) + ")";
  } else if (planner == "timetable") {
    k += "(" + std::string(wordOf(surrogate)) + ")";
  } else if (planner == "schedule") {
    k += "(" + schedule_file + ")";
  }
  k += ";seed=" + std::to_string(seed);
  if (!emulate) return k + ";runs=" + std::to_string(runs);
  const EmulatedRuns& e = *emulate;
  const auto section = [](const std::string& name, const std::string& yaml) {
    return name.empty() ? std::string("scenario") : name + "#" + digestOf(yaml).substr(0, 8);
  };
  return k + ";emulate(episodes=" + std::to_string(e.episodes) +
         ",time_scale=" + exact(e.time_scale) +
         ",network=" + section(e.network_name, e.network_yaml) +
         ",faults=" + section(e.faults_name, e.faults_yaml) + ",on_sensor_failure=" +
         (e.on_sensor_failure.empty() ? "default" : e.on_sensor_failure) + ")";
}

std::string SweepCell::id() const { return digestOf(key()); }

std::string SweepCell::scenarioYaml() const {
  YAML::Node root;
  if (scenario.random) {
    const RandomPlantSpec& r = *scenario.random;
    root["horizon"] = exact(r.horizon_s);
    root["intervals"] = r.intervals;
    YAML::Node random;
    random["states"] = r.state_dim;
    random["sensors"] = r.sensor_count;
    random["rows_per_sensor"] = r.rows_per_sensor;
    random["seed"] = r.seed;
    random["budget"] = exact(scenario.budget.value_or(r.budget));
    random["noise_scale"] = exact(r.noise_scale);
    const double energy = scenario.energy.value_or(r.energy);
    if (!std::isinf(energy)) random["energy"] = exact(energy);
    root["random"] = random;
  } else {
    root = parseYamlText(readTextFile(scenario.file, "scenario"), scenario.file);
    // withBudget's and withEnergy's changes, as the file says them.
    if (scenario.budget) {
      root["constraints"]["b"] = std::vector<std::string>{exact(*scenario.budget)};
    }
    if (scenario.energy) {
      root["constraints"]["energy"] =
          std::isinf(*scenario.energy) ? std::string(".inf") : exact(*scenario.energy);
    }
  }
  if (emulate) {
    const auto put = [&root](const char* key, const std::string& name, const std::string& yaml) {
      if (name.empty()) return;  // the scenario's own
      if (yaml == "~") {
        root.remove(key);
      } else {
        root[key] = YAML::Load(yaml);
      }
    };
    put("network", emulate->network_name, emulate->network_yaml);
    put("faults", emulate->faults_name, emulate->faults_yaml);
  }
  YAML::Emitter out;
  out << root;
  return std::string(out.c_str()) + "\n";
}

Experiment parseExperimentYaml(const std::string& text, const std::string& source) {
  const YamlReader in(source);
  const YAML::Node root = parseYamlText(text, source);
  in.rejectUnknownKeys(root, "", {"name", "scenarios", "planners", "runs", "seeds", "emulate"});
  Experiment e;
  e.source = source;
  e.name = root["name"] && root["name"].IsScalar() ? root["name"].Scalar()
                                                   : fs::path(source).stem().string();
  const fs::path folder = fs::path(source).parent_path();

  const YAML::Node scenarios = in.required(root, "scenarios", "scenarios");
  if (!scenarios.IsSequence() || scenarios.size() == 0) {
    in.fail(scenarios, "scenarios", "a list of {file: PATH} or {random: {...}} entries");
  }
  std::vector<SweepScenario> all_scenarios;
  for (std::size_t i = 0; i < scenarios.size(); ++i) {
    const std::string field = "scenarios[" + std::to_string(i) + "]";
    for (SweepScenario& s : readScenario(in, scenarios[i], field, folder)) {
      // Bad input before the first cell runs: every scenario is read and checked now.
      (void)s.load(source + ":" + std::to_string(scenarios[i].Mark().line + 1) + " " + field);
      all_scenarios.push_back(std::move(s));
    }
  }

  const YAML::Node planners = in.required(root, "planners", "planners");
  std::vector<PlannerChoice> all_planners;
  for (const YAML::Node& p : axisValues(in, planners, "planners")) {
    all_planners.push_back(
        readPlanner(in, p, "planners[" + std::to_string(all_planners.size()) + "]", folder));
  }

  int runs = 1000;
  if (root["runs"]) {
    runs = static_cast<int>(in.integer(root["runs"], "runs"));
    if (runs < 2 || runs > 100'000'000)
      in.fail(root["runs"], "runs", "an integer from 2 to 100000000");
  }
  std::vector<std::uint64_t> seeds = {1};
  if (root["seeds"]) {
    seeds.clear();
    for (const YAML::Node& s : axisValues(in, root["seeds"], "seeds")) {
      const long seed = in.integer(s, "seeds");
      if (seed < 0) in.fail(s, "seeds", "integers >= 0");
      seeds.push_back(static_cast<std::uint64_t>(seed));
    }
  }

  // Emulated runs: every value of emulate:'s axes; else one in-process Monte Carlo.
  std::vector<std::optional<EmulatedRuns>> measures = {std::nullopt};
  if (const YAML::Node emulate = root["emulate"]) {
    if (root["runs"]) {
      in.fail(root["runs"], "runs",
              "no runs: beside emulate: (emulated cells run emulate.episodes)");
    }
    measures.clear();
    for (EmulatedRuns& m : readEmulate(in, emulate)) measures.emplace_back(std::move(m));
  }

  std::map<std::string, bool> seen;
  for (const SweepScenario& s : all_scenarios) {
    for (const PlannerChoice& p : all_planners) {
      for (const std::uint64_t seed : seeds) {
        for (const std::optional<EmulatedRuns>& measure : measures) {
          SweepCell cell{s,    p.name, p.surrogate,     p.replan_every_s,
                         seed, runs,   p.schedule_file, measure};
          if (!p.schedule_file.empty() && seed == seeds.front()) {
            // A schedule that does not fit a scenario is bad input, found before any cell runs.
            (void)loadScheduleFile(p.schedule_file, s.load(source));
          }
          if (measure && seed == seeds.front() && &p == &all_planners.front()) {
            checkEmulatedScenario(cell, root["emulate"], source);
          }
          if (!seen.emplace(cell.key(), true).second) {
            throw InputError(source, "scenarios",
                             "cells that differ (two are the same: " + cell.key() + ")");
          }
          e.cells.push_back(std::move(cell));
        }
      }
    }
  }
  return e;
}

Experiment loadExperimentFile(const std::string& path) {
  return parseExperimentYaml(readTextFile(path, "experiment"), path);
}

}  // namespace sensornet
