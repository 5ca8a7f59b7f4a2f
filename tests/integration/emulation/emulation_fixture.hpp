#pragma once
// Whole emulation runs for the integration tests: the real coordinator, sensor agents and
// fusion center as separate processes over real Cyclone DDS on loopback, each run with its own
// run id (its own partition, and a domain id hashed from it). Every process is stopped by its
// BackgroundProcess guard whatever the outcome.
//
//   Emulation run(uniqueRunId("stall"));
//   run.startFusionCenter();
//   run.startSensors("0-5");
//   run.startCoordinator({"--scenario", kDefaultScenario, "--episodes", "3"});
//   ::kill(run.pidOf("fusion_center"), SIGSTOP);
//   const nlohmann::json report = run.finish(60s);

#include <gtest/gtest.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <optional>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "support/background_process.hpp"
#include "support/scratch_dir.hpp"

namespace sensornet::testing {

inline const std::string kCoordinator = SENSORNET_COORDINATOR;
inline const std::string kFusionCenter = SENSORNET_FUSION_CENTER;
inline const std::string kSensorAgent = SENSORNET_SENSOR_AGENT;
inline const std::string kDefaultScenario =
    std::string(SENSORNET_SOURCE_DIR) + "/scenarios/default.yaml";

inline std::string readText(const std::filesystem::path& path) {
  std::ifstream in(path);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

inline std::string uniqueRunId(const std::string& what) {
  return "t" + std::to_string(::getpid()) + "-" + what;
}

// One run's processes, their logs in a scratch directory, all stopped by the destructor.
class Emulation {
 public:
  explicit Emulation(std::string run_id)
      : run_id_(std::move(run_id)), scratch_(run_id_), dir_(scratch_.path()) {}
  ~Emulation() {
    processes_.clear();  // stops whatever still runs, before the folder goes
  }

  std::string reportPath() const { return (dir_ / "report.json").string(); }
  std::string episodeLogPath() const { return (dir_ / "report.jsonl").string(); }
  // The pid of a process started as `name` ("fusion_center", "sensors-0-2", "coordinator").
  pid_t pidOf(const std::string& name) const {
    for (const auto& [n, process] : processes_) {
      if (n == name) return process.pid();
    }
    ADD_FAILURE() << "no process " << name;
    return -1;
  }
  // Lines in the episode log so far: the episodes the fusion center has finished.
  std::size_t episodesLogged() const {
    std::ifstream in(episodeLogPath());
    std::size_t lines = 0;
    for (std::string line; std::getline(in, line);) lines += !line.empty();
    return lines;
  }
  const std::string& runId() const { return run_id_; }

  void startFusionCenter(const std::vector<std::string>& extra = {}) {
    std::vector<std::string> argv = {kFusionCenter, "serve",    "--run-id",
                                     run_id_,       "--report", reportPath()};
    argv.insert(argv.end(), extra.begin(), extra.end());
    start("fusion_center", argv);
  }
  void startSensors(const std::string& block, const std::vector<std::string>& extra = {}) {
    std::vector<std::string> argv = {kSensorAgent, "--run-id", run_id_, "--sensors", block};
    argv.insert(argv.end(), extra.begin(), extra.end());
    start("sensors-" + block, argv);
  }
  void startCoordinator(const std::vector<std::string>& extra) {
    std::vector<std::string> argv = {kCoordinator, "serve", "--run-id", run_id_};
    argv.insert(argv.end(), extra.begin(), extra.end());
    start("coordinator", argv);
  }

  // Waits for every process to exit 0 (the coordinator first), then reads the report.
  nlohmann::json finish(std::chrono::seconds limit) {
    for (auto& [name, process] : processes_) {
      const std::optional<int> code = process.waitForExit(limit);
      EXPECT_TRUE(code.has_value()) << name << " still running:\n" << process.log();
      if (code) {
        EXPECT_EQ(*code, 0) << name << " failed:\n" << process.log();
      }
    }
    for (auto& [name, process] : processes_) EXPECT_FALSE(processExists(process.pid()));
    std::ifstream in(reportPath());
    EXPECT_TRUE(in.good()) << "no report at " << reportPath();
    if (!in.good()) return {};
    return nlohmann::json::parse(in);
  }

 private:
  void start(const std::string& name, const std::vector<std::string>& argv) {
        processes_.emplace_back(name, BackgroundProcess(argv, (dir_ / (name + ".log")).string()));
  }

  std::string run_id_;
  sensornet::testing::ScratchDir scratch_;  // kept when the test failed
  std::filesystem::path dir_;
  std::vector<std::pair<std::string, BackgroundProcess>> processes_;
};


}  // namespace sensornet::testing
