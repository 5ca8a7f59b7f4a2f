// Error paths through the C API seam: real Cyclone everywhere except the one call a test
// replaces, so a timeout or a failure is produced on demand and the layer's answer observed.
#include "sensornet/dds/c_api.hpp"

#include <gtest/gtest.h>

#include <stdexcept>
#include <string>

#include "dds_test_support.hpp"
#include "sensornet/dds/dds_error.hpp"
#include "sensornet/dds/participant.hpp"
#include "sensornet/dds/reader.hpp"
#include "sensornet/dds/topics.hpp"
#include "sensornet/dds/wire.hpp"
#include "sensornet/dds/writer.hpp"

namespace sensornet::dds {
namespace {

using namespace std::chrono_literals;

int& flushes() {
  static int count = 0;
  return count;
}

TEST(CApiSeam, WriteThatTimesOutIsATimeoutResult) {
  CApi api = realCApi();
  api.write = [](dds_entity_t, const void*) -> dds_return_t { return DDS_RETCODE_TIMEOUT; };
  Domain domain(testing::isolatedDomain(), api);
  Participant participant(domain);
  Topic<sensornet_Measurement> topic(participant);
  Writer<sensornet_Measurement> writer(participant, topic);
  sensornet_Measurement sample{};
  EXPECT_EQ(writer.write(sample), WriteResult::TimedOut);
}

TEST(CApiSeam, WriteThatFailsThrowsDdsErrorNamingTheCallAndCode) {
  CApi api = realCApi();
  api.write = [](dds_entity_t, const void*) -> dds_return_t {
    return DDS_RETCODE_OUT_OF_RESOURCES;
  };
  Domain domain(testing::isolatedDomain(), api);
  Participant participant(domain);
  Topic<sensornet_Measurement> topic(participant);
  Writer<sensornet_Measurement> writer(participant, topic);
  sensornet_Measurement sample{};
  try {
    (void)writer.write(sample);
    FAIL() << "no exception";
  } catch (const DdsError& e) {
    EXPECT_EQ(e.call(), "dds_write");
    EXPECT_EQ(e.code(), DDS_RETCODE_OUT_OF_RESOURCES);
    EXPECT_NE(std::string(e.what()).find("dds_write failed: " + returnCodeText(e.code())),
              std::string::npos)
        << e.what();
    EXPECT_NE(std::string(e.what()).find("writer.cpp:"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.where().file_name()).find("writer.cpp"), std::string::npos);
  }
}

TEST(CApiSeam, FailedCreateThrowsDdsErrorNamingTheCall) {
  CApi api = realCApi();
  api.create_writer = [](dds_entity_t, dds_entity_t, const dds_qos_t*,
                         const dds_listener_t*) -> dds_entity_t { return DDS_RETCODE_ERROR; };
  Domain domain(testing::isolatedDomain(), api);
  Participant participant(domain);
  Topic<sensornet_Measurement> topic(participant);
  try {
    Writer<sensornet_Measurement> writer(participant, topic);
    FAIL() << "no exception";
  } catch (const DdsError& e) {
    EXPECT_EQ(e.call(), "dds_create_writer");
    EXPECT_EQ(e.code(), DDS_RETCODE_ERROR);
  }
}

TEST(CApiSeam, RealCycloneRefusalAlsoThrowsDdsError) {
  Domain domain(testing::isolatedDomain());
  Participant participant(domain);
  try {
    Topic<sensornet_Measurement> topic(participant, "not a topic name");
    FAIL() << "no exception";
  } catch (const DdsError& e) {
    EXPECT_EQ(e.call(), "dds_create_topic");
    EXPECT_EQ(e.code(), DDS_RETCODE_BAD_PARAMETER);
  }
}

TEST(CApiSeam, FailedTakeThrowsAndAFailedWaitForAcksIsFalse) {
  CApi api = realCApi();
  api.take = [](dds_entity_t, void**, dds_sample_info_t*, size_t, uint32_t) -> dds_return_t {
    return DDS_RETCODE_ILLEGAL_OPERATION;
  };
  api.wait_for_acks = [](dds_entity_t, dds_duration_t) -> dds_return_t {
    return DDS_RETCODE_TIMEOUT;
  };
  Domain domain(testing::isolatedDomain(), api);
  Participant participant(domain);
  Topic<sensornet_Measurement> topic(participant);
  Reader<sensornet_Measurement> reader(participant, topic);
  Writer<sensornet_Measurement> writer(participant, topic);
  EXPECT_THROW((void)reader.take(), DdsError);
  EXPECT_FALSE(writer.waitForAcks(10ms));
}

// What DomainConfig::write_batching promises, in the calls made: on a batching domain a write
// outside a burst is flushed at once, the writes of a burst once when the outermost burst ends,
// and waitForAcks flushes first; on any other domain nothing is ever flushed.
TEST(CApiSeam, ABatchingDomainFlushesEachWriteOutsideABurstAndABurstOnceAtItsEnd) {
  CApi api = realCApi();
  api.write_flush = [](dds_entity_t writer) {
    ++flushes();
    ::dds_write_flush(writer);
  };
  DomainConfig config = testing::isolatedDomain();
  config.write_batching = true;
  Domain domain(config, api);
  Participant participant(domain);
  Topic<sensornet_Measurement> topic(participant);
  Writer<sensornet_Measurement> writer(participant, topic);
  sensornet_Measurement sample{};
  flushes() = 0;
  ASSERT_EQ(writer.write(sample), WriteResult::Written);
  EXPECT_EQ(flushes(), 1);
  {
    const auto burst = writer.burst();
    for (int i = 0; i < 5; ++i) ASSERT_EQ(writer.write(sample), WriteResult::Written);
    {
      const auto inner = writer.burst();
      ASSERT_EQ(writer.write(sample), WriteResult::Written);
    }
    EXPECT_EQ(flushes(), 1);
  }
  EXPECT_EQ(flushes(), 2);
  {
    const auto burst = writer.burst();
    ASSERT_EQ(writer.write(sample), WriteResult::Written);
    EXPECT_TRUE(writer.waitForAcks(1s));  // no reader: nothing to wait for
    EXPECT_EQ(flushes(), 3);
  }
  EXPECT_EQ(flushes(), 4);
}

TEST(CApiSeam, ADomainWithoutBatchingNeverFlushes) {
  CApi api = realCApi();
  api.write_flush = [](dds_entity_t) { ++flushes(); };
  Domain domain(testing::isolatedDomain(), api);
  Participant participant(domain);
  Topic<sensornet_Measurement> topic(participant);
  Writer<sensornet_Measurement> writer(participant, topic);
  sensornet_Measurement sample{};
  flushes() = 0;
  {
    const auto burst = writer.burst();
    ASSERT_EQ(writer.write(sample), WriteResult::Written);
  }
  ASSERT_EQ(writer.write(sample), WriteResult::Written);
  writer.flush();
  EXPECT_EQ(flushes(), 0);
}

}  // namespace
}  // namespace sensornet::dds
