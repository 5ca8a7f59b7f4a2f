// The hosts file of `sensornet launch --hosts` (launcher/hosts_file.hpp): a good file is read
// as written; every bad one is refused with the file and line, the field and what was expected.

#include "sensornet/launcher/hosts_file.hpp"

#include <gtest/gtest.h>

#include <string>

#include "sensornet/core/input_error.hpp"

namespace sensornet::launcher {
namespace {

constexpr const char* kGood = R"(hosts:
  - name: control
    address: 10.78.0.1
    exec: ip netns exec sn-ctl
    coordinator: true
    fusion_center: true
  - name: edge-1
    address: 10.78.0.2
    exec: [ssh, -tt, user@edge-1]
    sensors: 0-1,4
  - name: edge-2
    address: 10.78.0.3
    sensors: "2-3"
launcher:
  address: 10.78.0.254
)";

// The message of the InputError that parsing `text` (for 5 sensors) throws; "" if none.
std::string refusal(const std::string& text, int sensors = 5) {
  try {
    (void)parseHostsYaml(text, "hosts.yaml", sensors);
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

// kGood with `from` replaced by `to` (once).
std::string goodWith(const std::string& from, const std::string& to) {
  std::string text = kGood;
  const std::size_t at = text.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  return text.replace(at, from.size(), to);
}

TEST(HostsFile, ReadsEveryFieldAsWritten) {
  const HostsFile file = parseHostsYaml(kGood, "hosts.yaml", 5);
  ASSERT_EQ(file.hosts.size(), 3u);
  EXPECT_EQ(file.hosts[0].name, "control");
  EXPECT_EQ(file.hosts[0].where, "hosts.yaml:2");
  EXPECT_EQ(file.hosts[0].exec, (std::vector<std::string>{"ip", "netns", "exec", "sn-ctl"}));
  EXPECT_TRUE(file.hosts[0].coordinator);
  EXPECT_TRUE(file.hosts[0].fusion_center);
  EXPECT_TRUE(file.hosts[0].sensors.empty());
  EXPECT_EQ(file.hosts[1].exec, (std::vector<std::string>{"ssh", "-tt", "user@edge-1"}));
  EXPECT_EQ(file.hosts[1].sensors, (std::vector<int>{0, 1, 4}));
  EXPECT_FALSE(file.hosts[1].coordinator);
  EXPECT_TRUE(file.hosts[2].exec.empty());
  EXPECT_EQ(file.hosts[2].sensors, (std::vector<int>{2, 3}));
  EXPECT_EQ(file.launcher_address, "10.78.0.254");
  EXPECT_EQ(&file.coordinatorHost(), &file.hosts[0]);
  EXPECT_EQ(&file.fusionCenterHost(), &file.hosts[0]);
  EXPECT_EQ(&file.hostOfSensor(4), &file.hosts[1]);
  EXPECT_EQ(&file.hostOfSensor(3), &file.hosts[2]);
  EXPECT_EQ(file.hubAddresses(), std::vector<std::string>{"10.78.0.1"});
}

TEST(HostsFile, HubAddressesListEachHubHostOnce) {
  const std::string split = R"(hosts:
  - {name: a, address: 10.0.0.1, coordinator: true, sensors: 0}
  - {name: b, address: 10.0.0.2, sensors: 1-3}
  - {name: c, address: 10.0.0.3, fusion_center: true, sensors: 4}
)";
  EXPECT_EQ(parseHostsYaml(split, "h", 5).hubAddresses(),
            (std::vector<std::string>{"10.0.0.1", "10.0.0.3"}));
}

TEST(HostsFile, RefusesEachMistakeNamingLineFieldAndExpectation) {
  struct Case {
    std::string text;
    std::string message;
  };
  const Case cases[] = {
      {"", "hosts.yaml: hosts: expected a hosts: list (the file is empty)"},
      {"hosts: [\n", "hosts.yaml:2: expected valid YAML"},
      {"hosts: []\n", "hosts.yaml:1: hosts: expected a non-empty list of hosts"},
      {goodWith("launcher:", "launchers:"),
       "hosts.yaml:14: launchers: expected one of the known keys (hosts, launcher), got unknown "
       "key 'launchers'"},
      {goodWith("    sensors: 0-1,4", "    sensor: 0-1,4"),
       "hosts.yaml:10: hosts[1].sensor: expected one of the known keys"},
      {goodWith("address: 10.78.0.2", "address: 10.78.0.256"),
       "hosts.yaml:8: hosts[1].address: expected an IPv4 address such as 10.78.0.2, got "
       "'10.78.0.256'"},
      {goodWith("address: 10.78.0.2", "address: edge-1.example"),
       "hosts.yaml:8: hosts[1].address: expected an IPv4 address"},
      {goodWith("address: 10.78.0.2", "address: 224.0.0.1"),
       "hosts.yaml:8: hosts[1].address: expected an IPv4 address"},
      {goodWith("address: 10.78.0.2", "address: 10.78.0.1"),
       "hosts.yaml:8: hosts[1].address: expected an address no other host has (10.78.0.1 is "
       "host control's)"},
      {goodWith("name: edge-2", "name: edge-1"),
       "hosts.yaml:11: hosts[2].name: expected a name no other host has"},
      {goodWith("name: edge-2", "name: edge 2"),
       "hosts.yaml:11: hosts[2].name: expected 1 to 64 letters, digits"},
      {goodWith("  - name: edge-1\n", "  - \n"),
       "hosts.yaml:8: hosts[1].name: expected a value (the field is missing)"},
      {goodWith("    coordinator: true\n", ""),
       "hosts.yaml:2: hosts: expected exactly one host with coordinator: true (none has)"},
      {goodWith("    sensors: \"2-3\"", "    sensors: \"2-3\"\n    coordinator: true"),
       "hosts.yaml:14: hosts[2].coordinator: expected exactly one host with coordinator: true "
       "(host control has it already)"},
      {goodWith("    fusion_center: true\n", ""),
       "hosts.yaml:2: hosts: expected exactly one host with fusion_center: true (none has)"},
      {goodWith("coordinator: true", "coordinator: maybe"),
       "hosts.yaml:5: hosts[0].coordinator: expected true or false, got 'maybe'"},
      {goodWith("sensors: 0-1,4", "sensors: 0-1,3"),
       "hosts.yaml:13: hosts[2].sensors: expected each sensor on one host only (sensor 3 is on "
       "host edge-1 already)"},
      {goodWith("sensors: 0-1,4", "sensors: 0-1"),
       "hosts.yaml:2: hosts: expected every sensor of the scenario (0 to 4) on one host (sensor "
       "4 is on none)"},
      {goodWith("sensors: 0-1,4", "sensors: 0-1,4-5"),
       "hosts.yaml:10: hosts[1].sensors: expected sensors of the scenario, 0 to 4, got 5"},
      {goodWith("sensors: 0-1,4", "sensors: 1-0,4"),
       "hosts.yaml:10: hosts[1].sensors: expected ascending ranges"},
      {goodWith("exec: [ssh, -tt, user@edge-1]", "exec: \"  \""),
       "hosts.yaml:9: hosts[1].exec: expected a command prefix"},
      {goodWith("    sensors: \"2-3\"", "    sensors: \"\""),
       "hosts.yaml:13: hosts[2].sensors: expected a non-empty text"},
      {goodWith("  address: 10.78.0.254", "  address: 10.78.0"),
       "hosts.yaml:15: launcher.address: expected an IPv4 address"},
  };
  for (const Case& c : cases) {
    const std::string message = refusal(c.text);
    EXPECT_EQ(message.substr(0, c.message.size()), c.message) << c.text;
  }
}

TEST(HostsFile, RefusesAHostThatRunsNothing) {
  const std::string idle = goodWith("    sensors: \"2-3\"\n", "");
  EXPECT_EQ(refusal(idle),
            "hosts.yaml:11: hosts[2]: expected a host that runs something: coordinator: true, "
            "fusion_center: true or sensors:");
}

TEST(HostsFile, UnreadableFileIsAnInputError) {
  EXPECT_THROW((void)loadHostsFile("/nonexistent/hosts.yaml", 5), InputError);
}

TEST(HostsFile, Ipv4AddressesAreDottedQuadUnicast) {
  EXPECT_TRUE(isHostIpv4Address("10.78.0.1"));
  EXPECT_TRUE(isHostIpv4Address("127.0.0.1"));
  EXPECT_FALSE(isHostIpv4Address("0.0.0.0"));
  EXPECT_FALSE(isHostIpv4Address("255.255.255.255"));
  EXPECT_FALSE(isHostIpv4Address("239.255.0.1"));
  EXPECT_FALSE(isHostIpv4Address("10.78.0"));
  EXPECT_FALSE(isHostIpv4Address("10.78.0.1 "));
  EXPECT_FALSE(isHostIpv4Address("::1"));
}

}  // namespace
}  // namespace sensornet::launcher
