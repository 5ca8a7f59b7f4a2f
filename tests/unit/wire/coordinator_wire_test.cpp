// The coordinator's samples as its core's events and back: every command kind maps to its
// event kind, a command's fields and sender arrive as sent, a
// report's summary and a fusion state's covariance are copied, and an episode control sample
// says what the control says.
#include "sensornet/wire/coordinator_wire.hpp"

#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "sensornet/dds/wire.hpp"

namespace sensornet::wire {
namespace {

using namespace sensornet::emulator;  // the core types the samples carry

TEST(CoordinatorWire, EveryCommandKindIsItsEventKind) {
  EXPECT_EQ(commandKindOf(sensornet_COMMAND_REPLAN), CommandKind::Replan);
  EXPECT_EQ(commandKindOf(sensornet_COMMAND_EXCLUDE_SENSORS), CommandKind::ExcludeSensors);
  EXPECT_EQ(commandKindOf(sensornet_COMMAND_SET_BUDGET), CommandKind::SetBudget);
  EXPECT_EQ(commandKindOf(sensornet_COMMAND_SCHEDULE_FILE), CommandKind::ScheduleFile);
  EXPECT_EQ(commandKindOf(sensornet_COMMAND_STATUS), CommandKind::Status);
  EXPECT_EQ(commandKindOf(sensornet_COMMAND_SHUTDOWN), CommandKind::Shutdown);
  EXPECT_EQ(commandKindOf(sensornet_COMMAND_SENSORS_FAILED), CommandKind::SensorsFailed);
  EXPECT_EQ(commandKindOf(sensornet_COMMAND_INCLUDE_SENSORS), CommandKind::IncludeSensors);
}

TEST(CoordinatorWire, ACommandArrivesAsSentWithItsSender) {
  const std::string run = "run-7", issuer = "ops", surrogate = "cov", schedule = "{}",
                    detail = "why";
  std::vector<std::uint32_t> ids{2, 5};
  std::vector<double> budget{1.5, 2.5};
  sensornet_Command c{};
  c.run_id = dds::borrowString(run);
  c.command_id = 42;
  c.kind = sensornet_COMMAND_REPLAN;
  c.issuer = dds::borrowString(issuer);
  c.surrogate = dds::borrowString(surrogate);
  c.schedule_json = dds::borrowString(schedule);
  c.detail = dds::borrowString(detail);
  dds::borrowSequence(c.sensor_ids, ids);
  dds::borrowSequence(c.budget, budget);
  const CommandEvent e = commandOf(c, CommandSender::Operator);
  EXPECT_EQ(e.sender, CommandSender::Operator);
  EXPECT_EQ(e.run_id, run);
  EXPECT_EQ(e.command_id, 42u);
  EXPECT_EQ(e.kind, CommandKind::Replan);
  EXPECT_EQ(e.issuer, issuer);
  EXPECT_EQ(e.surrogate, surrogate);
  EXPECT_EQ(e.sensor_ids, ids);
  EXPECT_EQ(e.budget, budget);
  EXPECT_EQ(e.schedule_json, schedule);
  EXPECT_EQ(e.detail, detail);
}

TEST(CoordinatorWire, AReportAndAFusionStateAreCopied) {
  sensornet_Report r{};
  r.episode = 3;
  r.realized_cost = 1.25;
  r.bracket_lower = 1.0;
  r.bracket_upper = 2.0;
  r.summary.episodes = 4;
  r.summary.realized_mean = 1.5;
  r.summary.realized_ci95_low = 1.375;
  r.summary.realized_ci95_high = 1.625;
  const ReportEvent e = reportOf(r);
  EXPECT_EQ(e.episode, 3u);
  EXPECT_EQ(e.realized_cost, 1.25);
  EXPECT_EQ(e.bracket_upper, 2.0);
  EXPECT_EQ(e.episodes_summarized, 4u);
  EXPECT_EQ(e.realized_ci95_high, 1.625);

  std::vector<double> p{1.0, 0.5, 0.5, 2.0};
  sensornet_FusionState s{};
  s.episode = 2;
  s.emulated_time_s = 0.75;
  s.state_dim = 2;
  dds::borrowSequence(s.covariance, p);
  const FusionStateEvent f = fusionStateOf(s);
  EXPECT_EQ(f.episode, 2u);
  EXPECT_EQ(f.emulated_time_s, 0.75);
  EXPECT_EQ(f.state_dim, 2u);
  EXPECT_EQ(f.values, p);
}

TEST(CoordinatorWire, AnEpisodeControlSampleSaysWhatTheControlSays) {
  EpisodeControl control;
  control.kind = ControlKind::SensorsFailed;
  control.episode = 5;
  control.start_wall_ns = 123;
  control.time_scale = 2.0;
  control.seed = 9;
  control.schedule_version = 3;
  control.episodes_planned = 10;
  control.failed_at_s = 0.5;
  control.aborted = true;
  control.detail = "sensor 1 died";
  control.failed_sensors = {1};
  const std::string run = "run-1";
  const sensornet_EpisodeControl c = wireControl(control, run);
  EXPECT_EQ(dds::viewString(c.run_id), run);
  EXPECT_EQ(c.command, sensornet_EPISODE_SENSORS_FAILED);
  EXPECT_EQ(c.episode, 5u);
  EXPECT_EQ(c.start_wall_time_ns, 123);
  EXPECT_EQ(c.time_scale, 2.0);
  EXPECT_EQ(c.schedule_version, 3u);
  EXPECT_EQ(c.episodes_planned, 10u);
  EXPECT_TRUE(c.aborted);
  EXPECT_EQ(dds::viewString(c.detail), "sensor 1 died");
  ASSERT_EQ(dds::viewSequence(c.failed_sensors).size(), 1u);
  EXPECT_EQ(episodeCommandOf(ControlKind::EpisodeStart), sensornet_EPISODE_START);
  EXPECT_EQ(episodeCommandOf(ControlKind::RunShutdown), sensornet_RUN_SHUTDOWN);
}

}  // namespace
}  // namespace sensornet::wire
