#include "sensornet/launcher/hosts_file.hpp"

#include <arpa/inet.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <initializer_list>
#include <map>
#include <set>
#include <sstream>

#include "sensornet/core/input_error.hpp"
#include "sensornet/emulator/sensor_ids.hpp"
#include "sensornet/io/scenario_file.hpp"
#include "sensornet/io/yaml_text.hpp"

namespace sensornet::launcher {
namespace {

// "file:line" of a node (the file alone when the node has no position).
std::string whereIs(const std::string& source, const YAML::Node& node) {
  if (node.IsDefined() && node.Mark().line >= 0) {
    return source + ":" + std::to_string(node.Mark().line + 1);
  }
  return source;
}

[[noreturn]] void fail(const std::string& source, const YAML::Node& node, const std::string& field,
                       const std::string& expected) {
  throw InputError(whereIs(source, node), field, expected);
}

void rejectUnknownKeys(const std::string& source, const YAML::Node& node, const std::string& field,
                       std::initializer_list<const char*> known) {
  if (!node.IsMap()) fail(source, node, field, "a mapping of keys");
  for (const auto& entry : node) {
    const std::string key = entry.first.Scalar();
    if (std::none_of(known.begin(), known.end(), [&](const char* k) { return key == k; })) {
      std::string list;
      for (const char* k : known) list += (list.empty() ? "" : ", ") + std::string(k);
      fail(source, entry.first, field.empty() ? key : field + "." + key,
           "one of the known keys (" + list + "), got unknown key '" + key + "'");
    }
  }
}

std::string text(const std::string& source, const YAML::Node& node, const std::string& field) {
  if (!node.IsScalar() || node.Scalar().empty()) fail(source, node, field, "a non-empty text");
  return node.Scalar();
}

bool flag(const std::string& source, const YAML::Node& node, const std::string& field) {
  if (!node.IsDefined() || node.IsNull()) return false;
  bool value = false;
  if (!node.IsScalar() || !YAML::convert<bool>::decode(node, value)) {
    fail(source, node, field, "true or false, got '" + (node.IsScalar() ? node.Scalar() : "") + "'");
  }
  return value;
}

bool isNameCharacter(char c) {
  return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '.' ||
         c == '_' || c == '-';
}

// The prefix as words: a text split at white space (no quoting), or a list of texts.
std::vector<std::string> execWords(const std::string& source, const YAML::Node& node,
                                   const std::string& field) {
  std::vector<std::string> words;
  if (!node.IsDefined() || node.IsNull()) return words;
  if (node.IsScalar()) {
    std::istringstream in(node.Scalar());
    for (std::string word; in >> word;) words.push_back(word);
  } else if (node.IsSequence()) {
    for (std::size_t i = 0; i < node.size(); ++i) {
      words.push_back(text(source, node[i], field + "[" + std::to_string(i) + "]"));
    }
  }
  if (words.empty()) {
    fail(source, node, field,
         "a command prefix such as 'ip netns exec NAME' or 'ssh -tt user@host' (a text or a "
         "list of words), or no exec key to run on the launcher's machine");
  }
  return words;
}

Host parseHost(const std::string& source, const YAML::Node& node, const std::string& field) {
  rejectUnknownKeys(source, node, field,
                    {"name", "address", "exec", "coordinator", "fusion_center", "sensors"});
  Host host;
  host.where = whereIs(source, node);
  if (!node["name"]) fail(source, node, field + ".name", "a value (the field is missing)");
  host.name = text(source, node["name"], field + ".name");
  if (!std::all_of(host.name.begin(), host.name.end(), isNameCharacter) || host.name.size() > 64) {
    fail(source, node["name"], field + ".name",
         "1 to 64 letters, digits, '.', '_' or '-', got '" + host.name + "'");
  }
  if (!node["address"]) fail(source, node, field + ".address", "a value (the field is missing)");
  host.address = text(source, node["address"], field + ".address");
  if (!isHostIpv4Address(host.address)) {
    fail(source, node["address"], field + ".address",
         "an IPv4 address such as 10.78.0.2, got '" + host.address + "'");
  }
  host.exec = execWords(source, node["exec"], field + ".exec");
  host.coordinator = flag(source, node["coordinator"], field + ".coordinator");
  host.fusion_center = flag(source, node["fusion_center"], field + ".fusion_center");
  if (const YAML::Node sensors = node["sensors"]; sensors && !sensors.IsNull()) {
    const std::string spec = text(source, sensors, field + ".sensors");
    try {
      host.sensors = emulator::parseSensorIds(spec, source);
    } catch (const InputError& e) {
      fail(source, sensors, field + ".sensors", e.expected());
    }
  }
  if (!host.coordinator && !host.fusion_center && host.sensors.empty()) {
    fail(source, node, field,
         "a host that runs something: coordinator: true, fusion_center: true or sensors:");
  }
  return host;
}

// Names and addresses differ from host to host.
void checkDistinct(const std::string& source, const YAML::Node& list,
                   const std::vector<Host>& hosts) {
  for (std::size_t i = 0; i < hosts.size(); ++i) {
    for (std::size_t k = 0; k < i; ++k) {
      const std::string field = "hosts[" + std::to_string(i) + "]";
      if (hosts[i].name == hosts[k].name) {
        fail(source, list[i]["name"], field + ".name",
             "a name no other host has ('" + hosts[i].name + "' is hosts[" + std::to_string(k) +
                 "]'s)");
      }
      if (hosts[i].address == hosts[k].address) {
        fail(source, list[i]["address"], field + ".address",
             "an address no other host has (" + hosts[i].address + " is host " + hosts[k].name +
                 "'s)");
      }
    }
  }
}

// Exactly one host has `key: true`.
void checkExactlyOne(const std::string& source, const YAML::Node& list,
                     const std::vector<Host>& hosts, bool Host::*role, const std::string& key) {
  std::optional<std::size_t> first;
  for (std::size_t i = 0; i < hosts.size(); ++i) {
    if (!(hosts[i].*role)) continue;
    if (first) {
      fail(source, list[i][key], "hosts[" + std::to_string(i) + "]." + key,
           "exactly one host with " + key + ": true (host " + hosts[*first].name +
               " has it already)");
    }
    first = i;
  }
  if (!first) fail(source, list, "hosts", "exactly one host with " + key + ": true (none has)");
}

// Every sensor of the scenario on exactly one host, and no other sensor.
void checkSensorCoverage(const std::string& source, const YAML::Node& list,
                         const std::vector<Host>& hosts, int sensor_count) {
  std::map<int, std::string> host_of;
  for (std::size_t i = 0; i < hosts.size(); ++i) {
    const std::string field = "hosts[" + std::to_string(i) + "].sensors";
    for (const int j : hosts[i].sensors) {
      if (j >= sensor_count) {
        fail(source, list[i]["sensors"], field,
             "sensors of the scenario, 0 to " + std::to_string(sensor_count - 1) + ", got " +
                 std::to_string(j));
      }
      if (const auto [it, added] = host_of.emplace(j, hosts[i].name); !added) {
        fail(source, list[i]["sensors"], field,
             "each sensor on one host only (sensor " + std::to_string(j) + " is on host " +
                 it->second + " already)");
      }
    }
  }
  for (int j = 0; j < sensor_count; ++j) {
    if (!host_of.contains(j)) {
      fail(source, list, "hosts",
           "every sensor of the scenario (0 to " + std::to_string(sensor_count - 1) +
               ") on one host (sensor " + std::to_string(j) + " is on none)");
    }
  }
}

std::optional<std::string> parseLauncher(const std::string& source, const YAML::Node& node) {
  if (!node || node.IsNull()) return std::nullopt;
  rejectUnknownKeys(source, node, "launcher", {"address"});
  if (!node["address"]) return std::nullopt;
  const std::string address = text(source, node["address"], "launcher.address");
  if (!isHostIpv4Address(address)) {
    fail(source, node["address"], "launcher.address",
         "an IPv4 address such as 10.78.0.254, got '" + address + "'");
  }
  return address;
}

HostsFile parseHostsTree(const YAML::Node& root, const std::string& source, int sensor_count) {
  if (!root.IsDefined() || root.IsNull()) fail(source, root, "hosts", "a hosts: list (the file is empty)");
  rejectUnknownKeys(source, root, "", {"hosts", "launcher"});
  const YAML::Node list = root["hosts"];
  if (!list || !list.IsSequence() || list.size() == 0) {
    fail(source, list ? list : root, "hosts", "a non-empty list of hosts");
  }
  HostsFile file;
  file.source = source;
  for (std::size_t i = 0; i < list.size(); ++i) {
    file.hosts.push_back(parseHost(source, list[i], "hosts[" + std::to_string(i) + "]"));
  }
  checkDistinct(source, list, file.hosts);
  checkExactlyOne(source, list, file.hosts, &Host::coordinator, "coordinator");
  checkExactlyOne(source, list, file.hosts, &Host::fusion_center, "fusion_center");
  checkSensorCoverage(source, list, file.hosts, sensor_count);
  file.launcher_address = parseLauncher(source, root["launcher"]);
  return file;
}

}  // namespace

bool isHostIpv4Address(std::string_view text) {
  in_addr address{};
  const std::string copy(text);
  if (::inet_pton(AF_INET, copy.c_str(), &address) != 1) return false;
  const std::uint32_t value = ntohl(address.s_addr);
  const bool multicast = (value >> 28) == 0xe;
  return value != 0 && value != 0xffffffffU && !multicast;
}

HostsFile parseHostsYaml(const std::string& text, const std::string& source, int sensor_count) {
  return parseHostsTree(parseYamlText(text, source), source, sensor_count);
}

HostsFile loadHostsFile(const std::string& path, int sensor_count) {
  return parseHostsYaml(readTextFile(path, "hosts"), path, sensor_count);
}

const Host& HostsFile::coordinatorHost() const {
  return *std::find_if(hosts.begin(), hosts.end(), [](const Host& h) { return h.coordinator; });
}

const Host& HostsFile::fusionCenterHost() const {
  return *std::find_if(hosts.begin(), hosts.end(), [](const Host& h) { return h.fusion_center; });
}

const Host& HostsFile::hostOfSensor(int sensor) const {
  return *std::find_if(hosts.begin(), hosts.end(), [&](const Host& h) {
    return std::binary_search(h.sensors.begin(), h.sensors.end(), sensor);
  });
}

std::vector<std::string> HostsFile::hubAddresses() const {
  std::vector<std::string> addresses;
  for (const Host& host : hosts) {
    if ((host.coordinator || host.fusion_center) &&
        std::find(addresses.begin(), addresses.end(), host.address) == addresses.end()) {
      addresses.push_back(host.address);
    }
  }
  return addresses;
}

}  // namespace sensornet::launcher
