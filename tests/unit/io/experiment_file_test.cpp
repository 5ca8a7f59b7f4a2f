// The experiment file of `sensornet sweep` (experiment_file.hpp): its cells are the product of
// its axes, each named by a key that tells them apart, and a bad file is one line naming the
// file, the line and the field, before any cell runs.

#include "sensornet/io/experiment_file.hpp"

#include <gtest/gtest.h>

#include <set>
#include <string>

#include "sensornet/core/input_error.hpp"
#include "sensornet/io/scenario_file.hpp"

namespace sensornet {
namespace {

const std::string kSource = std::string(SENSORNET_SOURCE_DIR) + "/examples/experiments/test.yaml";

// Matrices of the same size and entries (Eigen's == needs the same size).
bool same(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b) {
  return a.rows() == b.rows() && a.cols() == b.cols() && a == b;
}

std::string errorOf(const std::string& yaml) {
  try {
    (void)parseExperimentYaml(yaml, kSource);
  } catch (const InputError& e) {
    return e.what();
  }
  return "(no error)";
}

TEST(ExperimentFile, CellsAreTheProductOfTheAxes) {
  const Experiment e = parseExperimentYaml(R"(
scenarios:
  - random: {states: 3, sensors: [4, 6], seed: [1, 2, 3], budget: [2, 5]}
    intervals: 6
  - file: ../../scenarios/default.yaml
planners: [info, uniform, {closed_loop: cov, replan_every: 0.5}]
runs: 200
seeds: [7, 8]
)",
                                           kSource);
  // (2 sensors x 3 seeds x 2 budgets + 1 file) scenarios x 3 planners x 2 seeds.
  ASSERT_EQ(e.cells.size(), (2u * 3u * 2u + 1u) * 3u * 2u);
  std::set<std::string> keys;
  for (const SweepCell& c : e.cells) keys.insert(c.key());
  EXPECT_EQ(keys.size(), e.cells.size());
  EXPECT_EQ(e.name, "test");  // the file's stem without name:
  const SweepCell& first = e.cells.front();
  ASSERT_TRUE(first.scenario.random.has_value());
  EXPECT_EQ(first.scenario.random->state_dim, 3);
  EXPECT_EQ(first.scenario.random->intervals, 6);
  EXPECT_EQ(first.planner, "info");
  EXPECT_EQ(first.seed, 7u);
  EXPECT_EQ(first.runs, 200);
  const SweepCell& last = e.cells.back();
  EXPECT_EQ(last.scenario.file, std::string(SENSORNET_SOURCE_DIR) + "/scenarios/default.yaml");
  EXPECT_EQ(last.planner, "closed_loop");
  EXPECT_EQ(last.surrogate, PlanSurrogate::Covariance);
  EXPECT_EQ(last.replan_every_s, 0.5);
  EXPECT_EQ(last.seed, 8u);
  // The budget axis reaches the random plant, and the scenario it loads.
  std::set<double> budgets;
  for (const SweepCell& c : e.cells) {
    if (c.scenario.random) budgets.insert(c.scenario.random->budget);
  }
  EXPECT_EQ(budgets, (std::set<double>{2.0, 5.0}));
  EXPECT_EQ(e.cells[3 * 2].scenario.random->budget, 5.0);  // the budget varies fastest
  EXPECT_EQ(first.scenario.load("test").constraints.b(0), 2.0);
}

TEST(ExperimentFile, ABudgetOfAFileNeedsOneConstraintRow) {
  const Experiment e = parseExperimentYaml(R"(
scenarios: [{file: ../../scenarios/paper.yaml, budget: [3, 4.5]}]
planners: cov
)",
                                           kSource);
  ASSERT_EQ(e.cells.size(), 2u);
  EXPECT_EQ(e.cells[1].scenario.load("test").constraints.b(0), 4.5);
  EXPECT_NE(e.cells[0].key(), e.cells[1].key());
  EXPECT_NE(
      errorOf("scenarios: [{file: ../../scenarios/default.yaml, budget: 3}]\nplanners: [info]\n")
          .find("one constraint row (this one has 2"),
      std::string::npos);
}

