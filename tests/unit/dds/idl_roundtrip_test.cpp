// Every IDL type survives a write and a take through real Cyclone DDS (serialized and
// deserialized by the idlc-generated descriptors, with the topic's catalogue QoS on both
// sides): each field read back equals the field written, bit for bit.
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>
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

// Writes `sample` from one participant and takes it at another one of the same domain.
template <class T>
OwnedSample<T> roundTrip(const T& sample) {
  Domain domain(testing::isolatedDomain());
  Participant writer_side(domain);
  Participant reader_side(domain);
  Topic<T> writer_topic(writer_side);
  Topic<T> reader_topic(reader_side);
  Reader<T> reader(reader_side, reader_topic);
  Writer<T> writer(writer_side, writer_topic);
  EXPECT_TRUE(writer.waitForReaders(1, 5s));
  EXPECT_EQ(writer.write(sample), WriteResult::Written);
  Batch<T> batch = testing::takeAtLeast(reader_side, reader, 1, 5s);
  if (batch.samples.size() != 1) {
    ADD_FAILURE() << "expected one sample, got " << batch.samples.size();
    return OwnedSample<T>();
  }
  return std::move(batch.samples.front().sample);
}

std::vector<double> ramp(std::size_t n, double start, double step) {
  std::vector<double> values(n);
  for (std::size_t i = 0; i < n; ++i) values[i] = start + step * static_cast<double>(i);
  return values;
}

template <class Seq, class V>
void expectSequence(const Seq& field, const std::vector<V>& expected) {
  EXPECT_EQ(toVector(field), expected);
}

TEST(IdlRoundTrip, ScenarioKeepsEveryField) {
  const std::string run = "run-7";
  const std::string digest = "9f86d081884c7d659a2feaa0c55ad015a3bf4f1b2b0b822cd15d6c15b0f00a08";
  std::string yaml = "horizon: 3.0\nintervals: 30\n# λ and ∫ survive as UTF-8\n";
  yaml += std::string(20000, 'x');  // larger than one UDP fragment
  sensornet_Scenario s{};
  s.run_id = borrowString(run);
  s.digest = borrowString(digest);
  s.yaml = borrowString(yaml);
  s.horizon_s = 3.25;
  s.intervals = 30;
  s.sensor_count = 12;
  s.state_dim = 5;
  s.seed = 0xfedcba9876543210ULL;

  const OwnedSample<sensornet_Scenario> got = roundTrip(s);
  EXPECT_EQ(viewString(got->run_id), run);
  EXPECT_EQ(viewString(got->digest), digest);
  EXPECT_EQ(viewString(got->yaml), yaml);
  EXPECT_EQ(got->horizon_s, 3.25);
  EXPECT_EQ(got->intervals, 30u);
  EXPECT_EQ(got->sensor_count, 12u);
  EXPECT_EQ(got->state_dim, 5u);
  EXPECT_EQ(got->seed, 0xfedcba9876543210ULL);
}

TEST(IdlRoundTrip, ScheduleKeepsEveryField) {
  const std::string run = "run-7", digest = "abc", surrogate = "info";
  const std::vector<double> rates = ramp(30 * 12, 0.125, 1.0 / 3.0);
  sensornet_Schedule s{};
  s.run_id = borrowString(run);
  s.version = 4;
  s.scenario_digest = borrowString(digest);
  s.effective_episode = 17;
  s.effective_time_s = 1.4999999999999998;
  s.horizon_s = 3.0;
  s.intervals = 30;
  s.sensor_count = 12;
  borrowSequence(s.rates_hz, rates);
  s.surrogate = borrowString(surrogate);
  s.bracket_lower = 0.1234567890123;
  s.bracket_upper = std::numeric_limits<double>::max();
  s.command_id = 99;
  s.issued_wall_time_ns = -5;

  const OwnedSample<sensornet_Schedule> got = roundTrip(s);
  EXPECT_EQ(viewString(got->run_id), run);
  EXPECT_EQ(got->version, 4u);
  EXPECT_EQ(viewString(got->scenario_digest), digest);
  EXPECT_EQ(got->effective_episode, 17u);
  EXPECT_EQ(got->effective_time_s, 1.4999999999999998);
  EXPECT_EQ(got->horizon_s, 3.0);
  EXPECT_EQ(got->intervals, 30u);
  EXPECT_EQ(got->sensor_count, 12u);
  expectSequence(got->rates_hz, rates);
  EXPECT_EQ(viewString(got->surrogate), surrogate);
  EXPECT_EQ(got->bracket_lower, 0.1234567890123);
  EXPECT_EQ(got->bracket_upper, std::numeric_limits<double>::max());
  EXPECT_EQ(got->command_id, 99u);
  EXPECT_EQ(got->issued_wall_time_ns, -5);
}

