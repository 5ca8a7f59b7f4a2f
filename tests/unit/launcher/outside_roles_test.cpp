// What the launcher says to whoever fills a role from outside (issue 48): the advice names the
// domain, the partition and the Cyclone configuration file, and the file it names is the
// configuration the run's own processes use; nothing is said when every role has spoken.

#include "sensornet/launcher/outside_roles.hpp"

#include <gtest/gtest.h>

#include <fstream>
#include <sstream>
#include <string>

#include "sensornet/core/scenario.hpp"
#include "sensornet/dds/domain.hpp"
#include "support/scratch_dir.hpp"

namespace sensornet::launcher {
namespace {

using sensornet::testing::ScratchDir;

Scenario twoSensors() {
  RandomPlantSpec spec;
  spec.state_dim = 3;
  spec.sensor_count = 2;
  spec.seed = 4;
  return generateRandomScenario(spec);
}

std::string readAll(const std::filesystem::path& path) {
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

TEST(OutsideRoles, TheAdviceNamesTheDomainThePartitionTheConfigurationAndTheExample) {
  const Scenario scenario = twoSensors();
  const OutsideRoles roles{{1}, false, false};
  const OutsideReach reach{34, "sensornet/mine", "/tmp/logs/cyclone-outside.xml",
                           {"--run-id", "mine", "--domain-id", "34"}};
  const std::string advice = outsideRolesAdvice(reach, scenario, {1}, false);
  EXPECT_NE(advice.find("domain 34, partition sensornet/mine"), std::string::npos) << advice;
  EXPECT_NE(advice.find("CYCLONEDDS_URI=file:///tmp/logs/cyclone-outside.xml"), std::string::npos)
      << advice;
  const auto p = std::to_string(scenario.sensors[1].H.rows());
  EXPECT_NE(advice.find("external_sensor --run-id mine --domain-id 34 --sensor 1 --dim " + p),
            std::string::npos)
      << advice;
  EXPECT_EQ(outsideRolesAdvice(reach, scenario, {}, false), "");
  EXPECT_NE(outsideRolesAdvice(reach, scenario, {}, true).find("fusion center"),
            std::string::npos);
  EXPECT_NE(outsideRolesAnnouncement(roles, reach).find("sensornet/mine/sensors/<their ids>"),
            std::string::npos);
  EXPECT_NE(outsideRolesAnnouncement(roles, reach)
                .find("CYCLONEDDS_URI=file:///tmp/logs/cyclone-outside.xml"),
            std::string::npos);
  EXPECT_EQ(outsideRolesAnnouncement({}, reach), "");
}

// Without a configuration of the user's, the file named is the shipped loopback configuration
// (the one every process of the run loads); one given as a path is named as given.
TEST(OutsideRoles, TheConfigurationFileIsTheOneTheRunUses) {
  ScratchDir dir;
  wire::RunOptions run;
  run.run_id = "mine";
  ::unsetenv(wire::kCycloneConfigVariable);
  const std::filesystem::path written = outsideConfigFile(dir.path(), run, false);
  EXPECT_EQ(written, dir.path() / "cyclone-outside.xml");
  EXPECT_EQ(readAll(written), dds::loopbackConfigXml() + "\n");
  run.cyclone_config = "file:///etc/mine.xml";
  EXPECT_EQ(outsideConfigFile(dir.path(), run, false), "/etc/mine.xml");
  EXPECT_EQ(outsideConfigFile(dir.path(), run, true), dir.path() / "cyclone-launcher.xml");
}

}  // namespace
}  // namespace sensornet::launcher
