#pragma once
// Helpers of the many-hosts tests around NetnsHosts (tests/support/netns_hosts.hpp): the
// counters of a host's link and the namespace a process runs in.

#include <sys/stat.h>
#include <unistd.h>

#include <cstdint>
#include <filesystem>
#include <string>

#include "emulation_fixture.hpp"
#include "support/netns_hosts.hpp"
#include "support/process.hpp"

namespace sensornet::testing {

// A counter of an interface of the root namespace (/sys/class/net/IF/statistics/NAME).
inline std::uint64_t linkCounter(const std::string& interface, const std::string& counter) {
  const std::string text = readText("/sys/class/net/" + interface + "/statistics/" + counter);
  return text.empty() ? 0 : std::stoull(text);
}

// True when `pid` runs in the named network namespace (same namespace inode).
inline bool runsInNamespace(pid_t pid, const std::string& ns) {
  struct stat a {}, b {};
  const std::string proc = "/proc/" + std::to_string(pid) + "/ns/net";
  const std::string named = "/run/netns/" + ns;
  return ::stat(proc.c_str(), &a) == 0 && ::stat(named.c_str(), &b) == 0 && a.st_ino == b.st_ino &&
         a.st_dev == b.st_dev;
}

}  // namespace sensornet::testing
