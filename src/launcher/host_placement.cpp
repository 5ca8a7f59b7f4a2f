#include "sensornet/launcher/host_placement.hpp"

#include <arpa/inet.h>
#include <ifaddrs.h>
#include <net/if.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cstdlib>
#include <filesystem>
#include <memory>
#include <optional>
#include <sstream>
#include <string_view>

#include "sensornet/core/input_error.hpp"
#include "sensornet/dds/unicast_config.hpp"
#include "sensornet/io/command_line.hpp"

namespace sensornet::launcher {

std::uint32_t ipv4Number(const std::string& text) {
  in_addr address{};
  if (::inet_pton(AF_INET, text.c_str(), &address) != 1) return 0;
  return ntohl(address.s_addr);
}

std::string chooseLauncherAddress(const std::vector<LocalAddress>& local,
                                  const std::optional<std::string>& given,
                                  const std::string& coordinator_address,
                                  const std::string& hosts_source) {
  if (given) {
    const bool ours = std::any_of(local.begin(), local.end(),
                                  [&](const LocalAddress& a) { return a.text == *given; });
    if (!ours) {
      throw InputError(hosts_source, "launcher.address",
                       "an address of an interface of this machine that is up, got " + *given);
    }
    return *given;
  }
  const std::uint32_t target = ipv4Number(coordinator_address);
  for (const LocalAddress& a : local) {
    if (a.netmask != 0 && (a.address & a.netmask) == (target & a.netmask)) return a.text;
  }
  throw InputError(hosts_source, "launcher.address",
                   "an address of this machine on the hosts' network: no interface of this "
                   "machine is on the network of " + coordinator_address +
                       " (the coordinator's host); give launcher: address:");
}

std::vector<std::string> prefixedArgv(const std::vector<std::string>& prefix,
                                      const std::vector<std::string>& argv) {
  if (prefix.empty()) return argv;
  const bool ssh = std::filesystem::path(prefix.front()).filename() == "ssh";
  std::vector<std::string> out = prefix;
  for (const std::string& word : argv) out.push_back(ssh ? shellQuoted(word) : word);
  return out;
}

std::string shellQuoted(const std::string& word) {
  std::string quoted = "'";
  for (const char c : word) quoted += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return quoted + "'";
}

std::string shellLine(const std::vector<std::string>& words) {
  const auto plain = [](const std::string& word) {
    return !word.empty() && std::all_of(word.begin(), word.end(), [](char c) {
      return std::isalnum(static_cast<unsigned char>(c)) != 0 ||
             std::string_view("_./:=@%+,-").find(c) != std::string_view::npos;
    });
  };
  std::string line;
  for (const std::string& word : words) {
    line += (line.empty() ? "" : " ") + (plain(word) ? word : shellQuoted(word));
  }
  return line;
}


namespace {

namespace fs = std::filesystem;

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

// launcher.address if given (it must be this machine's), else the address of the local
// interface on the coordinator host's network.
std::string findLauncherAddress(const launcher::HostsFile& hosts) {
  return chooseLauncherAddress(localAddresses(), hosts.launcher_address,
                               hosts.coordinatorHost().address, hosts.source);
}

// The prefix with its program as an absolute path (ProcessGroup does not search PATH).
std::vector<std::string> resolvedPrefix(const launcher::Host& host) {
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

}  // namespace

HostPlacement::HostPlacement(const launcher::HostsFile& hosts)
    : hosts_(hosts), launcher_address_(findLauncherAddress(hosts)), peers_(hosts.hubAddresses()) {
  if (std::find(peers_.begin(), peers_.end(), launcher_address_) == peers_.end()) {
    peers_.push_back(launcher_address_);
  }
  for (const launcher::Host& host : hosts.hosts) prefixes_.push_back(resolvedPrefix(host));
}

void HostPlacement::place(ChildSpec& child, const launcher::Host& host,
                          dds::DiscoveryRole role) const {
  child.argv.insert(child.argv.end(),
                    {"--cyclone-config", dds::unicastConfigXml(host.address, peers_, role)});
  const auto index = static_cast<std::size_t>(&host - hosts_.hosts.data());
  child.argv = prefixedArgv(prefixes_.at(index), child.argv);
}

std::string HostPlacement::launcherConfigXml() const {
  return dds::unicastConfigXml(launcher_address_, peers_, dds::DiscoveryRole::Hub);
}

CLI::Validator sensorsPerProcessValue() {
  return CLI::Validator(
      [count = integerRange(1, kMaxSensorsPerProcess)](std::string& input) -> std::string {
        return input == "auto" ? std::string() : count(input);
      },
      "auto|N");
}

}  // namespace sensornet::launcher
