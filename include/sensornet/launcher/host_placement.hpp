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
// The decisions underneath are free functions, free of the system (unit-tested): which address
// of this machine the launcher speaks from, and how a child's argv runs through a prefix.
//
//   const std::string me = chooseLauncherAddress(localAddresses(), hosts.launcher_address,
//                                                hosts.coordinatorHost().address, hosts.source);
//   child.argv = prefixedArgv({"/usr/bin/ssh", "-tt", "pi@edge-1"}, child.argv);
//   // ssh runs its words through the remote shell: each of child.argv is quoted ('...')
//
// The prefix runs the program's own argv: `ip netns exec NS` execs it as given; `ssh` (the
// prefix's program named ssh) hands the words to the remote shell, so each is quoted for it.

#include <CLI/CLI.hpp>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "sensornet/dds/domain.hpp"
#include "sensornet/launcher/hosts_file.hpp"
#include "sensornet/launcher/launch_plan.hpp"  // ChildSpec

namespace sensornet::launcher {

// An IPv4 address of an interface of this machine that is up (host byte order).
struct LocalAddress {
  std::uint32_t address = 0;
  std::uint32_t netmask = 0;
  std::string text;
};

// The dotted quad `text` in host byte order (0 when it is not one).
[[nodiscard]] std::uint32_t ipv4Number(const std::string& text);

// `given` (launcher.address of the hosts file) if it is one of `local`, else the local address
// on the network of `coordinator_address`. Throws InputError naming `hosts_source` and
// launcher.address when there is none.
[[nodiscard]] std::string chooseLauncherAddress(const std::vector<LocalAddress>& local,
                                                const std::optional<std::string>& given,
                                                const std::string& coordinator_address,
                                                const std::string& hosts_source);

// `argv` run through `prefix` (empty: unchanged); after an ssh prefix each word is quoted.
[[nodiscard]] std::vector<std::string> prefixedArgv(const std::vector<std::string>& prefix,
                                                    const std::vector<std::string>& argv);

// `word` quoted for a POSIX shell ('...', with ' as '\'').
[[nodiscard]] std::string shellQuoted(const std::string& word);
// `words` as one line a POSIX shell reads back as them: each word quoted only where it holds a
// character the shell would take apart (a space, a quote, '$', ...).
[[nodiscard]] std::string shellLine(const std::vector<std::string>& words);

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
