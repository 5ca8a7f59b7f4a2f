// Which participants an endpoint matched, against the participants' own GUIDs (dds_get_guid):
// the coordinator counts the fusion center present only when one participant matched its
// EpisodeControl writer with a reader and its Report reader with a writer.
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cstring>
#include <optional>
#include <thread>
#include <vector>

#include "dds_test_support.hpp"
#include "sensornet/dds/matched_endpoints.hpp"
#include "sensornet/dds/participant.hpp"
#include "sensornet/dds/reader.hpp"
#include "sensornet/dds/topics.hpp"
#include "sensornet/dds/writer.hpp"

namespace sensornet::dds {
namespace {

using namespace std::chrono_literals;

ParticipantKey keyOf(const Participant& participant) {
  dds_guid_t guid{};
  EXPECT_EQ(dds_get_guid(participant.handle(), &guid), DDS_RETCODE_OK);
  ParticipantKey key{};
  std::memcpy(key.data(), guid.v, key.size());
  return key;
}

std::vector<ParticipantKey> sorted(std::vector<ParticipantKey> keys) {
  std::sort(keys.begin(), keys.end());
  return keys;
}

class MatchedEndpoints : public ::testing::Test {
 protected:
  Domain domain_{testing::isolatedDomain()};
  Participant coordinator_{domain_};
  Participant fusion_center_{domain_};
  Participant sensor_{domain_};
};

TEST_F(MatchedEndpoints, AWriterNamesTheParticipantOfEachMatchedReaderOnce) {
  Topic<sensornet_EpisodeControl> at_coordinator(coordinator_);
  Writer<sensornet_EpisodeControl> control(coordinator_, at_coordinator);
  EXPECT_TRUE(participantsOfMatchedReaders(control).empty());

  Topic<sensornet_EpisodeControl> at_fusion(fusion_center_);
  Topic<sensornet_EpisodeControl> at_sensor(sensor_);
  Reader<sensornet_EpisodeControl> fusion_reader(fusion_center_, at_fusion);
  Reader<sensornet_EpisodeControl> sensor_reader(sensor_, at_sensor);
  Reader<sensornet_EpisodeControl> second_sensor_reader(sensor_, at_sensor);
  ASSERT_TRUE(control.waitForReaders(3, 5s));

  EXPECT_EQ(participantsOfMatchedReaders(control),
            sorted({keyOf(fusion_center_), keyOf(sensor_)}));
}

TEST_F(MatchedEndpoints, AReaderNamesTheParticipantsOfItsMatchedWritersAndForgetsOneThatLeft) {
  Topic<sensornet_Report> at_coordinator(coordinator_);
  Reader<sensornet_Report> reports(coordinator_, at_coordinator);
  Topic<sensornet_Report> at_fusion(fusion_center_);
  Writer<sensornet_Report> fusion_writer(fusion_center_, at_fusion, reportWriterQos());
  {
    Topic<sensornet_Report> at_sensor(sensor_);
    Writer<sensornet_Report> other_writer(sensor_, at_sensor, reportWriterQos());
    ASSERT_TRUE(reports.waitForWriters(2, 5s));
    EXPECT_EQ(participantsOfMatchedWriters(reports),
              sorted({keyOf(fusion_center_), keyOf(sensor_)}));
  }
  const auto deadline = std::chrono::steady_clock::now() + 5s;
  while (reports.matchedWriters() > 1 && std::chrono::steady_clock::now() < deadline) {
    std::this_thread::sleep_for(10ms);
  }
  EXPECT_EQ(participantsOfMatchedWriters(reports), std::vector{keyOf(fusion_center_)});
}

TEST_F(MatchedEndpoints, PresenceNeedsOneParticipantOnBothTopicsNotTwoThatEachHaveOne) {
  Topic<sensornet_EpisodeControl> control_topic(coordinator_);
  Writer<sensornet_EpisodeControl> control(coordinator_, control_topic);
  Topic<sensornet_Report> report_topic(coordinator_);
  Reader<sensornet_Report> reports(coordinator_, report_topic);

  // The sensor reads controls; the fusion center writes reports but reads no control yet.
  Topic<sensornet_EpisodeControl> sensor_control(sensor_);
  Reader<sensornet_EpisodeControl> sensor_reader(sensor_, sensor_control);
  Topic<sensornet_Report> fusion_reports(fusion_center_);
  Writer<sensornet_Report> fusion_writer(fusion_center_, fusion_reports, reportWriterQos());
  ASSERT_TRUE(control.waitForReaders(1, 5s));
  ASSERT_TRUE(reports.waitForWriters(1, 5s));
  EXPECT_FALSE(sharesParticipant(
      {participantsOfMatchedReaders(control), participantsOfMatchedWriters(reports)}));

  Topic<sensornet_EpisodeControl> fusion_control(fusion_center_);
  Reader<sensornet_EpisodeControl> fusion_reader(fusion_center_, fusion_control);
  ASSERT_TRUE(control.waitForReaders(2, 5s));
  EXPECT_TRUE(sharesParticipant(
      {participantsOfMatchedReaders(control), participantsOfMatchedWriters(reports)}));
}

TEST(SharesParticipant, IsTheNonEmptyIntersectionOfEverySet) {
  const ParticipantKey a{1};
  const ParticipantKey b{2};
  const ParticipantKey c{3};
  EXPECT_FALSE(sharesParticipant({}));
  EXPECT_FALSE(sharesParticipant({{}}));
  EXPECT_TRUE(sharesParticipant({{a}}));
  EXPECT_TRUE(sharesParticipant({{a, b}, {b, c}, {b}}));
  EXPECT_FALSE(sharesParticipant({{a, b}, {b, c}, {a, c}}));  // each pair shares, all three not
  EXPECT_FALSE(sharesParticipant({{a, b, c}, {}}));
}

}  // namespace
}  // namespace sensornet::dds
