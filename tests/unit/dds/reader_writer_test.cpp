// Typed writers and readers against real Cyclone DDS in one process (participants of one domain
// exchange data through Cyclone's local delivery, serialized as over the network): durability for
// late joiners, isolation by partition and by domain, instance life cycle, read versus take,
// waitsets, and a reliable writer's real timeout.
#include <gtest/gtest.h>

#include <chrono>
#include <span>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "dds_test_support.hpp"
#include "sensornet/core/input_error.hpp"
#include "sensornet/dds/participant.hpp"
#include "sensornet/dds/reader.hpp"
#include "sensornet/dds/topics.hpp"
#include "sensornet/dds/waitset.hpp"
#include "sensornet/dds/wire.hpp"
#include "sensornet/dds/writer.hpp"

namespace sensornet::dds {
namespace {

using namespace std::chrono_literals;
using Clock = std::chrono::steady_clock;

const std::string kRun = "run-test";

sensornet_Schedule scheduleVersion(std::uint32_t version) {
  sensornet_Schedule s{};
  s.run_id = borrowString(kRun);
  s.version = version;
  s.effective_time_s = 0.1 * version;
  return s;
}

sensornet_Measurement measurement(std::uint32_t sensor, std::uint64_t seq) {
  sensornet_Measurement m{};
  m.sensor_id = sensor;
  m.run_id = borrowString(kRun);
  m.seq = seq;
  return m;
}

std::vector<std::uint32_t> versionsOf(const Batch<sensornet_Schedule>& batch) {
  std::vector<std::uint32_t> versions;
  for (const auto& s : batch.samples) versions.push_back(s.sample->version);
  return versions;
}

// A Measurement writer on one participant and a reader on the other, both with the topic's QoS.
struct MeasurementLink {
  MeasurementLink(const Participant& publisher_side, const Participant& subscriber_side)
      : pub_topic(publisher_side),
        sub_topic(subscriber_side),
        reader(subscriber_side, sub_topic),
        writer(publisher_side, pub_topic) {}
  Topic<sensornet_Measurement> pub_topic;
  Topic<sensornet_Measurement> sub_topic;
  Reader<sensornet_Measurement> reader;
  Writer<sensornet_Measurement> writer;
};

class ReaderWriter : public ::testing::Test {
 protected:
  Domain domain_{testing::isolatedDomain()};
  Participant publisher_side_{domain_};
  Participant subscriber_side_{domain_};
};

TEST_F(ReaderWriter, LateJoinerGetsTheScheduleVersionsTheDurabilityServiceKeeps) {
  Topic<sensornet_Schedule> topic(publisher_side_);
  Writer<sensornet_Schedule> writer(publisher_side_, topic);
  for (std::uint32_t v = 1; v <= 20; ++v)
    ASSERT_EQ(writer.write(scheduleVersion(v)), WriteResult::Written);

  Topic<sensornet_Schedule> late_topic(subscriber_side_);
  Reader<sensornet_Schedule> late(subscriber_side_, late_topic);  // created after the writes
  const auto batch = testing::takeAtLeast(subscriber_side_, late, kScheduleVersionsKept, 5s);
  std::vector<std::uint32_t> expected;
  for (std::uint32_t v = 20 - kScheduleVersionsKept + 1; v <= 20; ++v) expected.push_back(v);
  EXPECT_EQ(versionsOf(batch), expected);
}

// Cyclone's rule (issues #146, #1616): late joiners get the durability-service history, whatever
// the writer history keeps.
TEST_F(ReaderWriter, DurabilityServiceDepthNotWriterHistoryBoundsWhatLateJoinersGet) {
  const Qos qos = Qos().reliable().transientLocal().keepLast(16).durabilityService(3);
  Topic<sensornet_Schedule> topic(publisher_side_);
  Writer<sensornet_Schedule> writer(publisher_side_, topic, qos);
  for (std::uint32_t v = 1; v <= 10; ++v)
    ASSERT_EQ(writer.write(scheduleVersion(v)), WriteResult::Written);

  Topic<sensornet_Schedule> late_topic(subscriber_side_);
  Reader<sensornet_Schedule> late(subscriber_side_, late_topic, qos);
  const auto batch = testing::takeAtLeast(subscriber_side_, late, 3, 5s);
  EXPECT_EQ(versionsOf(batch), (std::vector<std::uint32_t>{8, 9, 10}));
  std::this_thread::sleep_for(200ms);
  EXPECT_TRUE(late.take().empty()) << "more history than the durability service keeps";
}

TEST_F(ReaderWriter, DifferentPartitionsDoNotSeeEachOthersData) {
  Topic<sensornet_Measurement> pub_topic(publisher_side_);
  Topic<sensornet_Measurement> sub_topic(subscriber_side_);
  Writer<sensornet_Measurement> writer_a(publisher_side_, pub_topic,
                                         measurementQos().partition("run-a"));
  Reader<sensornet_Measurement> reader_a(subscriber_side_, sub_topic,
                                         measurementQos().partition("run-a"));
  Reader<sensornet_Measurement> reader_b(subscriber_side_, sub_topic,
                                         measurementQos().partition("run-b"));
  ASSERT_TRUE(writer_a.waitForReaders(1, 5s));
  for (std::uint64_t seq = 0; seq < 10; ++seq)
    ASSERT_EQ(writer_a.write(measurement(1, seq)), WriteResult::Written);

  EXPECT_EQ(testing::takeAtLeast(subscriber_side_, reader_a, 10, 5s).samples.size(), 10u);
  // Reader a has everything, so delivery is over; b never matched and holds nothing.
  EXPECT_EQ(writer_a.matchedReaders(), 1u);
  EXPECT_EQ(reader_b.matchedWriters(), 0u);
  EXPECT_TRUE(reader_b.take().empty());
}

TEST_F(ReaderWriter, ParticipantsJoinTheirDomainsPartitionByDefault) {
  Topic<sensornet_Measurement> pub_topic(publisher_side_);
  Topic<sensornet_Measurement> sub_topic(subscriber_side_);
  Writer<sensornet_Measurement> writer(publisher_side_, pub_topic);
  Reader<sensornet_Measurement> same_run(subscriber_side_, sub_topic);
  Reader<sensornet_Measurement> default_partition(subscriber_side_, sub_topic,
                                                  measurementQos().partition(""));
  ASSERT_TRUE(writer.waitForReaders(1, 5s));
  ASSERT_EQ(writer.write(measurement(1, 0)), WriteResult::Written);
  EXPECT_EQ(testing::takeAtLeast(subscriber_side_, same_run, 1, 5s).samples.size(), 1u);
  EXPECT_EQ(default_partition.matchedWriters(), 0u);
  EXPECT_TRUE(default_partition.take().empty());
}

TEST_F(ReaderWriter, InstanceGoesNoWritersWhenTheWritersParticipantIsDeleted) {
  Topic<sensornet_Measurement> sub_topic(subscriber_side_);
  Reader<sensornet_Measurement> reader(subscriber_side_, sub_topic);
  Participant sensor_side(domain_);
  Topic<sensornet_Measurement> pub_topic(sensor_side);
  Writer<sensornet_Measurement> writer(sensor_side, pub_topic);
  ASSERT_TRUE(writer.waitForReaders(1, 5s));
  ASSERT_EQ(writer.write(measurement(7, 0)), WriteResult::Written);
  ASSERT_EQ(testing::takeAtLeast(subscriber_side_, reader, 1, 5s).samples.size(), 1u);

  const auto start = Clock::now();
  sensor_side.close();  // takes its topic and writer with it
  EXPECT_TRUE(testing::waitForInstanceState(
      subscriber_side_, reader, InstanceState::NoWriters,
      [](const sensornet_Measurement& key) { return key.sensor_id == 7; }, kSensorLivelinessLease));
  EXPECT_LT(Clock::now() - start, kSensorLivelinessLease);
}

TEST_F(ReaderWriter, DisposeReachesTheReaderAsAnInstanceChangeWithTheKey) {
  Topic<sensornet_SensorStatus> pub_topic(publisher_side_);
  Topic<sensornet_SensorStatus> sub_topic(subscriber_side_);
  Reader<sensornet_SensorStatus> reader(subscriber_side_, sub_topic);
  Writer<sensornet_SensorStatus> writer(publisher_side_, pub_topic);
  ASSERT_TRUE(writer.waitForReaders(1, 5s));
  sensornet_SensorStatus status{};
  status.sensor_id = 12;
  status.run_id = borrowString(kRun);
  status.state = sensornet_SENSOR_RUNNING;
  ASSERT_EQ(writer.write(status), WriteResult::Written);
  ASSERT_EQ(writer.dispose(status), WriteResult::Written);

  const auto batch = testing::takeAtLeast(subscriber_side_, reader, 1, 5s);
  ASSERT_EQ(batch.samples.size(), 1u);
  EXPECT_EQ(batch.samples[0].sample->state, sensornet_SENSOR_RUNNING);
  // If the disposal arrived before the take, the valid sample carries it (no separate change);
  // otherwise it comes as an instance change that names the key.
  const bool carried = batch.samples[0].info.instance_state == InstanceState::Disposed;
  EXPECT_TRUE(carried || !batch.changes.empty() ||
              testing::waitForInstanceState(
                  subscriber_side_, reader, InstanceState::Disposed,
                  [](const sensornet_SensorStatus& key) { return key.sensor_id == 12; }, 5s));
  for (const auto& change : batch.changes) {
    EXPECT_EQ(change.info.instance_state, InstanceState::Disposed);
    EXPECT_EQ(change.key->sensor_id, 12u);
  }
}

TEST_F(ReaderWriter, ReadLeavesSamplesAndTakeRemovesThem) {
  MeasurementLink link(publisher_side_, subscriber_side_);
  ASSERT_TRUE(link.writer.waitForReaders(1, 5s));
  for (std::uint64_t seq = 0; seq < 3; ++seq)
    ASSERT_EQ(link.writer.write(measurement(2, seq)), WriteResult::Written);

  ReadCondition unread(link.reader);
  WaitSet waitset(subscriber_side_);
  waitset.attach(unread, 5);
  const auto deadline = Clock::now() + 5s;
  std::size_t seen = 0;
  while (seen < 3 && Clock::now() < deadline) {
    seen += link.reader.read(16).samples.size();  // marks them read: `unread` stops triggering
    if (seen < 3) (void)waitset.wait(100ms);
  }
  ASSERT_EQ(seen, 3u);
  EXPECT_TRUE(waitset.wait(0ns).timedOut());
  EXPECT_EQ(link.reader.read(16).samples.size(), 3u);  // still there
  EXPECT_EQ(link.reader.take(16).samples.size(), 3u);
  EXPECT_TRUE(link.reader.take(16).empty());
}

// takeEach with a maximum that grows and shrinks from call to call: each call visits what it
// took, in the order written, and leaves the rest.
TEST_F(ReaderWriter, TakeEachVisitsUpToItsMaximumInOrderWhateverTheMaximum) {
  MeasurementLink link(publisher_side_, subscriber_side_);
  ASSERT_TRUE(link.writer.waitForReaders(1, 5s));
  constexpr std::uint64_t kWritten = 100;
  for (std::uint64_t seq = 0; seq < kWritten; ++seq)
    ASSERT_EQ(link.writer.write(measurement(4, seq)), WriteResult::Written);

  std::vector<std::uint64_t> seqs;
  const auto takeUpTo = [&](std::size_t max) {
    return link.reader.takeEach(
        max, [&](const sensornet_Measurement& m, const SampleInfo&) { seqs.push_back(m.seq); },
        [](const sensornet_Measurement&, const SampleInfo&) {});
  };
  EXPECT_EQ(takeUpTo(40), 40u);  // more than fit on the stack
  EXPECT_EQ(takeUpTo(1), 1u);
  EXPECT_EQ(takeUpTo(32), 32u);  // as many as fit
  EXPECT_EQ(takeUpTo(64), kWritten - 73);
  EXPECT_EQ(takeUpTo(8), 0u);
  ASSERT_EQ(seqs.size(), kWritten);
  for (std::uint64_t i = 0; i < kWritten; ++i) EXPECT_EQ(seqs[i], i);
}

// takeEach refills the samples it keeps: a run id or a z longer, shorter or emptier than the one
// the same slot held before comes out whole, never a stale tail or a stale length.
TEST_F(ReaderWriter, TakeEachRefillsItsSamplesWhateverTheyHeldBefore) {
  MeasurementLink link(publisher_side_, subscriber_side_);
  ASSERT_TRUE(link.writer.waitForReaders(1, 5s));
  const std::vector<std::string> runs = {"short", "a-much-longer-run-identifier-than-before", "",
                                         "mid-length-run", "x"};
  const std::vector<std::vector<double>> zs = {{1.5}, {2.5, -3.0, 4.25, 8.0}, {}, {7.0, 9.0}, {}};
  std::vector<std::string> seen_runs;
  std::vector<std::vector<double>> seen_zs;
  for (std::size_t round = 0; round < runs.size(); ++round) {
    for (std::uint32_t sensor = 0; sensor < 2; ++sensor) {  // two slots filled a call
      const std::size_t k = (round + sensor) % runs.size();
      sensornet_Measurement m = measurement(sensor, round);
      m.run_id = borrowString(runs[k]);
      borrowSequence(m.z, std::span<const double>(zs[k]));
      ASSERT_EQ(link.writer.write(m), WriteResult::Written);
    }
    ASSERT_EQ(link.reader.takeEach(
                  4,
                  [&](const sensornet_Measurement& m, const SampleInfo&) {
                    seen_runs.emplace_back(viewString(m.run_id));
                    const auto z = viewSequence(m.z);
                    seen_zs.emplace_back(z.begin(), z.end());
                  },
                  [](const sensornet_Measurement&, const SampleInfo&) {}),
              2u);
  }
  ASSERT_EQ(seen_runs.size(), 2 * runs.size());
  for (std::size_t round = 0; round < runs.size(); ++round) {
    for (std::size_t sensor = 0; sensor < 2; ++sensor) {
      const std::size_t k = (round + sensor) % runs.size();
      EXPECT_EQ(seen_runs[2 * round + sensor], runs[k]) << "round " << round;
      EXPECT_EQ(seen_zs[2 * round + sensor], zs[k]) << "round " << round;
    }
  }
}

// A visitor that throws loses only the sample it was given: the next call visits the rest.
TEST_F(ReaderWriter, TakeEachGoesOnAfterAVisitorThrows) {
  MeasurementLink link(publisher_side_, subscriber_side_);
  ASSERT_TRUE(link.writer.waitForReaders(1, 5s));
  for (std::uint64_t seq = 0; seq < 3; ++seq)
    ASSERT_EQ(link.writer.write(measurement(1, seq)), WriteResult::Written);
  const auto no_change = [](const sensornet_Measurement&, const SampleInfo&) {};
  EXPECT_THROW(link.reader.takeEach(
                   1,
                   [](const sensornet_Measurement&, const SampleInfo&) {
                     throw std::runtime_error("visitor failed");
                   },
                   no_change),
               std::runtime_error);
  std::vector<std::uint64_t> seqs;
  EXPECT_EQ(link.reader.takeEach(
                8, [&](const sensornet_Measurement& m, const SampleInfo&) { seqs.push_back(m.seq); },
                no_change),
            2u);
  EXPECT_EQ(seqs, (std::vector<std::uint64_t>{1, 2}));
  EXPECT_EQ(link.reader.takeEach(8, [&](const sensornet_Measurement&, const SampleInfo&) {}, no_change),
            0u);
}

TEST_F(ReaderWriter, ReliableKeepAllWriterTimesOutWhenAReaderStopsTaking) {
  // A reader that holds at most 5 samples and never takes: once it is full, the reliable writer
  // cannot deliver, blocks for max_blocking_time and reports a timeout.
  const Qos writer_qos = Qos().reliable(20ms).keepAll();
  const Qos reader_qos = Qos().reliable().keepAll().resourceLimits(5, DDS_LENGTH_UNLIMITED, 5);
  Topic<sensornet_Measurement> pub_topic(publisher_side_);
  Topic<sensornet_Measurement> sub_topic(subscriber_side_);
  Reader<sensornet_Measurement> reader(subscriber_side_, sub_topic, reader_qos);
  Writer<sensornet_Measurement> writer(publisher_side_, pub_topic, writer_qos);
  ASSERT_TRUE(writer.waitForReaders(1, 5s));
  std::uint64_t written = 0;
  WriteResult result = WriteResult::Written;
  while (written < 10'000 &&
         (result = writer.write(measurement(3, written))) == WriteResult::Written) {
    ++written;
  }
  EXPECT_EQ(result, WriteResult::TimedOut);
  EXPECT_GE(written, 5u);
  EXPECT_EQ(reader.take(16).samples.size(), 5u);
}

TEST(WaitSet, TimesOutWhenNothingHappens) {
  Domain domain(testing::isolatedDomain());
  Participant participant(domain);
  WaitSet waitset(participant);
  const auto start = Clock::now();
  const WaitResult result = waitset.wait(50ms);
  EXPECT_TRUE(result.timedOut());
  EXPECT_GE(Clock::now() - start, 50ms);
}

TEST(WaitSet, WakeFromAnotherThreadEndsTheWait) {
  Domain domain(testing::isolatedDomain());
  Participant participant(domain);
  WaitSet waitset(participant);
  const auto start = Clock::now();
  std::thread waker([&] {
    std::this_thread::sleep_for(50ms);
    waitset.wake();
  });
  const WaitResult result = waitset.wait(30s);
  waker.join();
  EXPECT_TRUE(result.woken);
  EXPECT_TRUE(result.tokens.empty());
  EXPECT_LT(Clock::now() - start, 10s);
  EXPECT_TRUE(waitset.wait(0ns).timedOut());  // the wake was consumed
}

TEST(WaitSet, RefusesTheReservedWakeToken) {
  Domain domain(testing::isolatedDomain());
  Participant participant(domain);
  Topic<sensornet_Measurement> topic(participant);
  Reader<sensornet_Measurement> reader(participant, topic);
  ReadCondition condition(reader);
  WaitSet waitset(participant);
  EXPECT_THROW(waitset.attach(condition, WaitSet::kWakeToken), InputError);
}

TEST(DomainIsolation, DifferentDomainsDoNotSeeEachOther) {
  DomainConfig config_a = testing::isolatedDomain();
  DomainConfig config_b = config_a;
  config_b.domain_id = config_a.domain_id == kMaxDomainId ? 1 : config_a.domain_id + 1;
  Domain domain_a(config_a);
  Domain domain_b(config_b);
  Participant pa(domain_a), pb(domain_b), pa_reader(domain_a);
  Topic<sensornet_Measurement> ta(pa), tb(pb), ta_reader(pa_reader);
  Writer<sensornet_Measurement> writer(pa, ta);
  Reader<sensornet_Measurement> same_domain(pa_reader, ta_reader);
  Reader<sensornet_Measurement> other_domain(pb, tb);
  ASSERT_TRUE(writer.waitForReaders(1, 5s));
  ASSERT_EQ(writer.write(measurement(1, 0)), WriteResult::Written);
  EXPECT_EQ(testing::takeAtLeast(pa_reader, same_domain, 1, 5s).samples.size(), 1u);
  EXPECT_FALSE(other_domain.waitForWriters(1, 300ms));
  EXPECT_TRUE(other_domain.take().empty());
}

}  // namespace
}  // namespace sensornet::dds
