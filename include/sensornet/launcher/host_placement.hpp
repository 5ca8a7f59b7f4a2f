#pragma once
// The decisions of placing a launch on several hosts (`sensornet launch --hosts FILE`), free of
// the system: which address of this machine the launcher speaks from, and how a child's argv
// runs through its host's exec prefix. launcher/host_placement.cpp lists the interfaces,
// resolves the prefixes on PATH and writes the Cyclone configurations.
//
//   const std::string me = chooseLauncherAddress(localAddresses(), hosts.launcher_address,
//                                                hosts.coordinatorHost().address, hosts.source);
//   child.argv = prefixedArgv({"/usr/bin/ssh", "-tt", "pi@edge-1"}, child.argv);
//   // ssh runs its words through the remote shell: each of child.argv is quoted ('...')
//
// The prefix runs the program's own argv: `ip netns exec NS` execs it as given; `ssh` (the
// prefix's program named ssh) hands the words to the remote shell, so each is quoted for it.

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

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

}  // namespace sensornet::launcher
