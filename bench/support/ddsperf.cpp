#include "ddsperf.hpp"

#include <chrono>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>
#include <thread>

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

}  // namespace

std::vector<DdsperfSecond> runDdsperf(const fs::path& dir, int domain_id, int rate_hz,
                                      int seconds) {
  fs::create_directories(dir);
  const fs::path config = dir / "cyclonedds-loopback.xml";
  std::ofstream(config) << dds::loopbackConfigXml();
  // ddsperf reads its configuration from the environment (the bench's own domains are created
  // explicitly, so the variable does not touch them).
  ::setenv("CYCLONEDDS_URI", ("file://" + config.string()).c_str(), 1);
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
  ::unsetenv("CYCLONEDDS_URI");

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

}  // namespace sensornet::bench
