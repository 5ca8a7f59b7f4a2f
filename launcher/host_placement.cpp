#include "host_placement.hpp"

#include <arpa/inet.h>
#include <ifaddrs.h>
#include <net/if.h>
#include <unistd.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <memory>
#include <optional>
#include <sstream>

#include "sensornet/core/input_error.hpp"
#include "sensornet/io/command_line.hpp"
#include "sensornet/dds/unicast_config.hpp"

namespace sensornet::launcher {
namespace {

namespace fs = std::filesystem;

struct LocalAddress {
  std::uint32_t address = 0;  // host byte order
  std::uint32_t netmask = 0;
  std::string text;
};

// The IPv4 addresses of this machine's interfaces that are up.
std::vector<LocalAddress> localAddresses() {
  ifaddrs* list = nullptr;
  if (::getifaddrs(&list) != 0) return {};
  const std::unique_ptr<ifaddrs, decltype(&::freeifaddrs)> owner(list, &::freeifaddrs);
  std::vector<LocalAddress> found;
  for (const ifaddrs* entry = list; entry != nullptr; entry = entry->ifa_next) {
    if (entry->ifa_addr == nullptr || entry->ifa_netmask == nullptr ||
        entry->ifa_addr->sa_family != AF_INET || (entry->ifa_flags & IFF_UP) == 0) {
      continue;
    }
    const auto* address = reinterpret_cast<const sockaddr_in*>(entry->ifa_addr);
    const auto* netmask = reinterpret_cast<const sockaddr_in*>(entry->ifa_netmask);
    char text[INET_ADDRSTRLEN] = {};
    ::inet_ntop(AF_INET, &address->sin_addr, text, sizeof text);
    found.push_back({ntohl(address->sin_addr.s_addr), ntohl(netmask->sin_addr.s_addr), text});
  }
  return found;
}

std::uint32_t parsedAddress(const std::string& text) {
  in_addr address{};
  (void)::inet_pton(AF_INET, text.c_str(), &address);
  return ntohl(address.s_addr);
}

// launcher.address if given (it must be this machine's), else the address of the local
// interface on the coordinator host's network.
std::string findLauncherAddress(const emulator::HostsFile& hosts) {
  const std::vector<LocalAddress> local = localAddresses();
  if (hosts.launcher_address) {
    const bool ours = std::any_of(local.begin(), local.end(), [&](const LocalAddress& a) {
      return a.text == *hosts.launcher_address;
    });
    if (!ours) {
      throw InputError(hosts.source, "launcher.address",
                       "an address of an interface of this machine that is up, got " +
                           *hosts.launcher_address);
    }
    return *hosts.launcher_address;
  }
  const std::uint32_t target = parsedAddress(hosts.coordinatorHost().address);
  for (const LocalAddress& a : local) {
    if (a.netmask != 0 && (a.address & a.netmask) == (target & a.netmask)) return a.text;
  }
  throw InputError(hosts.source, "launcher.address",
                   "an address of this machine on the hosts' network: no interface of this "
                   "machine is on the network of " + hosts.coordinatorHost().address +
                       " (the coordinator's host); give launcher: address:");
}

// The prefix with its program as an absolute path (ProcessGroup does not search PATH).
std::vector<std::string> resolvedPrefix(const emulator::Host& host) {
  std::vector<std::string> prefix = host.exec;
  if (prefix.empty()) return prefix;
  const std::string& program = prefix.front();
  const auto executable = [](const fs::path& path) {
    return fs::is_regular_file(path) && ::access(path.c_str(), X_OK) == 0;
  };
  std::optional<fs::path> found;
  if (program.find('/') != std::string::npos) {
    if (executable(program)) found = fs::absolute(program);
  } else if (const char* path = std::getenv("PATH")) {
    std::istringstream dirs(path);
    for (std::string dir; !found && std::getline(dirs, dir, ':');) {
      if (!dir.empty() && executable(fs::path(dir) / program)) found = fs::path(dir) / program;
    }
  }
  if (!found) {
    throw InputError(host.where, "exec (host " + host.name + ")",
                     "a prefix whose program is an executable file or on PATH, got '" + program +
                         "'");
  }
  prefix.front() = found->string();
  return prefix;
}

bool isSsh(const std::vector<std::string>& prefix) {
  return !prefix.empty() && fs::path(prefix.front()).filename() == "ssh";
}

}  // namespace

HostPlacement::HostPlacement(const emulator::HostsFile& hosts)
    : hosts_(hosts), launcher_address_(findLauncherAddress(hosts)), peers_(hosts.hubAddresses()) {
  if (std::find(peers_.begin(), peers_.end(), launcher_address_) == peers_.end()) {
    peers_.push_back(launcher_address_);
  }
  for (const emulator::Host& host : hosts.hosts) prefixes_.push_back(resolvedPrefix(host));
}

void HostPlacement::place(ChildSpec& child, const emulator::Host& host,
                          dds::DiscoveryRole role) const {
  child.argv.insert(child.argv.end(),
                    {"--cyclone-config", dds::unicastConfigXml(host.address, peers_, role)});
  const auto index = static_cast<std::size_t>(&host - hosts_.hosts.data());
  const std::vector<std::string>& prefix = prefixes_.at(index);
  if (prefix.empty()) return;
  std::vector<std::string> argv = prefix;
  for (const std::string& word : child.argv) {
    argv.push_back(isSsh(prefix) ? shellQuoted(word) : word);
  }
  child.argv = std::move(argv);
}

std::string HostPlacement::launcherConfigXml() const {
  return dds::unicastConfigXml(launcher_address_, peers_, dds::DiscoveryRole::Hub);
}

std::vector<std::vector<int>> sensorBlocks(const emulator::HostsFile* hosts, int sensor_count,
                                           int per_process) {
  std::vector<std::vector<int>> groups;
  if (hosts == nullptr) {
    groups.emplace_back();
    for (int j = 0; j < sensor_count; ++j) groups.back().push_back(j);
  } else {
    for (const emulator::Host& host : hosts->hosts) groups.push_back(host.sensors);
  }
  std::vector<std::vector<int>> blocks;
  const auto size = static_cast<std::size_t>(std::max(1, per_process));
  for (const std::vector<int>& group : groups) {
    for (std::size_t first = 0; first < group.size(); first += size) {
      const auto last = std::min(first + size, group.size());
      blocks.emplace_back(group.begin() + static_cast<std::ptrdiff_t>(first),
                          group.begin() + static_cast<std::ptrdiff_t>(last));
    }
  }
  return blocks;
}

CLI::Validator sensorsPerProcessValue() {
  return CLI::Validator(
      [count = integerRange(1, kMaxSensorsPerProcess)](std::string& input) -> std::string {
        return input == "auto" ? std::string() : count(input);
      },
      "auto|N");
}

int sensorsPerProcess(const std::string& given, int sensor_count) {
  if (given != "auto") return std::stoi(given);  // checked by the option's validator
  return std::max(1, (sensor_count + kAutoSensorProcesses - 1) / kAutoSensorProcesses);
}

std::string shellQuoted(const std::string& word) {
  std::string quoted = "'";
  for (const char c : word) quoted += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return quoted + "'";
}

}  // namespace sensornet::launcher
