// The Cyclone configuration of a process on one host of a many-hosts run
// (dds/unicast_config.hpp): what it says, and that Cyclone takes it for both discovery roles
// and really binds to the address it names (an address no interface has is refused).
#include "sensornet/dds/unicast_config.hpp"

#include <gtest/gtest.h>

#include <string>

#include "dds_test_support.hpp"
#include "sensornet/dds/dds_error.hpp"
#include "sensornet/dds/participant.hpp"

namespace sensornet::dds {
namespace {

std::size_t occurrences(const std::string& text, const std::string& what) {
  std::size_t count = 0;
  for (std::size_t at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) {
    ++count;
  }
  return count;
}

TEST(UnicastConfig, BindsToTheHostListsTheHubsAndAllowsNoMulticast) {
  const std::string hub =
      unicastConfigXml("10.78.0.2", {"10.78.0.1", "10.78.0.254"}, DiscoveryRole::Hub);
  EXPECT_EQ(occurrences(hub, "<NetworkInterface "), 1u);
  EXPECT_NE(hub.find("<NetworkInterface address=\"10.78.0.2\" multicast=\"false\"/>"),
            std::string::npos);
  EXPECT_NE(hub.find("<AllowMulticast>false</AllowMulticast>"), std::string::npos);
  EXPECT_EQ(occurrences(hub, "<Peer "), 2u);
  EXPECT_NE(hub.find("<Peer Address=\"10.78.0.1\"/>"), std::string::npos);
  EXPECT_NE(hub.find("<Peer Address=\"10.78.0.254\"/>"), std::string::npos);
  EXPECT_NE(hub.find("<ParticipantIndex>auto</ParticipantIndex>"), std::string::npos);
  // The stall tolerance of the loopback configuration (docs/ARCHITECTURE.md: 10 s absorbed).
  EXPECT_NE(hub.find("<LeaseDuration>20 s</LeaseDuration>"), std::string::npos);
  const std::string leaf = unicastConfigXml("10.78.0.2", {"10.78.0.1"}, DiscoveryRole::Leaf);
  EXPECT_NE(leaf.find("<ParticipantIndex>none</ParticipantIndex>"), std::string::npos);
  EXPECT_EQ(leaf.find("127.0.0.1"), std::string::npos);
}

TEST(UnicastConfig, CycloneTakesItForBothRolesOnALocalAddress) {
  for (const DiscoveryRole role : {DiscoveryRole::Hub, DiscoveryRole::Leaf}) {
    DomainConfig config = testing::isolatedDomain();
    config.cyclone_config = unicastConfigXml("127.0.0.1", {"127.0.0.1"}, role);
    const Domain domain(config);
    EXPECT_NO_THROW(Participant participant(domain));
  }
}

TEST(UnicastConfig, CycloneRefusesAnAddressNoInterfaceHas) {
  DomainConfig config = testing::isolatedDomain();
  config.cyclone_config = unicastConfigXml("198.51.100.77", {"127.0.0.1"}, DiscoveryRole::Hub);
  EXPECT_THROW(
      {
        const Domain domain(config);
        Participant participant(domain);
      },
      DdsError);
}

}  // namespace
}  // namespace sensornet::dds