TEST(IdlRoundTrip, EpisodeControlKeepsEveryField) {
  const std::string run = "run-7";
  sensornet_EpisodeControl s{};
  s.run_id = borrowString(run);
  s.episode = 3;
  s.command = sensornet_RUN_SHUTDOWN;
  s.start_wall_time_ns = 1'700'000'000'123'456'789LL;
  s.time_scale = 12.5;
  s.seed = 42;
  s.schedule_version = 2;
  s.episodes_planned = 20;
  s.aborted = true;
  const std::string detail = "no report of episode 3";
  s.detail = borrowString(detail);

  const OwnedSample<sensornet_EpisodeControl> got = roundTrip(s);
  EXPECT_EQ(viewString(got->run_id), run);
  EXPECT_EQ(got->episode, 3u);
  EXPECT_EQ(got->command, sensornet_RUN_SHUTDOWN);
  EXPECT_EQ(got->start_wall_time_ns, 1'700'000'000'123'456'789LL);
  EXPECT_EQ(got->time_scale, 12.5);
  EXPECT_EQ(got->seed, 42u);
  EXPECT_EQ(got->schedule_version, 2u);
  EXPECT_EQ(got->episodes_planned, 20u);
  EXPECT_TRUE(got->aborted);
  EXPECT_EQ(viewString(got->detail), detail);
}

TEST(IdlRoundTrip, MeasurementKeepsEveryField) {
  const std::string run = "run-7";
  const std::vector<double> z = {-1.5, 0.0, 2.25e-300, 7.0, -0.0};
  sensornet_Measurement s{};
  s.sensor_id = 29;
  s.run_id = borrowString(run);
  s.episode = 1000;
  s.seq = 123456789012ULL;
  s.emulated_time_s = 2.999;
  s.schedule_version = 3;
  s.publish_wall_time_ns = 1'700'000'000'000'000'001LL;
  borrowSequence(s.z, z);

  const OwnedSample<sensornet_Measurement> got = roundTrip(s);
  EXPECT_EQ(got->sensor_id, 29u);
  EXPECT_EQ(viewString(got->run_id), run);
  EXPECT_EQ(got->episode, 1000u);
  EXPECT_EQ(got->seq, 123456789012ULL);
  EXPECT_EQ(got->emulated_time_s, 2.999);
  EXPECT_EQ(got->schedule_version, 3u);
  EXPECT_EQ(got->publish_wall_time_ns, 1'700'000'000'000'000'001LL);
  expectSequence(got->z, z);
  EXPECT_TRUE(std::signbit(viewSequence(got->z)[4]));  // -0.0 stays negative
}

