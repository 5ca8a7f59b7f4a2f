// Your code in the loop (issue 25): `sensornet launch --external-sensors IDS` starts no agent
// for those sensors and waits for a participant that speaks for them in their partition
// (docs/wire-protocol.md, "Sensor"). Here the participant is a sensor_agent the test starts
// itself, outside the launch, so its arrivals are drawn as ours are: the run must be the same run
// as one where the launcher started every agent (costs and counts per episode to the bit). A
// participant that never comes fails the run naming the sensors; an id the scenario does not
// have is bad input before anything starts.

#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "launch_fixture.hpp"

namespace sensornet {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using namespace std::chrono_literals;
using testing::LeftoverGuard;
using testing::readJson;
using testing::RunningProgram;
using testing::runProcess;

constexpr int kEpisodes = 3;
const std::string kSensorAgentProgram = SENSORNET_SENSOR_AGENT;

class ExternalRoles : public testing::LaunchTest {};

TEST_F(ExternalRoles, SensorsSpokenForByAParticipantOfTheUsersMakeTheSameRun) {
  const LeftoverGuard guard(run_id_);
  std::vector<std::string> clean = launchArgs(kEpisodes, "5", dir_ / "clean.json", dir_ / "clean-logs");
  clean.insert(clean.end(), {"--seed", "7", "--no-html"});
  const testing::ProcessResult c = runProcess(clean, 120s);
  ASSERT_EQ(c.exit_code, 0) << c.err;
  const json expected = readJson(dir_ / "clean.json");

  std::vector<std::string> argv = launchArgs(kEpisodes, "5", dir_ / "ext.json", dir_ / "ext-logs");
  argv.insert(argv.end(), {"--seed", "7", "--no-html", "--external-sensors", "2,5"});
  RunningProgram launcher(argv, 120s);
  // The user's participant: it speaks for sensors 2 and 5 only, and leaves with the run.
  RunningProgram external({kSensorAgentProgram, "--run-id", run_id_, "--sensors", "2,5"}, 120s);
  const testing::ProcessResult& r = launcher.result();
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(external.result().exit_code, 0) << external.result().err;
  EXPECT_NE(r.err.find("sensors 2,5 are external"), std::string::npos) << r.err;
  EXPECT_EQ(r.err.find("sensor_agent-2"), std::string::npos) << "an agent was started for sensor 2";
  EXPECT_EQ(r.err.find("sensor_agent-5"), std::string::npos) << "an agent was started for sensor 5";

  const json report = readJson(dir_ / "ext.json");
  ASSERT_TRUE(report.is_object()) << r.err;
  EXPECT_EQ(report.at("status"), "completed") << report.at("faults").dump();
  EXPECT_EQ(report.at("external").at("sensors"), json::array({2, 5}));
  const json& got = report.at("per_episode");
  const json& want = expected.at("per_episode");
  ASSERT_EQ(got.size(), want.size());
  for (std::size_t k = 0; k < got.size(); ++k) {
    EXPECT_EQ(got[k].at("realized_cost").get<double>(), want[k].at("realized_cost").get<double>())
        << "episode " << k;
    EXPECT_EQ(got[k].at("received"), want[k].at("received")) << "episode " << k;
    EXPECT_EQ(got[k].at("sent"), got[k].at("received")) << "episode " << k;
  }
}

TEST_F(ExternalRoles, AnExternalSensorNobodySpeaksForFailsTheRunNamingIt) {
  const LeftoverGuard guard(run_id_);
  std::vector<std::string> argv = launchArgs(2, "5");
  argv.insert(argv.end(), {"--no-html", "--external-sensors", "3", "--ready-timeout", "3"});
  const testing::ProcessResult r = runProcess(argv, 90s);
  EXPECT_EQ(r.exit_code, 1) << r.err;
  const std::string why = "no participant spoke for the external sensors 3 (--external-sensors)";
  EXPECT_NE(r.err.find(why), std::string::npos) << r.err;
  const json report = readJson(dir_ / "report.json");
  ASSERT_TRUE(report.is_object()) << r.err;
  EXPECT_EQ(report.at("status"), "failed");
  EXPECT_EQ(report.at("episodes_planned"), 2) << "the plan is what the launch asked for";
  EXPECT_NE(r.out.find("episodes: 0 complete, 0 incomplete, of 2 planned"), std::string::npos)
      << r.out;
  bool named = false;
  for (const json& f : report.at("faults")) {
    named |= f.at("process") == "coordinator" &&
             f.at("detail").get<std::string>().find(why) != std::string::npos;
  }
  EXPECT_TRUE(named) << report.at("faults").dump();
}

TEST_F(ExternalRoles, AnExternalSensorTheScenarioDoesNotHaveIsBadInput) {
  std::vector<std::string> argv = launchArgs(2, "5");
  argv.insert(argv.end(), {"--external-sensors", "2,9"});
  const testing::ProcessResult r = runProcess(argv, 30s);
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  EXPECT_NE(r.err.find("--external-sensors"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("got 9"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(dir_ / "logs")) << "nothing may start on bad input";
}

}  // namespace
}  // namespace sensornet
