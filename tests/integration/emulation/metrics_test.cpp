// Live metrics (`sensornet launch --metrics 127.0.0.1:PORT`, emulator/fusion_metrics.hpp)
// scraped by a real Prometheus server (Debian's `prometheus`, started here with its own
// configuration and storage in the test's folder, scraping every second on loopback): after the
// run, a query through Prometheus' own client (promtool query) gives the final counters equal to
// the report's; `promtool check metrics` accepts the exposition taken during the run.
#include <arpa/inet.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <chrono>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <optional>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "launch_fixture.hpp"
#include "support/background_process.hpp"

namespace sensornet {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using namespace std::chrono_literals;
using testing::LeftoverGuard;
using testing::readJson;
using testing::RunningProgram;
using testing::runProcess;

// A port nobody listens on now (the kernel's choice for port 0).
std::uint16_t freePort() {
  const int s = ::socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  (void)::bind(s, reinterpret_cast<sockaddr*>(&a), sizeof a);
  socklen_t length = sizeof a;
  (void)::getsockname(s, reinterpret_cast<sockaddr*>(&a), &length);
  ::close(s);
  return ntohs(a.sin_port);
}

// GET http://127.0.0.1:port/path: the body, or nullopt when nothing answered.
std::optional<std::string> httpGet(std::uint16_t port, const std::string& path) {
  const int s = ::socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_port = htons(port);
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  if (::connect(s, reinterpret_cast<sockaddr*>(&a), sizeof a) != 0) {
    ::close(s);
    return std::nullopt;
  }
  const std::string request =
      "GET " + path + " HTTP/1.1\r\nHost: 127.0.0.1\r\nConnection: close\r\n\r\n";
  (void)::send(s, request.data(), request.size(), MSG_NOSIGNAL);
  std::string response;
  char buffer[4096];
  ssize_t n = 0;
  while ((n = ::recv(s, buffer, sizeof buffer, 0)) > 0) response.append(buffer, static_cast<std::size_t>(n));
  ::close(s);
  const auto body = response.find("\r\n\r\n");
  if (body == std::string::npos || !response.starts_with("HTTP/1.1 200")) return std::nullopt;
  return response.substr(body + 4);
}

// The value of an instant query that returns one series ("{} => 42 @[...]" from promtool).
std::optional<double> queryOne(std::uint16_t prometheus_port, const std::string& expression) {
  const testing::ProcessResult r = runProcess(
      {SENSORNET_PROMTOOL, "query", "instant", "http://127.0.0.1:" + std::to_string(prometheus_port),
       expression},
      30s);
  const auto arrow = r.out.find("=> ");
  if (r.exit_code != 0 || arrow == std::string::npos) return std::nullopt;
  return std::stod(r.out.substr(arrow + 3));
}

class Metrics : public testing::LaunchTest {};

TEST_F(Metrics, APrometheusServerScrapesTheRunAndEndsWithTheReportsCounts) {
  const LeftoverGuard guard(run_id_);
  const std::uint16_t port = freePort();
  const std::uint16_t prometheus_port = freePort();
  std::ofstream(dir_ / "prometheus.yml")
      << "global:\n  scrape_interval: 1s\n  evaluation_interval: 1s\n"
      << "scrape_configs:\n  - job_name: sensornet\n    static_configs:\n"
      << "      - targets: ['127.0.0.1:" << port << "']\n";
  testing::BackgroundProcess prometheus(
      {SENSORNET_PROMETHEUS, "--config.file=" + (dir_ / "prometheus.yml").string(),
       "--storage.tsdb.path=" + (dir_ / "tsdb").string(),
       "--web.listen-address=127.0.0.1:" + std::to_string(prometheus_port)},
      (dir_ / "prometheus.log").string());
  ASSERT_TRUE(testing::waitUntil(
      [&] { return httpGet(prometheus_port, "/-/ready").has_value(); }, 30s))
      << prometheus.log();

  std::vector<std::string> argv = launchArgs(4, "2");
  argv.insert(argv.end(), {"--seed", "5", "--no-html", "--metrics",
                           "127.0.0.1:" + std::to_string(port)});
  RunningProgram launcher(argv, 120s);
  // During the run: the exposition, checked by promtool.
  std::optional<std::string> exposition;
  ASSERT_TRUE(testing::waitUntil(
      [&] {
        exposition = httpGet(port, "/metrics");
        return exposition && exposition->find("sensornet_episodes_total") != std::string::npos;
      },
      60s));
  std::ofstream(dir_ / "exposition.txt") << *exposition;
  const testing::ProcessResult check = runProcess(
      {"/bin/sh", "-c",
       std::string(SENSORNET_PROMTOOL) + " check metrics < '" + (dir_ / "exposition.txt").string() + "'"},
      30s);
  EXPECT_EQ(check.exit_code, 0) << check.out << check.err << *exposition;
  EXPECT_NE(exposition->find("# TYPE sensornet_publish_to_fusion_latency_seconds histogram"),
            std::string::npos);
  EXPECT_EQ(httpGet(port, "/other"), std::nullopt) << "only /metrics is served";

  const testing::ProcessResult& r = launcher.result();
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const json report = readJson(dir_ / "report.json");
  ASSERT_TRUE(report.is_object());
  const json& summary = report.at("summary");
  // What Prometheus holds last (range selectors skip the staleness markers of the target that
  // left with the run), against the report.
  const auto last = [&](const std::string& metric) {
    return queryOne(prometheus_port, "sum(last_over_time(" + metric + "[10m]))");
  };
  EXPECT_EQ(last("sensornet_measurements_received_total"),
            std::optional<double>(summary.at("received").get<double>()));
  EXPECT_EQ(last("sensornet_measurements_sent_total"),
            std::optional<double>(summary.at("sent").get<double>()));
  EXPECT_EQ(last("sensornet_measurements_lost_total"),
            std::optional<double>(summary.at("lost").get<double>()));
  EXPECT_EQ(last("sensornet_episodes_total{outcome=\"complete\"}"),
            std::optional<double>(summary.at("episodes_complete").get<double>()));
  const std::optional<double> mean = last("sensornet_realized_cost_mean");
  ASSERT_TRUE(mean.has_value());
  EXPECT_NEAR(*mean, summary.at("mean").get<double>(), 1e-9 * summary.at("mean").get<double>());
  EXPECT_EQ(last("sensornet_publish_to_fusion_latency_seconds_count"),
            std::optional<double>(summary.at("received").get<double>()))
      << "one latency per fused measurement";
  // Per sensor, the report's sensors table.
  for (std::size_t j = 0; j < report.at("sensors").size(); ++j) {
    EXPECT_EQ(queryOne(prometheus_port, "last_over_time(sensornet_measurements_sent_total{sensor=\"" +
                                            std::to_string(j) + "\"}[10m])"),
              std::optional<double>(report.at("sensors")[j].at("sent").get<double>()))
        << "sensor " << j;
  }
}

TEST_F(Metrics, AnAddressThatCannotBeServedIsBadInput) {
  std::vector<std::string> argv = launchArgs(2, "5");
  argv.insert(argv.end(), {"--metrics", "localhost:9464"});
  const testing::ProcessResult r = runProcess(argv, 30s);
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("numeric IPv4 address"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(dir_ / "logs")) << "nothing may start on bad input";
}

}  // namespace
}  // namespace sensornet
