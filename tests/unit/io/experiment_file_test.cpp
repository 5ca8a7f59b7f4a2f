// The experiment file of `sensornet sweep` (experiment_file.hpp): its cells are the product of
// its axes, each named by a key that tells them apart, and a bad file is one line naming the
// file, the line and the field, before any cell runs.

#include "sensornet/io/experiment_file.hpp"

#include <gtest/gtest.h>

#include <set>
#include <string>

#include "sensornet/core/input_error.hpp"

namespace sensornet {
namespace {

const std::string kSource = std::string(SENSORNET_SOURCE_DIR) + "/examples/experiments/test.yaml";

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