TEST(IdlRoundTrip, SensorStatusKeepsEveryField) {
  const std::string run = "run-7", detail = "no schedule after 5 s";
  sensornet_SensorStatus s{};
  s.sensor_id = 4;
  s.run_id = borrowString(run);
  s.state = sensornet_SENSOR_FAILED;
  s.episode = 8;
  s.schedule_version = 2;
  s.current_rate_hz = 0.75;
  s.sent_in_episode = 11;
  s.sent_total = 1234;
  s.write_timeouts = 3;
  s.process_id = 31337;
  s.wall_time_ns = 99;
  s.detail = borrowString(detail);

  const OwnedSample<sensornet_SensorStatus> got = roundTrip(s);
  EXPECT_EQ(got->sensor_id, 4u);
  EXPECT_EQ(viewString(got->run_id), run);
  EXPECT_EQ(got->state, sensornet_SENSOR_FAILED);
  EXPECT_EQ(got->episode, 8u);
  EXPECT_EQ(got->schedule_version, 2u);
  EXPECT_EQ(got->current_rate_hz, 0.75);
  EXPECT_EQ(got->sent_in_episode, 11u);
  EXPECT_EQ(got->sent_total, 1234u);
  EXPECT_EQ(got->write_timeouts, 3u);
  EXPECT_EQ(got->process_id, 31337);
  EXPECT_EQ(got->wall_time_ns, 99);
  EXPECT_EQ(viewString(got->detail), detail);
}

TEST(IdlRoundTrip, ReportKeepsEveryFieldIncludingNestedOnes) {
  const std::string run = "run-7";
  const std::vector<std::uint32_t> versions = {1, 2, 5};
  std::vector<sensornet_SensorCounts> counts(3);
  for (std::uint32_t j = 0; j < 3; ++j) {
    counts[j] = sensornet_SensorCounts{j, 100u + j, 99.5 + j, j, 2u * j, 100u + 2u * j + 3u, 3u};
  }
  sensornet_Report s{};
  s.run_id = borrowString(run);
  s.episode = 6;
  s.realized_cost = 1.25;
  s.bracket_lower = 1.0;
  s.bracket_upper = 1.5;
  borrowSequence(s.schedule_versions, versions);
  s.nees = 0.98;
  borrowSequence(s.counts, counts);
  s.latency_median_s = 0.0003;
  s.latency_p99_s = 0.002;
  s.summary = sensornet_RunSummary{7,    1.2,  1.1, 1.3, 1.0, 1.5,  true, 1.01, 700,  2,
                                   0.0004, 0.003, 6, 711, 9,  1.25, 0.9, 1.4,  false};
  s.complete = true;

  const OwnedSample<sensornet_Report> got = roundTrip(s);
  EXPECT_EQ(viewString(got->run_id), run);
  EXPECT_EQ(got->episode, 6u);
  EXPECT_EQ(got->realized_cost, 1.25);
  EXPECT_EQ(got->bracket_lower, 1.0);
  EXPECT_EQ(got->bracket_upper, 1.5);
  expectSequence(got->schedule_versions, versions);
  EXPECT_EQ(got->nees, 0.98);
  const auto got_counts = viewSequence(got->counts);
  ASSERT_EQ(got_counts.size(), 3u);
  for (std::uint32_t j = 0; j < 3; ++j) {
    EXPECT_EQ(got_counts[j].sensor_id, j);
    EXPECT_EQ(got_counts[j].received, 100u + j);
    EXPECT_EQ(got_counts[j].expected, 99.5 + j);
    EXPECT_EQ(got_counts[j].lost, j);
    EXPECT_EQ(got_counts[j].late, 2u * j);
    EXPECT_EQ(got_counts[j].sent, 100u + 2u * j + 3u);
    EXPECT_EQ(got_counts[j].dropped_by_network, 3u);
  }
  EXPECT_TRUE(got->complete);
  EXPECT_EQ(got->summary.episodes_complete, 6u);
  EXPECT_EQ(got->summary.sent, 711u);
  EXPECT_EQ(got->summary.dropped_by_network, 9u);
  EXPECT_EQ(got->summary.realtime_mean, 1.25);
  EXPECT_EQ(got->summary.delivered_lower_mean, 0.9);
  EXPECT_EQ(got->summary.delivered_upper_mean, 1.4);
  EXPECT_FALSE(got->summary.meets_delivered_bracket);
  EXPECT_EQ(got->latency_median_s, 0.0003);
  EXPECT_EQ(got->latency_p99_s, 0.002);
  const sensornet_RunSummary& summary = got->summary;
  EXPECT_EQ(summary.episodes, 7u);
  EXPECT_EQ(summary.realized_mean, 1.2);
  EXPECT_EQ(summary.realized_ci95_low, 1.1);
  EXPECT_EQ(summary.realized_ci95_high, 1.3);
  EXPECT_EQ(summary.bracket_lower_mean, 1.0);
  EXPECT_EQ(summary.bracket_upper_mean, 1.5);
  EXPECT_TRUE(summary.meets_bracket);
  EXPECT_EQ(summary.nees_mean, 1.01);
  EXPECT_EQ(summary.received, 700u);
  EXPECT_EQ(summary.lost, 2u);
  EXPECT_EQ(summary.latency_median_s, 0.0004);
  EXPECT_EQ(summary.latency_p99_s, 0.003);
}