// An energy axis beside budget: (or inside random:) multiplies the scenarios, reaches the
// scenario each cell loads, and names its cells apart; without one the keys are as before.
TEST(ExperimentFile, AnEnergyAxisReachesEveryCellsScenario) {
  const Experiment e = parseExperimentYaml(R"(
scenarios:
  - random: {states: 3, sensors: 4, seed: 1, energy: [0.5, 2]}
    intervals: 6
  - file: ../../scenarios/paper.yaml
    budget: [3, 4]
    energy: 1.5
planners: [info]
)",
                                           kSource);
  ASSERT_EQ(e.cells.size(), 4u);
  EXPECT_EQ(e.cells[0].scenario.energy, 0.5);
  EXPECT_EQ(e.cells[1].scenario.energy, 2.0);
  EXPECT_TRUE(e.cells[0].scenario.load("test").constraints.energy.isApprox(
      Eigen::VectorXd::Constant(4, 0.5)));
  const Scenario paper = e.cells[3].scenario.load("test");
  EXPECT_EQ(paper.constraints.b(0), 4.0);
  EXPECT_TRUE(paper.constraints.energy.isApprox(Eigen::VectorXd::Constant(paper.sensorCount(), 1.5)));
  EXPECT_NE(e.cells[0].key(), e.cells[1].key());
  EXPECT_NE(e.cells[0].key().find(";energy=0.5"), std::string::npos) << e.cells[0].key();
  const Experiment plain = parseExperimentYaml(
      "scenarios: [{random: {states: 3, sensors: 4, seed: 1}}]\nplanners: [info]\n", kSource);
  EXPECT_EQ(plain.cells[0].key().find("energy"), std::string::npos);
  EXPECT_FALSE(plain.cells[0].scenario.load("test").constraints.hasEnergyBudgets());
  EXPECT_NE(errorOf("scenarios: [{random: {states: 2, sensors: 3, seed: 1, energy: 1}, energy: 2}]\n"
                    "planners: [info]\n")
                .find("the energy in one place only"),
            std::string::npos);
  EXPECT_NE(errorOf("scenarios: [{random: {states: 2, sensors: 3, seed: 1}, energy: [1, 0]}]\n"
                    "planners: [info]\n")
                .find("test.yaml:1: scenarios[0].energy: expected a number > 0"),
            std::string::npos)
      << errorOf("scenarios: [{random: {states: 2, sensors: 3, seed: 1}, energy: [1, 0]}]\n"
                 "planners: [info]\n");
}

// A fixed schedule file as a planner, relative to the experiment; one that does not fit a
// scenario is bad input before any cell runs.
TEST(ExperimentFile, AScheduleFileIsAPlannerThatMustFitEveryScenario) {
  const Experiment e = parseExperimentYaml(R"(
scenarios:
  - random: {states: 5, sensors: 30, seed: 1, budget: 5, noise_scale: [1, 10]}
planners: [{schedule: schedules/reference-info.json}, info]
)",
                                           kSource);
  ASSERT_EQ(e.cells.size(), 4u);
  EXPECT_EQ(e.cells[0].planner, "schedule");
  EXPECT_EQ(e.cells[0].schedule_file,
            std::string(SENSORNET_SOURCE_DIR) + "/examples/experiments/schedules/reference-info.json");
  EXPECT_NE(e.cells[0].key(), e.cells[2].key());  // the two noise scales
  EXPECT_NE(e.cells[0].key().find("planner=schedule("), std::string::npos) << e.cells[0].key();
  const std::string misfit =
      errorOf("scenarios: [{random: {states: 5, sensors: 4, seed: 1}}]\n"
              "planners: [{schedule: schedules/reference-info.json}]\n");
  EXPECT_NE(misfit.find("reference-info.json"), std::string::npos) << misfit;
  EXPECT_NE(misfit.find("30 x 30"), std::string::npos) << misfit;
  EXPECT_NE(errorOf("scenarios: [{random: {states: 5, sensors: 4, seed: 1}}]\n"
                    "planners: [{schedule: nowhere.json}]\n")
                .find("nowhere.json"),
            std::string::npos);
}

