#pragma once
// The hosts file of a run across several machines (`sensornet launch SCENARIO --hosts FILE`):
// which host runs the coordinator, the fusion center and which sensors, the address each host
// has on the network the run uses, and the command prefix that runs a program there. Checked
// like the scenario file: every problem is an InputError naming the file and line, the field
// and what was expected.
//
//   hosts:
//     - name: control
//       address: 10.78.0.1          # IPv4, on the network the run uses
//       exec: ip netns exec sn-ctl  # or a list of words; or ssh -tt user@host; none: run here
//       coordinator: true
//       fusion_center: true
//     - name: edge-1
//       address: 10.78.0.2
//       exec: ip netns exec sn-e1
//       sensors: 0-2                # like sensor_agent --sensors
//   launcher:                       # optional: the launcher's own address (default: the
//     address: 10.78.0.254          # local interface on the hosts' network)
//
//   const HostsFile hosts = loadHostsFile("hosts.yaml", scenario.sensorCount());
//   const Host& control = hosts.coordinatorHost();
//   std::vector<std::string> peers = hosts.hubAddresses();   // where the hubs run

#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace sensornet::launcher {

struct Host {
  std::string name;               // letters, digits, '.', '_', '-'
  std::string address;            // dotted-quad IPv4
  std::vector<std::string> exec;  // the prefix's words; empty: runs on the launcher's machine
  bool coordinator = false;
  bool fusion_center = false;
  std::vector<int> sensors;  // sorted, each sensor of the scenario on exactly one host
  std::string where;         // "hosts.yaml:12", where the entry starts
};

struct HostsFile {
  std::string source;  // the file's path, for messages
  std::vector<Host> hosts;
  std::optional<std::string> launcher_address;  // launcher: address:

  [[nodiscard]] const Host& coordinatorHost() const;
  [[nodiscard]] const Host& fusionCenterHost() const;
  // The host that runs `sensor` (checked to exist by the parser).
  [[nodiscard]] const Host& hostOfSensor(int sensor) const;
  // The addresses of the hosts that run the coordinator or the fusion center, once each, in
  // file order: the hubs of discovery (include/sensornet/dds/domain.hpp, DiscoveryRole).
  [[nodiscard]] std::vector<std::string> hubAddresses() const;
};

// Parses and checks a hosts file for a scenario of `sensor_count` sensors; `source` names it in
// error messages. Throws InputError.
[[nodiscard]] HostsFile parseHostsYaml(const std::string& text, const std::string& source,
                                       int sensor_count);
[[nodiscard]] HostsFile loadHostsFile(const std::string& path, int sensor_count);

// True for a dotted-quad IPv4 unicast address a host can have (not 0.0.0.0, not multicast,
// not the broadcast address).
[[nodiscard]] bool isHostIpv4Address(std::string_view text);

}  // namespace sensornet::launcher
