// The emulator's speed targets (issue 4), each with real processes over Cyclone DDS on
// loopback, one run id per measurement:
//   startup     (issue 12) sensor processes started at once after the fusion center and the
//               coordinator: the time until every sensor reports READY (scenario and schedule
//               received, writers matched), for 30, 100 and 200 one-sensor processes and for
//               1000 sensors in 50 processes of 20 (--sensors-per-process auto), median of 3
//               unless told. Beside each, in the same run, as many `ddsperf pub` processes
//               started the same way (leaves of the loopback configuration) and one
//               `ddsperf sub` as the hub: the time until the hub has discovered all of them.
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
//   overload    (issue 10) the highest total measurement rate the fusion center keeps up with:
//               the default scenario (n = 4) with one bandwidth row and constant equal rates,
//               6 sensors in 2 processes ("0-2", "3-5"), time scale 1, one episode of 3 s, at
//               rising total rates until one clearly fails. Keeps up = status "completed",
//               nothing lost, median publish-to-fusion latency < 1 ms, p99 < 10 ms. Per rate: sent,
//               received, lost, status, drain, backlog, latency median and p99, wall time and
//               the busiest threads (peak share of a core over 1 s, from /proc, as `top -H`,
//               and their CPU time per measurement received). Wall time runs from the
//               coordinator's start to the fusion center's exit.
//               Beside it, in the same run, ddsperf pub/sub throughput of 64-byte samples
//               (reliable, keep-all, 2 processes) before and after the sweep.
//   fleet       (issue 28) the same measurement of many sensors in many processes: by
//               default 1000 one-row sensors (n = 4) in 50 processes of 20, each at 100 Hz
//               (100,000 measurements/s), one episode at time scale 1, 3 rounds. Then, as
//               the yardstick, ddsperf of the same shape (as many publishers, each at the
//               same rate, one subscriber) and how busy it keeps the machine.
//
//   security    (issue 12) the cost of DDS Security: per round, unsecured then secured (every
//               process with --security DIR from one `sensornet pki init`), the latency run
//               above (6 one-sensor processes) and one overload episode at 10,000 and 40,000
//               measurements/s: latency median and p99, secured/unsecured ratio per round, and
//               the fusion center's CPU time per measurement and whether it keeps up.
//
//   turnaround  (issue 15) episodes back to back: the default scenario (T = 3 s, 6 one-sensor
//               processes) for 1000 episodes at time scale 1000, 200 at 100 and 30 at 10; a
//               probe on the run's topics stamps every EpisodeControl and Report. Per run:
//               episodes per second against the emulated-time limit (time scale / T), wall
//               seconds of overhead per episode ((last report - first start - episodes x T /
//               time scale) / episodes), the median gap between an episode's end and the next
//               one's start, the median from an episode's end to the publication of its last
//               EpisodeTally and to its Report at the probe, and the whole run from the
//               processes' start to the coordinator's exit. Median of 3 rounds
//               unless told. SENSORNET_BENCH_PROGRAMS=<build dir> takes the coordinator, fusion
//               center and sensor agent from another build (a baseline in the same run; give
//               it fewer episodes: `turnaround 3 50,20,10`).
//
//   emulator_bench [startup|latency|throughput|turnaround|all] [rounds: latency 3, startup 3]
//   emulator_bench turnaround [rounds = 3] [episodes at time scale 1000,100,10 = 1000,200,30]
//   emulator_bench overload [total rates/s, comma-separated = 30000,45000,60000,90000,...]
//   emulator_bench fleet [rounds = 3] [processes = 50] [sensors = 1000] [Hz each = 100]
//   emulator_bench security [rounds = 3] [total rates/s = 10000,40000]
//   emulator_bench recording [rounds = 3] [total rates/s = 10000,40000]
//               (issue 26) one overload episode plain, with the fusion center's --metrics, and
//               recorded (a RunRecorder in the bench's process): latency median, fusion center
//               CPU per measurement, kept up; medians over rounds and ratios to plain.
//   emulator_bench memory [episodes = 5000] [checkpoint = 1000]
//               (issue 15) `sensornet launch` of the default scenario at --time-scale 1000:
//               VmRSS of the launcher and of each process it started after `checkpoint`
//               episodes (the episode log's line count), every `checkpoint` after, and when the
//               last is logged: both, their ratio and the growth in bytes per episode.

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <functional>
#include <fstream>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <set>
#include <sstream>
#include <stdexcept>
#include <string>
#include <system_error>
#include <thread>
#include <tuple>
#include <utility>
#include <vector>

#include "sensornet/dds/domain.hpp"
#include "sensornet/dds/participant.hpp"
#include "sensornet/dds/reader.hpp"
#include "sensornet/dds/topics.hpp"
#include "sensornet/wire/messages.hpp"
#include "sensornet/wire/run_options.hpp"
#include "sensornet/emulator/run_partitions.hpp"
#include "sensornet/recording/run_recorder.hpp"
#include "sensornet/emulator/run_report.hpp"
#include "sensornet/report/report_files.hpp"
#include "support/background_process.hpp"
#include "support/ddsperf.hpp"
#include "support/process.hpp"

namespace {


using namespace std::chrono_literals;
using sensornet::testing::BackgroundProcess;
namespace fs = std::filesystem;
namespace recording = sensornet::recording;
namespace wire = sensornet::wire;

const std::string kCoordinator = SENSORNET_COORDINATOR;
const std::string kFusionCenter = SENSORNET_FUSION_CENTER;
const std::string kSensorAgent = SENSORNET_SENSOR_AGENT;
const std::string kSourceDir = SENSORNET_SOURCE_DIR;
const std::string kLauncher = SENSORNET_LAUNCHER;

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

std::vector<std::string> withFlags(std::vector<std::string> argv,
                                   const std::vector<std::string>& extra) {
  argv.insert(argv.end(), extra.begin(), extra.end());
  return argv;
}

// The report, or null when the run wrote none (or not a whole one).
nlohmann::json readReport(const fs::path& path) {
  return sensornet::report::readReport(path).report;
}

// Sets an environment variable for the processes started while it lives.
class ScopedEnvironment {
 public:
  ScopedEnvironment(const char* name, const std::string& value) : name_(name) {
    ::setenv(name, value.c_str(), 1);
  }
  ~ScopedEnvironment() { ::unsetenv(name_); }
  ScopedEnvironment(const ScopedEnvironment&) = delete;
  ScopedEnvironment& operator=(const ScopedEnvironment&) = delete;

