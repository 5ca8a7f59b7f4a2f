// Run isolation and the shipped loopback configuration. The configuration is checked twice:
// as text (it is the file the repository ships) and by what Cyclone itself reports when it runs
// with it (its trace: the interface it selected and the destination of every packet it sent).
#include "sensornet/dds/domain.hpp"

#include <gtest/gtest.h>

#include <cctype>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "dds_test_support.hpp"
#include "sensornet/core/input_error.hpp"
#include "sensornet/dds/dds_error.hpp"
#include "sensornet/dds/participant.hpp"
#include "sensornet/dds/reader.hpp"
#include "sensornet/dds/topics.hpp"

namespace sensornet::dds {
namespace {

using namespace std::chrono_literals;

std::string readFile(const std::filesystem::path& path) {
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

// The complete destinations "udp/<address>:<port>@" of an nn_xpack_send trace line (a line cut
// short by the trace, ending in "(trunc)", leaves its last one incomplete: skipped).
std::vector<std::string> sendDestinations(const std::string& line) {
  std::vector<std::string> addresses;
  for (std::size_t at = line.find("udp/"); at != std::string::npos;
       at = line.find("udp/", at + 1)) {
    const std::size_t begin = at + 4;
    const std::size_t colon = line.find(':', begin);
    if (colon == std::string::npos) break;
    std::size_t end = colon + 1;
    while (end < line.size() && std::isdigit(static_cast<unsigned char>(line[end]))) ++end;
    if (end == colon + 1 || end >= line.size() || line[end] != '@') continue;
    addresses.push_back(line.substr(begin, colon - begin));
  }
  return addresses;
}

TEST(RunIsolation, ForRunGivesTheSameDomainAndPartitionEveryTime) {
  const DomainConfig a = DomainConfig::forRun("run-42");
  const DomainConfig b = DomainConfig::forRun("run-42");
  EXPECT_EQ(a.domain_id, b.domain_id);
  EXPECT_EQ(a.partition, "sensornet/run-42");
  EXPECT_EQ(a.cyclone_config, b.cyclone_config);
}

TEST(RunIsolation, DomainIdsStayInTheSafeRangeAndSpreadOverIt) {
  std::set<dds_domainid_t> seen;
  for (int i = 0; i < 1000; ++i) {
    const dds_domainid_t id = domainIdForRun("run-" + std::to_string(i));
    ASSERT_GE(id, 1u);
    ASSERT_LE(id, kMaxDomainId);
    seen.insert(id);
  }
  // 1000 draws into 230 bins leave a bin empty with probability 230 (229/230)^1000 < 3e-4 for a
  // uniform hash; demand most of them.
  EXPECT_GT(seen.size(), 200u);
}

TEST(RunIsolation, RefusesRunIdsThatCannotNameAPartition) {
  EXPECT_NO_THROW(validateRunId("Run_1.a-b", "test"));
  EXPECT_THROW(validateRunId("", "test"), InputError);
  EXPECT_THROW(validateRunId("run 1", "test"), InputError);
  EXPECT_THROW(validateRunId("run*", "test"), InputError);
  EXPECT_THROW(validateRunId(std::string(65, 'a'), "test"), InputError);
  EXPECT_THROW((void)DomainConfig::forRun("a/b"), InputError);
}

TEST(RunIsolation, ParsesDomainIdsAndRefusesOthers) {
  EXPECT_EQ(parseDomainId("0", "flag"), 0u);
  EXPECT_EQ(parseDomainId("230", "flag"), 230u);
  EXPECT_THROW((void)parseDomainId("231", "flag"), InputError);
  EXPECT_THROW((void)parseDomainId("-1", "flag"), InputError);
  EXPECT_THROW((void)parseDomainId("7x", "flag"), InputError);
  EXPECT_THROW((void)parseDomainId("", "flag"), InputError);
}

TEST(LoopbackConfig, CompiledInTextIsTheShippedFile) {
  const std::string shipped =
      readFile(std::filesystem::path(SENSORNET_SOURCE_DIR) / "config/cyclonedds-loopback.xml");
  ASSERT_FALSE(shipped.empty());
  EXPECT_EQ(loopbackConfigXml(), shipped);
}

TEST(LoopbackConfig, NamesLoopbackUnicastAndTheRaisedLimits) {
  const std::string& xml = loopbackConfigXml();
  EXPECT_NE(xml.find(R"(<NetworkInterface name="lo" multicast="false"/>)"), std::string::npos);
  EXPECT_NE(xml.find("<AllowMulticast>false</AllowMulticast>"), std::string::npos);
  EXPECT_NE(xml.find(R"(<Peer Address="127.0.0.1"/>)"), std::string::npos);
  EXPECT_NE(xml.find("<ParticipantIndex>auto</ParticipantIndex>"), std::string::npos);
  EXPECT_NE(xml.find("<MaxAutoParticipantIndex>31</MaxAutoParticipantIndex>"), std::string::npos);
  EXPECT_NE(xml.find("<LeaseDuration>20 s</LeaseDuration>"), std::string::npos);
}

TEST(LoopbackConfig, ALeafTakesNoParticipantIndexAndCyclonesAcceptsTheFragment) {
  const DomainConfig hub = DomainConfig::forRun("leaf-config-test");
  const DomainConfig leaf = DomainConfig::forRun("leaf-config-test", DiscoveryRole::Leaf);
  EXPECT_EQ(leaf.cyclone_config, loopbackConfigXml() + "," + leafConfigXml());
  EXPECT_NE(leafConfigXml().find("<ParticipantIndex>none</ParticipantIndex>"), std::string::npos);
  EXPECT_EQ(leaf.cyclone_config.find("HeartbeatInterval>1 s<"), std::string::npos);
  EXPECT_EQ(leaf.domain_id, hub.domain_id);
  EXPECT_EQ(leaf.partition, hub.partition);
  const Domain domain(leaf);  // Cyclone parses the combined configuration
  EXPECT_GT(domain.handle(), 0);
}

// A hub heartbeats once a second (DiscoveryRole): the fragment comes last, so it overrides the
// shipped 100 ms, and Cyclone accepts the combination.
TEST(LoopbackConfig, AHubHeartbeatsOnceASecondAndCycloneAcceptsTheFragment) {
  const DomainConfig hub = DomainConfig::forRun("hub-config-test");
  EXPECT_EQ(hub.cyclone_config, loopbackConfigXml() + "," + hubConfigXml());
  EXPECT_NE(hubConfigXml().find(R"(<HeartbeatInterval max="1 s">1 s</HeartbeatInterval>)"),
            std::string::npos);
  EXPECT_EQ(hubConfigXml().find("ParticipantIndex"), std::string::npos);  // the shipped auto
  const Domain domain(hub);
  EXPECT_GT(domain.handle(), 0);
}

TEST(Domain, RefusesADomainIdOutsideThePortMapping) {
  EXPECT_THROW(Domain(DomainConfig::loopback(kMaxDomainId + 1, "p")), InputError);
}

TEST(Domain, CreatingTheSameDomainTwiceInOneProcessThrowsNamingTheCall) {
  const DomainConfig config = testing::isolatedDomain();
  Domain first(config);
  try {
    Domain second(config);
    FAIL() << "second domain created";
  } catch (const DdsError& e) {
    EXPECT_EQ(e.call(), "dds_create_domain");
    EXPECT_EQ(e.code(), DDS_RETCODE_PRECONDITION_NOT_MET);
  }
}

// Cyclone's finest trace lists every packet it sends with its destinations
// ("nn_xpack_send ... [ udp/127.0.0.1:7410@1 ... ]"); the trace gives addresses, not names. A child
// process publishes, this process reads over the network, and every destination in the trace must
// be 127.0.0.1.
TEST(LoopbackConfig, CycloneSelectsLoopbackAndSendsOnlyToLoopback) {
  const std::filesystem::path trace =
      std::filesystem::path(::testing::TempDir()) /
      ("sensornet-loopback-trace-" + std::to_string(::getpid()) + ".log");
  DomainConfig config = testing::isolatedDomain();
  const DomainConfig child_config = config;
  config.cyclone_config += ",<Tracing><Verbosity>finest</Verbosity><OutputFile>" + trace.string() +
                           "</OutputFile></Tracing>";
  {
    Domain domain(config);
    Participant participant(domain);
    Topic<sensornet_Scenario> topic(participant);
    Reader<sensornet_Scenario> reader(participant, topic);
    testing::ChildProcess child("PublishScenarioAndSchedules", child_config);
    ASSERT_TRUE(child.waitReady(10s));
    EXPECT_EQ(testing::takeAtLeast(participant, reader, 1, 10s).samples.size(), 1u);
  }
  const std::string log = readFile(trace);
  std::filesystem::remove(trace);
  EXPECT_NE(log.find("selected interfaces: lo "), std::string::npos);
  EXPECT_NE(log.find("ownip: udp/127.0.0.1"), std::string::npos);

  std::istringstream lines(log);
  std::string line;
  std::size_t sends = 0;
  std::set<std::string> addresses;
  while (std::getline(lines, line)) {
    if (line.find("nn_xpack_send") == std::string::npos) continue;
    ++sends;
    for (const std::string& address : sendDestinations(line)) addresses.insert(address);
  }
  EXPECT_GT(sends, 0u);
  EXPECT_EQ(addresses, std::set<std::string>{"127.0.0.1"});
}

}  // namespace
}  // namespace sensornet::dds
