// The documents `sensornet pki init` signs: what each identity may publish and subscribe, in
// which partitions, and which files --force may replace. Expected values are read off the
// wire protocol (docs/wire-protocol.md): who writes which topic.

#include "sensornet/launcher/security_policy.hpp"

#include <gtest/gtest.h>

#include <regex>
#include <string>
#include <vector>

namespace sensornet::launcher {
namespace {

using dds::SecurityIdentity;
using dds::SecurityRole;

// The text between the first <tag> and </tag> after `from`.
std::string section(const std::string& xml, const std::string& tag) {
  const auto open = xml.find("<" + tag + ">");
  const auto close = xml.find("</" + tag + ">");
  if (open == std::string::npos || close == std::string::npos) return {};
  return xml.substr(open + tag.size() + 2, close - open - tag.size() - 2);
}

std::vector<std::string> all(const std::string& xml, const std::string& tag) {
  std::vector<std::string> found;
  const std::regex pattern("<" + tag + ">([^<]*)</" + tag + ">");
  for (auto it = std::sregex_iterator(xml.begin(), xml.end(), pattern); it != std::sregex_iterator();
       ++it) {
    found.push_back((*it)[1]);
  }
  return found;
}

const Validity kYear{"2026-12-04T10:00:00", "2027-12-05T10:00:00"};

TEST(SecurityPolicy, ASensorProcessPublishesItsOwnTopicsInItsOwnPartitionOnly) {
  const std::string xml = permissionsXml({SecurityRole::Sensor, "0-4"}, kYear);
  const std::string publish = section(xml, "publish");
  EXPECT_EQ(all(publish, "topic"), (std::vector<std::string>{"sensornet/Measurement",
                                                             "sensornet/EpisodeTally",
                                                             "sensornet/SensorStatus",
                                                             "sensornet/ClockEcho"}));
  EXPECT_EQ(all(publish, "partition"), std::vector<std::string>{"sensornet/*/sensors/0-4"});
  const std::string subscribe = section(xml, "subscribe");
  EXPECT_EQ(all(subscribe, "topic"), (std::vector<std::string>{"sensornet/Scenario",
                                                               "sensornet/Schedule",
                                                               "sensornet/EpisodeControl",
                                                               "sensornet/ClockProbe"}));
  EXPECT_EQ(all(subscribe, "partition"), std::vector<std::string>{"sensornet/*"});
  EXPECT_EQ(all(xml, "subject_name"), std::vector<std::string>{"CN=sensor-0-4,O=sensornet"});
  EXPECT_NE(xml.find("<grant name=\"sensornet_sensor-0-4\">"), std::string::npos);
  EXPECT_EQ(all(xml, "default"), std::vector<std::string>{"DENY"});
}

TEST(SecurityPolicy, TwoSensorBlocksNeverShareAPartition) {
  const std::string a = section(permissionsXml({SecurityRole::Sensor, "0-1"}, kYear), "publish");
  const std::string b = section(permissionsXml({SecurityRole::Sensor, "2"}, kYear), "publish");
  EXPECT_EQ(all(a, "partition"), std::vector<std::string>{"sensornet/*/sensors/0-1"});
  EXPECT_EQ(all(b, "partition"), std::vector<std::string>{"sensornet/*/sensors/2"});
}

TEST(SecurityPolicy, OnlyTheCoordinatorWritesTheRunsInputs) {
  for (const SecurityRole role : dds::kSecurityRoles) {
    const TopicRights rights = rightsOf({role, role == SecurityRole::Sensor ? "3" : ""});
    for (const char* topic : {"Scenario", "Schedule", "EpisodeControl"}) {
      const bool publishes =
          std::find(rights.publish.begin(), rights.publish.end(), topic) != rights.publish.end();
      EXPECT_EQ(publishes, role == SecurityRole::Coordinator)
          << dds::securityRoleName(role) << " " << topic;
    }
  }
}

TEST(SecurityPolicy, TheFusionCenterAloneWritesReports) {
  for (const SecurityRole role : dds::kSecurityRoles) {
    const TopicRights rights = rightsOf(role);
    const bool reports =
        std::find(rights.publish.begin(), rights.publish.end(), "Report") != rights.publish.end();
    EXPECT_EQ(reports, role == SecurityRole::FusionCenter) << dds::securityRoleName(role);
  }
  EXPECT_EQ(rightsOf(SecurityRole::FusionCenter).publish,
            (std::vector<std::string>{"Report", "FusionState", "ClockProbe"}));
}

TEST(SecurityPolicy, OperatorAndLauncherSendCommandsEachInTheirOwnPartition) {
  const TopicRights op = rightsOf(SecurityRole::Operator);
  const TopicRights launcher = rightsOf(SecurityRole::Launcher);
  EXPECT_EQ(op.publish, std::vector<std::string>{"Command"});
  EXPECT_EQ(launcher.publish, std::vector<std::string>{"Command"});
  EXPECT_EQ(op.publish_partition, "sensornet/*/operator");
  EXPECT_EQ(launcher.publish_partition, "sensornet/*/launcher");
  EXPECT_EQ(rightsOf(SecurityRole::Coordinator).publish_partition, "sensornet/*");
}

TEST(SecurityPolicy, PermissionsCarryTheirValidityAndTheRunsDomains) {
  const std::string xml = permissionsXml(SecurityRole::Coordinator, kYear);
  EXPECT_EQ(all(xml, "not_before"), std::vector<std::string>{"2026-12-04T10:00:00"});
  EXPECT_EQ(all(xml, "not_after"), std::vector<std::string>{"2027-12-05T10:00:00"});
  EXPECT_EQ(all(xml, "min"), std::vector<std::string>{"0"});
  EXPECT_EQ(all(xml, "max"), std::vector<std::string>{"230"});
}

TEST(SecurityPolicy, GovernanceProtectsEveryTopicAndAdmitsOnlyAuthenticatedParticipants) {
  const std::string xml = governanceXml();
  EXPECT_EQ(all(xml, "allow_unauthenticated_participants"), std::vector<std::string>{"false"});
  EXPECT_EQ(all(xml, "enable_join_access_control"), std::vector<std::string>{"true"});
  EXPECT_EQ(all(xml, "topic_expression"), std::vector<std::string>{"*"});
  EXPECT_EQ(all(xml, "enable_read_access_control"), std::vector<std::string>{"true"});
  EXPECT_EQ(all(xml, "enable_write_access_control"), std::vector<std::string>{"true"});
  EXPECT_EQ(all(xml, "data_protection_kind"), std::vector<std::string>{"ENCRYPT"});
  EXPECT_EQ(all(xml, "metadata_protection_kind"), std::vector<std::string>{"SIGN"});
  EXPECT_EQ(all(xml, "discovery_protection_kind"), std::vector<std::string>{"ENCRYPT"});
}

TEST(SecurityPolicy, NamesAreEscapedInTheDocument) {
  // A block name never holds markup, but the document must stay XML whatever it holds.
  const std::string xml = permissionsXml({SecurityRole::Sensor, "1<2"}, kYear);
  EXPECT_EQ(xml.find("sensor-1<2"), std::string::npos);
  EXPECT_NE(xml.find("sensor-1&lt;2"), std::string::npos);
}

TEST(SecurityPolicy, IdentitiesAreTheRolesThenEachDistinctSensorBlock) {
  std::vector<std::string> names;
  for (const SecurityIdentity& id : securityIdentities({{0, 1}, {2}, {0, 1}})) {
    names.push_back(id.name());
  }
  EXPECT_EQ(names, (std::vector<std::string>{"coordinator", "fusion_center", "operator",
                                             "launcher", "sensor-0-1", "sensor-2"}));
}

TEST(SecurityPolicy, ForceReplacesOnlyWhatPkiInitMade) {
  for (const char* made : {"ca.pem", "governance.p7s", "ca", "coordinator", "launcher",
                           "sensor-0-4"}) {
    EXPECT_TRUE(madeByPkiInit(PkiFolder::Root, made)) << made;
  }
  for (const char* other : {"notes.txt", "governance.xml", "ca.key", "sensors"}) {
    EXPECT_FALSE(madeByPkiInit(PkiFolder::Root, other)) << other;
  }
  EXPECT_TRUE(madeByPkiInit(PkiFolder::Identity, "key.pem"));
  EXPECT_FALSE(madeByPkiInit(PkiFolder::Identity, "ca.key")) << "a CA key is never in a role's";
  EXPECT_TRUE(madeByPkiInit(PkiFolder::Ca, "ca.key"));
  EXPECT_FALSE(madeByPkiInit(PkiFolder::Ca, "key.pem"));
}

}  // namespace
}  // namespace sensornet::launcher
