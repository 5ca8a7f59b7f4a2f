#pragma once
// Where the processes of a launch run when a hosts file is given (`sensornet launch --hosts`):
// each child's command goes through its host's exec prefix and carries a Cyclone configuration
// of its own (that host's address as the interface, no multicast, unicast peers: the hub hosts
// and the launcher; dds/unicast_config.hpp), and the launcher's own participant gets one that
// reaches the hosts from the machine it runs on.
//
//   const HostsFile hosts = launcher::loadHostsFile(path, scenario.sensorCount());
//   const HostPlacement placement(hosts);          // finds the launcher's address, the prefixes
//   placement.place(child, hosts.hostOfSensor(3), dds::DiscoveryRole::Leaf);
//   domain.cyclone_config = placement.launcherConfigXml();
//
// The prefix runs the program's own argv: `ip netns exec NS` execs it (the pid the launcher
// watches and signals is the program's); with `ssh` the launcher watches and signals the ssh
// client, and quotes every argument for the remote shell (README, "Many hosts", says what that
// does and does not guarantee).

#include <CLI/CLI.hpp>
#include <string>
#include <vector>

#include "process_group.hpp"
#include "sensornet/dds/domain.hpp"
#include "sensornet/launcher/hosts_file.hpp"

namespace sensornet::launcher {

class HostPlacement {
 public:
  // Throws InputError naming the hosts file when a prefix's program is not found or the
  // launcher has no address on the hosts' network (or launcher.address is not this machine's).
  explicit HostPlacement(const launcher::HostsFile& hosts);

  // Puts `child` on `host`: appends --cyclone-config with the host's configuration for `role`
  // to its argv, then puts the host's prefix in front.
  void place(ChildSpec& child, const launcher::Host& host, dds::DiscoveryRole role) const;

  [[nodiscard]] const std::string& launcherAddress() const noexcept { return launcher_address_; }
  // The launcher's configuration: a hub on its own address with the same peers as every host.
  [[nodiscard]] std::string launcherConfigXml() const;

 private:
  const launcher::HostsFile& hosts_;
  std::string launcher_address_;
  std::vector<std::string> peers_;  // the hub hosts' addresses and the launcher's
  std::vector<std::vector<std::string>> prefixes_;  // per host: its exec prefix, resolved
};

// --sensors-per-process: "auto" or a whole number in [1, kMaxSensorsPerProcess] (launch_plan.hpp).
[[nodiscard]] CLI::Validator sensorsPerProcessValue();

}  // namespace sensornet::launcher