// emulate: makes every cell a whole run: its axes (time_scale, named network and fault sections)
// multiply the cells, and each cell's scenario file is the scenario its Monte Carlo would load,
// with the section of its name in place of the file's own (~: none), read back field by field.
TEST(ExperimentFile, EmulatedCellsWriteTheScenarioTheirRunReads) {
  const Experiment e = parseExperimentYaml(R"(
scenarios:
  - file: ../../scenarios/lossy.yaml
    energy: 2.5
  - random: {states: 3, sensors: 4, seed: 5, budget: 3}
    intervals: 6
planners: [cov]
seeds: [1, 2]
emulate:
  episodes: 3
  time_scale: [2, 8]
  network: {own: ~, lossy: {default: {loss: 0.25}}}
  faults: {crash: [{kind: crash, sensor: 1, episode: 2, at: 0.5}]}
)",
                                           kSource);
  // 2 scenarios x 1 planner x 2 seeds x 2 time scales x 2 networks.
  ASSERT_EQ(e.cells.size(), 16u);
  std::set<std::string> keys, ids;
  for (const SweepCell& c : e.cells) {
    keys.insert(c.key());
    ids.insert(c.id());
    ASSERT_TRUE(c.emulate.has_value());
    EXPECT_EQ(c.emulate->episodes, 3);
    EXPECT_EQ(c.key().find(";runs="), std::string::npos);
    const Scenario loaded = c.scenario.load("test");
    const Scenario written = parseScenarioYaml(c.scenarioYaml(), "written");
    EXPECT_TRUE(same(written.plant.A, loaded.plant.A));
    EXPECT_TRUE(same(written.plant.Q, loaded.plant.Q));
    ASSERT_EQ(written.sensorCount(), loaded.sensorCount());
    for (int j = 0; j < loaded.sensorCount(); ++j) {
      EXPECT_TRUE(same(written.sensors[j].H, loaded.sensors[j].H));
      EXPECT_TRUE(same(written.sensors[j].R, loaded.sensors[j].R));
    }
    EXPECT_TRUE(same(written.constraints.C, loaded.constraints.C));
    EXPECT_TRUE(same(written.constraints.b, loaded.constraints.b));
    EXPECT_TRUE(same(written.constraints.energy, loaded.constraints.energy));
    EXPECT_EQ(written.horizon_s, loaded.horizon_s);
    if (c.emulate->network_name == "lossy") {
      ASSERT_TRUE(written.network.has_value());
      EXPECT_EQ(written.network->links.at(1).loss, 0.25);
      EXPECT_TRUE(written.network->outages.empty());  // lossy.yaml's own section is replaced
    } else {
      EXPECT_FALSE(written.network.has_value());  // ~: none, though lossy.yaml has one
    }
    ASSERT_EQ(written.faults.size(), 1u);
    EXPECT_EQ(written.faults[0].sensor, 1);
    EXPECT_EQ(written.faults[0].episode, 2u);
  }
  EXPECT_EQ(keys.size(), 16u);
  EXPECT_EQ(ids.size(), 16u);
  EXPECT_EQ(e.cells[0].emulate->time_scale, 2.0);
  EXPECT_TRUE(e.cells[0].scenario.load("test").constraints.energy.isApprox(
      Eigen::VectorXd::Constant(6, 2.5)));
  // The same name with another section is another cell (a digest of it is in the key).
  const std::string other =
      parseExperimentYaml(
          "scenarios: [{random: {states: 3, sensors: 4, seed: 5}}]\nplanners: [cov]\n"
          "emulate: {network: {lossy: {default: {loss: 0.5}}}}\n",
          kSource)
          .cells[0]
          .key();
  const std::string first =
      parseExperimentYaml(
          "scenarios: [{random: {states: 3, sensors: 4, seed: 5}}]\nplanners: [cov]\n"
          "emulate: {network: {lossy: {default: {loss: 0.25}}}}\n",
          kSource)
          .cells[0]
          .key();
  EXPECT_NE(other, first);
  EXPECT_NE(first.find("network=lossy#"), std::string::npos) << first;
}

