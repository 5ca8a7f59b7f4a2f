// The emulator's speed targets (issue 4), each with real processes over Cyclone DDS on
// loopback, one run id per measurement:
//   startup     30 sensor processes (one sensor each) started at once: the time until all 30
//               report READY (scenario and schedule received), median of 3.
//   latency     publish-to-fusion median at light load (the default scenario at 10x real
//               time: about 120 measurements/s reach the fusion center), with one process per
//               sensor and with one process for all 6, against Cyclone's own `ddsperf`
//               ping/pong round trip / 2 at 100 Hz (each side receives 100 messages/s) measured
//               in the same round, same loopback configuration; 3 rounds unless told.
//               Comparable rates matter: an idle process wakes slowly (ddsperf is about 3x
//               slower at 10 Hz than at 100 Hz on this machine). ddsperf prints round trip / 2
//               already: the bench checks that on the installed binary (support/ddsperf.hpp).
//   throughput  100 sensors at 200 Hz each (20,000 measurements/s, n = 5) in real time,
//               10 processes of 10 sensors: received, lost, late, latency median and p99.
//
//   emulator_bench [startup|latency|throughput|all] [latency rounds = 3]

#include <unistd.h>

#include <algorithm>
#include <cstdlib>
#include <memory>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <optional>
#include <set>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "sensornet/dds/participant.hpp"
#include "sensornet/dds/reader.hpp"
#include "sensornet/dds/topics.hpp"
#include "sensornet/emulator/run_options.hpp"
#include "sensornet/emulator/run_report.hpp"
#include "support/background_process.hpp"
#include "support/ddsperf.hpp"

namespace {

using namespace std::chrono_literals;
using sensornet::testing::BackgroundProcess;
namespace fs = std::filesystem;

const std::string kCoordinator = SENSORNET_COORDINATOR;
const std::string kFusionCenter = SENSORNET_FUSION_CENTER;
const std::string kSensorAgent = SENSORNET_SENSOR_AGENT;
const std::string kSourceDir = SENSORNET_SOURCE_DIR;

double secondsSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

double median(std::vector<double> values) {
  return sensornet::emulator::quantile(std::move(values), 0.5);
}

// Processes of one measurement, each logging to <dir>/<name>.log; all stopped (SIGTERM, then
// SIGKILL) when it goes away.
class Processes {
 public:
  explicit Processes(fs::path dir) : dir_(std::move(dir)) { fs::create_directories(dir_); }
  BackgroundProcess& start(const std::string& name, const std::vector<std::string>& argv) {
    processes_.push_back(
        std::make_unique<BackgroundProcess>(argv, (dir_ / (name + ".log")).string()));
    return *processes_.back();
  }
  [[nodiscard]] const fs::path& dir() const { return dir_; }