 private:
  const char* name_;
};

// `processes` sensor_agent processes hosting `sensors` sensors in equal blocks, started at once
// once the fusion center and the coordinator are up: the time until every sensor is READY, or
// -1 if not within 60 s.
double startupSeconds(int process_count, int sensors, int repeat) {
  const std::string run =
      runId("startup" + std::to_string(process_count) + "x" + std::to_string(sensors), repeat);
  Processes processes(fs::temp_directory_path() / run);
  const fs::path scenario = writeRandomScenario(processes.dir(), 5, sensors, 5.0);
  wire::RunOptions options;
  options.run_id = run;
  sensornet::dds::Domain domain(options.domainConfig());
  sensornet::dds::Participant participant(domain);
  sensornet::dds::Topic<sensornet_SensorStatus> topic(participant);
  // Sensors write in their blocks' partitions (emulator/run_partitions.hpp).
  sensornet::dds::Reader<sensornet_SensorStatus> statuses(
      participant, topic,
      sensornet::dds::readerQosMatching<sensornet_SensorStatus>(
          sensornet::emulator::sensorPartitionPattern(participant.partition())));

  processes.start("fusion_center", {kFusionCenter, "serve", "--run-id", run});
  BackgroundProcess& coordinator = processes.start(
      "coordinator", {kCoordinator, "serve", "--run-id", run, "--scenario", scenario.string(),
                      "--surrogate", "uniform", "--episodes", "1", "--time-scale", "10",
                      "--ready-timeout", "60"});
  std::this_thread::sleep_for(1500ms);  // scenario and schedule published
  const int per_process = (sensors + process_count - 1) / process_count;
  const auto start = std::chrono::steady_clock::now();
  for (int first = 0; first < sensors; first += per_process) {
    const int last = std::min(first + per_process, sensors) - 1;
    const std::string block = std::to_string(first) + "-" + std::to_string(last);
    processes.start("sensor-" + block, {kSensorAgent, "--run-id", run, "--sensors", block});
  }
  std::set<std::uint32_t> ready;
  const auto wanted = static_cast<std::size_t>(sensors);
  while (ready.size() < wanted && secondsSince(start) < 60.0) {
    for (auto& s : statuses.take(1024).samples) {
      if (s.sample->schedule_version >= 1) ready.insert(s.sample->sensor_id);
    }
    std::this_thread::sleep_for(5ms);
  }
  const double seconds = secondsSince(start);
  const int code = coordinator.waitForExit(90s).value_or(-1);
  std::printf("  %d processes, %d sensors, repeat %d: %zu/%d ready after %.3f s; the run %s\n",
              process_count, sensors, repeat, ready.size(), sensors, seconds,
              code == 0 ? "completed" : "FAILED");
  std::fflush(stdout);
  return ready.size() == wanted ? seconds : -1.0;
}

// The same start-up with Cyclone's own ddsperf: one `ddsperf sub` as the hub (the loopback
// configuration), then `process_count` `ddsperf pub` processes at once as leaves; the time until
// the hub has discovered all of them (its "participant ...: new" lines), or -1 within 60 s.
double ddsperfStartupSeconds(int process_count, int repeat) {
  const std::string run = runId("ddsperf-startup" + std::to_string(process_count), repeat);
  Processes processes(fs::temp_directory_path() / run);
  const fs::path hub_config = processes.dir() / "hub.xml";
  std::ofstream(hub_config) << sensornet::dds::loopbackConfigXml();
  const std::string loopback_uri = "file://" + hub_config.string();
  const std::string hub_uri = loopback_uri + "," + sensornet::dds::hubConfigXml();
  const std::string domain = std::to_string(sensornet::dds::domainIdForRun(run));
  const std::string duration = "75";
  {
    const ScopedEnvironment hub("CYCLONEDDS_URI", hub_uri);
    processes.start("sub", {"/usr/bin/ddsperf", "-i", domain, "-D", duration, "sub"});
  }
  std::this_thread::sleep_for(1500ms);
  const auto start = std::chrono::steady_clock::now();
  {
    const ScopedEnvironment leaf("CYCLONEDDS_URI",
                                 loopback_uri + "," + sensornet::dds::leafConfigXml());
    for (int p = 0; p < process_count; ++p) {
      processes.start("pub-" + std::to_string(p),
                      {"/usr/bin/ddsperf", "-i", domain, "-D", duration, "pub", "1Hz"});
    }
  }
  const fs::path sub_log = processes.dir() / "sub.log";
  long discovered = 0;
  while (discovered < process_count && secondsSince(start) < 60.0) {
    std::ifstream in(sub_log);
    discovered = 0;
    for (std::string line; std::getline(in, line);) {
      if (line.find(": new") != std::string::npos && line.find("(self)") == std::string::npos) {
        ++discovered;
      }
    }
    std::this_thread::sleep_for(20ms);
  }
  const double seconds = secondsSince(start);
  std::printf("  ddsperf: %d pub processes, repeat %d: %ld/%d discovered by the sub after %.3f s\n",
              process_count, repeat, discovered, process_count, seconds);
  std::fflush(stdout);
  return discovered >= process_count ? seconds : -1.0;
}

void startup(int repeats) {
  struct Case {
    int processes;
    int sensors;
  };
  const std::vector<Case> cases = {{30, 30}, {100, 100}, {200, 200}, {50, 1000}};
  std::printf("startup: sensor processes started at once, time until every sensor is READY "
              "(median of %d; -1 = not within 60 s); beside it ddsperf, as many processes\n",
              repeats);
  for (const Case& c : cases) {
    std::vector<double> ours, theirs;
    for (int repeat = 0; repeat < repeats; ++repeat) {
      ours.push_back(startupSeconds(c.processes, c.sensors, repeat));
      theirs.push_back(ddsperfStartupSeconds(c.processes, repeat));
    }
    const double a = median(ours), b = median(theirs);
    std::printf("startup: %d processes, %d sensors: %.3f s; ddsperf %d processes: %.3f s; "
                "ratio %.2f (target: all ready in < 10 s)\n",
                c.processes, c.sensors, a, c.processes, b, b > 0.0 ? a / b : 0.0);
    std::fflush(stdout);
  }
}

// One emulation of the default scenario at 10x: the publish-to-fusion median and p99 (µs), or
// nullopt if the run failed. `agents` sensor processes share the 6 sensors.
struct LatencyRun {
  double median_us = 0.0;
  double p99_us = 0.0;
  int received = 0;
};

// `extra`: flags every process gets (--security DIR).
std::optional<LatencyRun> latencyRun(const std::string& run, int agents,
                                     const std::vector<std::string>& extra = {}) {
  Processes processes(fs::temp_directory_path() / run);
  const fs::path report = processes.dir() / "report.json";
  processes.start("fusion_center", withFlags({kFusionCenter, "serve", "--run-id", run,
                                              "--report", report.string()},
                                             extra));
  for (int a = 0; a < agents; ++a) {
    const std::string sensors =
        agents == 1 ? "0-5" : std::to_string(a);  // 6 sensors: one each, or all in one
    processes.start("sensor-" + std::to_string(a),
                    withFlags({kSensorAgent, "--run-id", run, "--sensors", sensors}, extra));
  }
  BackgroundProcess& coordinator = processes.start(
      "coordinator", withFlags({kCoordinator, "serve", "--run-id", run, "--scenario",
                                kSourceDir + "/scenarios/default.yaml", "--surrogate", "uniform",
                                "--episodes", "20", "--time-scale", "10"},
                               extra));
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
  // Ratios against ddsperf at 100 Hz (the fusion center's total rate) and at 20 Hz (the rate of
  // one sensor's writer, which is what sets the latency of a one-sensor process; see
  // bench/README.md).
  std::vector<double> ddsperf_100, ddsperf_20, per_sensor, per_sensor_p99, one_agent,
      one_agent_p99, per_sensor_ratio, per_sensor_ratio_20, one_agent_ratio;
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
    per_sensor_ratio_20.push_back(a->median_us / ddsperf_20.back());
    one_agent_ratio.push_back(b->median_us / ddsperf_100.back());
    std::printf("  round %d: ddsperf round trip / 2: %.1f us at 100 Hz, %.1f us at 20 Hz; "
                "publish-to-fusion median %.1f us (6 agents), %.1f us (1 agent); %d and %d "
                "measurements\n",
                round, ddsperf_100.back(), ddsperf_20.back(), a->median_us, b->median_us,
                a->received, b->received);
    std::fflush(stdout);
  }
  std::printf("latency, medians of %d rounds (ratios: per round, against ddsperf at 100 Hz in "
              "that round unless said; issue 15 asks <= 1.5x):\n",
              rounds);
  std::printf("  ddsperf round trip / 2:               %.1f us at 100 Hz, %.1f us at 20 Hz\n",
              median(ddsperf_100), median(ddsperf_20));
  std::printf("  one process per sensor (6 x ~20/s):  median %.1f us, p99 %.1f us, %.2fx (%.2fx "
              "against ddsperf at 20 Hz)\n",
              median(per_sensor), median(per_sensor_p99), median(per_sensor_ratio),
              median(per_sensor_ratio_20));
  std::printf("  one process for all 6 (~120/s):      median %.1f us, p99 %.1f us, %.2fx\n",
              median(one_agent), median(one_agent_p99), median(one_agent_ratio));
}

