#include "ddsperf.hpp"

#include <chrono>
#include <cstdlib>
#include <fstream>
#include <optional>
#include <sstream>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "sensornet/dds/domain.hpp"
#include "sensornet/emulator/run_report.hpp"
#include "support/background_process.hpp"

namespace sensornet::bench {
namespace {

using namespace std::chrono_literals;
namespace fs = std::filesystem;

double median(std::vector<double> values) { return emulator::quantile(std::move(values), 0.5); }

// The number after `key` in `line` ("... mean 51.4us min 19.2us 50% 30.6us ... cnt 98").
bool numberAfter(const std::string& line, const std::string& key, double& value) {
  const auto at = line.find(key);
  if (at == std::string::npos) return false;
  value = std::atof(line.c_str() + at + key.size());
  return true;
}

// The samples per second of a `ddsperf sub` line ("... size 64 total 780328 lost 0 delta 527364
// lost 0 rate 526.60 kS/s 269.62 Mb/s ..."), or nullopt for any other line.
std::optional<double> subscriberRate(const std::string& line) {
  double rate = 0.0;
  if (line.find(" size ") == std::string::npos || !numberAfter(line, " rate ", rate)) {
    return std::nullopt;
  }
  const auto unit = line.find(' ', line.find(" rate ") + 6);
  const char prefix = unit + 1 < line.size() ? line[unit + 1] : ' ';
  return rate * (prefix == 'M' ? 1e6 : prefix == 'k' ? 1e3 : 1.0);
}

// What `ddsperf sub` printed: its rate for each second, the running count of samples lost, and
// the participants it saw besides itself.
struct SubscriberLog {
  std::vector<double> samples_per_s;
  long lost = 0;
  int peers = 0;
};

SubscriberLog readSubscriberLog(const std::string& text) {
  SubscriberLog log;
  std::istringstream lines(text);
  for (std::string line; std::getline(lines, line);) {
    if (line.find(" participant ") != std::string::npos &&
        line.find(": new") != std::string::npos && line.find("(self)") == std::string::npos) {
      ++log.peers;
    }
    if (const auto rate = subscriberRate(line)) {
      log.samples_per_s.push_back(*rate);
      double lost = 0.0;
      if (numberAfter(line, " lost ", lost)) log.lost = static_cast<long>(lost);  // running
    }
  }
  return log;
}

// `seconds` without the first `head` and the last `tail` (empty if nothing is left).
std::vector<double> middleSeconds(std::vector<double> seconds, std::size_t head, std::size_t tail) {
  if (seconds.size() <= head + tail) return {};
  seconds.erase(seconds.begin(), seconds.begin() + static_cast<std::ptrdiff_t>(head));
  seconds.resize(seconds.size() - tail);
  return seconds;
}

// Points ddsperf at sensornet's loopback configuration while it lives. ddsperf reads its
// configuration from the environment (the bench's own domains are created explicitly, so the
// variable does not touch them).
class LoopbackEnvironment {
 public:
  explicit LoopbackEnvironment(const fs::path& dir) {
    fs::create_directories(dir);
    const fs::path config = dir / "cyclonedds-loopback.xml";
    std::ofstream(config) << dds::loopbackConfigXml();
    ::setenv("CYCLONEDDS_URI", ("file://" + config.string()).c_str(), 1);
  }
  ~LoopbackEnvironment() { ::unsetenv("CYCLONEDDS_URI"); }
  LoopbackEnvironment(const LoopbackEnvironment&) = delete;
  LoopbackEnvironment& operator=(const LoopbackEnvironment&) = delete;
};

}  // namespace

std::vector<DdsperfSecond> runDdsperf(const fs::path& dir, int domain_id, int rate_hz,
                                      int seconds) {
  const LoopbackEnvironment environment(dir);
  const std::string domain = std::to_string(domain_id);
  fs::remove(dir / "ddsperf-pong.log");  // the logs are appended to: start afresh
  fs::remove(dir / "ddsperf-ping.log");
  testing::BackgroundProcess pong(
      {"/usr/bin/ddsperf", "-i", domain, "-D", std::to_string(seconds + 2), "pong"},
      (dir / "ddsperf-pong.log").string());
  std::this_thread::sleep_for(500ms);
  std::vector<std::string> ping_argv = {"/usr/bin/ddsperf", "-i", domain, "-D",
                                        std::to_string(seconds), "ping"};
  if (rate_hz > 0) ping_argv.push_back(std::to_string(rate_hz) + "Hz");
  testing::BackgroundProcess ping(ping_argv, (dir / "ddsperf-ping.log").string());
  (void)ping.waitForExit(std::chrono::seconds(seconds + 10));

  std::vector<DdsperfSecond> result;
  std::istringstream log(ping.log());
  for (std::string line; std::getline(log, line);) {
    DdsperfSecond s;
    double count = 0.0;
    if (numberAfter(line, " 50% ", s.median_us) && numberAfter(line, " mean ", s.mean_us) &&
        numberAfter(line, " cnt ", count)) {
      s.round_trips = static_cast<long>(count);
      result.push_back(s);
    }
  }
  return result;
}

double ddsperfHalfRoundTripUs(const fs::path& dir, int domain_id, int rate_hz) {
  std::vector<double> medians;
  for (const DdsperfSecond& s : runDdsperf(dir, domain_id, rate_hz, 6)) medians.push_back(s.median_us);
  return median(medians);
}

double checkHalving(const fs::path& dir, int domain_id) {
  std::vector<double> filled;
  for (const DdsperfSecond& s : runDdsperf(dir, domain_id, 0, 4)) {
    filled.push_back(2.0 * s.mean_us * 1e-6 * static_cast<double>(s.round_trips));
  }
  return median(filled);
}

DdsperfThroughput ddsperfThroughput(const fs::path& dir, int domain_id, int sample_bytes,
                                    int seconds) {
  const LoopbackEnvironment environment(dir);
  const std::string domain = std::to_string(domain_id);
  fs::remove(dir / "ddsperf-sub.log");  // the logs are appended to: start afresh
  fs::remove(dir / "ddsperf-pub.log");
  // Reliable (ddsperf's default) and keep-all, as the Measurement topic (dds/topics.hpp).
  testing::BackgroundProcess sub(
      {"/usr/bin/ddsperf", "-i", domain, "-k", "all", "-D", std::to_string(seconds + 2), "sub"},
      (dir / "ddsperf-sub.log").string());
  std::this_thread::sleep_for(500ms);
  testing::BackgroundProcess pub(
      {"/usr/bin/ddsperf", "-i", domain, "-k", "all", "-D", std::to_string(seconds), "pub", "size",
       std::to_string(sample_bytes)},
      (dir / "ddsperf-pub.log").string());
  (void)pub.waitForExit(std::chrono::seconds(seconds + 10));
  (void)sub.waitForExit(std::chrono::seconds(10));

  DdsperfThroughput result;
  const SubscriberLog log = readSubscriberLog(sub.log());
  result.lost = log.lost;
  result.peers = log.peers;
  // The first second holds discovery, the last one is cut short.
  result.samples_per_s = middleSeconds(log.samples_per_s, 1, 1);
  return result;
}

namespace {

// Busy and total jiffies of all cores (/proc/stat's first line).
std::pair<long long, long long> cpuJiffies() {
  std::ifstream stat("/proc/stat");
  std::string cpu;
  long long user = 0, nice = 0, system = 0, idle = 0, iowait = 0, irq = 0, softirq = 0,
            steal = 0;
  stat >> cpu >> user >> nice >> system >> idle >> iowait >> irq >> softirq >> steal;
  const long long busy = user + nice + system + irq + softirq + steal;
  return {busy, busy + idle + iowait};
}

}  // namespace

DdsperfFleet ddsperfFleet(const fs::path& dir, int domain_id, int publishers, double rate_hz_each,
                          int sample_bytes, int seconds) {
  const LoopbackEnvironment environment(dir);
  const std::string domain = std::to_string(domain_id);
  const std::string hub_uri = std::getenv("CYCLONEDDS_URI");
  fs::remove(dir / "ddsperf-fleet-sub.log");
  testing::BackgroundProcess sub(
      {"/usr/bin/ddsperf", "-i", domain, "-k", "all", "-D", std::to_string(seconds + 3), "sub"},
      (dir / "ddsperf-fleet-sub.log").string());
  std::this_thread::sleep_for(500ms);
  // More publishers than participant indices: as leaves, like sensor agents.
  ::setenv("CYCLONEDDS_URI", (hub_uri + "," + dds::leafConfigXml()).c_str(), 1);
  std::vector<testing::BackgroundProcess> pubs;
  for (int i = 0; i < publishers; ++i) {
    const fs::path log = dir / ("ddsperf-fleet-pub-" + std::to_string(i) + ".log");
    fs::remove(log);
    pubs.emplace_back(std::vector<std::string>{"/usr/bin/ddsperf", "-i", domain, "-k", "all", "-D",
                                               std::to_string(seconds), "pub",
                                               std::to_string(rate_hz_each) + "Hz", "size",
                                               std::to_string(sample_bytes)},
                      log.string());
  }
  // The middle of the run: after discovery, before the first publisher stops.
  std::this_thread::sleep_for(std::chrono::seconds(seconds / 3));
  const auto [busy0, total0] = cpuJiffies();
  std::this_thread::sleep_for(std::chrono::seconds(seconds / 3));
  const auto [busy1, total1] = cpuJiffies();
  for (auto& pub : pubs) (void)pub.waitForExit(std::chrono::seconds(seconds + 10));
  (void)sub.waitForExit(std::chrono::seconds(10));

  DdsperfFleet result;
  result.cores = static_cast<int>(std::thread::hardware_concurrency());
  result.busy_share = total1 > total0 ? static_cast<double>(busy1 - busy0) /
                                            static_cast<double>(total1 - total0)
                                      : 0.0;
  const SubscriberLog log = readSubscriberLog(sub.log());
  result.lost = log.lost;
  // Whole seconds with every publisher running: the first holds discovery, the last ones stop.
  if (const auto rates = middleSeconds(log.samples_per_s, 1, 2); !rates.empty()) {
    result.samples_per_s = median(rates);
  }
  return result;
}

}  // namespace sensornet::bench
