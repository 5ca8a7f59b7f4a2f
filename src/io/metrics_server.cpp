#include "sensornet/io/metrics_server.hpp"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <charconv>
#include <chrono>
#include <cmath>
#include <cstring>
#include <stdexcept>

#include "sensornet/core/input_error.hpp"

namespace sensornet {

std::string prometheusNumber(double value) {
  if (std::isnan(value)) return "NaN";
  if (std::isinf(value)) return value > 0 ? "+Inf" : "-Inf";
  char text[32];
  const auto [end, ec] = std::to_chars(std::begin(text), std::end(text), value);
  return ec == std::errc() ? std::string(text, end) : "NaN";
}

namespace {

std::string escapedLabel(const std::string& value) {
  std::string out;
  for (const char c : value) {
    if (c == '\\') out += "\\\\";
    else if (c == '"') out += "\\\"";
    else if (c == '\n') out += "\\n";
    else out += c;
  }
  return out;
}

std::string escapedHelp(const std::string& help) {
  std::string out;
  for (const char c : help) {
    if (c == '\\') out += "\\\\";
    else if (c == '\n') out += "\\n";
    else out += c;
  }
  return out;
}

}  // namespace

void PrometheusText::family(const std::string& name, const std::string& help, const char* type) {
  if (families_.contains(name)) return;
  order_.push_back(name);
  families_[name] = "# HELP " + name + " " + escapedHelp(help) + "\n# TYPE " + name + " " + type + "\n";
}

void PrometheusText::sample(const std::string& name, const MetricLabels& labels, double value) {
  std::string line = name;
  if (!labels.empty()) {
    line += "{";
    for (std::size_t i = 0; i < labels.size(); ++i) {
      line += (i == 0 ? "" : ",") + labels[i].first + "=\"" + escapedLabel(labels[i].second) + "\"";
    }
    line += "}";
  }
  families_[name] += line + " " + prometheusNumber(value) + "\n";
}

void PrometheusText::counter(const std::string& name, const std::string& help,
                             const MetricLabels& labels, double value) {
  family(name, help, "counter");
  sample(name, labels, value);
}

void PrometheusText::gauge(const std::string& name, const std::string& help,
                           const MetricLabels& labels, double value) {
  family(name, help, "gauge");
  sample(name, labels, value);
}

void PrometheusText::histogram(const std::string& name, const std::string& help,
                               const std::vector<double>& upper_bounds,
                               const std::vector<std::uint64_t>& cumulative, std::uint64_t count,
                               double sum) {
  family(name, help, "histogram");
  std::string& lines = families_[name];
  for (std::size_t i = 0; i < upper_bounds.size() && i < cumulative.size(); ++i) {
    lines += name + "_bucket{le=\"" + prometheusNumber(upper_bounds[i]) + "\"} " +
             std::to_string(cumulative[i]) + "\n";
  }
  lines += name + "_bucket{le=\"+Inf\"} " + std::to_string(count) + "\n";
  lines += name + "_sum " + prometheusNumber(sum) + "\n";
  lines += name + "_count " + std::to_string(count) + "\n";
}

std::string PrometheusText::str() const {
  std::string out;
  for (const std::string& name : order_) out += families_.at(name);
  return out;
}

MetricsServer::MetricsServer(const std::string& address) {
  const auto colon = address.rfind(':');
  const auto refuse = [&](const std::string& why) {
    if (listener_ >= 0) ::close(listener_);
    throw InputError("--metrics " + address, "address", why);
  };
  if (colon == std::string::npos) refuse("HOST:PORT (for example 127.0.0.1:9464)");
  const std::string host = address.substr(0, colon);
  unsigned port = 0;
  const std::string port_text = address.substr(colon + 1);
  const auto [end, ec] = std::from_chars(port_text.data(), port_text.data() + port_text.size(), port);
  if (ec != std::errc() || end != port_text.data() + port_text.size() || port > 65535) {
    refuse("a port in 0..65535 after the colon, got '" + port_text + "'");
  }
  sockaddr_in where{};
  where.sin_family = AF_INET;
  where.sin_port = htons(static_cast<std::uint16_t>(port));
  if (::inet_pton(AF_INET, host.c_str(), &where.sin_addr) != 1) {
    refuse("a numeric IPv4 address before the colon, got '" + host + "'");
  }
  listener_ = ::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
  if (listener_ < 0) refuse(std::string("a socket (") + std::strerror(errno) + ")");
  const int yes = 1;
  (void)::setsockopt(listener_, SOL_SOCKET, SO_REUSEADDR, &yes, sizeof yes);
  if (::bind(listener_, reinterpret_cast<const sockaddr*>(&where), sizeof where) != 0) {
    refuse(std::string("an address this host can listen on (") + std::strerror(errno) + ")");
  }
  if (::listen(listener_, 16) != 0) refuse(std::string("listen: ") + std::strerror(errno));
  socklen_t length = sizeof where;
  (void)::getsockname(listener_, reinterpret_cast<sockaddr*>(&where), &length);
  port_ = ntohs(where.sin_port);
  thread_ = std::thread([this] { serve(); });
}

MetricsServer::~MetricsServer() {
  stop_ = true;
  if (thread_.joinable()) thread_.join();
  if (listener_ >= 0) ::close(listener_);
}

void MetricsServer::publish(std::string text) {
  const std::lock_guard lock(mutex_);
  text_ = std::move(text);
}

void MetricsServer::serve() {
  while (!stop_) {
    pollfd p{listener_, POLLIN, 0};
    if (::poll(&p, 1, 100) <= 0) continue;
    const int connection = ::accept4(listener_, nullptr, nullptr, SOCK_CLOEXEC);
    if (connection < 0) continue;
    answer(connection);
    ::close(connection);
  }
}

void MetricsServer::answer(int connection) {
  std::string request;
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(1);
  char buffer[1024];
  while (request.find("\r\n\r\n") == std::string::npos && request.size() < 8192) {
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(
        deadline - std::chrono::steady_clock::now());
    if (left.count() <= 0) return;
    pollfd p{connection, POLLIN, 0};
    if (::poll(&p, 1, static_cast<int>(left.count())) <= 0) return;
    const ssize_t n = ::recv(connection, buffer, sizeof buffer, 0);
    if (n <= 0) return;
    request.append(buffer, static_cast<std::size_t>(n));
  }
  std::string status = "404 Not Found", type = "text/plain; charset=utf-8", body = "not found\n";
  if (request.starts_with("GET /metrics ") || request.starts_with("GET /metrics?")) {
    status = "200 OK";
    type = "text/plain; version=0.0.4; charset=utf-8";
    const std::lock_guard lock(mutex_);
    body = text_;
    ++scrapes_;
  }
  const std::string response = "HTTP/1.1 " + status + "\r\nContent-Type: " + type +
                               "\r\nContent-Length: " + std::to_string(body.size()) +
                               "\r\nConnection: close\r\n\r\n" + body;
  std::size_t sent = 0;
  while (sent < response.size()) {
    const ssize_t n = ::send(connection, response.data() + sent, response.size() - sent, MSG_NOSIGNAL);
    if (n <= 0) return;
    sent += static_cast<std::size_t>(n);
  }
}

}  // namespace sensornet
