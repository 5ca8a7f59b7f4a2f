// How the coordinator starts a run: version 1 is the schedule file's (surrogate "file") or the
// plan of the run's surrogate, with its bracket from P0; a journal of another scenario or seed
// is refused naming the field.
#include "sensornet/emulator/coordinator_start.hpp"

#include <gtest/gtest.h>

#include <string>

#include "sensornet/core/input_error.hpp"
#include "sensornet/io/scenario_file.hpp"

namespace sensornet::emulator {
namespace {

Scenario defaultScenario() {
  return loadScenarioFile(std::string(SENSORNET_SOURCE_DIR) + "/scenarios/default.yaml");
}

TEST(CoordinatorStart, AScheduleFileIsVersionOneAsItIs) {
  const Scenario scenario = defaultScenario();
  RateSchedule file = uniformSchedule(scenario);
  const ScheduleVersion v = firstVersion(scenario, PlanSurrogate::Covariance, false, file);
  EXPECT_EQ(v.version, 1u);
  EXPECT_EQ(v.effective_episode, 0u);
  EXPECT_EQ(v.surrogate, SurrogateKind::File);
  EXPECT_EQ(v.schedule.rates(), file.rates());
  const CostBracket bracket = computeBracket(scenario, file);
  EXPECT_EQ(v.bracket.info, bracket.info);
  EXPECT_EQ(v.bracket.cov, bracket.cov);
}

TEST(CoordinatorStart, WithoutAFileVersionOneIsThePlanOfTheRunsSurrogate) {
  const Scenario scenario = defaultScenario();
  const ScheduleVersion v = firstVersion(scenario, PlanSurrogate::Uniform, false, std::nullopt);
  EXPECT_EQ(v.surrogate, SurrogateKind::Uniform);
  EXPECT_EQ(v.schedule.rates(), uniformSchedule(scenario).rates());
  EXPECT_LE(v.bracket.info, v.bracket.cov);
}

TEST(CoordinatorStart, AJournalOfAnotherScenarioOrSeedIsRefused) {
  CoordinatorJournal journal;
  journal.scenario_digest = "abc";
  journal.seed = 7;
  EXPECT_NO_THROW(checkJournalOfRun(journal, "state.json", "abc", "s.yaml", 7));
  try {
    checkJournalOfRun(journal, "state.json", "def", "s.yaml", 7);
    FAIL() << "accepted another scenario's journal";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("scenario_digest"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("def from --scenario s.yaml"), std::string::npos)
        << e.what();
  }
  try {
    checkJournalOfRun(journal, "state.json", "abc", "s.yaml", 8);
    FAIL() << "accepted another seed's journal";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("--seed 8"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace sensornet::emulator
