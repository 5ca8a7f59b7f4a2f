// The Prometheus exposition (io/metrics_server.hpp): the text format 0.0.4 line by line (HELP
// and TYPE once per family, labels escaped, histogram buckets cumulative with +Inf, NaN and
// infinities spelled as Prometheus reads them), and the server answering GET /metrics on
// loopback with the latest text, 404 elsewhere, a bad address refused naming it.
#include <arpa/inet.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cmath>
#include <limits>
#include <string>

#include "sensornet/core/input_error.hpp"
#include "sensornet/io/metrics_server.hpp"

namespace sensornet {
namespace {

std::string get(std::uint16_t port, const std::string& path) {
  const int s = ::socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_port = htons(port);
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  EXPECT_EQ(::connect(s, reinterpret_cast<sockaddr*>(&a), sizeof a), 0);
  const std::string request = "GET " + path + " HTTP/1.1\r\nHost: x\r\n\r\n";
  (void)::send(s, request.data(), request.size(), MSG_NOSIGNAL);
  std::string response;
  char buffer[1024];
  ssize_t n = 0;
  while ((n = ::recv(s, buffer, sizeof buffer, 0)) > 0) response.append(buffer, static_cast<std::size_t>(n));
  ::close(s);
  return response;
}

TEST(PrometheusText, WritesEachFamilyOnceWithEscapedLabelsAndCumulativeBuckets) {
  PrometheusText t;
  t.counter("a_total", "first \\ help", {{"sensor", "0"}}, 3);
  t.gauge("b", "a gauge", {}, std::numeric_limits<double>::quiet_NaN());
  t.counter("a_total", "ignored the second time", {{"sensor", "say \"hi\"\n"}}, 4.5);
  t.histogram("lat_seconds", "latency", {0.001, 0.01}, {2, 5}, 7, 0.125);
  t.gauge("c", "infinite", {}, -std::numeric_limits<double>::infinity());
  EXPECT_EQ(t.str(),
            "# HELP a_total first \\\\ help\n# TYPE a_total counter\n"
            "a_total{sensor=\"0\"} 3\n"
            "a_total{sensor=\"say \\\"hi\\\"\\n\"} 4.5\n"
            "# HELP b a gauge\n# TYPE b gauge\nb NaN\n"
            "# HELP lat_seconds latency\n# TYPE lat_seconds histogram\n"
            "lat_seconds_bucket{le=\"0.001\"} 2\nlat_seconds_bucket{le=\"0.01\"} 5\n"
            "lat_seconds_bucket{le=\"+Inf\"} 7\nlat_seconds_sum 0.125\nlat_seconds_count 7\n"
            "# HELP c infinite\n# TYPE c gauge\nc -Inf\n");
  EXPECT_EQ(prometheusNumber(0.1), "0.1") << "shortest round trip";
  EXPECT_EQ(prometheusNumber(1e300), "1e+300");
}

TEST(MetricsServer, ServesTheLatestTextAtMetricsOnly) {
  MetricsServer server("127.0.0.1:0");
  ASSERT_GT(server.port(), 0);
  server.publish("x 1\n");
  server.publish("x 2\n");
  const std::string ok = get(server.port(), "/metrics");
  EXPECT_TRUE(ok.starts_with("HTTP/1.1 200 OK\r\n")) << ok;
  EXPECT_NE(ok.find("Content-Type: text/plain; version=0.0.4"), std::string::npos) << ok;
  EXPECT_TRUE(ok.ends_with("\r\n\r\nx 2\n")) << ok;
  EXPECT_TRUE(get(server.port(), "/").starts_with("HTTP/1.1 404")) << "only /metrics";
  EXPECT_EQ(server.scrapes(), 1u);
}

TEST(MetricsServer, AnAddressItCannotServeIsRefusedNamingIt) {
  for (const char* bad : {"9464", "localhost:9464", "127.0.0.1:99999", "127.0.0.1:x"}) {
    try {
      MetricsServer server(bad);
      ADD_FAILURE() << bad << " was accepted";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(bad), std::string::npos) << e.what();
    }
  }
  MetricsServer first("127.0.0.1:0");
  EXPECT_THROW(MetricsServer("127.0.0.1:" + std::to_string(first.port())), InputError)
      << "a port in use";
}

}  // namespace
}  // namespace sensornet
