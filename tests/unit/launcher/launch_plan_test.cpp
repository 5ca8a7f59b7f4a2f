// The launch plan: which processes a launch starts, in which order, and what reaches each one's
// argv. Every expected argv here is written out by hand from the option it tests.

#include "sensornet/launcher/launch_plan.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <string>
#include <vector>

#include "sensornet/core/input_error.hpp"

namespace sensornet::launcher {
namespace {

using Argv = std::vector<std::string>;

PlanContext context(int sensors) {
  PlanContext c;
  c.run_id = "run-7";
  c.programs = {"/bin/coordinator", "/bin/fusion_center", "/bin/sensor_agent"};
  c.run_flags = {"--run-id", "run-7"};
  c.default_log_dir = "/scratch/run-7";
  c.sensor_count = sensors;
  return c;
}

LaunchOptions options() {
  LaunchOptions o;
  o.scenario_path = "/s/scenario.yaml";
  return o;
}

const ChildSpec& child(const LaunchPlan& plan, const std::string& name) {
  const auto it = std::find_if(plan.children.begin(), plan.children.end(),
                               [&](const ChildSpec& c) { return c.name == name; });
  if (it == plan.children.end()) throw std::runtime_error("no child " + name);
  return *it;
}

bool has(const Argv& argv, const Argv& words) {
  return std::search(argv.begin(), argv.end(), words.begin(), words.end()) != argv.end();
}

std::vector<std::string> names(const LaunchPlan& plan) {
  std::vector<std::string> out;
  for (const ChildSpec& c : plan.children) out.push_back(c.name);
  return out;
}

TEST(LaunchPlan, ByDefaultFusionCenterThenOneAgentPerSensorThenCoordinator) {
  const LaunchPlan plan = planLaunch(options(), context(3));
  EXPECT_EQ(names(plan), (std::vector<std::string>{"fusion_center", "sensor_agent-0",
                                                   "sensor_agent-1", "sensor_agent-2",
                                                   "coordinator"}));
  EXPECT_EQ(plan.log_dir, "/scratch/run-7");
  EXPECT_TRUE(plan.default_log_dir);
  EXPECT_EQ(plan.report_path, "/scratch/run-7/report.json");
  EXPECT_EQ(child(plan, "fusion_center").argv,
            (Argv{"/bin/fusion_center", "serve", "--report", "/scratch/run-7/report.json",
                  "--report-fallback", "/scratch/run-7", "--run-id", "run-7"}));
  EXPECT_EQ(child(plan, "sensor_agent-1").argv,
            (Argv{"/bin/sensor_agent", "--sensors", "1", "--run-id", "run-7"}));
  EXPECT_EQ(child(plan, "sensor_agent-1").log_path, "/scratch/run-7/sensor_agent-1.log");
  EXPECT_EQ(child(plan, "fusion_center").parent_death_signal, SIGUSR1)
      << "the fusion center writes the report when the launcher dies";
  EXPECT_EQ(child(plan, "coordinator").parent_death_signal, SIGKILL);
}

TEST(LaunchPlan, TheCoordinatorGetsEveryForwardedOptionWithItsDefaults) {
  const LaunchPlan plan = planLaunch(options(), context(2));
  EXPECT_EQ(child(plan, "coordinator").argv,
            (Argv{"/bin/coordinator", "serve", "--scenario", "/s/scenario.yaml", "--surrogate",
                  "cov", "--episodes", "20", "--time-scale", "1", "--seed", "1",
                  "--on-sensor-failure", "replan", "--state", "/scratch/run-7/coordinator-state.json",
                  "--ready-timeout", "30", "--run-id", "run-7"}));
  EXPECT_EQ(plan.coordinator_state, "/scratch/run-7/coordinator-state.json");
}

TEST(LaunchPlan, EachCoordinatorOptionReachesTheCoordinatorAlone) {
  LaunchOptions o = options();
  o.surrogate = PlanSurrogate::Information;
  o.episodes = 5;
  o.time_scale = 12.5;
  o.seed = "42";
  o.schedule_path = "/s/schedule.json";
  o.on_sensor_failure = emulator::FailurePolicy::Stop;
  o.arrivals = "timetable";
  o.ready_timeout_s = 7;
  o.replan_every_s = 0.25;
  o.switch_margin_s = 0.5;
  o.network_aware = "yes";
  const LaunchPlan plan = planLaunch(o, context(2));
  const Argv& coordinator = child(plan, "coordinator").argv;
  const std::vector<Argv> forwarded = {
      {"--surrogate", "info"},        {"--episodes", "5"},        {"--time-scale", "12.5"},
      {"--seed", "42"},               {"--schedule", "/s/schedule.json"},
      {"--on-sensor-failure", "stop"}, {"--arrivals", "timetable"}, {"--ready-timeout", "7"},
      {"--replan-every", "0.25"},     {"--switch-margin", "0.5"}, {"--network-aware"}};
  for (const Argv& words : forwarded) {
    EXPECT_TRUE(has(coordinator, words)) << words.front();
    for (const ChildSpec& c : plan.children) {
      if (c.name != "coordinator") {
        EXPECT_FALSE(has(c.argv, {words.front()})) << c.name;
      }
    }
  }
}

TEST(LaunchPlan, OptionalCoordinatorOptionsAreLeftOutWhenNotGiven) {
  const Argv& coordinator = child(planLaunch(options(), context(2)), "coordinator").argv;
  for (const char* flag : {"--schedule", "--arrivals", "--replan-every", "--switch-margin",
                           "--network-aware", "--security"}) {
    EXPECT_FALSE(has(coordinator, {flag})) << flag;
  }
}

TEST(LaunchPlan, NetworkAwareAutoFollowsTheScenario) {
  EXPECT_TRUE(networkAware("auto", true));
  EXPECT_FALSE(networkAware("auto", false));
  EXPECT_TRUE(networkAware("yes", false));
  EXPECT_FALSE(networkAware("no", true));
  PlanContext with_network = context(1);
  with_network.scenario_has_network = true;
  EXPECT_TRUE(has(child(planLaunch(options(), with_network), "coordinator").argv,
                  {"--network-aware"}));
}

TEST(LaunchPlan, MetricsReachTheFusionCenterAlone) {
  LaunchOptions o = options();
  o.metrics_address = "127.0.0.1:9464";
  const LaunchPlan plan = planLaunch(o, context(2));
  EXPECT_TRUE(has(child(plan, "fusion_center").argv, {"--metrics", "127.0.0.1:9464"}));
  EXPECT_FALSE(has(child(plan, "coordinator").argv, {"--metrics"}));
  EXPECT_FALSE(has(child(plan, "sensor_agent-0").argv, {"--metrics"}));
}

TEST(LaunchPlan, SensorsPerProcessMakesConsecutiveBlocks) {
  LaunchOptions o = options();
  o.sensors_per_process = "3";
  const LaunchPlan plan = planLaunch(o, context(7));
  EXPECT_EQ(plan.sensor_agents, (std::vector<std::string>{"sensor_agent-0-2", "sensor_agent-3-5",
                                                          "sensor_agent-6"}));
  EXPECT_EQ(plan.sensors_of.at("sensor_agent-3-5"), (std::vector<int>{3, 4, 5}));
  EXPECT_TRUE(has(child(plan, "sensor_agent-0-2").argv, {"--sensors", "0-2"}));
}

TEST(LaunchPlan, AutoIsOneSensorEachUpToFiftyProcessesThenEqualBlocks) {
  EXPECT_EQ(sensorsPerProcess("auto", 1), 1);
  EXPECT_EQ(sensorsPerProcess("auto", 50), 1);
  EXPECT_EQ(sensorsPerProcess("auto", 51), 2);
  EXPECT_EQ(sensorsPerProcess("auto", 1000), 20);
  EXPECT_EQ(sensorsPerProcess("auto", 1001), 21);
  EXPECT_EQ(sensorsPerProcess("4", 1000), 4);
}

TEST(LaunchPlan, ExternalSensorsGetNoAgentAndSplitBlocksKeepTheRest) {
  LaunchOptions o = options();
  o.sensors_per_process = "3";
  o.external_sensors = "1,6";
  const LaunchPlan plan = planLaunch(o, context(7));
  EXPECT_EQ(plan.sensor_agents, (std::vector<std::string>{"sensor_agent-0,2", "sensor_agent-3-5"}));
  EXPECT_EQ(plan.sensors_of.at("sensor_agent-0,2"), (std::vector<int>{0, 2}));
}

TEST(LaunchPlan, ExternalSensorsMustBeTheScenarios) {
  EXPECT_EQ(externalSensors("", 3), std::vector<int>{});
  EXPECT_EQ(externalSensors("2,0", 3), (std::vector<int>{0, 2}));
  EXPECT_THROW((void)externalSensors("3", 3), InputError);
  LaunchOptions o = options();
  o.external_sensors = "0-3";
  EXPECT_THROW((void)planLaunch(o, context(3)), InputError);
}

TEST(LaunchPlan, OnSeveralHostsEachHostsSensorsFormTheirOwnBlocks) {
  launcher::HostsFile hosts;
  hosts.hosts = {{"a", "10.0.0.1", {}, true, true, {0, 1, 2}, "h:1"},
                 {"b", "10.0.0.2", {}, false, false, {3, 4}, "h:7"}};
  EXPECT_EQ(sensorBlocks(&hosts, 5, 2),
            (std::vector<std::vector<int>>{{0, 1}, {2}, {3, 4}}));
  EXPECT_EQ(sensorBlocks(nullptr, 5, 2), (std::vector<std::vector<int>>{{0, 1}, {2, 3}, {4}}));
  PlanContext c = context(5);
  c.hosts = &hosts;
  LaunchOptions o = options();
  o.sensors_per_process = "2";
  EXPECT_EQ(planLaunch(o, c).sensor_agents,
            (std::vector<std::string>{"sensor_agent-0-1", "sensor_agent-2", "sensor_agent-3-4"}));
}

TEST(LaunchPlan, AnExternalFusionCenterIsNotStartedAndAReferenceRunsBesideIt) {
  LaunchOptions o = options();
  o.external_fusion_center = true;
  EXPECT_EQ(names(planLaunch(o, context(1))),
            (std::vector<std::string>{"sensor_agent-0", "coordinator"}));
  o.reference_fusion = true;
  const LaunchPlan plan = planLaunch(o, context(1));
  EXPECT_EQ(names(plan), (std::vector<std::string>{"reference_fusion_center", "sensor_agent-0",
                                                   "coordinator"}));
  EXPECT_EQ(plan.reference_report, "/scratch/run-7/reference-report.json");
  EXPECT_EQ(child(plan, "reference_fusion_center").argv,
            (Argv{"/bin/fusion_center", "serve", "--reference", "--report",
                  "/scratch/run-7/reference-report.json", "--run-id", "run-7"}));
  EXPECT_EQ(child(plan, "reference_fusion_center").parent_death_signal, SIGUSR1);
}

TEST(LaunchPlan, GivenLogDirAndReportAreUsed) {
  LaunchOptions o = options();
  o.log_dir = "/logs";
  const LaunchPlan in_logs = planLaunch(o, context(1));
  EXPECT_FALSE(in_logs.default_log_dir);
  EXPECT_EQ(in_logs.report_path, "/logs/report.json");
  EXPECT_TRUE(in_logs.default_report);
  EXPECT_EQ(child(in_logs, "coordinator").log_path, "/logs/coordinator.log");
  o.report_path = "/out/r.json";
  const LaunchPlan elsewhere = planLaunch(o, context(1));
  EXPECT_FALSE(elsewhere.default_report);
  EXPECT_TRUE(has(child(elsewhere, "fusion_center").argv, {"--report", "/out/r.json"}));
}

TEST(LaunchPlan, ASecuredRunGivesEachProcessItsOwnIdentitysFolder) {
  PlanContext c = context(2);
  c.run_flags = {"--run-id", "run-7", "--domain-id", "9"};
  c.security_folder = [](const dds::SecurityIdentity& identity) {
    return "/pki/" + identity.name();
  };
  LaunchOptions o = options();
  o.sensors_per_process = "2";
  const LaunchPlan plan = planLaunch(o, c);
  const std::vector<std::pair<std::string, std::string>> expected = {
      {"fusion_center", "/pki/fusion_center"},
      {"sensor_agent-0-1", "/pki/sensor-0-1"},
      {"coordinator", "/pki/coordinator"}};
  for (const auto& [name, folder] : expected) {
    const Argv& argv = child(plan, name).argv;
    ASSERT_GE(argv.size(), 6u);
    EXPECT_EQ(Argv(argv.end() - 6, argv.end()),
              (Argv{"--run-id", "run-7", "--domain-id", "9", "--security", folder}))
        << name;
  }
}

}  // namespace
}  // namespace sensornet::launcher
