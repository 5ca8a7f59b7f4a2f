#pragma once
// "Hosts" on this machine: network namespaces joined by veth pairs to a bridge, made by
// scripts/netns-hosts.sh and removed again by the guard's destructor, pass or fail. Each guard
// picks a name and a /24 of its own (from the process's pid and a counter, retrying when one is
// in use), so that tests and chaos trials run in parallel. Used by the many-hosts tests
// (tests/integration/emulation/hosts_fixture.hpp) and by the chaos checker's network trials.
//
//   if (const auto why = NetnsHosts::unavailable()) GTEST_SKIP() << *why;
//   NetnsHosts hosts(3);                    // hosts.ns(1) = "s1234a-h1" at hosts.address(1)
//   ... ip netns exec hosts.ns(2) ...; hosts.veth(2) is its link's end on the bridge
//
// Needs root (CAP_NET_ADMIN) and `ip netns`; unavailable() says why not. The including target
// defines SENSORNET_SOURCE_DIR (where scripts/netns-hosts.sh is).

#include <unistd.h>

#include <cstdint>
#include <filesystem>
#include <optional>
#include <stdexcept>
#include <string>

#include "support/process.hpp"

namespace sensornet::testing {

inline const std::string kNetnsScript =
    std::string(SENSORNET_SOURCE_DIR) + "/scripts/netns-hosts.sh";

class NetnsHosts {
 public:
  // Why the harness cannot run here (not root, no `ip netns`), or nullopt when it can.
  static std::optional<std::string> unavailable() {
    if (::geteuid() != 0) return "not root: network namespaces need CAP_NET_ADMIN";
    if (!std::filesystem::exists("/usr/bin/ip") && !std::filesystem::exists("/sbin/ip") &&
        !std::filesystem::exists("/usr/sbin/ip")) {
      return "iproute2 (ip) is not installed";
    }
    const ProcessResult list = runProcess({"/usr/bin/env", "ip", "netns", "list"});
    if (list.exit_code != 0) return "`ip netns list` fails: " + list.err;
    return std::nullopt;
  }

  explicit NetnsHosts(int count) : count_(count) {
    static int made = 0;
    for (int attempt = 0; attempt < 8; ++attempt, ++made) {
      const auto pid = static_cast<std::uint32_t>(::getpid());
      name_ = "s" + std::to_string(pid % 100000) + static_cast<char>('a' + made % 26);
      subnet_ = "10.231." + std::to_string((pid * 7 + static_cast<std::uint32_t>(made) * 13) % 250);
      const ProcessResult up =
          runProcess({"/bin/bash", kNetnsScript, "up", name_, subnet_, std::to_string(count)});
      if (up.exit_code == 0) return;
      if (up.exit_code != 3) {  // 3: name or subnet in use; anything else is a real failure
        throw std::runtime_error("netns-hosts.sh up failed: " + up.err);
      }
    }
    throw std::runtime_error("netns-hosts.sh: no free name and subnet after 8 attempts");
  }
  NetnsHosts(const NetnsHosts&) = delete;
  NetnsHosts& operator=(const NetnsHosts&) = delete;
  ~NetnsHosts() { (void)runProcess({"/bin/bash", kNetnsScript, "down", name_}); }

  [[nodiscard]] const std::string& name() const { return name_; }
  [[nodiscard]] std::string ns(int i) const { return name_ + "-h" + std::to_string(i); }
  [[nodiscard]] std::string address(int i) const { return subnet_ + "." + std::to_string(i); }
  [[nodiscard]] std::string bridgeAddress() const { return subnet_ + ".254"; }
  [[nodiscard]] std::string veth(int i) const { return name_ + "-v" + std::to_string(i); }
  [[nodiscard]] int count() const { return count_; }

 private:
  int count_;
  std::string name_;
  std::string subnet_;
};

}  // namespace sensornet::testing
