// The emulated network's decisions (network_emulation.hpp) against their laws: binomial drop
// and duplicate counts, exact outage windows, the jitter's mean, and reproducibility from the
// seed alone. Statistical checks use a fixed seed and a band of 4.9 standard deviations
// (two-sided normal tail 9.6e-7: a false alarm rate below 1e-6 per check).

#include "sensornet/emulator/network_emulation.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <vector>

namespace sensornet::emulator {
namespace {

constexpr double kBand = 4.9;  // standard deviations; P(|Z| > 4.9) = 9.6e-7
constexpr std::uint64_t kSeed = 20261130;
constexpr int kDraws = 100000;

NetworkSpec oneLink(const LinkSpec& link, int sensors = 1) {
  NetworkSpec network;
  network.links.assign(static_cast<std::size_t>(sensors), link);
  return network;
}

LinkSpec lossy(double loss) {
  LinkSpec link;
  link.loss = loss;
  return link;
}

TEST(NetworkEmulation, SameKeysGiveTheSameDecisionsInAnyOrder) {
  LinkSpec link = lossy(0.3);
  link.duplicate = 0.2;
  link.delay_fixed_s = 0.001;
  link.jitter = Jitter::Lognormal;
  link.jitter_mean_s = 0.02;
  link.jitter_sigma = 0.5;
  const NetworkSpec network = oneLink(link, 3);
  std::vector<NetworkDecision> forward;
  for (std::uint64_t seq = 0; seq < 500; ++seq) {
    forward.push_back(decideDelivery(network, kSeed, 2, 7, seq, 0.001 * static_cast<double>(seq)));
  }
  int differs_with_other_seed = 0;
  for (std::uint64_t seq = 500; seq-- > 0;) {  // backwards: no hidden state
    const NetworkDecision again =
        decideDelivery(network, kSeed, 2, 7, seq, 0.001 * static_cast<double>(seq));
    EXPECT_EQ(again.drop, forward[seq].drop);
    EXPECT_EQ(again.duplicated, forward[seq].duplicated);
    EXPECT_EQ(again.delay_s, forward[seq].delay_s);  // bit for bit
    const NetworkDecision other =
        decideDelivery(network, kSeed + 1, 2, 7, seq, 0.001 * static_cast<double>(seq));
    if (other.drop != again.drop || other.delay_s != again.delay_s) ++differs_with_other_seed;
  }
  EXPECT_GT(differs_with_other_seed, 250);
  // The sensor and the episode are keys too.
  int differs_with_other_sensor = 0;
  for (std::uint64_t seq = 0; seq < 500; ++seq) {
    const NetworkDecision other = decideDelivery(network, kSeed, 1, 7, seq, 0.0);
    if (other.drop != forward[seq].drop || other.delay_s != forward[seq].delay_s) {
      ++differs_with_other_sensor;
    }
  }
  EXPECT_GT(differs_with_other_sensor, 250);
}

TEST(NetworkEmulation, DroppedCountIsBinomial) {
  for (const double p : {0.1, 0.5}) {
    const NetworkSpec network = oneLink(lossy(p));
    int dropped = 0;
    for (int seq = 0; seq < kDraws; ++seq) {
      const NetworkDecision d =
          decideDelivery(network, kSeed, 0, 3, static_cast<std::uint64_t>(seq), 1.0);
      if (d.dropped()) {
        EXPECT_EQ(d.drop, DropCause::Loss);
        ++dropped;
      }
    }
    const double mean = kDraws * p;
    const double sd = std::sqrt(kDraws * p * (1.0 - p));
    EXPECT_LE(std::abs(dropped - mean), kBand * sd) << "p = " << p << ", dropped " << dropped;
  }
}

TEST(NetworkEmulation, DuplicatesAreBinomialAmongDeliveredOnes) {
  LinkSpec link = lossy(0.2);
  link.duplicate = 0.25;
  const NetworkSpec network = oneLink(link);
  int delivered = 0;
  int duplicated = 0;
  for (int seq = 0; seq < kDraws; ++seq) {
    const NetworkDecision d =
        decideDelivery(network, kSeed, 0, 0, static_cast<std::uint64_t>(seq), 0.5);
    EXPECT_FALSE(d.dropped() && d.duplicated);
    if (!d.dropped()) ++delivered;
    if (d.duplicated) ++duplicated;
  }
  const double mean = delivered * 0.25;
  EXPECT_LE(std::abs(duplicated - mean), kBand * std::sqrt(delivered * 0.25 * 0.75)) << duplicated;
}

TEST(NetworkEmulation, OutageDropsExactlyTheMeasurementsInItsWindowOfItsEpisodes) {
  NetworkSpec network = oneLink(LinkSpec{}, 2);
  Outage outage;
  outage.sensor = 1;
  outage.from_s = 0.5;
  outage.to_s = 1.2;
  outage.episodes = {0, 2};
  network.outages.push_back(outage);
  for (int i = 0; i <= 3000; ++i) {
    const double t = 0.001 * i;  // a grid through both edges
    const bool inside = t >= 0.5 && t < 1.2;
    for (const std::uint32_t episode : {0U, 1U, 2U}) {
      const NetworkDecision d =
          decideDelivery(network, kSeed, 1, episode, static_cast<std::uint64_t>(i), t);
      EXPECT_EQ(d.drop, inside && episode != 1 ? DropCause::Outage : DropCause::None)
          << "t = " << t << ", episode " << episode;
      EXPECT_FALSE(
          decideDelivery(network, kSeed, 0, episode, static_cast<std::uint64_t>(i), t).dropped());
    }
  }
  EXPECT_TRUE(decideDelivery(network, kSeed, 1, 0, 0, 0.5).dropped());
  EXPECT_FALSE(decideDelivery(network, kSeed, 1, 0, 0, 1.2).dropped());
  EXPECT_FALSE(decideDelivery(network, kSeed, 1, 0, 0, std::nextafter(0.5, 0.0)).dropped());
}

TEST(NetworkEmulation, ExponentialJitterHasItsMeanAboveTheFixedDelay) {
  LinkSpec link;
  link.delay_fixed_s = 0.005;
  link.jitter = Jitter::Exponential;
  link.jitter_mean_s = 0.010;
  const NetworkSpec network = oneLink(link);
  double sum = 0.0;
  for (int seq = 0; seq < kDraws; ++seq) {
    const NetworkDecision d =
        decideDelivery(network, kSeed, 0, 1, static_cast<std::uint64_t>(seq), 0.0);
    ASSERT_FALSE(d.dropped());
    ASSERT_GE(d.delay_s, link.delay_fixed_s);
    sum += d.delay_s - link.delay_fixed_s;
  }
  // The exponential's standard deviation equals its mean.
  const double standard_error = link.jitter_mean_s / std::sqrt(kDraws);
  EXPECT_LE(std::abs(sum / kDraws - link.jitter_mean_s), kBand * standard_error) << sum / kDraws;
}

TEST(NetworkEmulation, LognormalJitterHasItsMean) {
  LinkSpec link;
  link.jitter = Jitter::Lognormal;
  link.jitter_mean_s = 0.02;
  link.jitter_sigma = 0.5;
  const NetworkSpec network = oneLink(link);
  double sum = 0.0;
  for (int seq = 0; seq < kDraws; ++seq) {
    sum += decideDelivery(network, kSeed, 0, 1, static_cast<std::uint64_t>(seq), 0.0).delay_s;
  }
  // Lognormal variance: mean^2 (exp(sigma^2) - 1).
  const double sd = link.jitter_mean_s * std::sqrt(std::exp(0.25) - 1.0);
  EXPECT_LE(std::abs(sum / kDraws - link.jitter_mean_s), kBand * sd / std::sqrt(kDraws))
      << sum / kDraws;
}

TEST(NetworkEmulation, APerfectOrAbsentNetworkChangesNothing) {
  const NetworkSpec absent;
  const NetworkSpec perfect = oneLink(LinkSpec{}, 4);
  EXPECT_FALSE(impairs(absent));
  EXPECT_FALSE(impairs(perfect));
  EXPECT_TRUE(impairs(oneLink(lossy(0.01))));
  for (int seq = 0; seq < 10000; ++seq) {
    for (const NetworkSpec* network : {&absent, &perfect}) {
      const NetworkDecision d =
          decideDelivery(*network, kSeed, seq % 4, 0, static_cast<std::uint64_t>(seq), 0.3);
      EXPECT_FALSE(d.dropped());
      EXPECT_FALSE(d.duplicated);
      EXPECT_EQ(d.delay_s, 0.0);
    }
  }
}

HeldMeasurement held(std::uint64_t seq) {
  HeldMeasurement m;
  m.seq = seq;
  m.z = Eigen::VectorXd::Constant(1, static_cast<double>(seq));
  return m;
}

TEST(DelayLine, ReleasesWhatIsDueEarliestFirstAndCopiesTwice) {
  DelayLine line;
  EXPECT_TRUE(line.empty());
  EXPECT_FALSE(line.nextDueWallNs().has_value());
  line.hold(300, held(0), 1);
  line.hold(100, held(1), 2);  // duplicated
  line.hold(200, held(2), 1);
  line.hold(100, held(3), 1);  // same time as seq 1: after it, in the order held
  EXPECT_EQ(line.size(), 5U);
  EXPECT_EQ(line.nextDueWallNs(), 100);
  EXPECT_TRUE(line.takeDue(99).empty());
  std::vector<std::uint64_t> seqs;
  for (const HeldMeasurement& m : line.takeDue(200)) seqs.push_back(m.seq);
  EXPECT_EQ(seqs, (std::vector<std::uint64_t>{1, 1, 3, 2}));
  EXPECT_EQ(line.nextDueWallNs(), 300);
  const std::vector<HeldMeasurement> rest = line.takeAll();
  ASSERT_EQ(rest.size(), 1U);
  EXPECT_EQ(rest[0].z(0), 0.0);
  EXPECT_TRUE(line.empty());
}

}  // namespace
}  // namespace sensornet::emulator
