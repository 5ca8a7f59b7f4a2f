// docker/compose.yaml without a Docker engine: `docker-compose config` accepts it (when the
// Debian docker-compose is installed), its Cyclone configuration names every service as a
// unicast peer, its sensor services cover every sensor of the scenario once, and the same
// topology runs as local processes: each service's command, with a fresh run id, few episodes,
// a fast time scale and the loopback configuration instead of the container one, completes a
// run and writes the report.

#include <gtest/gtest.h>
#include <signal.h>
#include <unistd.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <set>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "sensornet/emulator/sensor_ids.hpp"
#include "sensornet/io/scenario_file.hpp"
#include "support/background_process.hpp"
#include "support/process.hpp"
#include "support/scratch_dir.hpp"

namespace {

namespace fs = std::filesystem;
using sensornet::testing::ProcessResult;
using sensornet::testing::runProcess;
using sensornet::testing::LeftoverGuard;
using sensornet::testing::processesMentioning;
using namespace std::chrono_literals;

const fs::path kSourceDir = SENSORNET_SOURCE_DIR;
const fs::path kCompose = kSourceDir / "docker" / "compose.yaml";
const fs::path kSwarm = kSourceDir / "docker" / "compose.swarm.yaml";
const fs::path kCycloneConfig = kSourceDir / "docker" / "cyclonedds-containers.xml";
// Where the image keeps what the commands name (docker/Dockerfile, compose.yaml).
const std::string kImageScenarios = "/usr/local/share/sensornet/";
const std::string kReportVolume = "/reports/";

std::string readText(const fs::path& path) {
  std::ifstream in(path);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

struct Service {
  std::string name;
  std::vector<std::string> command;
  std::map<std::string, std::string> environment;
  std::optional<std::string> replicas;  // deploy.replicas, as written
};

std::vector<Service> readServices(const fs::path& compose) {
  const YAML::Node doc = YAML::LoadFile(compose.string());
  std::vector<Service> services;
  for (const auto& entry : doc["services"]) {
    Service service{entry.first.as<std::string>(), {}, {}, {}};
    for (const auto& arg : entry.second["command"])
      service.command.push_back(arg.as<std::string>());
    for (const auto& variable : entry.second["environment"]) {
      service.environment[variable.first.as<std::string>()] = variable.second.as<std::string>();
    }
    if (const YAML::Node replicas = entry.second["deploy"]["replicas"]) {
      service.replicas = replicas.as<std::string>();
    }
    services.push_back(std::move(service));
  }
  return services;
}

// The value after `flag` in a command, if any.
std::optional<std::string> flagValue(const std::vector<std::string>& command,
                                     const std::string& flag) {
  for (std::size_t i = 0; i + 1 < command.size(); ++i) {
    if (command[i] == flag) return command[i + 1];
  }
  return std::nullopt;
}

// "${NAME:-default}" becomes "default", as compose does when NAME is unset.
std::string withDefaults(std::string arg) {
  for (std::size_t open = arg.find("${"); open != std::string::npos; open = arg.find("${")) {
    const std::size_t close = arg.find('}', open);
    const std::size_t fallback = arg.find(":-", open);
    if (close == std::string::npos) break;
    const std::string value = fallback != std::string::npos && fallback < close
                                  ? arg.substr(fallback + 2, close - fallback - 2)
                                  : "";
    arg.replace(open, close + 1 - open, value);
  }
  return arg;
}

std::optional<fs::path> findOnPath(const std::string& program) {
  const char* path = std::getenv("PATH");
  std::stringstream dirs(path != nullptr ? path : "");
  for (std::string dir; std::getline(dirs, dir, ':');) {
    const fs::path candidate = fs::path(dir) / program;
    if (::access(candidate.c_str(), X_OK) == 0) return candidate;
  }
  return std::nullopt;
}

TEST(ComposeTopology, ConfigIsValid) {
  const std::optional<fs::path> compose = findOnPath("docker-compose");
  if (!compose) GTEST_SKIP() << "docker-compose is not installed (scripts/install-deps.sh)";
  const ProcessResult r = runProcess({compose->string(), "-f", kCompose.string(), "config"}, 30s);
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("coordinator"), std::string::npos) << r.out;
}

TEST(ComposeTopology, EveryServiceIsAUnicastPeerOfTheContainerConfig) {
  const std::string xml = readText(kCycloneConfig);
  ASSERT_FALSE(xml.empty()) << kCycloneConfig;
  std::set<std::string> peers;
  const std::string attribute = "<Peer Address=\"";
  for (std::size_t at = xml.find(attribute); at != std::string::npos;
       at = xml.find(attribute, at + 1)) {
    const std::size_t begin = at + attribute.size();
    peers.insert(xml.substr(begin, xml.find('"', begin) - begin));
  }
  // The services of compose.yaml and those the swarm file adds: the same configuration serves
  // both (a name that does not resolve in one of them is skipped).
  std::set<std::string> names;
  for (Service& service : readServices(kCompose)) {
    names.insert(service.name);
    EXPECT_EQ(service.environment["SENSORNET_CYCLONE_CONFIG"],
              "file:///etc/sensornet/cyclonedds-containers.xml")
        << service.name;
  }
  for (Service& service : readServices(kSwarm)) {
    if (names.insert(service.name).second) {  // a service of its own: its environment too
      EXPECT_EQ(service.environment["SENSORNET_CYCLONE_CONFIG"],
                "file:///etc/sensornet/cyclonedds-containers.xml")
          << service.name;
    }
  }
  EXPECT_EQ(peers, names);
  EXPECT_NE(xml.find("<NetworkInterface name=\"eth0\""), std::string::npos)
      << "the stack network's interface, not docker_gwbridge's on a swarm";
  EXPECT_NE(xml.find("<AllowMulticast>false</AllowMulticast>"), std::string::npos);
  EXPECT_EQ(xml.find("multicast=\"true\""), std::string::npos);
  // The image puts the file where the services look for it.
  EXPECT_NE(
      readText(kSourceDir / "docker" / "Dockerfile")
          .find("cp docker/cyclonedds-containers.xml /opt/sensornet/etc/sensornet/"),
      std::string::npos);
}

TEST(ComposeTopology, SensorServicesCoverEverySensorOnce) {
  const std::vector<Service> services = readServices(kCompose);
  std::multiset<int> hosted;
  int coordinators = 0, fusion_centers = 0;
  std::optional<std::string> scenario;
  for (const Service& service : services) {
    ASSERT_FALSE(service.command.empty()) << service.name;
    const std::string& program = service.command.front();
    coordinators += program == "coordinator";
    fusion_centers += program == "fusion_center";
    if (program == "coordinator") scenario = flagValue(service.command, "--scenario");
    if (program != "sensor_agent") continue;
    const auto spec = flagValue(service.command, "--sensors");
    ASSERT_TRUE(spec.has_value()) << service.name;
    for (int id : sensornet::emulator::parseSensorIds(*spec, service.name)) hosted.insert(id);
  }
  EXPECT_EQ(coordinators, 1);
  EXPECT_EQ(fusion_centers, 1);
  ASSERT_TRUE(scenario.has_value() && scenario->starts_with(kImageScenarios));
  const auto model =
      sensornet::loadScenarioFile((kSourceDir / scenario->substr(kImageScenarios.size())).string());
  std::multiset<int> expected;
  for (int j = 0; j < model.sensorCount(); ++j) expected.insert(j);
  EXPECT_EQ(hosted, expected);
}

// On a swarm (compose.swarm.yaml over compose.yaml) the sensor services of compose.yaml get no
// task and the replicated `sensors` hosts every sensor once: its command, run by sh with each
// task slot and a stand-in sensor_agent that prints its arguments, names blocks that together
// are the scenario's sensors.
TEST(ComposeTopology, SwarmSensorTasksCoverEverySensorOnce) {
  const std::vector<Service> swarm = readServices(kSwarm);
  std::optional<Service> sensors;
  for (const Service& service : swarm) {
    if (service.name == "sensors") {
      sensors = service;
    } else if (service.name.starts_with("sensors-")) {
      EXPECT_EQ(service.replicas, "0") << service.name << " would host its sensors twice";
    }
  }
  ASSERT_TRUE(sensors.has_value() && sensors->replicas.has_value());
  const int tasks = std::stoi(withDefaults(*sensors->replicas));
  // The command after sensornet-await-peers ... --: sh -c SCRIPT NAME RUN_ID.
  const auto dashes = std::find(sensors->command.begin(), sensors->command.end(), "--");
  ASSERT_NE(dashes, sensors->command.end());
  std::vector<std::string> shell(dashes + 1, sensors->command.end());
  ASSERT_EQ(shell.size(), 5u);
  ASSERT_EQ(shell[0], "sh");
  std::string script = shell[2];
  for (std::size_t at = script.find("$$"); at != std::string::npos; at = script.find("$$", at + 1)) {
    script.erase(at, 1);  // compose's escape of a literal $
  }

  const sensornet::testing::ScratchDir scratch;
  const fs::path dir = scratch.path();
  const fs::path stand_in = dir / "sensor_agent";
  std::ofstream(stand_in) << "#!/bin/sh\necho \"$@\"\n";
  fs::permissions(stand_in, fs::perms::owner_all);
  const std::string per_task = withDefaults(sensors->environment.at("SENSORNET_SENSORS_PER_TASK"));
  std::multiset<int> hosted;
  for (int slot = 1; slot <= tasks; ++slot) {
    const ProcessResult r = runProcess(
        {"/usr/bin/env", "PATH=" + dir.string() + ":/usr/bin:/bin",
         "SENSORNET_TASK_SLOT=" + std::to_string(slot), "SENSORNET_SENSORS_PER_TASK=" + per_task,
         "sh", "-c", script, shell[3], "run-x"},
        10s);
    ASSERT_EQ(r.exit_code, 0) << r.err;
    std::istringstream words(r.out);
    std::vector<std::string> argv{std::istream_iterator<std::string>(words), {}};
    EXPECT_EQ(flagValue(argv, "--run-id"), "run-x") << r.out;
    const auto spec = flagValue(argv, "--sensors");
    ASSERT_TRUE(spec.has_value()) << r.out;
    for (int id : sensornet::emulator::parseSensorIds(*spec, "slot " + std::to_string(slot))) {
      hosted.insert(id);
    }
  }
  const auto model = sensornet::loadScenarioFile((kSourceDir / "scenarios/default.yaml").string());
  std::multiset<int> expected;
  for (int j = 0; j < model.sensorCount(); ++j) expected.insert(j);
  EXPECT_EQ(hosted, expected);
}

// Each service's command as a local process of this host.
std::vector<std::string> localCommand(const Service& service, const std::string& run_id,
                                      const fs::path& report_dir) {
  const std::map<std::string, std::string> programs = {{"coordinator", SENSORNET_COORDINATOR},
                                                       {"fusion_center", SENSORNET_FUSION_CENTER},
                                                       {"sensor_agent", SENSORNET_SENSOR_AGENT}};
  // Few, fast episodes; a short wait for sensors that will never come if something is wrong.
  const std::map<std::string, std::string> overrides = {
      {"--run-id", run_id}, {"--episodes", "2"}, {"--time-scale", "20"}, {"--ready-timeout", "15"}};
  std::vector<std::string> argv;
  for (std::size_t i = 0; i < service.command.size(); ++i) {
    std::string arg = withDefaults(service.command[i]);
    if (i == 0) {
      arg = programs.at(arg);
    } else if (const auto o = overrides.find(service.command[i - 1]); o != overrides.end()) {
      arg = o->second;
    } else if (arg.starts_with(kImageScenarios)) {
      arg = (kSourceDir / arg.substr(kImageScenarios.size())).string();
    } else if (arg.starts_with(kReportVolume)) {
      arg = (report_dir / arg.substr(kReportVolume.size())).string();
    }
    argv.push_back(arg);
  }
  return argv;
}

TEST(ComposeTopology, RunsAsLocalProcesses) {
  const sensornet::testing::ScratchDir scratch;
  const fs::path dir = scratch.path();
  const std::string run_id = "compose-" + std::to_string(::getpid());
  ::unsetenv("SENSORNET_CYCLONE_CONFIG");  // loopback, never the container configuration

  std::vector<Service> services = readServices(kCompose);
  ASSERT_GE(services.size(), 3u);
  // The coordinator last, as depends_on orders it.
  std::stable_partition(services.begin(), services.end(),
                        [](const Service& s) { return s.command.front() != "coordinator"; });
  std::map<std::string, ProcessResult> results;
  std::map<std::string, std::vector<std::string>> commands;
  {
    std::vector<std::jthread> running;  // joined after the guard below has killed leftovers
    const LeftoverGuard guard(run_id);
    for (const Service& service : services) {
      commands[service.name] = localCommand(service, run_id, dir);
      results[service.name];  // created before any thread writes into the map
    }
    for (const Service& service : services) {
      running.emplace_back(
          [&, name = service.name] { results.at(name) = runProcess(commands.at(name), 40s); });
    }
    for (std::jthread& thread : running) thread.join();
  }
  for (const Service& service : services) {
    const ProcessResult& r = results[service.name];
    EXPECT_EQ(r.exit_code, 0) << service.name << ":\n" << r.err;
    EXPECT_FALSE(r.timed_out) << service.name;
  }
  const nlohmann::json report =
      nlohmann::json::parse(readText(dir / "report.json"), nullptr, false);
  ASSERT_TRUE(report.is_object()) << "no report in " << dir;
  EXPECT_EQ(report["run_id"], run_id);
  EXPECT_EQ(report["episodes"], 2);
  EXPECT_EQ(report["status"], "completed");
  EXPECT_TRUE(fs::exists(dir / "report.html")) << "the fusion center's --page";
  EXPECT_TRUE(processesMentioning(run_id).empty());
}

}  // namespace
