// How the coordinator starts a run: version 1 is the schedule file's (surrogate "file") or the
// plan of the run's surrogate, with its bracket from P0; a journal of another scenario or seed
// is refused naming the field; what cannot start is refused before any planning; a resumed run
// keeps its own episode count and time scale, whatever the command line says.
#include "sensornet/emulator/coordinator_start.hpp"

#include <gtest/gtest.h>

#include <string>

#include "sensornet/core/input_error.hpp"
#include "sensornet/io/scenario_file.hpp"
#include "../../support/scratch_dir.hpp"

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

RunScenario defaultRun(std::uint64_t seed = 5) {
  return {defaultScenario(), "digest-of-default", "", seed};
}

TEST(CoordinatorStart, WhatCannotStartIsRefusedNamingTheOption) {
  const Scenario scenario = defaultScenario();  // no network: section
  CoordinatorConfig config;
  EXPECT_NO_THROW(checkServeRequest(config, scenario, "s.yaml", PlanSurrogate::Uniform));
  config.network_aware = true;
  try {
    checkServeRequest(config, scenario, "s.yaml", PlanSurrogate::Covariance);
    FAIL() << "--network-aware without a network: section was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("s.yaml"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("network"), std::string::npos) << e.what();
  }
  config.network_aware = false;
  config.replan_every_s = 2.0;
  EXPECT_NO_THROW(checkServeRequest(config, scenario, "s.yaml", PlanSurrogate::Information));
  try {
    checkServeRequest(config, scenario, "s.yaml", PlanSurrogate::Uniform);
    FAIL() << "a closed loop with the uniform schedule was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("--replan-every"), std::string::npos) << e.what();
  }
}

TEST(CoordinatorStart, AFreshJournalHoldsTheRunAndVersionOne) {
  const RunScenario run = defaultRun();
  CoordinatorConfig config;
  config.run_id = "fresh";
  config.episodes = 12;
  const RateSchedule file = uniformSchedule(run.scenario);
  const CoordinatorJournal journal = freshJournal(config, run, PlanSurrogate::Covariance, file);
  EXPECT_EQ(journal.run_id, "fresh");
  EXPECT_EQ(journal.scenario_digest, run.digest);
  EXPECT_EQ(journal.seed, run.seed);
  EXPECT_EQ(journal.episodes_planned, 12U);
  ASSERT_EQ(journal.versions.size(), 1U);
  EXPECT_EQ(journal.versions[0].surrogate, SurrogateKind::File);
  EXPECT_EQ(journal.versions[0].schedule.rates(), file.rates());
}

TEST(CoordinatorStart, AResumedRunKeepsItsOwnLengthAndPace) {
  testing::ScratchDir dir;
  const RunScenario run = defaultRun();
  CoordinatorConfig first;
  first.run_id = "resumed";
  first.episodes = 7;
  first.time_scale = 2.5;
  const std::string state = dir.file("state.json");
  saveJournal(state, freshJournal(first, run, PlanSurrogate::Uniform, std::nullopt));

  CoordinatorConfig again;  // the command line of the restart: other values
  again.run_id = "resumed";
  again.episodes = 20;
  again.time_scale = 1.0;
  const CoordinatorJournal journal = resumedJournal(again, run, state, "s.yaml");
  EXPECT_EQ(again.episodes, 7);
  EXPECT_EQ(again.time_scale, 2.5);
  EXPECT_EQ(journal.versions.size(), 1U);

  CoordinatorConfig other_seed = again;
  EXPECT_THROW((void)resumedJournal(other_seed, defaultRun(6), state, "s.yaml"), InputError);
}

}  // namespace
}  // namespace sensornet::emulator