// ---- memory: the resident memory of every process of a long run (issue 15)

// VmRSS of a process in bytes (from /proc/PID/status), or 0 when it is gone.
std::uint64_t residentBytes(pid_t pid) {
  std::ifstream in("/proc/" + std::to_string(pid) + "/status");
  for (std::string line; std::getline(in, line);) {
    if (line.rfind("VmRSS:", 0) == 0) return 1024ULL * std::strtoull(line.c_str() + 6, nullptr, 10);
  }
  return 0;
}

// The processes whose parent is `parent`, by pid, with their names (/proc/PID/comm).
std::map<pid_t, std::string> childrenOf(pid_t parent) {
  std::map<pid_t, std::string> children;
  std::error_code error;
  for (fs::directory_iterator entry("/proc", error); !error && entry != fs::directory_iterator();
       entry.increment(error)) {
    const std::string name = entry->path().filename();
    if (name.empty() || name.find_first_not_of("0123456789") != std::string::npos) continue;
    std::ifstream stat(entry->path() / "stat");
    std::string line;
    if (!std::getline(stat, line)) continue;
    const auto close = line.rfind(')');
    if (close == std::string::npos) continue;
    std::istringstream fields(line.substr(close + 2));
    std::string state;
    long ppid = 0;
    fields >> state >> ppid;
    if (ppid != parent) continue;
    std::ifstream comm(entry->path() / "comm");
    std::string command;
    std::getline(comm, command);
    children[static_cast<pid_t>(std::atol(name.c_str()))] = command;
  }
  return children;
}

// Lines appended to a growing file, counted as they come (the episode log: one per episode).
class LineCounter {
 public:
  explicit LineCounter(fs::path path) : path_(std::move(path)) {}
  std::uint64_t count() {
    std::ifstream in(path_, std::ios::binary);
    if (!in) return lines_;
    in.seekg(static_cast<std::streamoff>(offset_));
    char buffer[65536];
    while (in.read(buffer, sizeof buffer) || in.gcount() > 0) {
      const auto got = static_cast<std::size_t>(in.gcount());
      lines_ += static_cast<std::uint64_t>(std::count(buffer, buffer + got, '\n'));
      offset_ += got;
    }
    return lines_;
  }

 private:
  fs::path path_;
  std::uint64_t offset_ = 0;
  std::uint64_t lines_ = 0;
};

// One sample of every process of the run: name (pid) -> VmRSS bytes.
using MemorySample = std::map<std::string, std::uint64_t>;

MemorySample sampleMemory(pid_t launcher) {
  MemorySample sample;
  sample["sensornet (launcher)"] = residentBytes(launcher);
  for (const auto& [pid, name] : childrenOf(launcher)) {
    sample[name + " (" + std::to_string(pid) + ")"] = residentBytes(pid);
  }
  return sample;
}

// The least-squares slope of RSS against episodes over the samples from the checkpoint on.
double slopeBytesPerEpisode(const std::vector<std::pair<std::uint64_t, MemorySample>>& samples,
                            const std::string& process) {
  double n = 0, sx = 0, sy = 0, sxx = 0, sxy = 0;
  for (const auto& [episodes, sample] : samples) {
    const auto it = sample.find(process);
    if (it == sample.end() || it->second == 0) continue;
    const double x = static_cast<double>(episodes), y = static_cast<double>(it->second);
    n += 1;
    sx += x;
    sy += y;
    sxx += x * x;
    sxy += x * y;
  }
  const double d = n * sxx - sx * sx;
  return n >= 2 && d > 0 ? (n * sxy - sx * sy) / d : 0.0;
}

