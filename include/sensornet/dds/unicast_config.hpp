#pragma once
// The Cyclone configuration of a participant on one host of a run that spans several hosts
// (`sensornet launch --hosts`): bound to that host's address, no multicast, discovery by
// unicast to the hub hosts. It keeps the discovery roles of the loopback configuration
// (domain.hpp, DiscoveryRole): a hub takes a participant index and probes the ports of the
// indices 0..31 at every peer address, so the hubs find one another; a leaf (a sensor agent)
// takes none, probes the hubs, and is found through its own announcements. Lease, announcement
// and heartbeat intervals are those of config/cyclonedds-loopback.xml, so a stall or a cut
// link of up to 10 s is absorbed the same way.
//
//   const std::string xml = unicastConfigXml("10.78.0.2", {"10.78.0.1", "10.78.0.254"},
//                                            DiscoveryRole::Leaf);
//   Domain domain(DomainConfig{domain_id, "sensornet/run-1", xml});

#include <string>
#include <vector>

#include "sensornet/dds/domain.hpp"

namespace sensornet::dds {

// `interface_address`: the host's own IPv4 address (the interface Cyclone binds to);
// `peer_addresses`: the hub hosts' addresses (a hub lists its own too when other hubs share its
// host). Addresses are taken as given (check them first: launcher/hosts_file.hpp).
[[nodiscard]] std::string unicastConfigXml(const std::string& interface_address,
                                           const std::vector<std::string>& peer_addresses,
                                           DiscoveryRole role);

}  // namespace sensornet::dds
