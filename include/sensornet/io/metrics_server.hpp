#pragma once
// Live metrics in the Prometheus text exposition format (version 0.0.4), served over HTTP at
// GET /metrics from a thread of its own (`sensornet launch --metrics 127.0.0.1:9464`).
//
//   MetricsServer server("127.0.0.1:0");     // port 0: any free one; server.port() says which
//   PrometheusText text;
//   text.counter("sensornet_measurements_received_total", "Measurements fused", {{"sensor", "0"}}, 42);
//   server.publish(text.str());               // what the next scrape gets
//
// The address is HOST:PORT with HOST a numeric IPv4 address (loopback by default in the
// programs); one that cannot be bound is an InputError naming it. Every other path is 404; a
// request must arrive within a second and fit 8 KiB. The server never blocks the publisher: it
// serves the latest published text.

#include <atomic>
#include <cstdint>
#include <map>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

namespace sensornet {

using MetricLabels = std::vector<std::pair<std::string, std::string>>;

// Builds an exposition: each metric family once with its # HELP and # TYPE lines, samples in the
// order given. Names and label names must match Prometheus' [a-zA-Z_:][a-zA-Z0-9_:]*; label
// values are escaped.
class PrometheusText {
 public:
  void counter(const std::string& name, const std::string& help, const MetricLabels& labels,
               double value);
  void gauge(const std::string& name, const std::string& help, const MetricLabels& labels,
             double value);
  // A histogram from cumulative bucket counts at the upper bounds `le` (the +Inf bucket is
  // `count`), with the sum of the observations.
  void histogram(const std::string& name, const std::string& help,
                 const std::vector<double>& upper_bounds, const std::vector<std::uint64_t>& cumulative,
                 std::uint64_t count, double sum);
  [[nodiscard]] std::string str() const;

 private:
  void family(const std::string& name, const std::string& help, const char* type);
  void sample(const std::string& name, const MetricLabels& labels, double value);
  std::vector<std::string> order_;
  std::map<std::string, std::string> families_;  // name -> its lines
};

class MetricsServer {
 public:
  explicit MetricsServer(const std::string& address);
  ~MetricsServer();
  MetricsServer(const MetricsServer&) = delete;
  MetricsServer& operator=(const MetricsServer&) = delete;

  void publish(std::string text);
  [[nodiscard]] std::uint16_t port() const noexcept { return port_; }
  [[nodiscard]] std::uint64_t scrapes() const noexcept { return scrapes_.load(); }

 private:
  void serve();
  void answer(int connection);

  int listener_ = -1;
  std::uint16_t port_ = 0;
  std::mutex mutex_;
  std::string text_;
  std::atomic<bool> stop_{false};
  std::atomic<std::uint64_t> scrapes_{0};
  std::thread thread_;
};

// The metric value as the exposition format writes it: shortest round-trip decimal, "NaN",
// "+Inf", "-Inf".
[[nodiscard]] std::string prometheusNumber(double value);

}  // namespace sensornet
