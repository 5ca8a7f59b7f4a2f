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

  // "scenario=...;planner=...;seed=...;runs=..." with every number written exactly.
  [[nodiscard]] std::string key() const;
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
