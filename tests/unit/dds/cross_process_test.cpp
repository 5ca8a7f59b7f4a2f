// Real DDS between two processes over loopback: this test executable is the reader and starts
// itself again as the writer (a DdsChild.DISABLED_ role, see dds_test_support.hpp). Covers what
// in-process delivery cannot: the reliable protocol over UDP, durability for a process that
// joins late, and noticing a process that dies without a goodbye.
#include <gtest/gtest.h>
#include <signal.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <string>
#include <thread>
#include <vector>

#include "dds_test_support.hpp"
#include "sensornet/dds/participant.hpp"
#include "sensornet/dds/reader.hpp"
#include "sensornet/dds/topics.hpp"
#include "sensornet/dds/wire.hpp"
#include "sensornet/dds/writer.hpp"

namespace sensornet::dds {
namespace {

using namespace std::chrono_literals;
using Clock = std::chrono::steady_clock;

const std::string kRun = "run-xp";
const std::string kYaml = "horizon: 3.0\nintervals: 30\n";
constexpr std::uint32_t kVersionsWritten = 20;
constexpr std::uint64_t kStreamLength = 10'000;
constexpr std::uint32_t kStreamSensor = 5;
constexpr std::uint32_t kDoomedSensor = 7;

// The payload of sample `seq` of the stream: checkable without keeping what was sent.
std::vector<double> streamPayload(std::uint64_t seq) {
  const double s = static_cast<double>(seq);
  return {s, -s, s * 0.5, std::sqrt(s), 1.0 / (s + 1.0)};
}

// A child lingers until its parent (the test) kills it, or exits if the parent is gone.
void lingerUntilKilled() {
  const pid_t parent = ::getppid();
  const auto give_up = Clock::now() + 60s;
  while (::getppid() == parent && Clock::now() < give_up) std::this_thread::sleep_for(20ms);
}

// ---- child roles ----------------------------------------------------------------------------

TEST(DdsChild, DISABLED_PublishScenarioAndSchedules) {
  if (!testing::runningAsChild()) GTEST_SKIP() << "runs only as a child of a cross-process test";
  Domain domain(testing::childDomain());
  Participant participant(domain);
  Topic<sensornet_Scenario> scenario_topic(participant);
  Topic<sensornet_Schedule> schedule_topic(participant);
  Writer<sensornet_Scenario> scenario_writer(participant, scenario_topic);
  Writer<sensornet_Schedule> schedule_writer(participant, schedule_topic);

  sensornet_Scenario scenario{};
  scenario.run_id = borrowString(kRun);
  scenario.yaml = borrowString(kYaml);
  scenario.seed = 11;
  ASSERT_EQ(scenario_writer.write(scenario), WriteResult::Written);
  const std::vector<double> rates(6, 0.5);
  for (std::uint32_t v = 1; v <= kVersionsWritten; ++v) {
    sensornet_Schedule schedule{};
    schedule.run_id = borrowString(kRun);
    schedule.version = v;
    borrowSequence(schedule.rates_hz, rates);
    ASSERT_EQ(schedule_writer.write(schedule), WriteResult::Written);
  }
  testing::tellParentReady();
  lingerUntilKilled();  // transient-local data lives as long as its writer
}

TEST(DdsChild, DISABLED_PublishMeasurementStream) {
  if (!testing::runningAsChild()) GTEST_SKIP() << "runs only as a child of a cross-process test";
  Domain domain(testing::childDomain());
  Participant participant(domain);
  Topic<sensornet_Measurement> topic(participant);
  Writer<sensornet_Measurement> writer(participant, topic);
  ASSERT_TRUE(writer.waitForReaders(1, 20s));
  testing::tellParentReady();

  std::uint64_t timeouts = 0;
  for (std::uint64_t seq = 0; seq < kStreamLength; ++seq) {
    const std::vector<double> z = streamPayload(seq);
    sensornet_Measurement m{};
    m.sensor_id = kStreamSensor;
    m.run_id = borrowString(kRun);
    m.seq = seq;
    m.emulated_time_s = 1e-3 * static_cast<double>(seq);
    borrowSequence(m.z, z);
    while (writer.write(m) == WriteResult::TimedOut) {
      ASSERT_LT(++timeouts, 1000u) << "reader stopped acknowledging";
    }
  }
  ASSERT_TRUE(writer.waitForAcks(30s));
  std::fprintf(stderr, "stream child: %llu write timeouts (retried)\n",
               static_cast<unsigned long long>(timeouts));
}

TEST(DdsChild, DISABLED_PublishOneMeasurementThenHang) {
  if (!testing::runningAsChild()) GTEST_SKIP() << "runs only as a child of a cross-process test";
  Domain domain(testing::childDomain());
  Participant participant(domain);
  Topic<sensornet_Measurement> topic(participant);
  Writer<sensornet_Measurement> writer(participant, topic);
  ASSERT_TRUE(writer.waitForReaders(1, 20s));
  sensornet_Measurement m{};
  m.sensor_id = kDoomedSensor;
  m.run_id = borrowString(kRun);
  ASSERT_EQ(writer.write(m), WriteResult::Written);
  ASSERT_TRUE(writer.waitForAcks(10s));
  testing::tellParentReady();
  lingerUntilKilled();
}

constexpr std::uint64_t kBurstLength = 40;
constexpr std::uint32_t kBurstSensor = 9;
constexpr auto kBurstHeld = 1500ms;

sensornet_Measurement burstSample(std::uint64_t seq) {
  sensornet_Measurement m{};
  m.sensor_id = kBurstSensor;
  m.run_id = borrowString(kRun);
  m.seq = seq;
  return m;
}

// On a batching domain: kBurstLength writes in one burst held open for kBurstHeld after the
// parent is told, then one write outside any burst; never waits for acknowledgements (which
// would send what is held).
TEST(DdsChild, DISABLED_PublishABurstOnABatchingDomain) {
  if (!testing::runningAsChild()) GTEST_SKIP() << "runs only as a child of a cross-process test";
  DomainConfig config = testing::childDomain();
  config.write_batching = true;
  Domain domain(config);
  Participant participant(domain);
  Topic<sensornet_Measurement> topic(participant);
  Writer<sensornet_Measurement> writer(participant, topic);
  ASSERT_TRUE(writer.waitForReaders(1, 20s));
  {
    const auto burst = writer.burst();
    for (std::uint64_t seq = 0; seq < kBurstLength; ++seq) {
      ASSERT_EQ(writer.write(burstSample(seq)), WriteResult::Written);
    }
    testing::tellParentReady();
    std::this_thread::sleep_for(kBurstHeld);
  }
  ASSERT_EQ(writer.write(burstSample(kBurstLength)), WriteResult::Written);
  lingerUntilKilled();
}

// ---- the tests ------------------------------------------------------------------------------

TEST(CrossProcess, LateJoiningProcessGetsScenarioAndTheKeptScheduleVersions) {
  const DomainConfig config = testing::isolatedDomain();
  testing::ChildProcess child("PublishScenarioAndSchedules", config);
  ASSERT_TRUE(child.waitReady(20s));  // everything is written before this process joins

  Domain domain(config);
  Participant participant(domain);
  Topic<sensornet_Scenario> scenario_topic(participant);
  Topic<sensornet_Schedule> schedule_topic(participant);
  Reader<sensornet_Scenario> scenarios(participant, scenario_topic);
  Reader<sensornet_Schedule> schedules(participant, schedule_topic);

  const auto scenario = testing::takeAtLeast(participant, scenarios, 1, 10s);
  ASSERT_EQ(scenario.samples.size(), 1u);
  EXPECT_EQ(viewString(scenario.samples[0].sample->yaml), kYaml);
  EXPECT_EQ(scenario.samples[0].sample->seed, 11u);

  const auto batch = testing::takeAtLeast(participant, schedules, kScheduleVersionsKept, 10s);
  ASSERT_EQ(batch.samples.size(), static_cast<std::size_t>(kScheduleVersionsKept));
  for (std::size_t i = 0; i < batch.samples.size(); ++i) {
    EXPECT_EQ(batch.samples[i].sample->version,
              kVersionsWritten - static_cast<std::uint32_t>(kScheduleVersionsKept) + 1 + i);
    EXPECT_EQ(toVector(batch.samples[i].sample->rates_hz), std::vector<double>(6, 0.5));
  }
}

TEST(CrossProcess, ReliableKeepAllStreamArrivesCompleteAndInOrder) {
  const DomainConfig config = testing::isolatedDomain();
  Domain domain(config);
  Participant participant(domain);
  Topic<sensornet_Measurement> topic(participant);
  Reader<sensornet_Measurement> reader(participant, topic);
  testing::ChildProcess child("PublishMeasurementStream", config);
  ASSERT_TRUE(child.waitReady(20s));

  const auto start = Clock::now();
  const auto batch = testing::takeAtLeast(participant, reader, kStreamLength, 60s);
  const auto elapsed = std::chrono::duration<double>(Clock::now() - start).count();
  ASSERT_EQ(batch.samples.size(), kStreamLength);
  std::uint64_t mismatched_payloads = 0;
  for (std::uint64_t i = 0; i < kStreamLength; ++i) {
    const sensornet_Measurement& m = *batch.samples[i].sample;
    ASSERT_EQ(m.seq, i) << "lost or reordered at position " << i;
    ASSERT_EQ(m.sensor_id, kStreamSensor);
    if (toVector(m.z) != streamPayload(i)) ++mismatched_payloads;
  }
  EXPECT_EQ(mismatched_payloads, 0u);
  std::printf("[ measured ] %llu samples in %.3f s (%.0f samples/s)\n",
              static_cast<unsigned long long>(kStreamLength), elapsed,
              static_cast<double>(kStreamLength) / elapsed);
  EXPECT_EQ(child.waitExit(30s), 0);
  // The writer left with its process (no autodispose): its instance has no writers now. The child
  // exits once everything is acknowledged, which can be before the last take here; then the taken
  // samples carry the state and no separate change follows (see reader.hpp).
  const bool gone_before_last_take =
      batch.samples.back().info.instance_state == InstanceState::NoWriters;
  EXPECT_TRUE(gone_before_last_take ||
              testing::waitForInstanceState(
                  participant, reader, InstanceState::NoWriters,
                  [](const sensornet_Measurement& key) { return key.sensor_id == kStreamSensor; },
                  5s));
}

// DomainConfig::write_batching: a burst's writes stay in the writer's packet until the burst
// ends (all but what a piggybacked heartbeat sends early), then all arrive, in order, with the
// write after it.
TEST(CrossProcess, ABurstOnABatchingDomainIsHeldUntilItEndsThenArrivesWholeAndInOrder) {
  const DomainConfig config = testing::isolatedDomain();
  Domain domain(config);
  Participant participant(domain);
  Topic<sensornet_Measurement> topic(participant);
  Reader<sensornet_Measurement> reader(participant, topic);
  testing::ChildProcess child("PublishABurstOnABatchingDomain", config);
  ASSERT_TRUE(child.waitReady(20s));
  const auto ready = Clock::now();

  // Cyclone sends the packet early when a heartbeat it piggybacks asks for an answer (the
  // first write of a writer does): a sample or two may come before the burst ends, not all.
  const auto held = testing::takeAtLeast(participant, reader, kBurstLength, kBurstHeld / 2);
  const auto held_for = Clock::now() - ready;
  EXPECT_LE(held.samples.size(), 2u);
  const auto rest =
      testing::takeAtLeast(participant, reader, kBurstLength + 1 - held.samples.size(), 10s);
  ASSERT_EQ(held.samples.size() + rest.samples.size(), kBurstLength + 1);
  for (std::uint64_t i = 0; i <= kBurstLength; ++i) {
    const std::size_t held_count = held.samples.size();
    const auto& sample = i < held_count ? held.samples[i] : rest.samples[i - held_count];
    EXPECT_EQ(sample.sample->seq, i);
  }
  std::printf("[ measured ] %zu of %llu samples of the burst arrived while it was open (%.3f s)\n",
              held.samples.size(), static_cast<unsigned long long>(kBurstLength),
              std::chrono::duration<double>(held_for).count());
}

TEST(CrossProcess, KilledWritersInstanceGoesNoWritersWithinTheLivelinessLease) {
  const DomainConfig config = testing::isolatedDomain();
  Domain domain(config);
  Participant participant(domain);
  Topic<sensornet_Measurement> topic(participant);
  Reader<sensornet_Measurement> reader(participant, topic);
  testing::ChildProcess child("PublishOneMeasurementThenHang", config);
  ASSERT_TRUE(child.waitReady(20s));
  ASSERT_EQ(testing::takeAtLeast(participant, reader, 1, 10s).samples.size(), 1u);

  child.kill(SIGKILL);  // no goodbye: only the lease can tell
  const auto killed = Clock::now();
  ASSERT_EQ(child.waitExit(5s), 128 + SIGKILL);
  // The lease is 1 s; allow one more for the lease check and delivery on a loaded machine, still
  // under the 2 s participant lease of the configuration.
  const bool noticed = testing::waitForInstanceState(
      participant, reader, InstanceState::NoWriters,
      [](const sensornet_Measurement& key) { return key.sensor_id == kDoomedSensor; }, 10s);
  const auto after = std::chrono::duration<double>(Clock::now() - killed).count();
  EXPECT_TRUE(noticed);
  std::printf("[ measured ] killed writer noticed after %.3f s (lease %.1f s)\n", after,
              std::chrono::duration<double>(kSensorLivelinessLease).count());
  EXPECT_LT(after, 2.0);
}

}  // namespace
}  // namespace sensornet::dds
