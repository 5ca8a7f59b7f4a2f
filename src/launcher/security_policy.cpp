#include "sensornet/launcher/security_policy.hpp"

#include <set>

#include "sensornet/core/xml_text.hpp"
#include "sensornet/emulator/sensor_ids.hpp"

namespace sensornet::launcher {
namespace {

using dds::SecurityIdentity;
using dds::SecurityRole;

// Domain ids of every run: hashed into 1..230, or 0..230 with --domain-id.
const char* const kDomains =
    "<domains><id_range><min>0</min><max>230</max></id_range></domains>";

std::string topicList(const std::vector<std::string>& topics, const std::string& partition) {
  std::string xml = "<topics>";
  for (const std::string& t : topics) xml += "<topic>sensornet/" + t + "</topic>";
  return xml + "</topics><partitions><partition>" + escapeXml(partition) +
         "</partition></partitions>";
}

}  // namespace

TopicRights rightsOf(const SecurityIdentity& identity) {
  switch (identity.role) {
    case SecurityRole::Coordinator:
      return {{"Scenario", "Schedule", "EpisodeControl", "CommandReply"},
              {"Scenario", "Schedule", "EpisodeControl", "Command", "SensorStatus", "Report",
               "FusionState"}};
    case SecurityRole::Sensor:
      return {{"Measurement", "EpisodeTally", "SensorStatus", "ClockEcho"},
              {"Scenario", "Schedule", "EpisodeControl", "ClockProbe"},
              "sensornet/*/sensors/" + identity.sensors};
    case SecurityRole::FusionCenter:  // CommandReply: a command refused by right is a fault
      return {{"Report", "FusionState", "ClockProbe"},
              {"Scenario", "Schedule", "EpisodeControl", "Measurement", "EpisodeTally",
               "SensorStatus", "CommandReply", "ClockEcho"}};
    case SecurityRole::Operator:
    case SecurityRole::Launcher:  // it sends the sensors' failure notices as Commands
      return {{"Command"},
              {"Scenario", "Schedule", "EpisodeControl", "SensorStatus", "Report", "FusionState",
               "CommandReply"},
              "sensornet/*/" + std::string(dds::securityRoleName(identity.role))};
  }
  return {};
}

std::string governanceXml() {
  return std::string(R"(<?xml version="1.0" encoding="UTF-8"?>
<dds xmlns:xsi="http://www.w3.org/2001/XMLSchema-instance"
     xsi:noNamespaceSchemaLocation="http://www.omg.org/spec/DDS-SECURITY/20170901/omg_shared_ca_governance.xsd">
  <domain_access_rules>
    <domain_rule>
      )") + kDomains + R"(
      <allow_unauthenticated_participants>false</allow_unauthenticated_participants>
      <enable_join_access_control>true</enable_join_access_control>
      <discovery_protection_kind>ENCRYPT</discovery_protection_kind>
      <liveliness_protection_kind>ENCRYPT</liveliness_protection_kind>
      <rtps_protection_kind>NONE</rtps_protection_kind>
      <topic_access_rules>
        <topic_rule>
          <topic_expression>*</topic_expression>
          <enable_discovery_protection>true</enable_discovery_protection>
          <enable_liveliness_protection>true</enable_liveliness_protection>
          <enable_read_access_control>true</enable_read_access_control>
          <enable_write_access_control>true</enable_write_access_control>
          <metadata_protection_kind>SIGN</metadata_protection_kind>
          <data_protection_kind>ENCRYPT</data_protection_kind>
        </topic_rule>
      </topic_access_rules>
    </domain_rule>
  </domain_access_rules>
</dds>
)";
}

std::string permissionsXml(const SecurityIdentity& identity, const Validity& validity) {
  const TopicRights rights = rightsOf(identity);
  return std::string(R"(<?xml version="1.0" encoding="UTF-8"?>
<dds xmlns:xsi="http://www.w3.org/2001/XMLSchema-instance"
     xsi:noNamespaceSchemaLocation="http://www.omg.org/spec/DDS-SECURITY/20170901/omg_shared_ca_permissions.xsd">
  <permissions>
    <grant name="sensornet_)") +
         escapeXml(identity.name()) + R"(">
      <subject_name>)" + escapeXml("CN=" + identity.name() + ",O=sensornet") + R"(</subject_name>
      <validity><not_before>)" + validity.not_before + "</not_before><not_after>" +
         validity.not_after + R"(</not_after></validity>
      <allow_rule>
        )" + kDomains + R"(
        <publish>)" + topicList(rights.publish, rights.publish_partition) + R"(</publish>
        <subscribe>)" + topicList(rights.subscribe, "sensornet/*") + R"(</subscribe>
      </allow_rule>
      <default>DENY</default>
    </grant>
  </permissions>
</dds>
)";
}

std::vector<SecurityIdentity> securityIdentities(const std::vector<std::vector<int>>& sensor_blocks) {
  std::vector<SecurityIdentity> identities;
  for (const SecurityRole role : dds::kSecurityRoles) {
    if (role != SecurityRole::Sensor) identities.emplace_back(role);
  }
  std::set<std::string> made;
  for (const std::vector<int>& block : sensor_blocks) {
    const std::string ids = emulator::formatSensorIds(block);
    if (made.insert(ids).second) identities.emplace_back(SecurityRole::Sensor, ids);
  }
  return identities;
}

bool madeByPkiInit(PkiFolder folder, const std::string& name) {
  switch (folder) {
    case PkiFolder::Root: {
      static const std::set<std::string> names = [] {
        std::set<std::string> n = {"ca.pem", "governance.p7s", "ca"};
        for (const SecurityRole role : dds::kSecurityRoles) n.emplace(dds::securityRoleName(role));
        return n;
      }();
      return names.count(name) > 0 || name.rfind("sensor-", 0) == 0;
    }
    case PkiFolder::Identity:
      return name == "identity.pem" || name == "key.pem" || name == "permissions.p7s" ||
             name == "ca.pem" || name == "governance.p7s";
    case PkiFolder::Ca:
      return name == "ca.key" || name == "ca.pem";
  }
  return false;
}

}  // namespace sensornet::launcher
