#pragma once
// The experiment file of `sensornet sweep` (docs/reference/file-formats.md, "Experiment files"):
// which scenarios, planners and seeds, every list value an axis, and how each cell is measured.
// A cell is one value of every axis; cells() lists them in a fixed order, each with a key that
// names it in the results (a cell whose key is already there is not run again).
//
//   const Experiment e = loadExperimentFile("fig1.yaml");   // or InputError naming the field
//   for (const SweepCell& cell : e.cells()) { ... cell.key() ... }

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "sensornet/core/scenario.hpp"
#include "sensornet/core/surrogate_kind.hpp"

namespace sensornet {

// One scenario of a cell: a scenario file, or the first paper's random plant; and the budget
// that replaces the bound of its one constraint row, when an axis sets it.
struct SweepScenario {
  std::string file;                       // a scenario file (as written, resolved), or empty
  std::optional<RandomPlantSpec> random;  // or a random plant
  std::optional<double> budget;
  std::optional<double> energy;  // every sensor's energy budget (Scenario: constraints.energy)

  // The validated scenario (throws InputError naming `source` when it is not one).
  [[nodiscard]] Scenario load(const std::string& source) const;
};

// How an emulated cell is measured (the experiment's `emulate:`): whole `sensornet launch` runs
// of the cell's scenario and schedule over Cyclone DDS, instead of the in-process Monte Carlo.
struct EmulatedRuns {
  int episodes = 5;
  double time_scale = 4.0;  // emulated seconds per wall second
  // The network and faults sections the cell's scenario file gets, each named in the results;
  // an empty name keeps the scenario's own section. The YAML is the section's value (flow
  // style), "~" for none.
  std::string network_name, network_yaml;
  std::string faults_name, faults_yaml;
  std::string on_sensor_failure;  // replan, continue or stop; empty: the launcher's default
};

struct SweepCell {
  SweepScenario scenario;
  // info, cov, uniform, mc, closed_loop, timetable (the plan of `surrogate` measured with
  // deterministic instants: sensor j's k-th where ∫λ_j reaches k - 1/2), or schedule (the
  // schedule file `schedule_file`, measured as it is: the paper's fixed-schedule sweeps)
  std::string planner;
  PlanSurrogate surrogate = PlanSurrogate::Information;  // the plan's (closed loop: the tails')
  double replan_every_s = 0.0;                           // closed_loop only
  std::uint64_t seed = 1;                                // the Monte Carlo's (and mc's) seed
  int runs = 1000;                                       // Monte Carlo episodes
  std::string schedule_file{};                           // schedule only (resolved)
  // Measured by emulated runs (then `seed` is the run's --seed and `runs` is not used).
  std::optional<EmulatedRuns> emulate{};

  // "scenario=...;planner=...;seed=...;runs=..." with every number written exactly (an
  // emulated cell: ";emulate(...)" in place of the runs, with a digest of each section).
  [[nodiscard]] std::string key() const;
  // 16 hex digits of a digest of key(): names the cell's folder and run.
  [[nodiscard]] std::string id() const;
  // The cell's scenario as a scenario file: the file or random plant with the cell's budget,
  // energy, and (emulated) network and faults sections. Loading it gives scenario.load().
  [[nodiscard]] std::string scenarioYaml() const;
};

struct Experiment {
  std::string source;  // the file, for messages
  std::string name;    // `name:`, else the file's stem
  std::vector<SweepCell> cells;
};

// Parses and checks the experiment (every scenario it names is loaded and validated, so that a
// bad cell is bad input before the first cell runs). Scenario files are relative to the
// experiment file's folder. Throws InputError naming the file, line and field.
[[nodiscard]] Experiment parseExperimentYaml(const std::string& text, const std::string& source);
[[nodiscard]] Experiment loadExperimentFile(const std::string& path);

}  // namespace sensornet