// `sensornet launch` of the default scenario at --time-scale 1000 for `episodes` episodes:
// VmRSS of the launcher and each of its children after `checkpoint` episodes (the episode log's
// line count), every `checkpoint` episodes after it, and when the last episode is logged.
int memory(std::uint64_t episodes, std::uint64_t checkpoint) {
#ifndef SENSORNET_LAUNCHER
  std::fprintf(stderr, "emulator_bench memory: built without the launcher\n");
  return 2;
#else
  const std::string run = runId("memory", 0);
  Processes processes(fs::temp_directory_path() / run);
  const fs::path report = processes.dir() / "report.json";
  const auto start = std::chrono::steady_clock::now();
  BackgroundProcess& launcher = processes.start(
      "launcher",
      {SENSORNET_LAUNCHER, "launch", kSourceDir + "/scenarios/default.yaml", "--episodes",
       std::to_string(episodes), "--time-scale", "1000", "--surrogate", "uniform", "--run-id", run,
       "--log-dir", processes.dir().string(), "--report", report.string(), "--no-html"});
  std::printf("memory: %llu episodes of the default scenario at --time-scale 1000 (%s); VmRSS "
              "of every process after %llu episodes, every %llu after, and at the last\n",
              static_cast<unsigned long long>(episodes), processes.dir().c_str(),
              static_cast<unsigned long long>(checkpoint),
              static_cast<unsigned long long>(checkpoint));
  std::fflush(stdout);
  LineCounter logged(sensornet::report::episodeLogPath(report));
  std::vector<std::pair<std::uint64_t, MemorySample>> samples;
  std::uint64_t next = checkpoint;
  std::optional<int> code;
  while (!(code = launcher.waitForExit(50ms))) {
    const std::uint64_t done = logged.count();
    if (done < next && done < episodes) continue;
    samples.emplace_back(done, sampleMemory(launcher.pid()));
    std::printf("  %llu episodes after %.0f s\n", static_cast<unsigned long long>(done),
                secondsSince(start));
    std::fflush(stdout);
    if (done >= episodes) break;
    next = (done / checkpoint + 1) * checkpoint;
  }
  if (!code) code = launcher.waitForExit(120s);
  const double wall = secondsSince(start);
  if (samples.size() < 2) {
    std::printf("memory: the run ended after %llu episodes, exit %d (see %s)\n",
                static_cast<unsigned long long>(logged.count()), code.value_or(-1),
                processes.dir().c_str());
    return 1;
  }
  const auto& [first_episodes, first] = samples.front();
  const auto& [last_episodes, last] = samples.back();
  std::printf("memory: launcher exit %d after %.0f s; VmRSS after %llu and %llu episodes:\n",
              code.value_or(-1), wall, static_cast<unsigned long long>(first_episodes),
              static_cast<unsigned long long>(last_episodes));
  for (const auto& [process, bytes] : first) {
    const auto it = last.find(process);
    const std::uint64_t end = it != last.end() ? it->second : 0;
    std::printf("  %-28s %8.2f MB -> %8.2f MB  ratio %.3f  slope %+7.1f bytes/episode (least "
                "squares over %zu samples)\n",
                process.c_str(), 1e-6 * static_cast<double>(bytes),
                1e-6 * static_cast<double>(end),
                bytes > 0 ? static_cast<double>(end) / static_cast<double>(bytes) : 0.0,
                slopeBytesPerEpisode(samples, process), samples.size());
  }
  std::fflush(stdout);
  return code == 0 ? 0 : 1;
#endif
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

// How busy one thread was: its busiest 1-second window (as `top -H` would show it) and its CPU
// time over the whole run.
struct ThreadLoad {
  std::string name;  // process/thread
  double peak_share = 0.0;
  double cpu_s = 0.0;
};

// CPU time of every thread of some processes, sampled while they run: which one saturates, and
// what each costs per measurement.
class ThreadCpu {
 public:
  // Reads /proc/<pid>/task/*/stat of a process started as `process`.
  void sample(pid_t pid, const std::string& process) {
    const double t = secondsSince(start_);
    std::error_code error;  // a process may end while it is read: what is gone is skipped
    for (fs::directory_iterator task("/proc/" + std::to_string(pid) + "/task", error);
         !error && task != fs::directory_iterator(); task.increment(error)) {
      std::ifstream in(task->path() / "stat");
      std::string line;
      if (!std::getline(in, line)) continue;
      const auto open = line.find('('), close = line.rfind(')');
      if (open == std::string::npos || close == std::string::npos || close < open) continue;
      std::istringstream fields(line.substr(close + 2));
      std::string field;
      double utime = 0.0, stime = 0.0;
      for (int i = 0; i < 13 && fields >> field; ++i) {  // state is field 3 of stat(5)
        if (i == 11) utime = std::atof(field.c_str());   // field 14
        if (i == 12) stime = std::atof(field.c_str());   // field 15
      }
      Series& series = threads_[std::atol(task->path().filename().c_str())];
      series.name = process + "/" + line.substr(open + 1, close - open - 1);
      series.points.emplace_back(t, (utime + stime) / ticks_per_s_);
    }
  }

  // CPU seconds of every thread of the processes started as `process`.
  [[nodiscard]] double cpuOf(const std::string& process) const {
    double total = 0.0;
    for (const auto& [tid, series] : threads_) {
      if (series.name.starts_with(process + "/")) {
        total += series.points.back().second - series.points.front().second;
      }
    }
    return total;
  }

  // The `count` threads with the highest peak share of one core over 1-second windows.
  [[nodiscard]] std::vector<ThreadLoad> busiest(std::size_t count) const {
    std::vector<ThreadLoad> loads;
    for (const auto& [tid, series] : threads_) {
      double peak = 0.0;
      std::size_t from = 0;
      for (std::size_t i = 0; i < series.points.size(); ++i) {
        const auto& [t, cpu] = series.points[i];
        while (from + 1 < i && t - series.points[from + 1].first >= 1.0) ++from;
        const double span = t - series.points[from].first;
        if (span >= 1.0) peak = std::max(peak, (cpu - series.points[from].second) / span);
      }
      const double cpu_s = series.points.back().second - series.points.front().second;
      loads.push_back({series.name, peak, cpu_s});
    }
    std::sort(loads.begin(), loads.end(),
              [](const ThreadLoad& a, const ThreadLoad& b) { return a.peak_share > b.peak_share; });
    if (loads.size() > count) loads.resize(count);
    return loads;
  }

 private:
  struct Series {
    std::string name;
    std::vector<std::pair<double, double>> points;  // (wall s since start, CPU s)
  };
  std::chrono::steady_clock::time_point start_ = std::chrono::steady_clock::now();
  double ticks_per_s_ = static_cast<double>(::sysconf(_SC_CLK_TCK));
  std::map<long, Series> threads_;
};

// The default scenario with its two constraint rows replaced by one loose bandwidth row, so that
// any equal rates are feasible (as Trust.OverloadIsFullyFusedOrReportedNeverCompletedWithLosses).
fs::path writeOverloadScenario(const fs::path& dir) {
  std::ifstream in(kSourceDir + "/scenarios/default.yaml");
  std::ostringstream text;
  text << in.rdbuf();
  std::string yaml = text.str();
  const auto at = yaml.find("constraints:");
  if (at == std::string::npos) {
    throw std::runtime_error("scenarios/default.yaml: no 'constraints:' to replace");
  }
  yaml = yaml.substr(0, at) + "constraints:\n  C: [[1, 1, 1, 1, 1, 1]]\n  b: [1.0e7]\n";
  const fs::path path = dir / "overload.yaml";
  std::ofstream(path) << yaml;
  return path;
}

// Every one of `sensors` sensors at `rate_hz` over the whole horizon (3 s, 30 intervals, as
// default.yaml).
fs::path writeConstantSchedule(const fs::path& dir, int sensors, double rate_hz) {
  nlohmann::json rates = nlohmann::json::array();
  for (int i = 0; i < 30; ++i) {
    rates.push_back(std::vector<double>(static_cast<std::size_t>(sensors), rate_hz));
  }
  const fs::path path = dir / "constant.json";
  std::ofstream(path) << nlohmann::json{{"horizon", 3.0}, {"intervals", 30}, {"rates", rates}};
  return path;
}

// What one throughput run emulates: a scenario, a schedule file and the blocks of sensors of
// the sensor_agent processes ("0-2", "3-5").
struct Layout {
  fs::path scenario;
  fs::path schedule;
  std::vector<std::string> blocks;
};

// The overload sweep's layout: the loosened default scenario (n = 4), its 6 sensors at equal
// rates in two processes.
Layout defaultLayout(const fs::path& dir, double total_rate_hz) {
  return {writeOverloadScenario(dir), writeConstantSchedule(dir, 6, total_rate_hz / 6.0),
          {"0-2", "3-5"}};
}

// The fleet: a random scenario of `sensors` one-row sensors (n = 4, one bandwidth row that the
// rates fill to 99%), each at `rate_hz`, in `process_count` processes of equal blocks.
Layout fleetLayout(const fs::path& dir, int process_count, int sensors, double rate_hz) {
  Layout layout{writeRandomScenario(dir, 4, sensors, 1.01 * sensors * rate_hz),
                writeConstantSchedule(dir, sensors, rate_hz),
                {}};
  const int per_process = (sensors + process_count - 1) / process_count;
  for (int first = 0; first < sensors; first += per_process) {
    const int last = std::min(first + per_process, sensors) - 1;
    layout.blocks.push_back(std::to_string(first) + "-" + std::to_string(last));
  }
  return layout;
}

struct OverloadRun {
  std::string status;
  std::vector<long long> sent, received, lost;  // per sensor, episode 0
  long long sent_total = 0, received_total = 0, lost_total = 0, rejected_total = 0;
  long long late_total = 0;  // arrived after the filter had passed them: the episode is re-fused
  double drain_s = 0.0;
  long long backlog = 0;
  double median_us = 0.0, p99_us = 0.0;
  double wall_s = 0.0;
  std::string faults;  // kinds and how often ("overload, sensor_lag x6")
  std::vector<ThreadLoad> busiest;
  double fusion_cpu_s = 0.0;  // all threads of the fusion center

  // Issue 28's bounds: completed, nothing lost, median under 1 ms and p99 under 10 ms.
  [[nodiscard]] bool keepsUp() const {
    return status == "completed" && lost_total == 0 && median_us < 1000.0 && p99_us < 10000.0;
  }
  // Far enough from keeping up that a higher rate is not worth a run.
  [[nodiscard]] bool clearlyFails() const {
    return status != "completed" || lost_total > 0 || median_us > 5000.0;
  }
};

std::string faultKinds(const nlohmann::json& faults) {
  std::map<std::string, int> kinds;
  for (const auto& f : faults) kinds[f.value("kind", std::string("?"))] += 1;
  std::string text;
  for (const auto& [kind, count] : kinds) {
    text += (text.empty() ? "" : ", ") + kind + (count > 1 ? " x" + std::to_string(count) : "");
  }
  return text.empty() ? "none" : text;
}

std::string joined(const std::vector<long long>& values) {
  std::string text;
  for (const long long v : values) text += (text.empty() ? "" : ",") + std::to_string(v);
  return text;
}

// One episode at time scale 1 of what `layoutIn(dir)` writes into the run's directory; nullopt
// (after saying why) if the run produced no report.
// `extra`: flags every process gets (--security DIR); `fusion_extra`: the fusion center's only
// (--metrics ADDR); `record`: a recording of the run (RunRecorder in this process, as `sensornet
// launch --record` runs one in the launcher), made before any process starts.
std::optional<OverloadRun> throughputRun(const std::string& run,
                                         const std::function<Layout(const fs::path&)>& layoutIn,
                                         const std::vector<std::string>& extra = {},
                                         const std::vector<std::string>& fusion_extra = {},
                                         bool record = false) {
  Processes processes(fs::temp_directory_path() / run);
  std::optional<sensornet::dds::Domain> record_domain;
  std::optional<sensornet::dds::Participant> record_participant;
  std::optional<recording::RunRecorder> recorder;
  if (record) {
    wire::RunOptions options;
    options.run_id = run;
    record_domain.emplace(options.domainConfig());
    record_participant.emplace(*record_domain);
    recorder.emplace(*record_participant, run, processes.dir() / "run.mcap", sensornet::McapMap{});
  }
  const Layout layout = layoutIn(processes.dir());
  const fs::path report = processes.dir() / "report.json";
  std::vector<std::pair<std::string, BackgroundProcess*>> watched;
  BackgroundProcess& fusion = processes.start(
      "fusion_center",
      withFlags(withFlags({kFusionCenter, "serve", "--run-id", run, "--report", report.string()},
                          extra),
                fusion_extra));
  watched.emplace_back("fusion_center", &fusion);
  for (const std::string& block : layout.blocks) {
    watched.emplace_back(
        std::string("sensors-") + block,
        &processes.start(std::string("sensors-") + block,
                         withFlags({kSensorAgent, "--run-id", run, "--sensors", block}, extra)));
  }
  const auto start = std::chrono::steady_clock::now();
  BackgroundProcess& coordinator = processes.start(
      "coordinator",
      withFlags({kCoordinator, "serve", "--run-id", run, "--scenario", layout.scenario.string(),
                 "--schedule", layout.schedule.string(), "--episodes", "1", "--time-scale", "1",
                 "--seed", "1"},
                extra));
  // The run ends when the coordinator has the episode's report; the fusion center then writes
  // the final report and exits. Overload can take long to drain: give it minutes.
  ThreadCpu cpu;
  std::optional<int> fusion_code;
  while (!(fusion_code = fusion.waitForExit(100ms)) && secondsSince(start) < 300.0) {
    for (const auto& [name, process] : watched) cpu.sample(process->pid(), name);
  }
  const double wall = secondsSince(start);
  const int code = coordinator.waitForExit(10s).value_or(-1);
  const nlohmann::json r = readReport(report);
  if (!fusion_code || r.is_null() || !r.contains("per_episode") || r["per_episode"].empty()) {
    std::printf("  no report after %.0f s (coordinator %d; see %s)\n", wall, code,
                processes.dir().c_str());
    return std::nullopt;
  }
  OverloadRun o;
  const auto& e = r["per_episode"][0];
  o.status = r["status"].get<std::string>();
  o.sent = e["sent"].get<std::vector<long long>>();
  o.received = e["received"].get<std::vector<long long>>();
  o.lost = e["lost"].get<std::vector<long long>>();
  const auto& s = r["summary"];
  o.sent_total = s["sent"].get<long long>();
  o.received_total = s["received"].get<long long>();
  o.lost_total = s["lost"].get<long long>();
  o.rejected_total = s["rejected"].get<long long>();
  for (const long long late : e["late"].get<std::vector<long long>>()) o.late_total += late;
  o.drain_s = e["drain_s"].get<double>();
  o.backlog = e["backlog"].get<long long>();
  o.median_us = 1e6 * r["latency_s"]["median"].get<double>();
  o.p99_us = 1e6 * r["latency_s"]["p99"].get<double>();
  o.wall_s = wall;
  o.faults = faultKinds(r.value("faults", nlohmann::json::array()));
  o.busiest = cpu.busiest(4);
  o.fusion_cpu_s = cpu.cpuOf("fusion_center");
  return o;
}

// The overload sweep's run: the default layout at `total_rate_hz`.
std::optional<OverloadRun> overloadRun(const std::string& run, double total_rate_hz,
                                       const std::vector<std::string>& extra = {},
                                       const std::vector<std::string>& fusion_extra = {},
                                       bool record = false) {
  return throughputRun(
      run, [total_rate_hz](const fs::path& dir) { return defaultLayout(dir, total_rate_hz); },
      extra, fusion_extra, record);
}

void printOverloadRun(double total_rate_hz, const OverloadRun& o) {
  std::printf("  %7.0f/s  %-9s sent %lld, received %lld, lost %lld, rejected %lld, late %lld; "
              "drain %.3f s, backlog %lld; latency median %.0f us, p99 %.0f us; wall %.1f s -> "
              "%s\n",
              total_rate_hz, o.status.c_str(), o.sent_total, o.received_total, o.lost_total,
              o.rejected_total, o.late_total, o.drain_s, o.backlog, o.median_us, o.p99_us, o.wall_s,
              o.keepsUp() ? "keeps up" : "does not keep up");
  if (o.sent.size() <= 12) {
    std::printf("            per sensor: sent [%s], received [%s], lost [%s]; faults: %s\n",
                joined(o.sent).c_str(), joined(o.received).c_str(), joined(o.lost).c_str(),
                o.faults.c_str());
  } else {
    std::printf("            %zu sensors; faults: %s\n", o.sent.size(), o.faults.c_str());
  }
  std::string threads;
  for (const ThreadLoad& t : o.busiest) {
    char text[128];
    std::snprintf(text, sizeof text, "%s%s %.0f%% (%.1f us)", threads.empty() ? "" : ", ",
                  t.name.c_str(), 100.0 * t.peak_share,
                  1e6 * t.cpu_s / static_cast<double>(std::max(1LL, o.received_total)));
    threads += text;
  }
  std::printf("            busiest threads, peak %% of a core over 1 s (CPU per measurement): %s\n",
              threads.c_str());
  std::fflush(stdout);
}

// ddsperf's domain: one of its own (ids up to 230 fit the loopback configuration's port mapping),
// so that another bench's ddsperf on this host is not counted.
int ddsperfDomain() { return 200 + static_cast<int>(::getpid() % 30); }

// ddsperf pub/sub of 64-byte samples, printed; the median samples/s (0 if it failed).
double ddsperfThroughputLine(const char* when) {
  const auto t = sensornet::bench::ddsperfThroughput(
      fs::temp_directory_path() / runId("ddsperf-throughput", 0), ddsperfDomain(), 64, 6);
  const double rate = median(t.samples_per_s);
  std::printf("  ddsperf pub/sub, 64-byte samples, reliable keep-all, %s: %.0f samples/s (median "
              "of %zu s), lost %ld%s\n",
              when, rate, t.samples_per_s.size(), t.lost,
              t.peers == 1 ? "" : " (WARNING: the subscriber did not see exactly one peer)");
  std::fflush(stdout);
  return rate;
}

std::vector<double> parseRates(const char* text) {
  std::vector<double> rates;
  std::istringstream in(text);
  for (std::string item; std::getline(in, item, ',');) {
    const double rate = std::atof(item.c_str());
    if (rate > 0.0) rates.push_back(rate);
  }
  return rates;
}

void overload(const std::vector<double>& rates) {
  std::printf(
      "overload: default scenario (n = 4), 6 sensors in 2 processes, time scale 1, one episode "
      "of 3 s, constant equal rates; keeps up = completed, 0 lost, median < 1 ms, p99 < 10 ms\n");
  const double ddsperf_before = ddsperfThroughputLine("before the sweep");
  std::optional<double> highest;
  for (std::size_t i = 0; i < rates.size(); ++i) {
    const auto o = overloadRun(runId("overload", static_cast<int>(i)), rates[i]);
    if (!o) break;
    printOverloadRun(rates[i], *o);
    if (o->keepsUp()) highest = std::max(highest.value_or(0.0), rates[i]);
    if (o->clearlyFails()) {
      std::printf("  (stopping: %.0f/s clearly fails)\n", rates[i]);
      break;
    }
  }
  const double ddsperf_after = ddsperfThroughputLine("after the sweep");
  const double ddsperf_rate = ddsperf_before > 0.0 && ddsperf_after > 0.0
                                  ? 0.5 * (ddsperf_before + ddsperf_after)
                                  : std::max(ddsperf_before, ddsperf_after);  // one failed
  if (!highest) {
    std::printf("overload: no rate kept up; ddsperf %.0f samples/s\n", ddsperf_rate);
    return;
  }
  std::printf("overload: highest rate that keeps up: %.0f measurements/s; ddsperf %.0f samples/s "
              "(mean of before and after); ratio %.3f (target 0.3)\n",
              *highest, ddsperf_rate, ddsperf_rate > 0.0 ? *highest / ddsperf_rate : 0.0);
}

// `rounds` runs of `sensors` sensors in `process_count` processes at `rate_hz` each (issue 28:
// 1000 sensors in 50 processes at 100 Hz), one episode at time scale 1 each.
void fleet(int rounds, int process_count, int sensors, double rate_hz) {
  std::printf("fleet: random scenario (n = 4), %d sensors in %d processes at %g Hz each (%.0f/s "
              "in all), time scale 1, one episode of 3 s; keeps up = completed, 0 lost, median "
              "< 1 ms, p99 < 10 ms\n",
              sensors, process_count, rate_hz, sensors * rate_hz);
  int kept_up = 0;
  std::vector<double> medians, p99s;
  for (int round = 0; round < rounds; ++round) {
    const auto o = throughputRun(runId("fleet", round), [&](const fs::path& dir) {
      return fleetLayout(dir, process_count, sensors, rate_hz);
    });
    if (!o) continue;
    printOverloadRun(sensors * rate_hz, *o);
    kept_up += o->keepsUp() ? 1 : 0;
    medians.push_back(o->median_us);
    p99s.push_back(o->p99_us);
  }
  std::printf("fleet: %d of %d rounds kept up; latency median %.0f us, p99 %.0f us (medians over "
              "the rounds)\n",
              kept_up, rounds, medians.empty() ? 0.0 : median(medians),
              p99s.empty() ? 0.0 : median(p99s));
  // The yardstick of the same shape: the transport alone, without sampling or fusion.
  const double each_hz = sensors * rate_hz / process_count;
  const auto d = sensornet::bench::ddsperfFleet(
      fs::temp_directory_path() / runId("ddsperf-fleet", 0), ddsperfDomain(), process_count,
      each_hz, 64, 9);
  std::printf("fleet: ddsperf alone, %d publishers at %.0f samples/s each (64 bytes, reliable "
              "keep-all) and one subscriber: received %.0f/s, lost %ld; the machine %.0f%% busy "
              "(%d cores), %.1f us of CPU per sample\n",
              process_count, each_hz, d.samples_per_s, d.lost, 100.0 * d.busy_share, d.cores,
              d.samples_per_s > 0.0 ? 1e6 * d.busy_share * d.cores / d.samples_per_s : 0.0);
}

// ---- security (issue 12, part 3): the cost of DDS Security, secured against unsecured ----

double fusionCpuPerMeasurementUs(const OverloadRun& o) {
  return 1e6 * o.fusion_cpu_s / static_cast<double>(std::max(1LL, o.received_total));
}

// A fresh `sensornet pki init` in a temporary folder; empty if it failed (said why).
std::string makeBenchPki() {
  const fs::path dir = fs::temp_directory_path() / runId("pki", 0);
  const sensornet::testing::ProcessResult r =
      sensornet::testing::runProcess({kLauncher, "pki", "init", dir.string(), "--force",
                                      "--sensors", "6", "--sensor-block", "0-5",
                                      "--sensor-block", "0-2", "--sensor-block", "3-5"},
                                     120s);
  if (r.exit_code != 0) {
    std::printf("security: sensornet pki init failed: %s\n", r.err.c_str());
    return {};
  }
  return dir.string();
}

// Per round, unsecured then secured: the latency run (default scenario at 10x, 6 one-sensor
// processes, 20 episodes) and one overload episode at each of `rates` (6 sensors in 2 processes,
// time scale 1). Latency: medians over rounds and the median of the per-round ratios. Fusion
// throughput: the highest rate kept up (completed, nothing lost, median < 1 ms) and the fusion
// center's CPU per measurement at each rate.
void security(int rounds, const std::vector<double>& rates) {
  const std::string pki = makeBenchPki();
  if (pki.empty()) return;
  const std::vector<std::string> secured = {"--security", pki};
  std::printf("security: unsecured against secured (governance: discovery and liveliness "
              "encrypted, payload encrypted, submessages signed), %d rounds\n",
              rounds);
  std::vector<double> plain_median, secure_median, plain_p99, secure_p99, ratio;
  std::map<double, std::vector<double>> plain_cpu, secure_cpu;
  std::map<double, int> plain_kept, secure_kept;
  for (int round = 0; round < rounds; ++round) {
    const auto a = latencyRun(runId("sec-plain", round), 6);
    const auto b = latencyRun(runId("sec-secured", round), 6, secured);
    if (!a || !b) return;
    plain_median.push_back(a->median_us);
    plain_p99.push_back(a->p99_us);
    secure_median.push_back(b->median_us);
    secure_p99.push_back(b->p99_us);
    ratio.push_back(b->median_us / a->median_us);
    std::printf("  round %d latency: unsecured median %.1f us (p99 %.1f), secured median %.1f us "
                "(p99 %.1f); %d and %d measurements\n",
                round, a->median_us, a->p99_us, b->median_us, b->p99_us, a->received,
                b->received);
    for (std::size_t i = 0; i < rates.size(); ++i) {
      const int tag = round * 100 + static_cast<int>(i);
      const auto p = overloadRun(runId("sec-plain-load", tag), rates[i]);
      const auto s = overloadRun(runId("sec-secured-load", tag), rates[i], secured);
      if (!p || !s) return;
      for (const auto& [run, into, kept, name] :
           {std::tuple{&*p, &plain_cpu, &plain_kept, "unsecured"},
            std::tuple{&*s, &secure_cpu, &secure_kept, "secured"}}) {
        const double fusion_cpu = fusionCpuPerMeasurementUs(*run);
        (*into)[rates[i]].push_back(fusion_cpu);
        (*kept)[rates[i]] += run->keepsUp() ? 1 : 0;
        std::printf("  round %d %.0f/s %-9s: %s, received %lld, lost %lld, drain %.3f s, latency "
                    "median %.0f us, p99 %.0f us, fusion center CPU %.1f us/measurement -> %s\n",
                    round, rates[i], name, run->status.c_str(), run->received_total,
                    run->lost_total, run->drain_s, run->median_us, run->p99_us, fusion_cpu,
                    run->keepsUp() ? "keeps up" : "does not keep up");
      }
      std::fflush(stdout);
    }
  }
  std::printf("security, medians of %d rounds (busy machine: other builds and benches run):\n",
              rounds);
  std::printf("  publish-to-fusion latency: unsecured %.1f us (p99 %.1f), secured %.1f us (p99 "
              "%.1f); secured/unsecured %.2fx (median of per-round ratios)\n",
              median(plain_median), median(plain_p99), median(secure_median),
              median(secure_p99), median(ratio));
  for (const double rate : rates) {
    std::printf("  %.0f/s: fusion center CPU per measurement unsecured %.1f us, secured %.1f us "
                "(%.2fx); kept up in %d/%d and %d/%d rounds\n",
                rate, median(plain_cpu[rate]), median(secure_cpu[rate]),
                median(secure_cpu[rate]) / median(plain_cpu[rate]), plain_kept[rate], rounds,
                secure_kept[rate], rounds);
  }
}

// (issue 26) What recording and live metrics cost: per round and rate, one overload episode
// plain, with --metrics on the fusion center (it rebuilds and serves its exposition every
// 250 ms; nothing scrapes it: the build is the cost), and recorded (one more reader of every
// topic, in this process, writing the MCAP file). Latency median, the fusion center's CPU per
// measurement and whether it keeps up; medians over rounds and the ratios to plain.
void recordingCost(int rounds, const std::vector<double>& rates) {
  std::printf("recording: plain against --metrics and against a recording, %d rounds\n", rounds);
  struct Variant {
    const char* name;
    std::vector<std::string> fusion_extra;
    bool record;
  };
  const std::vector<Variant> variants = {{"plain", {}, false},
                                         {"metrics", {"--metrics", "127.0.0.1:0"}, false},
                                         {"recorded", {}, true}};
  std::map<std::pair<double, std::string>, std::vector<double>> latency, cpu;
  std::map<std::pair<double, std::string>, int> kept;
  for (int round = 0; round < rounds; ++round) {
    for (std::size_t i = 0; i < rates.size(); ++i) {
      for (const Variant& v : variants) {
        const int tag = round * 100 + static_cast<int>(i);
        const auto o = overloadRun(runId(std::string("rec-") + v.name, tag), rates[i], {},
                                   v.fusion_extra, v.record);
        if (!o) return;
        const std::pair key{rates[i], std::string(v.name)};
        latency[key].push_back(o->median_us);
        cpu[key].push_back(fusionCpuPerMeasurementUs(*o));
        kept[key] += o->keepsUp() ? 1 : 0;
        std::printf("  round %d %.0f/s %-8s: %s, received %lld, lost %lld, latency median %.0f us, "
                    "p99 %.0f us, fusion center CPU %.1f us/measurement -> %s\n",
                    round, rates[i], v.name, o->status.c_str(), o->received_total, o->lost_total,
                    o->median_us, o->p99_us, fusionCpuPerMeasurementUs(*o),
                    o->keepsUp() ? "keeps up" : "does not keep up");
        std::fflush(stdout);
      }
    }
  }
  std::printf("recording, medians of %d rounds (busy machine: other builds and benches run):\n",
              rounds);
  for (const double rate : rates) {
    const double base_latency = median(latency[{rate, "plain"}]);
    const double base_cpu = median(cpu[{rate, "plain"}]);
    for (const Variant& v : variants) {
      const std::pair key{rate, std::string(v.name)};
      std::printf("  %.0f/s %-8s: latency median %.0f us (%.2fx), fusion center CPU %.1f "
                  "us/measurement (%.2fx), kept up in %d/%d rounds\n",
                  rate, v.name, median(latency[key]), median(latency[key]) / base_latency,
                  median(cpu[key]), median(cpu[key]) / base_cpu, kept[key], rounds);
    }
  }
}

// The programs of a turnaround run: this build's, or SENSORNET_BENCH_PROGRAMS=<build dir>'s.
struct Programs {
  std::string coordinator = kCoordinator;
  std::string fusion_center = kFusionCenter;
  std::string sensor_agent = kSensorAgent;
};

Programs benchPrograms() {
  Programs p;
  if (const char* dir = std::getenv("SENSORNET_BENCH_PROGRAMS"); dir != nullptr && *dir != '\0') {
    const fs::path d(dir);
    p.coordinator = (d / "coordinator" / "coordinator").string();
    p.fusion_center = (d / "fusion_center" / "fusion_center").string();
    p.sensor_agent = (d / "sensor_agent" / "sensor_agent").string();
  }
  return p;
}

// One run of `episodes` episodes of the default scenario at `time_scale`, watched on the wire.
struct TurnaroundRun {
  bool completed = false;
  int episodes_reported = 0;
  double run_s = 0.0;             // first episode's start to the last Report
  double whole_s = 0.0;           // processes started to the coordinator's exit
  double overhead_s = 0.0;        // per episode: (run_s - emulated limit) / episodes
  double gap_median_s = 0.0;      // an episode's end to the next one's start
  double report_median_s = 0.0;   // an episode's end to its Report at the probe
  double tally_median_s = 0.0;    // an episode's end to its last EpisodeTally's publication
  double episodes_per_s = 0.0;
};

constexpr double kDefaultHorizonS = 3.0;  // scenarios/default.yaml

std::optional<TurnaroundRun> turnaroundRun(const std::string& run, int episodes,
                                           double time_scale) {
  namespace em = sensornet::emulator;
  const Programs programs = benchPrograms();
  Processes processes(fs::temp_directory_path() / run);
  const fs::path report = processes.dir() / "report.json";
  sensornet::wire::RunOptions options;
  options.run_id = run;
  sensornet::dds::Domain domain(options.domainConfig());
  sensornet::dds::Participant participant(domain);
  sensornet::dds::Topic<sensornet_EpisodeControl> control_topic(participant);
  sensornet::dds::Topic<sensornet_Report> report_topic(participant);
  sensornet::dds::Reader<sensornet_EpisodeControl> controls(participant, control_topic);
  sensornet::dds::Reader<sensornet_Report> reports(participant, report_topic);
  sensornet::dds::Topic<sensornet_EpisodeTally> tally_topic(participant);
  sensornet::dds::Reader<sensornet_EpisodeTally> tallies(participant, tally_topic);

  const auto began = std::chrono::steady_clock::now();
  processes.start("fusion_center", {programs.fusion_center, "serve", "--run-id", run,
                                    "--report", report.string()});
  for (int j = 0; j < 6; ++j) {
    processes.start("sensor-" + std::to_string(j),
                    {programs.sensor_agent, "--run-id", run, "--sensors", std::to_string(j)});
  }
  std::ostringstream scale;
  scale << time_scale;
  BackgroundProcess& coordinator = processes.start(
      "coordinator", {programs.coordinator, "serve", "--run-id", run, "--scenario",
                      kSourceDir + "/scenarios/default.yaml", "--episodes",
                      std::to_string(episodes), "--time-scale", scale.str()});
  std::map<std::uint32_t, std::int64_t> starts;    // episode -> announced start (wall ns)
  std::map<std::uint32_t, std::int64_t> reported;  // episode -> Report seen at the probe
  std::map<std::uint32_t, std::int64_t> tallied;   // episode -> its last tally's publication
  std::optional<int> code;
  while (!code && secondsSince(began) < 300.0) {
    for (auto& c : controls.take(64).samples) {
      if (c.sample->command == sensornet_EPISODE_START) {
        starts[c.sample->episode] = c.sample->start_wall_time_ns;
      }
    }
    const std::int64_t now = em::wallNowNs();
    for (auto& r : reports.take(64).samples) reported.emplace(r.sample->episode, now);
    for (auto& t : tallies.take(256).samples) {
      std::int64_t& last = tallied[t.sample->episode];
      last = std::max(last, t.sample->wall_time_ns);
    }
    code = coordinator.waitForExit(std::chrono::milliseconds(0));
    if (!code) std::this_thread::sleep_for(500us);
  }
  TurnaroundRun t;
  t.whole_s = secondsSince(began);
  std::this_thread::sleep_for(1s);  // the fusion center writes the report
  const nlohmann::json r = readReport(report);
  t.completed = code == 0 && !r.is_null() && r.value("status", "") == "completed";
  t.episodes_reported = static_cast<int>(reported.size());
  if (starts.empty() || reported.empty()) return t;
  const auto episode_ns = static_cast<std::int64_t>(1e9 * kDefaultHorizonS / time_scale);
  std::vector<double> gaps, to_report, to_tally;
  for (const auto& [e, start] : starts) {
    if (const auto next = starts.find(e + 1); next != starts.end()) {
      gaps.push_back(1e-9 * static_cast<double>(next->second - (start + episode_ns)));
    }
    if (const auto seen = reported.find(e); seen != reported.end()) {
      to_report.push_back(1e-9 * static_cast<double>(seen->second - (start + episode_ns)));
    }
    if (const auto seen = tallied.find(e); seen != tallied.end()) {
      to_tally.push_back(1e-9 * static_cast<double>(seen->second - (start + episode_ns)));
    }
  }
  t.run_s = 1e-9 * static_cast<double>(reported.rbegin()->second - starts.begin()->second);
  const double limit_s = episodes * kDefaultHorizonS / time_scale;
  t.overhead_s = (t.run_s - limit_s) / episodes;
  t.episodes_per_s = episodes / t.run_s;
  t.gap_median_s = gaps.empty() ? 0.0 : median(gaps);
  t.report_median_s = to_report.empty() ? 0.0 : median(to_report);
  t.tally_median_s = to_tally.empty() ? 0.0 : median(to_tally);
  return t;
}

// `episodes`: per time scale 1000, 100 and 10 (fewer for a slow baseline).
void turnaround(int rounds, const std::vector<double>& episodes) {
  struct Case {
    double time_scale;
    int episodes;
  };
  const std::vector<double> scales = {1000.0, 100.0, 10.0};
  std::vector<Case> cases;
  for (std::size_t i = 0; i < scales.size() && i < episodes.size(); ++i) {
    cases.push_back({scales[i], std::max(2, static_cast<int>(episodes[i]))});
  }
  std::printf("turnaround: the default scenario (T = %g s), 6 sensor processes; median of %d "
              "rounds%s\n",
              kDefaultHorizonS, rounds,
              std::getenv("SENSORNET_BENCH_PROGRAMS") != nullptr ? " (SENSORNET_BENCH_PROGRAMS)"
                                                                 : "");
  for (const Case& c : cases) {
    std::vector<double> per_s, overhead, gap, to_report, to_tally, whole;
    int completed = 0;
    for (int round = 0; round < rounds; ++round) {
      const auto t = turnaroundRun(
          runId("turnaround" + std::to_string(static_cast<int>(c.time_scale)), round),
          c.episodes, c.time_scale);
      if (!t) continue;
      completed += t->completed ? 1 : 0;
      per_s.push_back(t->episodes_per_s);
      overhead.push_back(t->overhead_s);
      gap.push_back(t->gap_median_s);
      to_report.push_back(t->report_median_s);
      to_tally.push_back(t->tally_median_s);
      whole.push_back(t->whole_s);
      std::printf("  time scale %g, %d episodes, round %d: %s, %d reports seen; %.1f episodes/s "
                  "(limit %.1f), overhead %.2f ms/episode, gap %.2f ms, end to last tally %.2f "
                  "ms, end to report %.2f ms, whole run %.2f s\n",
                  c.time_scale, c.episodes, round, t->completed ? "completed" : "NOT COMPLETED",
                  t->episodes_reported, t->episodes_per_s, c.time_scale / kDefaultHorizonS,
                  1e3 * t->overhead_s, 1e3 * t->gap_median_s, 1e3 * t->tally_median_s,
                  1e3 * t->report_median_s, t->whole_s);
      std::fflush(stdout);
    }
    if (per_s.empty()) continue;
    std::printf("turnaround: time scale %g, %d episodes: %.1f episodes/s against a limit of %.1f "
                "(%.0f%%), overhead %.2f ms/episode, gap %.2f ms, end to last tally %.2f ms, end "
                "to report %.2f ms, whole run %.2f s; %d/%d rounds completed\n",
                c.time_scale, c.episodes, median(per_s), c.time_scale / kDefaultHorizonS,
                100.0 * median(per_s) * kDefaultHorizonS / c.time_scale, 1e3 * median(overhead),
                1e3 * median(gap), 1e3 * median(to_tally), 1e3 * median(to_report),
                median(whole), completed, rounds);
    std::fflush(stdout);
  }
}

}  // namespace