TEST(IdlRoundTrip, CommandKeepsEveryField) {
  const std::string run = "run-7", surrogate = "cov", json = R"({"horizon": 3, "rates": []})",
                    issuer = "sensornet replan (pid 12)";
  const std::vector<std::uint32_t> sensors = {3, 17};
  const std::vector<double> budget = {4.5, 2.0};
  sensornet_Command s{};
  s.run_id = borrowString(run);
  s.command_id = 1'700'000'000'000'000'000ULL;
  s.kind = sensornet_COMMAND_SCHEDULE_FILE;
  s.surrogate = borrowString(surrogate);
  borrowSequence(s.sensor_ids, sensors);
  borrowSequence(s.budget, budget);
  s.schedule_json = borrowString(json);
  s.issuer = borrowString(issuer);
  s.issued_wall_time_ns = 77;

  const OwnedSample<sensornet_Command> got = roundTrip(s);
  EXPECT_EQ(viewString(got->run_id), run);
  EXPECT_EQ(got->command_id, 1'700'000'000'000'000'000ULL);
  EXPECT_EQ(got->kind, sensornet_COMMAND_SCHEDULE_FILE);
  EXPECT_EQ(viewString(got->surrogate), surrogate);
  expectSequence(got->sensor_ids, sensors);
  expectSequence(got->budget, budget);
  EXPECT_EQ(viewString(got->schedule_json), json);
  EXPECT_EQ(viewString(got->issuer), issuer);
  EXPECT_EQ(got->issued_wall_time_ns, 77);
}

TEST(IdlRoundTrip, CommandReplyKeepsEveryField) {
  const std::string run = "run-7", reason = "stale: version 3 < 4";
  sensornet_CommandReply s{};
  s.run_id = borrowString(run);
  s.command_id = 5;
  s.accepted = false;
  s.schedule_version = 0;
  s.reason = borrowString(reason);

  const OwnedSample<sensornet_CommandReply> got = roundTrip(s);
  EXPECT_EQ(viewString(got->run_id), run);
  EXPECT_EQ(got->command_id, 5u);
  EXPECT_FALSE(got->accepted);
  EXPECT_EQ(got->schedule_version, 0u);
  EXPECT_EQ(viewString(got->reason), reason);
}

TEST(IdlRoundTrip, EmptyStringsAndSequencesComeBackEmpty) {
  const std::string empty;
  sensornet_Measurement s{};
  s.sensor_id = 1;
  s.run_id = borrowString(empty);
  const OwnedSample<sensornet_Measurement> got = roundTrip(s);
  EXPECT_EQ(viewString(got->run_id), "");
  EXPECT_TRUE(viewSequence(got->z).empty());
}

}  // namespace
}  // namespace sensornet::dds
