#include "sensornet/launcher/host_placement.hpp"

#include <arpa/inet.h>

#include <algorithm>
#include <filesystem>

#include "sensornet/core/input_error.hpp"

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

}  // namespace sensornet::launcher