TEST(ExperimentFile, BadEmulatedRunsAreOneLineNamingTheSection) {
  const std::string head =
      "scenarios: [{random: {states: 2, sensors: 3, seed: 1}}]\nplanners: [info]\n";
  EXPECT_NE(errorOf(head + "runs: 100\nemulate: {episodes: 2}\n")
                .find("test.yaml:3: runs: expected no runs: beside emulate:"),
            std::string::npos)
      << errorOf(head + "runs: 100\nemulate: {episodes: 2}\n");
  EXPECT_NE(errorOf(head + "emulate: {episodes: 0}\n")
                .find("emulate.episodes: expected an integer from 1"),
            std::string::npos);
  EXPECT_NE(errorOf(head + "emulate: {time_scale: [1, 0]}\n")
                .find("emulate.time_scale: expected a number from 0.001"),
            std::string::npos);
  EXPECT_NE(errorOf(head + "emulate: {on_sensor_failure: ignore}\n")
                .find("emulate.on_sensor_failure: expected replan, continue or stop"),
            std::string::npos);
  EXPECT_NE(errorOf(head + "emulate: {episode: 3}\n").find("episode"), std::string::npos);
  const std::string loss = errorOf(head + "emulate:\n  network:\n    bad: {default: {loss: 2}}\n");
  EXPECT_NE(loss.find("test.yaml:5: emulate.network.bad (network.default.loss): expected"),
            std::string::npos)
      << loss;
  const std::string sensor = errorOf(
      head + "emulate:\n  faults:\n    far: [{kind: crash, sensor: 7, episode: 0, at: 1}]\n");
  EXPECT_NE(sensor.find("test.yaml:5: emulate.faults.far (faults[0].sensor): expected"),
            std::string::npos)
      << sensor;
  EXPECT_EQ(sensor.find('\n'), std::string::npos);
}

TEST(ExperimentFile, BadInputNamesTheFileLineAndField) {
  EXPECT_NE(errorOf("planners: [info]\n").find("scenarios"), std::string::npos);
  EXPECT_NE(errorOf("scenarios: [{random: {states: 2, sensors: 3, seed: 1}}]\nplanners: [best]\n")
                .find("test.yaml:2: planners[0]: expected info, cov, uniform, mc, timetable,"),
            std::string::npos)
      << errorOf("scenarios: [{random: {states: 2, sensors: 3, seed: 1}}]\nplanners: [best]\n");
  EXPECT_NE(
      errorOf("scenarios: [{random: {states: 2, sensors: [3, x], seed: 1}}]\nplanners: [info]\n")
          .find("scenarios[0].random.sensors"),
      std::string::npos);
  EXPECT_NE(errorOf("scenarios: [{file: a.yaml, random: {states: 2}}]\nplanners: [info]\n")
                .find("either file:"),
            std::string::npos);
  EXPECT_NE(errorOf("scenarios: [{file: missing.yaml}]\nplanners: [info]\n").find("missing.yaml"),
            std::string::npos);
  EXPECT_NE(
      errorOf(
          "scenarios: [{random: {states: 2, sensors: 3, seed: 1}}]\nplanners: [info]\nrunz: 3\n")
          .find("runz"),
      std::string::npos);
  EXPECT_NE(
      errorOf(
          "scenarios: [{random: {states: 2, sensors: 3, seed: 1}}]\nplanners: [info]\nruns: 1\n")
          .find("runs: expected an integer from 2"),
      std::string::npos);
  EXPECT_NE(errorOf("scenarios: [{random: {states: 2, sensors: 3, seed: 1}}]\n"
                    "planners: [{closed_loop: info}]\n")
                .find("replan_every"),
            std::string::npos);
  EXPECT_NE(
      errorOf("scenarios: [{random: {states: 2, sensors: 3, seed: 1}}]\nplanners: [info, info]\n")
          .find("two are the same"),
      std::string::npos);
  EXPECT_NE(errorOf("scenarios: [\n").find("valid YAML"), std::string::npos);
}

}  // namespace
}  // namespace sensornet
