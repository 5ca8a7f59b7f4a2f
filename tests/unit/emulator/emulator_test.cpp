// The emulator's shared pieces, without DDS: schedule versions, sensor ids, the sensors'
// arrival timelines, the fusion of one episode in timestamp order, and the run summary. Each is
// checked against a direct computation with the math core (the CD-KF run in order by hand,
// Poisson expectations, sample statistics computed here).

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <set>

#include "sensornet/core/cdkf.hpp"
#include "sensornet/core/input_error.hpp"
#include "sensornet/core/network_spec.hpp"
#include "sensornet/core/surrogate.hpp"
#include "sensornet/emulator/episode_fusion.hpp"
#include "sensornet/emulator/run_report.hpp"
#include "sensornet/emulator/schedule_book.hpp"
#include "sensornet/emulator/sensor_ids.hpp"
#include "sensornet/emulator/sensor_timeline.hpp"

#include "emulator_test_support.hpp"

namespace sensornet::emulator {
namespace {

using test::smallScenario;
using test::versionOf;

// Sensor 0 taken out of service: the other three share the budget.
RateSchedule withoutSensorZero(const Scenario& s) {
  Eigen::MatrixXd rates = uniformSchedule(s).rates();
  rates.col(0).setZero();
  rates *= 4.0 / 3.0;
  return RateSchedule(s.horizon_s, rates);
}

TEST(ScheduleBook, KeepsVersionsInOrderAndSplitsTheEpisodeOfASwitch) {
  const Scenario s = smallScenario();
  ScheduleBook book;
  EXPECT_EQ(book.add(versionOf(1, uniformSchedule(s))), ScheduleBook::Outcome::Accepted);
  EXPECT_EQ(book.add(versionOf(3, withoutSensorZero(s), 2, 1.25)), ScheduleBook::Outcome::Accepted);
  EXPECT_EQ(book.add(versionOf(2, uniformSchedule(s), 5, 0.0)), ScheduleBook::Outcome::Stale);
  EXPECT_EQ(book.add(versionOf(3, uniformSchedule(s), 5, 0.0)), ScheduleBook::Outcome::Stale);
  EXPECT_EQ(book.inForce(2, 1.0)->version, 1u);
  EXPECT_EQ(book.inForce(2, 1.25)->version, 3u);
  EXPECT_EQ(book.inForce(3, 0.0)->version, 3u);

  const auto before = book.segments(1, s.horizon_s);
  ASSERT_EQ(before.size(), 1u);
  EXPECT_EQ(before[0].version->version, 1u);
  const auto during = book.segments(2, s.horizon_s);
  ASSERT_EQ(during.size(), 2u);
  EXPECT_EQ(during[0].to_s, 1.25);
  EXPECT_EQ(during[1].from_s, 1.25);
  EXPECT_EQ(during[1].to_s, s.horizon_s);
  EXPECT_EQ(during[1].version->version, 3u);
  EXPECT_TRUE(ScheduleBook().segments(0, 3.0).empty());
}

TEST(SensorIds, ParsesSinglesListsAndRangesAndRejectsTheRest) {
  EXPECT_EQ(parseSensorIds("3", "t"), std::vector<int>{3});
  EXPECT_EQ(parseSensorIds("0-2,7,1", "t"), (std::vector<int>{0, 1, 2, 7}));
  for (const char* bad : {"", "a", "-1", "3-1", "1,,2", "2-", "1.5", "99999999"}) {
    EXPECT_THROW((void)parseSensorIds(bad, "t"), InputError) << bad;
  }
}

// Recomputing a timeline after a new version must not change what was drawn before its
// effective time, and after it only the new rates count (sensor 0 is silent).
TEST(SensorTimeline, ANewVersionChangesOnlyWhatComesAfterItsEffectiveTime) {
  const Scenario s = smallScenario();
  const EmulatedPlant plant(s, 4);
  const std::vector<int> sensors = {0, 1, 2, 3};
  const double at = plant.timeOf(plant.tickAt(1.3));
  for (std::uint32_t episode = 0; episode < 50; ++episode) {
    ScheduleBook book;
    (void)book.add(versionOf(1, uniformSchedule(s)));
    const auto before = sensorTimeline(book, plant, 4, episode, sensors, s.horizon_s);
    (void)book.add(versionOf(2, withoutSensorZero(s), episode, at));
    const auto after = sensorTimeline(book, plant, 4, episode, sensors, s.horizon_s);
    std::vector<TimedArrival> head_before, head_after;
    for (const auto& a : before) if (a.time_s < at) head_before.push_back(a);
    for (const auto& a : after) if (a.time_s < at) head_after.push_back(a);
    ASSERT_EQ(head_before.size(), head_after.size()) << "episode " << episode;
    for (std::size_t i = 0; i < head_before.size(); ++i) {
      EXPECT_EQ(head_before[i].tick, head_after[i].tick);
      EXPECT_EQ(head_before[i].sensor, head_after[i].sensor);
      EXPECT_EQ(head_after[i].version, 1u);
    }
    for (const auto& a : after) {
      if (a.time_s >= at) {
        EXPECT_EQ(a.version, 2u);
        EXPECT_NE(a.sensor, 0);
      }
    }
  }
}

// Counts over many episodes against the schedule: Pearson's chi-square at level 0.001.
TEST(SensorTimeline, CountsPerSensorMatchTheScheduleInChiSquare) {
  const Scenario s = smallScenario();
  const EmulatedPlant plant(s, 4);
  ScheduleBook book;
  Eigen::MatrixXd rates = uniformSchedule(s).rates();
  rates.col(1) *= 0.25;  // unequal rates
  (void)book.add(versionOf(1, RateSchedule(s.horizon_s, rates)));
  const int episodes = 400;
  Eigen::VectorXd counts = Eigen::VectorXd::Zero(4);
  for (std::uint32_t e = 0; e < episodes; ++e) {
    for (const auto& a : sensorTimeline(book, plant, 11, e, {0, 1, 2, 3}, s.horizon_s)) {
      counts(a.sensor) += 1.0;
    }
  }
  const Eigen::VectorXd expected =
      episodes * book.latest().schedule.expectedCounts(0.0, s.horizon_s);
  const double statistic = ((counts - expected).array().square() / expected.array()).sum();
  EXPECT_LT(statistic, 18.47) << counts.transpose() << " vs " << expected.transpose();  // χ²(4)
}

// Measurements of one episode from a shuffled, partly late arrival order.
class EpisodeFusionTest : public ::testing::Test {
 protected:
  EpisodeFusionTest() : scenario_(smallScenario()), plant_(scenario_, 21) {
    (void)book_.add(versionOf(1, uniformSchedule(scenario_)));
  }

