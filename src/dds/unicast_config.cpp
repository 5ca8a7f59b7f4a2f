#include "sensornet/dds/unicast_config.hpp"

namespace sensornet::dds {

std::string unicastConfigXml(const std::string& interface_address,
                             const std::vector<std::string>& peer_addresses, DiscoveryRole role) {
  std::string peers;
  for (const std::string& address : peer_addresses) {
    peers += "<Peer Address=\"" + address + "\"/>";
  }
  const std::string index = role == DiscoveryRole::Leaf ? "none" : "auto";
  return "<CycloneDDS xmlns=\"https://cdds.io/config\"><Domain Id=\"any\"><General><Interfaces>"
         "<NetworkInterface address=\"" + interface_address + "\" multicast=\"false\"/>"
         "</Interfaces><AllowMulticast>false</AllowMulticast></General><Discovery>"
         "<ParticipantIndex>" + index + "</ParticipantIndex>"
         "<MaxAutoParticipantIndex>31</MaxAutoParticipantIndex><Peers>" + peers + "</Peers>"
         "<LeaseDuration>20 s</LeaseDuration><SPDPInterval>1 s</SPDPInterval></Discovery>"
         "<Internal><HeartbeatInterval max=\"500 ms\">100 ms</HeartbeatInterval></Internal>"
         "</Domain></CycloneDDS>";
}

}  // namespace sensornet::dds