int main(int argc, char** argv) {
  const std::string what = argc > 1 ? argv[1] : "all";
  if (what == "security") {  // emulator_bench security [rounds = 3] [total rates/s]
    const std::vector<double> rates = parseRates(argc > 3 ? argv[3] : "10000,40000");
    if (rates.empty()) {
      std::fprintf(stderr, "emulator_bench security: expected rates such as 10000,40000\n");
      return 2;
    }
    security(argc > 2 ? std::max(1, std::atoi(argv[2])) : 3, rates);
    return 0;
  }
  if (what == "recording") {  // emulator_bench recording [rounds = 3] [total rates/s]
    const std::vector<double> rates = parseRates(argc > 3 ? argv[3] : "10000,40000");
    if (rates.empty()) {
      std::fprintf(stderr, "emulator_bench recording: expected rates such as 10000,40000\n");
      return 2;
    }
    recordingCost(argc > 2 ? std::max(1, std::atoi(argv[2])) : 3, rates);
    return 0;
  }
  if (what == "memory") {  // emulator_bench memory [episodes = 5000] [checkpoint = 1000]
    return memory(argc > 2 ? std::max(2ULL, std::strtoull(argv[2], nullptr, 10)) : 5000,
                  argc > 3 ? std::max(1ULL, std::strtoull(argv[3], nullptr, 10)) : 1000);
  }
  if (what == "fleet") {  // emulator_bench fleet [rounds = 3] [processes = 50] [sensors = 1000]
                         //                       [Hz each = 100]
    fleet(argc > 2 ? std::max(1, std::atoi(argv[2])) : 3,
          argc > 3 ? std::max(1, std::atoi(argv[3])) : 50,
          argc > 4 ? std::max(1, std::atoi(argv[4])) : 1000, argc > 5 ? std::atof(argv[5]) : 100.0);
    return 0;
  }
  if (what != "all" && what != "startup" && what != "latency" && what != "throughput" &&
      what != "overload" && what != "turnaround") {
    std::fprintf(stderr,
                 "usage: emulator_bench [startup|latency|throughput|turnaround|all] [rounds]\n"
                 "       emulator_bench overload [total rates/s, comma-separated]\n"
                 "       emulator_bench fleet [rounds] [processes] [sensors] [Hz each]\n"
                 "       emulator_bench security|recording [rounds] [total rates/s]\n"
                 "       emulator_bench memory [episodes] [checkpoint]\n");
    return 2;
  }
  if (what == "overload") {
    const std::vector<double> rates =
        parseRates(argc > 2 ? argv[2]
                            : "30000,45000,60000,90000,120000,180000,250000,500000,750000,1000000");
    if (rates.empty()) {
      std::fprintf(stderr, "emulator_bench overload: expected rates such as 30000,60000\n");
      return 2;
    }
    overload(rates);
    return 0;
  }
  if (what == "all" || what == "startup") {
    startup(what == "startup" && argc > 2 ? std::max(1, std::atoi(argv[2])) : 3);
  }
  if (what == "all" || what == "latency") latency(argc > 2 ? std::max(1, std::atoi(argv[2])) : 3);
  if (what == "all" || what == "throughput") throughput();
  if (what == "all" || what == "turnaround") {
    turnaround(what == "turnaround" && argc > 2 ? std::max(1, std::atoi(argv[2])) : 3,
               parseRates(what == "turnaround" && argc > 3 ? argv[3] : "1000,200,30"));
  }
  return 0;
}