 private:
  fs::path dir_;
  std::vector<std::unique_ptr<BackgroundProcess>> processes_;
};

std::string runId(const std::string& what, int repeat) {
  return "bench-" + std::to_string(::getpid()) + "-" + what + "-" + std::to_string(repeat);
}

fs::path writeRandomScenario(const fs::path& dir, int states, int sensors, double budget) {
  const fs::path path = dir / "scenario.yaml";
  std::ofstream(path) << "horizon: 3.0\nintervals: 30\nrandom:\n  states: " << states
                      << "\n  sensors: " << sensors << "\n  rows_per_sensor: 1\n  seed: 1\n"
                      << "  budget: " << budget << "\n";
  return path;
}

nlohmann::json readReport(const fs::path& path) {
  std::ifstream in(path);
  if (!in) return {};
  return nlohmann::json::parse(in);
}

double startupSeconds(int repeat) {
  const std::string run = runId("startup", repeat);
  Processes processes(fs::temp_directory_path() / run);
  const fs::path scenario = writeRandomScenario(processes.dir(), 5, 30, 5.0);
  sensornet::emulator::RunOptions options;
  options.run_id = run;
  sensornet::dds::Domain domain(options.domainConfig());
  sensornet::dds::Participant participant(domain);
  sensornet::dds::Topic<sensornet_SensorStatus> topic(participant);
  sensornet::dds::Reader<sensornet_SensorStatus> statuses(participant, topic);

  processes.start("fusion_center", {kFusionCenter, "serve", "--run-id", run});
  BackgroundProcess& coordinator = processes.start(
      "coordinator", {kCoordinator, "serve", "--run-id", run, "--scenario", scenario.string(),
                      "--surrogate", "uniform", "--episodes", "1", "--time-scale", "10"});
  std::this_thread::sleep_for(1500ms);  // scenario and schedule published
  const auto start = std::chrono::steady_clock::now();
  for (int j = 0; j < 30; ++j) {
    processes.start("sensor-" + std::to_string(j),
                    {kSensorAgent, "--run-id", run, "--sensors", std::to_string(j)});
  }
  std::set<std::uint32_t> ready;
  while (ready.size() < 30 && secondsSince(start) < 60.0) {
    for (auto& s : statuses.take(64).samples) {
      if (s.sample->state == sensornet_SENSOR_READY ||
          s.sample->state == sensornet_SENSOR_RUNNING ||
          s.sample->state == sensornet_SENSOR_EXCLUDED) {
        ready.insert(s.sample->sensor_id);
      }
    }
    std::this_thread::sleep_for(2ms);
  }
  const double seconds = secondsSince(start);
  const int code = coordinator.waitForExit(60s).value_or(-1);
  std::printf("  repeat %d: %zu/30 ready after %.3f s; the run %s\n", repeat, ready.size(),
              seconds, code == 0 ? "completed" : "FAILED");
  return ready.size() == 30 ? seconds : -1.0;
}

// One emulation of the default scenario at 10x: the publish-to-fusion median and p99 (µs), or
// nullopt if the run failed. `agents` sensor processes share the 6 sensors.
struct LatencyRun {
  double median_us = 0.0;
  double p99_us = 0.0;
  int received = 0;
};

std::optional<LatencyRun> latencyRun(const std::string& run, int agents) {
  Processes processes(fs::temp_directory_path() / run);
  const fs::path report = processes.dir() / "report.json";
  processes.start("fusion_center", {kFusionCenter, "serve", "--run-id", run, "--report",
                                    report.string()});
  for (int a = 0; a < agents; ++a) {
    const std::string sensors =
        agents == 1 ? "0-5" : std::to_string(a);  // 6 sensors: one each, or all in one
    processes.start("sensor-" + std::to_string(a),
                    {kSensorAgent, "--run-id", run, "--sensors", sensors});
  }
  BackgroundProcess& coordinator = processes.start(
      "coordinator", {kCoordinator, "serve", "--run-id", run, "--scenario",
                      kSourceDir + "/scenarios/default.yaml", "--surrogate", "uniform",
                      "--episodes", "20", "--time-scale", "10"});
  const int code = coordinator.waitForExit(120s).value_or(-1);
  std::this_thread::sleep_for(1s);
  const nlohmann::json r = readReport(report);
  if (code != 0 || r.is_null()) {
    std::printf("latency: the run failed (see %s)\n", processes.dir().c_str());
    return std::nullopt;
  }
  return LatencyRun{1e6 * r["latency_s"]["median"].get<double>(),
                    1e6 * r["latency_s"]["p99"].get<double>(),
                    r["summary"]["received"].get<int>()};
}

void latency(int rounds) {
  const fs::path ddsperf_dir = fs::temp_directory_path() / runId("ddsperf", 0);
  std::printf("latency: ddsperf prints round trip / 2; back to back, 2 x mean x count / 1 s = "
              "%.2f (1 if so)\n",
              sensornet::bench::checkHalving(ddsperf_dir, 219));
  std::vector<double> ddsperf_100, ddsperf_20, per_sensor, per_sensor_p99, one_agent,
      one_agent_p99, per_sensor_ratio, one_agent_ratio;
  for (int round = 0; round < rounds; ++round) {
    const std::string tag = runId("latency", round);
    ddsperf_100.push_back(sensornet::bench::ddsperfHalfRoundTripUs(ddsperf_dir, 219, 100));
    ddsperf_20.push_back(sensornet::bench::ddsperfHalfRoundTripUs(ddsperf_dir, 219, 20));
    const auto a = latencyRun(tag + "-per-sensor", 6);
    const auto b = latencyRun(tag + "-one-agent", 1);
    if (!a || !b) return;
    per_sensor.push_back(a->median_us);
    per_sensor_p99.push_back(a->p99_us);
    one_agent.push_back(b->median_us);
    one_agent_p99.push_back(b->p99_us);
    per_sensor_ratio.push_back(a->median_us / ddsperf_100.back());
    one_agent_ratio.push_back(b->median_us / ddsperf_100.back());
    std::printf("  round %d: ddsperf round trip / 2: %.1f us at 100 Hz, %.1f us at 20 Hz; "
                "publish-to-fusion median %.1f us (6 agents), %.1f us (1 agent); %d and %d "
                "measurements\n",
                round, ddsperf_100.back(), ddsperf_20.back(), a->median_us, b->median_us,
                a->received, b->received);
    std::fflush(stdout);
  }
  std::printf("latency, medians of %d rounds (ratios: per round, against ddsperf at 100 Hz in "
              "that round; target <= 2x):\n",
              rounds);
  std::printf("  ddsperf round trip / 2:               %.1f us at 100 Hz, %.1f us at 20 Hz\n",
              median(ddsperf_100), median(ddsperf_20));
  std::printf("  one process per sensor (6 x ~20/s):  median %.1f us, p99 %.1f us, %.2fx\n",
              median(per_sensor), median(per_sensor_p99), median(per_sensor_ratio));
  std::printf("  one process for all 6 (~120/s):      median %.1f us, p99 %.1f us, %.2fx\n",
              median(one_agent), median(one_agent_p99), median(one_agent_ratio));
}

void throughput() {
  const std::string run = runId("throughput", 0);
  Processes processes(fs::temp_directory_path() / run);
  const fs::path scenario = writeRandomScenario(processes.dir(), 5, 100, 20000.0);
  const fs::path report = processes.dir() / "report.json";
  processes.start("fusion_center", {kFusionCenter, "serve", "--run-id", run, "--report",
                                    report.string()});
  for (int block = 0; block < 10; ++block) {
    const std::string ids = std::to_string(10 * block) + "-" + std::to_string(10 * block + 9);
    processes.start("sensors-" + std::to_string(block),
                    {kSensorAgent, "--run-id", run, "--sensors", ids});
  }
  const int episodes = 3;
  const auto start = std::chrono::steady_clock::now();
  BackgroundProcess& coordinator = processes.start(
      "coordinator", {kCoordinator, "serve", "--run-id", run, "--scenario", scenario.string(),
                      "--surrogate", "uniform", "--episodes", std::to_string(episodes),
                      "--time-scale", "1", "--ready-timeout", "60"});
  const int code = coordinator.waitForExit(180s).value_or(-1);
  const double wall = secondsSince(start);
  std::this_thread::sleep_for(1s);
  const nlohmann::json r = readReport(report);
  if (code != 0 || r.is_null()) {
    std::printf("throughput: the run failed (see %s)\n", processes.dir().c_str());
    return;
  }
  const auto& s = r["summary"];
  std::printf("throughput: 100 sensors x 200 Hz, n = 5, %d episodes of 3 s in real time (%.1f s "
              "wall with start-up)\n",
              episodes, wall);
  std::printf("            received %lld of %.0f expected (%.0f/s), lost %lld, late %lld, "
              "latency median %.0f us, p99 %.0f us\n",
              s["received"].get<long long>(), s["expected"].get<double>(),
              s["received"].get<double>() / (3.0 * episodes), s["lost"].get<long long>(),
              s["late"].get<long long>(), 1e6 * r["latency_s"]["median"].get<double>(),
              1e6 * r["latency_s"]["p99"].get<double>());
}

}  // namespace

int main(int argc, char** argv) {
  const std::string what = argc > 1 ? argv[1] : "all";
  if (what != "all" && what != "startup" && what != "latency" && what != "throughput") {
    std::fprintf(stderr, "usage: emulator_bench [startup|latency|throughput|all] [rounds]\n");
    return 2;
  }
  if (what == "all" || what == "startup") {
    std::printf("startup: 30 sensor processes\n");
    std::vector<double> times;
    for (int repeat = 0; repeat < 3; ++repeat) times.push_back(startupSeconds(repeat));
    std::printf("startup: median %.3f s (target < 3 s)\n", median(times));
  }
  if (what == "all" || what == "latency") latency(argc > 2 ? std::max(1, std::atoi(argv[2])) : 3);
  if (what == "all" || what == "throughput") throughput();
  return 0;
}