  std::vector<FusedMeasurement> measurements(std::uint32_t episode) const {
    std::vector<FusedMeasurement> all;
    std::vector<std::uint64_t> seq(4, 0);
    for (const auto& a :
         sensorTimeline(book_, plant_, 21, episode, {0, 1, 2, 3}, scenario_.horizon_s)) {
      FusedMeasurement m;
      m.sensor = a.sensor;
      m.seq = seq[static_cast<std::size_t>(a.sensor)]++;
      m.time_s = a.time_s;
      m.version = a.version;
      m.z = plant_.measure(plant_.stateAt(episode, a.tick), a.sensor, episode, m.seq);
      all.push_back(m);
    }
    return all;
  }

  double inOrderCost(std::vector<FusedMeasurement> all) const {
    return test::inOrderCost(scenario_, std::move(all));
  }

  EpisodeFusion::BracketOf bracketOf() const {
    return [this](const ScheduleVersion& v) { return computeBracket(scenario_, v.schedule); };
  }

  Scenario scenario_;
  EmulatedPlant plant_;
  ScheduleBook book_;
};

TEST_F(EpisodeFusionTest, FusesInTimestampOrderWhateverTheArrivalOrder) {
  for (std::uint32_t episode = 0; episode < 5; ++episode) {
    std::vector<FusedMeasurement> all = measurements(episode);
    ASSERT_GT(all.size(), 4u);
    std::vector<FusedMeasurement> shuffled = all;
    std::shuffle(shuffled.begin(), shuffled.end(), std::mt19937(episode));
    EpisodeFusion fusion(scenario_, plant_, book_, episode, bracketOf());
    // Half arrive, the filter moves on to 1.5 s, then the rest: some are late.
    const std::size_t half = shuffled.size() / 2;
    for (std::size_t i = 0; i < half; ++i) EXPECT_FALSE(fusion.add(shuffled[i]));
    fusion.fuseUpTo(1.5);
    for (std::size_t i = half; i < shuffled.size(); ++i) EXPECT_FALSE(fusion.add(shuffled[i]));
    std::vector<std::uint64_t> sent(4, 0);
    for (const auto& m : all) ++sent[static_cast<std::size_t>(m.sensor)];
    for (int j = 0; j < 4; ++j) {
      EXPECT_FALSE(fusion.settled(j));
      fusion.setTally(j, {sent[static_cast<std::size_t>(j)]});
    }
    EXPECT_TRUE(fusion.allSettled());
    const EpisodeResult r = fusion.finish();
    // The filter takes exactly the steps of an in-order pass (measurement to measurement, then
    // to T), so the cost is the same floating-point number, not merely close.
    EXPECT_EQ(r.realized_cost, inOrderCost(all));
    EXPECT_TRUE(r.complete);
    std::uint64_t received = 0, lost = 0;
    for (const auto& t : r.sensors) {
      received += t.received;
      lost += t.lost;
      EXPECT_EQ(t.wrong_version, 0u);
    }
    EXPECT_EQ(received, all.size());
    EXPECT_EQ(lost, 0u);
    const CostBracket bracket = computeBracket(scenario_, uniformSchedule(scenario_));
    EXPECT_EQ(r.bracket.info, bracket.info);
    EXPECT_EQ(r.bracket.cov, bracket.cov);
    EXPECT_EQ(r.latencies_s.size(), all.size());
  }
}

// Every measurement delivered twice, both copies in a random order (a sensor's seqs out of order,
// a copy before or after the original): each second copy, and only it, is a duplicate, and the
// cost is that of the measurements once, in order.
TEST_F(EpisodeFusionTest, ASecondCopyIsADuplicateInWhateverOrderTheCopiesCome) {
  const std::vector<FusedMeasurement> all = measurements(3);
  std::vector<FusedMeasurement> twice = all;
  twice.insert(twice.end(), all.begin(), all.end());
  std::shuffle(twice.begin(), twice.end(), std::mt19937(7));
  EpisodeFusion fusion(scenario_, plant_, book_, 3, bracketOf());
  std::set<std::pair<int, std::uint64_t>> seen;  // by hand
  std::size_t duplicates = 0;
  for (const FusedMeasurement& m : twice) {
    const bool first = seen.insert({m.sensor, m.seq}).second;
    const std::optional<Rejection> rejection = fusion.add(m);
    EXPECT_EQ(rejection.has_value(), !first) << "sensor " << m.sensor << " seq " << m.seq;
    if (rejection) {
      EXPECT_EQ(rejection->reason, "duplicate");
      ++duplicates;
    }
  }
  EXPECT_EQ(duplicates, all.size());
  EXPECT_EQ(fusion.finish().realized_cost, inOrderCost(all));
}

TEST_F(EpisodeFusionTest, RejectsMalformedAndDuplicateMeasurementsAndCountsLosses) {
  std::vector<FusedMeasurement> all = measurements(0);
  EpisodeFusion fusion(scenario_, plant_, book_, 0, bracketOf());
  FusedMeasurement bad = all[0];
  bad.sensor = 9;
  EXPECT_TRUE(fusion.add(bad));
  bad = all[0];
  bad.z = Eigen::VectorXd::Constant(1, std::nan(""));
  EXPECT_TRUE(fusion.add(bad));
  bad = all[0];
  bad.time_s = 99.0;
  EXPECT_TRUE(fusion.add(bad));
  EXPECT_FALSE(fusion.add(all[0]));
  EXPECT_TRUE(fusion.add(all[0]));  // duplicate seq
  // Sensor all[0].sensor says it sent one more than it delivered: one lost, not settled.
  fusion.setTally(all[0].sensor, {2});
  EXPECT_FALSE(fusion.settled(all[0].sensor));
  const EpisodeResult r = fusion.finish();
  EXPECT_EQ(r.rejected, (RejectionCounts{{"duplicate", 1}, {"malformed", 2}, {"unknown_sensor", 1}}));
  const SensorTally& t = r.sensors[static_cast<std::size_t>(all[0].sensor)];
  EXPECT_EQ(t.sent, 2u);
  EXPECT_EQ(t.received, 1u);
  EXPECT_EQ(t.lost, 1u);
  EXPECT_FALSE(r.complete);
}

TEST_F(EpisodeFusionTest, CountsALostTailAndFallsBackToTheBestLowerBoundWithoutATally) {
  std::vector<FusedMeasurement> all = measurements(1);
  EpisodeFusion fusion(scenario_, plant_, book_, 1, bracketOf());
  // Sensor a: tally 7, only seq 0 and 2 arrive: 5 lost, the tail included.
  // Sensor b: no tally; status said 4 sent, seq 0 arrived: sent 4, lost 3.
  // Sensor c: no tally, no status; seq 5 arrived: at least 6 sent, lost 5.
  const auto one = [&](int sensor, std::uint64_t seq) {
    FusedMeasurement m = all[0];
    m.sensor = sensor;
    m.seq = seq;
    m.z = Eigen::VectorXd::Zero(scenario_.sensors[static_cast<std::size_t>(sensor)].H.rows());
    return m;
  };
  EXPECT_FALSE(fusion.add(one(0, 0)));
  EXPECT_FALSE(fusion.add(one(0, 2)));
  fusion.setTally(0, {7});
  EXPECT_FALSE(fusion.add(one(1, 0)));
  fusion.noteSentAtLeast(1, 4);
  EXPECT_FALSE(fusion.add(one(2, 5)));
  fusion.setTally(3, {0});  // sent nothing: settled
  EXPECT_EQ(fusion.unsettled(), (std::vector<int>{0, 1, 2}));
  const EpisodeResult r = fusion.finish();
  const std::uint64_t sent[] = {7, 4, 6, 0}, received[] = {2, 1, 1, 0};
  for (std::size_t j = 0; j < 4; ++j) {
    EXPECT_EQ(r.sensors[j].sent, sent[j]) << j;
    EXPECT_EQ(r.sensors[j].received, received[j]) << j;
    EXPECT_EQ(r.sensors[j].sent, r.sensors[j].received + r.sensors[j].lost) << j;
  }
  EXPECT_FALSE(r.complete);
}

// The emulated network dropped two of sensor a's measurements and wrote three twice: the drops
// are neither received nor lost (the episode is complete), the three copies are the network's
// and a fourth copy is a real duplicate. Sensor b: one dropped and one more missing: lost 1.
TEST_F(EpisodeFusionTest, NetworkDropsAreNotLossesAndItsCopiesAreNoFault) {
  const std::vector<FusedMeasurement> all = measurements(3);
  std::vector<std::vector<FusedMeasurement>> by_sensor(4);
  for (const auto& m : all) by_sensor[static_cast<std::size_t>(m.sensor)].push_back(m);
  const auto& a = by_sensor[0];
  const auto& b = by_sensor[1];
  ASSERT_GE(a.size(), 5u);
  ASSERT_GE(b.size(), 3u);
  EpisodeFusion fusion(scenario_, plant_, book_, 3, bracketOf());
  std::vector<FusedMeasurement> delivered;
  for (std::size_t i = 2; i < a.size(); ++i) delivered.push_back(a[i]);  // seq 0, 1 dropped
  for (std::size_t i = 2; i < b.size(); ++i) delivered.push_back(b[i]);  // seq 0 dropped, 1 lost
  for (std::size_t j = 2; j < 4; ++j) {
    for (const auto& m : by_sensor[j]) delivered.push_back(m);
  }
  for (const auto& m : delivered) EXPECT_FALSE(fusion.add(m));
  for (int copy = 0; copy < 4; ++copy) {
    const auto rejection = fusion.add(a[2 + static_cast<std::size_t>(copy % 2)]);
    ASSERT_TRUE(rejection);
    EXPECT_EQ(rejection->reason, "duplicate");
  }
  fusion.setTally(0, {a.size(), 2, 3});
  EXPECT_TRUE(fusion.settled(0));
  fusion.setTally(1, {b.size(), 1, 0});
  EXPECT_FALSE(fusion.settled(1));
  for (int j = 2; j < 4; ++j) fusion.setTally(j, {by_sensor[static_cast<std::size_t>(j)].size()});
  EXPECT_EQ(fusion.unsettled(), std::vector<int>{1});
  const EpisodeResult r = fusion.finish();
  EXPECT_EQ(r.rejected, (RejectionCounts{{"duplicate", 1}, {kNetworkDuplicate, 3}}));
  EXPECT_EQ(faultyRejections(r.rejected), 1u);
  EXPECT_EQ(r.sensors[0].received, a.size() - 2);
  EXPECT_EQ(r.sensors[0].dropped_by_network, 2u);
  EXPECT_EQ(r.sensors[0].lost, 0u);
  EXPECT_EQ(r.sensors[1].received, b.size() - 2);
  EXPECT_EQ(r.sensors[1].dropped_by_network, 1u);
  EXPECT_EQ(r.sensors[1].lost, 1u);
  for (const SensorTally& t : r.sensors) {
    EXPECT_EQ(t.sent, t.received + t.lost + t.dropped_by_network);
  }
  EXPECT_FALSE(r.complete);  // sensor b lost one
  EXPECT_EQ(r.realized_cost, inOrderCost(delivered));

  // Without the lost one, the same drops leave the episode complete.
  EpisodeFusion whole(scenario_, plant_, book_, 3, bracketOf());
  for (const auto& m : delivered) EXPECT_FALSE(whole.add(m));
  EXPECT_FALSE(whole.add(b[1]));
  whole.setTally(0, {a.size(), 2, 0});
  whole.setTally(1, {b.size(), 1, 0});
  for (int j = 2; j < 4; ++j) whole.setTally(j, {by_sensor[static_cast<std::size_t>(j)].size()});
  EXPECT_TRUE(whole.allSettled());
  EXPECT_TRUE(whole.finish().complete);
}

// Sensor 2 dies at 1.5 s: what it sent before arrives, its tally never comes. The episode closes
// once the live sensors are settled, incomplete and saying why, with sensor 2's sent count the
// best lower bound (highest seq + 1); its missing tally is not waited for.
TEST_F(EpisodeFusionTest, ASensorThatDiesIsNotAwaitedAndLeavesItsEpisodeIncomplete) {
  const std::vector<FusedMeasurement> all = measurements(4);
  std::vector<FusedMeasurement> delivered;
  std::vector<std::uint64_t> sent(4, 0);
  for (const auto& m : all) {
    if (m.sensor == 2 && m.time_s >= 1.5) continue;
    delivered.push_back(m);
    sent[static_cast<std::size_t>(m.sensor)] = m.seq + 1;
  }
  ASSERT_GT(sent[2], 0u);
  EpisodeFusion fusion(scenario_, plant_, book_, 4, bracketOf());
  for (const auto& m : delivered) EXPECT_FALSE(fusion.add(m));
  for (const int j : {0, 1, 3}) fusion.setTally(j, {sent[static_cast<std::size_t>(j)]});
  EXPECT_EQ(fusion.unsettled(), std::vector<int>{2});
  fusion.sensorFailedAt(2, 1.5);
  fusion.sensorFailedAt(2, 1.75);  // a later notice naming it again: the earliest time stands
  EXPECT_TRUE(fusion.failed(2));
  EXPECT_TRUE(fusion.allSettled());
  EXPECT_TRUE(fusion.unsettled().empty());
  const EpisodeResult r = fusion.finish();
  EXPECT_FALSE(r.complete);
  EXPECT_EQ(r.incomplete_reason, "sensor 2 failed at 1.5 s");
  EXPECT_EQ(r.failed_sensors, std::vector<int>{2});
  EXPECT_EQ(r.sensors[2].sent, sent[2]);
  EXPECT_EQ(r.sensors[2].received, sent[2]);
  EXPECT_EQ(r.sensors[2].lost, 0u);
  EXPECT_EQ(r.realized_cost, inOrderCost(delivered));
}

// Dead before the episode: nothing sent, nothing awaited, the episode complete; the expected
// count still says what the schedule asked of it.
TEST_F(EpisodeFusionTest, ASensorDeadBeforeTheEpisodeSendsNothingAndLeavesItComplete) {
  std::vector<FusedMeasurement> live;
  for (const auto& m : measurements(5)) {
    if (m.sensor != 1) live.push_back(m);
  }
  std::vector<std::uint64_t> sent(4, 0);
  for (const auto& m : live) sent[static_cast<std::size_t>(m.sensor)] = m.seq + 1;
  EpisodeFusion fusion(scenario_, plant_, book_, 5, bracketOf());
  fusion.sensorFailedBefore(1);
  fusion.sensorFailedAt(1, 0.5);  // a notice listing every sensor dead so far: still "before"
  for (const auto& m : live) EXPECT_FALSE(fusion.add(m));
  for (const int j : {0, 2, 3}) fusion.setTally(j, {sent[static_cast<std::size_t>(j)]});
  EXPECT_TRUE(fusion.allSettled());
  const EpisodeResult r = fusion.finish();
  EXPECT_TRUE(r.complete);
  EXPECT_EQ(r.incomplete_reason, "");
  EXPECT_EQ(r.failed_sensors, std::vector<int>{1});
  EXPECT_EQ(r.sensors[1].sent, 0u);
  EXPECT_EQ(r.sensors[1].received, 0u);
  EXPECT_EQ(r.sensors[1].lost, 0u);
  EXPECT_DOUBLE_EQ(r.sensors[1].expected,
                   uniformSchedule(scenario_).expectedCounts(0.0, scenario_.horizon_s)(1));
  EXPECT_GT(r.sensors[1].expected, 0.0);
  // The planned bracket is the schedule's; what it can deliver is that schedule without sensor 1,
  // built here by hand, and costs more (fewer measurements).
  const RateSchedule planned = uniformSchedule(scenario_);
  Eigen::MatrixXd without_1 = planned.rates();
  without_1.col(1).setZero();
  const CostBracket planned_bracket = computeBracket(scenario_, planned);
  const CostBracket delivered = computeBracket(scenario_, RateSchedule(planned.horizon(), without_1));
  EXPECT_DOUBLE_EQ(r.bracket.info, planned_bracket.info);
  EXPECT_DOUBLE_EQ(r.delivered_bracket.info, delivered.info);
  EXPECT_DOUBLE_EQ(r.delivered_bracket.cov, delivered.cov);
  EXPECT_GT(r.delivered_bracket.info, r.bracket.info);
  EXPECT_GT(r.delivered_bracket.cov, r.bracket.cov);
}

// Samples for a sensor beyond what its tally says it sent (a silent sensor spoken for, issue
// 30): refused once the tally is in, counted as beyond_tally, and the cost is that of what the
// sensors sent, as if the forged ones never came (some arrive out of order on purpose).
TEST_F(EpisodeFusionTest, RefusesWhatASensorNeverSentOnceItsTallyIsIn) {
  const std::vector<FusedMeasurement> real = measurements(7);
  std::vector<std::uint64_t> sent(4, 0);
  for (const auto& m : real) sent[static_cast<std::size_t>(m.sensor)] = m.seq + 1;
  std::vector<FusedMeasurement> forged;
  for (std::uint64_t i = 0; i < 5; ++i) {  // sensor 1's next seqs, and sensor 3 beyond its count
    FusedMeasurement m = real.front();
    m.sensor = i < 3 ? 1 : 3;
    m.seq = sent[static_cast<std::size_t>(m.sensor)] + i;
    m.time_s = 0.3 * static_cast<double>(i + 1);
    m.z = Eigen::VectorXd::Constant(scenario_.sensors[static_cast<std::size_t>(m.sensor)].H.rows(),
                                    50.0);
    forged.push_back(m);
  }
  EpisodeFusion fusion(scenario_, plant_, book_, 7, bracketOf());
  for (std::size_t i = 0; i < real.size(); ++i) {
    EXPECT_FALSE(fusion.add(real[i]));
    if (i == real.size() / 2) {
      for (const auto& m : forged) EXPECT_FALSE(fusion.add(m));  // not yet known to be forged
    }
  }
  for (int j = 0; j < 4; ++j) fusion.setTally(j, {sent[static_cast<std::size_t>(j)]});
  const EpisodeResult r = fusion.finish();
  EXPECT_EQ(r.rejected.at("beyond_tally"), 5u);
  EXPECT_EQ(r.sensors[1].received, sent[1]);
  EXPECT_EQ(r.sensors[3].received, sent[3]);
  EXPECT_TRUE(r.complete);
  EXPECT_EQ(r.realized_cost, inOrderCost(real));
}

TEST_F(EpisodeFusionTest, AnIncompleteEpisodeSaysWhatItMissed) {
  const std::vector<FusedMeasurement> all = measurements(6);
  EpisodeFusion fusion(scenario_, plant_, book_, 6, bracketOf());
  const FusedMeasurement& m = all[0];
  EXPECT_FALSE(fusion.add(m));
  fusion.setTally(m.sensor, {3});
  const int other = (m.sensor + 1) % 4;
  fusion.sensorFailedAt(other, std::numeric_limits<double>::infinity());
  const EpisodeResult r = fusion.finish();
  EXPECT_FALSE(r.complete);
  EXPECT_NE(r.incomplete_reason.find("sensor " + std::to_string(other) +
                                     " failed after the episode's end, before its count arrived"),
            std::string::npos)
      << r.incomplete_reason;
  EXPECT_NE(r.incomplete_reason.find("sensor " + std::to_string(m.sensor) +
                                     ": 1 of 3 sent measurements arrived"),
            std::string::npos)
      << r.incomplete_reason;
  const nlohmann::json entry = episodeEntry(r);
  EXPECT_EQ(entry.at("incomplete_reason"), r.incomplete_reason);
  EXPECT_EQ(entry.at("failed_sensors"), nlohmann::json({other}));
}

TEST_F(EpisodeFusionTest, OnlineWatermarksNeverChangeTheRealizedCost) {
  std::vector<FusedMeasurement> all = measurements(2);
  std::sort(all.begin(), all.end(), [](const auto& a, const auto& b) { return a.time_s < b.time_s; });
  const auto costWith = [&](const std::vector<double>& watermarks) {
    EpisodeFusion fusion(scenario_, plant_, book_, 2, bracketOf());
    std::size_t next = 0;
    for (const double w : watermarks) {
      while (next < all.size() && all[next].time_s <= w + 0.2) EXPECT_FALSE(fusion.add(all[next++]));
      fusion.fuseUpTo(w);
    }
    while (next < all.size()) EXPECT_FALSE(fusion.add(all[next++]));
    return fusion.finish().realized_cost;
  };
  const double batch = costWith({});
  EXPECT_EQ(costWith({0.1, 0.37, 1.0, 1.01, 2.5}), batch);
  EXPECT_EQ(costWith({0.05, 0.1, 0.15, 0.2, 0.25, 0.3, 0.35, 0.4, 2.9}), batch);
  EXPECT_EQ(batch, inOrderCost(all));
}

// With a switch at s, the bracket is the realized ∫<W,P> up to s plus the surrogates of the new
// version from the fused P(s), computed here by hand with the core filter and rollouts.
TEST_F(EpisodeFusionTest, BracketsASwitchedEpisodeFromTheFusedCovarianceAtTheSwitch) {
  Scenario weighted = scenario_;
  weighted.cost.W = Eigen::MatrixXd::Identity(3, 3);  // a running cost, so the realized part counts
  const double at = plant_.timeOf(plant_.tickAt(1.1));
  ScheduleBook book;
  (void)book.add(versionOf(1, uniformSchedule(weighted)));
  (void)book.add(versionOf(2, withoutSensorZero(weighted), 0, at));
  std::vector<FusedMeasurement> all;
  std::vector<std::uint64_t> seq(4, 0);
  for (const auto& a : sensorTimeline(book, plant_, 21, 0, {0, 1, 2, 3}, weighted.horizon_s)) {
    FusedMeasurement m;
    m.sensor = a.sensor;
    m.seq = seq[static_cast<std::size_t>(a.sensor)]++;
    m.time_s = a.time_s;
    m.version = a.version;
    m.z = plant_.measure(plant_.stateAt(0, a.tick), a.sensor, 0, m.seq);
    all.push_back(m);
  }
  EpisodeFusion fusion(weighted, plant_, book, 0,
                       [&](const ScheduleVersion& v) { return computeBracket(weighted, v.schedule); });
  for (const auto& m : all) EXPECT_FALSE(fusion.add(m));
  const EpisodeResult r = fusion.finish();

  CdKalmanFilter filter(weighted);
  for (const auto& m : all) {
    if (m.time_s > at) break;
    filter.propagateTo(m.time_s);
    filter.update(m.sensor, m.z);
  }
  filter.propagateTo(at);
  RolloutOptions options;
  options.start_time = at;
  options.start_covariance = filter.covariance();
  const CostBracket rest = computeBracket(weighted, withoutSensorZero(weighted), options);
  EXPECT_NEAR(r.bracket.info, filter.runningCost() + rest.info, 1e-9 * r.bracket.info);
  EXPECT_NEAR(r.bracket.cov, filter.runningCost() + rest.cov, 1e-9 * r.bracket.cov);
  EXPECT_EQ(r.versions, (std::vector<std::uint32_t>{1, 2}));
  EXPECT_EQ(r.switch_time_s, at);
  for (const auto& t : r.sensors) EXPECT_EQ(t.wrong_version, 0u);
}

// A network that drops 30% of sensor 1's measurements in every episode and cuts sensor 2 off on
// [0.5, 1.5) in episode 1 only (on the 0.5 s grid of smallScenario: intervals 1 and 2).
NetworkSpec lossyNetwork() {
  NetworkSpec network;
  network.links.resize(4);
  network.links[1].loss = 0.3;
  network.outages.push_back({2, {1}, 0.5, 1.5});
  return network;
}

// The delivered schedule by hand: λ_1 (1 - 0.3) and, in episode 1, λ_2 = 0 on intervals 1, 2.
RateSchedule thinnedByHand(const RateSchedule& planned, std::uint32_t episode) {
  Eigen::MatrixXd rates = planned.rates();
  rates.col(1) *= 0.7;
  if (episode == 1) rates.block(1, 2, 2, 1).setZero();
  return RateSchedule(planned.horizon(), rates);
}

TEST_F(EpisodeFusionTest, BracketsWhatTheNetworkDeliversBesideWhatWasPlanned) {
  Scenario lossy = scenario_;
  ASSERT_DOUBLE_EQ(lossy.intervalLength(), 0.5);
  lossy.network = lossyNetwork();
  const RateSchedule planned = uniformSchedule(lossy);
  const CostBracket planned_bracket = computeBracket(lossy, planned);
  int computed_here = 0;
  for (std::uint32_t episode = 0; episode < 2; ++episode) {
    EpisodeFusion fusion(lossy, plant_, book_, episode,
                         [&](const ScheduleVersion& v) { return computeBracket(lossy, v.schedule); });
    const EpisodeResult r = fusion.finish();
    const CostBracket by_hand = computeBracket(lossy, thinnedByHand(planned, episode));
    EXPECT_EQ(r.bracket.info, planned_bracket.info);
    EXPECT_NEAR(r.delivered_bracket.info, by_hand.info, 1e-9 * by_hand.info) << episode;
    EXPECT_NEAR(r.delivered_bracket.cov, by_hand.cov, 1e-9 * by_hand.cov) << episode;
    // Less information arrives than planned: both surrogate costs are higher.
    EXPECT_GT(r.delivered_bracket.info, r.bracket.info);
    EXPECT_GT(r.delivered_bracket.cov, r.bracket.cov);
    // A caller's (cached) delivered bracket is used when given.
    EpisodeFusion cached(lossy, plant_, book_, episode,
                         [&](const ScheduleVersion& v) { return computeBracket(lossy, v.schedule); },
                         [&](const ScheduleVersion&) {
                           ++computed_here;
                           return CostBracket{1.0, 2.0};
                         });
    EXPECT_EQ(cached.finish().delivered_bracket.cov, 2.0);
  }
  EXPECT_EQ(computed_here, 2);
  // Without a network: the delivered bracket is the bracket.
  EpisodeFusion plain(scenario_, plant_, book_, 1, bracketOf());
  const EpisodeResult r = plain.finish();
  EXPECT_EQ(r.delivered_bracket.info, r.bracket.info);
  EXPECT_EQ(r.delivered_bracket.cov, r.bracket.cov);
}

// After a switch at s: the realized ∫<W,P> up to s plus the surrogates of the new version's
// delivered schedule from the fused P(s).
TEST_F(EpisodeFusionTest, BracketsWhatTheNetworkDeliversAfterASwitch) {
  Scenario lossy = scenario_;
  lossy.cost.W = Eigen::MatrixXd::Identity(3, 3);
  lossy.network = lossyNetwork();
  const double at = plant_.timeOf(plant_.tickAt(1.1));
  ScheduleBook book;
  (void)book.add(versionOf(1, uniformSchedule(lossy)));
  (void)book.add(versionOf(2, withoutSensorZero(lossy), 1, at));
  EpisodeFusion fusion(lossy, plant_, book, 1,
                       [&](const ScheduleVersion& v) { return computeBracket(lossy, v.schedule); });
  const EpisodeResult r = fusion.finish();  // no measurement: P(s) is the open-loop covariance
  CdKalmanFilter filter(lossy);
  filter.propagateTo(at);
  RolloutOptions options;
  options.start_time = at;
  options.start_covariance = filter.covariance();
  const CostBracket rest =
      computeBracket(lossy, thinnedByHand(withoutSensorZero(lossy), 1), options);
  EXPECT_NEAR(r.delivered_bracket.info, filter.runningCost() + rest.info, 1e-9 * r.delivered_bracket.info);
  EXPECT_NEAR(r.delivered_bracket.cov, filter.runningCost() + rest.cov, 1e-9 * r.delivered_bracket.cov);
  EXPECT_GT(r.delivered_bracket.info, r.bracket.info);
}

EpisodeResult episodeWith(std::uint32_t number, double cost, double info, bool complete) {
  EpisodeResult e;
  e.episode = number;
  e.realized_cost = cost;
  e.bracket = {info, 20.0};
  e.nees = 3.0;
  e.complete = complete;
  e.sensors.resize(2);
  e.sensors[0].sent = 5;
  e.sensors[0].received = 4;
  e.sensors[0].lost = 1;
  e.sensors[0].expected = 4.5;
  e.latencies_s = {0.001 * static_cast<double>(number + 1)};
  return e;
}

TEST(RunReport, SummarizesCompleteEpisodesWithAStudentTInterval) {
  RunReport report("r", "d", 2, 3);
  const std::vector<double> costs = {3.0, 5.0, 10.0, 2.0};
  for (std::size_t i = 0; i < costs.size(); ++i) {
    const EpisodeResult e = episodeWith(static_cast<std::uint32_t>(i), costs[i], 1.0 + static_cast<double>(i), true);
    report.addLatencies(e.latencies_s);
    report.add(episodeEntry(e));
  }
  // An incomplete episode counts in the totals, not in the statistics.
  report.add(episodeEntry(episodeWith(4, 1000.0, 1.0, false)));
  const RunSummary s = report.summary();
  EXPECT_EQ(s.episodes, 5u);
  EXPECT_EQ(s.episodes_complete, 4u);
  EXPECT_DOUBLE_EQ(s.mean, 5.0);
  EXPECT_NEAR(s.std_dev, std::sqrt((4.0 + 0.0 + 25.0 + 9.0) / 3.0), 1e-12);
  // t_{0.975, 3} = 3.18245 (tables), not 1.96.
  ASSERT_TRUE(s.ci95.has_value());
  EXPECT_NEAR(*s.ci95, 3.18245 * s.std_dev / 2.0, 1e-4);
  EXPECT_DOUBLE_EQ(s.bracket_mean.info, 2.5);
  EXPECT_EQ(s.meets_bracket, std::optional<bool>(true));
  EXPECT_EQ(s.sent, 25u);
  EXPECT_EQ(s.received, 20u);
  EXPECT_EQ(s.lost, 5u);
  EXPECT_DOUBLE_EQ(s.expected, 22.5);
  EXPECT_NEAR(s.latency_median_s, 0.0025, 0.0025 * kLatencyQuantileRelativeError);  // histogram
  EXPECT_DOUBLE_EQ(quantile({1.0, 2.0, 3.0, 4.0, 5.0}, 0.99), 4.96);
}

// Issue 31, finding 2: a run stopped before any episode completed reported 0.0 for the mean, the
// interval, the bracket and the latency; what was not measured is null.
TEST(RunReport, WritesNullForWhatNoCompleteEpisodeMeasured) {
  using nlohmann::json;
  RunReport none("r", "d", 2, 3);
  const EpisodeResult cut = episodeWith(0, 931.5, 1.0, false);  // cut short: not in the statistics
  none.addLatencies(cut.latencies_s);
  none.add(episodeEntry(cut));
  json s = none.toJson("interrupted", json::array(), json::array()).at("summary");
  for (const char* key : {"mean", "std", "ci95", "ci95_low", "ci95_high", "realtime_mean",
                          "nees_mean", "bracket", "delivered_bracket", "meets_bracket"}) {
    EXPECT_TRUE(s.at(key).is_null()) << key << " = " << s.at(key);
  }
  const json latency = none.toJson("interrupted", json::array(), json::array()).at("latency_s");
  EXPECT_NEAR(latency.at("median").get<double>(), 0.001, 0.001 * kLatencyQuantileRelativeError);

  RunReport one("r", "d", 2, 3);
  one.add(episodeEntry(episodeWith(0, 19.59, 1.0, true)));
  s = one.toJson("completed", json::array(), json::array()).at("summary");
  EXPECT_DOUBLE_EQ(s.at("mean").get<double>(), 19.59);
  for (const char* key : {"std", "ci95", "ci95_low", "ci95_high"}) {
    EXPECT_TRUE(s.at(key).is_null()) << key << ": one complete episode has no spread";
  }
  EXPECT_TRUE(s.at("bracket").is_object());

  RunReport empty("r", "d", 2, 3);
  const json nothing = empty.toJson("interrupted", json::array(), json::array());
  EXPECT_TRUE(nothing.at("latency_s").at("median").is_null());
  EXPECT_TRUE(nothing.at("latency_s").at("p99").is_null());
}

// The emulated network's delay, apart from the latency: the mean over every received
// measurement (episode means weighted by what each received), and the largest.
TEST(RunReport, KeepsTheEmulatedNetworkDelayApartFromTheLatency) {
  RunReport report("r", "d", 2, 3);
  EpisodeResult a = episodeWith(0, 3.0, 1.0, true);  // received 4 (sensor 0) + 0
  a.network_delay_mean_s = 0.010;
  a.network_delay_max_s = 0.030;
  EpisodeResult b = episodeWith(1, 4.0, 1.0, true);
  b.sensors[1].sent = b.sensors[1].received = 4;  // received 8
  b.network_delay_mean_s = 0.040;
  b.network_delay_max_s = 0.090;
  report.add(episodeEntry(a));
  report.add(episodeEntry(b));
  const nlohmann::json delay = report.toJson("completed", {}, {}).at("network_delay_s");
  EXPECT_NEAR(delay.at("mean").get<double>(), (4 * 0.010 + 8 * 0.040) / 12.0, 1e-15);
  EXPECT_DOUBLE_EQ(delay.at("max").get<double>(), 0.090);
  EXPECT_TRUE(RunReport("r", "d", 2, 3).toJson("completed", {}, {}).at("network_delay_s")
                  .at("mean").is_null());
}

// Ten expected counts of 0.1 add up to 0.9999999999999999 in doubles: the report says 1.
TEST(RunReport, ReportsTheExpectedTotalWithoutTheSummationsRoundingError) {
  RunReport report("r", "d", 2, 3);
  double direct = 0.0;
  for (std::uint32_t i = 0; i < 10; ++i) {
    EpisodeResult e = episodeWith(i, 3.0, 1.0, true);
    e.sensors[0].expected = 0.1;
    direct += 0.1;
    report.add(episodeEntry(e));
  }
  ASSERT_NE(direct, 1.0);
  EXPECT_EQ(report.toJson("completed", {}, {}).at("summary").at("expected").get<double>(), 1.0);
}

TEST(RunReport, CountsWhatTheNetworkDroppedPerEpisodePerSensorAndInTotal) {
  RunReport report("r", "d", 2, 3);
  for (std::uint32_t i = 0; i < 3; ++i) {
    EpisodeResult e = episodeWith(i, 2.0, 1.0, true);
    e.sensors[1].sent = 10 + i;
    e.sensors[1].received = 7;
    e.sensors[1].dropped_by_network = 3 + i;
    e.rejected[kNetworkDuplicate] = 2;
    report.add(episodeEntry(e));
  }
  const nlohmann::json doc = report.toJson("completed", nlohmann::json::array(), nlohmann::json::array());
  EXPECT_EQ(doc.at("per_episode").at(2).at("dropped_by_network"), nlohmann::json({0, 5}));
  EXPECT_EQ(doc.at("sensors").at(0).at("dropped_by_network"), 0);
  EXPECT_EQ(doc.at("sensors").at(1).at("dropped_by_network"), 12);
  EXPECT_EQ(doc.at("sensors").at(1).at("sent"), 33);
  EXPECT_EQ(doc.at("summary").at("dropped_by_network"), 12);
  EXPECT_EQ(doc.at("summary").at("rejected_by_reason").at(kNetworkDuplicate), 6);
  const RunSummary s = report.summary();
  EXPECT_EQ(s.sent, s.received + s.lost + s.dropped_by_network);
  EXPECT_EQ(faultyRejections(s.rejected), 0u);
}

// Costs 4, 5, 6 (mean 5, 95% interval 5 ± 4.30 * 1 / sqrt(3) = [2.52, 7.48]) against a planned
// bracket [1, 2] it misses and a delivered bracket [4, 6] it meets; an incomplete episode and
// an entry without a delivered bracket (an older log: the bracket stands in) as stated.
TEST(RunReport, SaysWhetherTheMeanMeetsTheDeliveredBracket) {
  RunReport report("r", "d", 2, 3);
  for (std::uint32_t i = 0; i < 3; ++i) {
    EpisodeResult e = episodeWith(i, 4.0 + i, 1.0, true);
    e.bracket = {1.0, 2.0};
    e.delivered_bracket = {3.0 + i, 5.0 + i};
    report.add(episodeEntry(e));
  }
  EpisodeResult incomplete = episodeWith(3, 100.0, 1.0, false);
  incomplete.delivered_bracket = {100.0, 200.0};
  report.add(episodeEntry(incomplete));
  RunSummary s = report.summary();
  EXPECT_DOUBLE_EQ(s.delivered_bracket_mean.info, 4.0);
  EXPECT_DOUBLE_EQ(s.delivered_bracket_mean.cov, 6.0);
  EXPECT_EQ(s.meets_bracket, std::optional<bool>(false));
  EXPECT_EQ(s.meets_delivered_bracket, std::optional<bool>(true));
  const nlohmann::json doc = report.toJson("completed", nlohmann::json::array(), nlohmann::json::array());
  EXPECT_EQ(doc.at("summary").at("delivered_bracket"), nlohmann::json({{"info", 4.0}, {"cov", 6.0}}));
  EXPECT_EQ(doc.at("summary").at("meets_delivered_bracket"), true);
  EXPECT_EQ(doc.at("per_episode").at(1).at("delivered_bracket").at("cov"), 6.0);

  nlohmann::json old = episodeEntry(episodeWith(4, 5.0, 1.0, true));
  old.erase("delivered_bracket");
  report.add(old);
  s = report.summary();
  EXPECT_DOUBLE_EQ(s.delivered_bracket_mean.info, (12.0 + 1.0) / 4.0);

  RunReport one("r", "d", 2, 3);
  one.add(episodeEntry(episodeWith(0, 3.0, 1.0, true)));
  EXPECT_TRUE(one.toJson("completed", nlohmann::json::array(), nlohmann::json::array())
                  .at("summary")
                  .at("meets_delivered_bracket")
                  .is_null());
}

TEST(RunReport, ClipsTheIntervalAtZeroAndLeavesOneEpisodeUndetermined) {
  RunReport two("r", "d", 2, 3);
  two.add(episodeEntry(episodeWith(0, 0.1, 1.0, true)));
  two.add(episodeEntry(episodeWith(1, 5.0, 1.0, true)));
  const RunSummary s = two.summary();
  // Mean 2.55, half-width 12.706 * 3.465 / sqrt(2) ~ 31: the low end would be negative.
  EXPECT_EQ(s.ci95_low, 0.0);
  EXPECT_NEAR(s.ci95_high, 2.55 + 12.7062 * std::sqrt(2.0 * 2.45 * 2.45) / std::sqrt(2.0), 1e-3);
  RunReport one("r", "d", 2, 3);
  one.add(episodeEntry(episodeWith(0, 3.0, 1.0, true)));
  EXPECT_FALSE(one.summary().ci95.has_value());
  EXPECT_FALSE(one.summary().meets_bracket.has_value());
  EXPECT_TRUE(one.toJson("completed", nlohmann::json::array(), nlohmann::json::array())
                  .at("summary")
                  .at("meets_bracket")
                  .is_null());
}

TEST(RunReport, RebuildsTheSameReportFromItsEpisodeLog) {
  char pattern[] = "/tmp/sensornet-report-test-XXXXXX";
  ASSERT_NE(::mkdtemp(pattern), nullptr);
  const std::filesystem::path dir = pattern;
  const std::filesystem::path report_path = dir / "report.json";
  EXPECT_EQ(episodeLogPath(report_path), dir / "report.jsonl");
  EXPECT_EQ(episodeLogPath(dir / "out"), dir / "out.jsonl");
  RunReport report("r", "d", 2, 3);
  {
    EpisodeLog log(episodeLogPath(report_path));
    for (std::uint32_t i = 0; i < 3; ++i) {
      const nlohmann::json entry = episodeEntry(episodeWith(i, 2.0 + i, 1.0, i != 1));
      log.append(entry);
      report.add(entry);
    }
  }
  std::ofstream(episodeLogPath(report_path), std::ios::app) << "{\"episode\": 3, \"realiz";  // torn
  const auto entries = readEpisodeLog(episodeLogPath(report_path));
  ASSERT_EQ(entries.size(), 3u);
  const nlohmann::json rebuilt = reportFromEpisodes("r", 2, entries, "failed", nlohmann::json::array());
  const nlohmann::json original = report.toJson("failed", nlohmann::json::array(), nlohmann::json::array());
  EXPECT_EQ(rebuilt.at("per_episode"), original.at("per_episode"));
  EXPECT_EQ(rebuilt.at("summary"), original.at("summary"));
  EXPECT_EQ(rebuilt.at("sensors"), original.at("sensors"));
  EXPECT_EQ(rebuilt.at("summary").at("episodes_incomplete"), 1);
  std::filesystem::remove_all(dir);
}

// A restarted fusion center: the log it died with (episodes 0, 2 and 3 finished, 1 was still
// waiting for a tally, a line torn mid-write) starts its report; it appends after it; episode 4,
// under way when it joined, and episode 1 are recorded as restarted; the rebuilt report has each
// episode once, the restarted ones incomplete with null costs.
TEST(ResumedRun, StartsFromTheEpisodeLogAndRecordsWhatItCouldNotFuse) {
  char pattern[] = "/tmp/sensornet-resume-test-XXXXXX";
  ASSERT_NE(::mkdtemp(pattern), nullptr);
  const std::filesystem::path dir = pattern;
  const std::filesystem::path log_path = dir / "report.jsonl";
  {
    EpisodeLog log(log_path);
    for (const std::uint32_t i : {0u, 2u, 3u}) log.append(episodeEntry(episodeWith(i, 2.0 + i, 1.0, true)));
  }
  std::ofstream(log_path, std::ios::app) << "{\"episode\": 4, \"realiz";  // torn by the death

  const std::int64_t joined_ns = 1'000'000'000;
  ResumedRun resumed(readEpisodeLog(log_path), joined_ns);
  ASSERT_EQ(resumed.entries().size(), 3u);
  EXPECT_TRUE(resumed.ignores(2));
  EXPECT_FALSE(resumed.ignores(1));
  // The durable start heard on joining: episode 4 began before the join.
  EXPECT_EQ(resumed.heardStart(4, joined_ns - 500), (std::vector<std::uint32_t>{1, 4}));
  EXPECT_TRUE(resumed.ignores(4));
  EXPECT_TRUE(resumed.ignores(1));
  // The next episode starts after the join: fused here, and noted once it is.
  EXPECT_TRUE(resumed.heardStart(5, joined_ns + 10).empty());
  EXPECT_FALSE(resumed.ignores(5));
  resumed.noteFused(5);
  EXPECT_TRUE(resumed.heardEnd(7) == std::vector<std::uint32_t>{6});  // never heard of: lost too
  EXPECT_EQ(resumed.restarted(), (std::set<std::uint32_t>{1, 4, 6}));

  {
    EpisodeLog log(log_path, EpisodeLog::Mode::Append);
    EpisodeResult restarted = restartedEpisode(4, 2);
    restarted.versions = {1};
    restarted.bracket = {1.0, 20.0};
    log.append(episodeEntry(restarted));
    log.append(episodeEntry(episodeWith(5, 7.0, 1.0, true)));
  }
  const std::vector<nlohmann::json> entries = readEpisodeLog(log_path);
  ASSERT_EQ(entries.size(), 5u);  // 0, 2, 3, the restarted 4 and 5: the torn line is skipped
  const nlohmann::json& four = entries[3];
  EXPECT_EQ(four.at("episode"), 4);
  EXPECT_EQ(four.at("complete"), false);
  EXPECT_EQ(four.at("incomplete_reason"), kRestartedReason);
  EXPECT_TRUE(four.at("realized_cost").is_null());
  EXPECT_TRUE(four.at("realtime_cost").is_null());
  EXPECT_TRUE(four.at("delivered_bracket").at("info").is_null());
  EXPECT_EQ(four.at("bracket").at("cov"), 20.0);
  EXPECT_EQ(four.at("sent"), nlohmann::json({0, 0}));

  const nlohmann::json rebuilt = reportFromEpisodes("r", 2, entries, "degraded", nlohmann::json::array());
  EXPECT_EQ(rebuilt.at("summary").at("episodes"), 5);
  EXPECT_EQ(rebuilt.at("summary").at("episodes_complete"), 4);
  EXPECT_DOUBLE_EQ(rebuilt.at("summary").at("mean").get<double>(), (2.0 + 4.0 + 5.0 + 7.0) / 4.0);
  std::filesystem::remove_all(dir);
}

TEST(ResumedRun, AnEpisodeUnderWayThatItNeverSawStartIsRestartedOnce) {
  ResumedRun resumed({episodeEntry(episodeWith(0, 1.0, 1.0, true))}, 100);
  EXPECT_EQ(resumed.heardOfRunning(2), (std::vector<std::uint32_t>{1, 2}));
  EXPECT_TRUE(resumed.heardOfRunning(2).empty());
  EXPECT_TRUE(resumed.heardStart(2, 50).empty());  // its start, replayed later: already recorded
  EXPECT_TRUE(resumed.heardStart(3, 150).empty());
  EXPECT_FALSE(resumed.ignores(3));
}

}  // namespace
}  // namespace sensornet::emulator
