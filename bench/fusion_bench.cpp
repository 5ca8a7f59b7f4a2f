// The fusion center's main thread per measurement, without DDS (issue 28): one episode of the
// default scenario (n = 4, 6 sensors) at a constant total rate, every measurement drawn as the
// sensor agents draw it (timeline, plant state, noise), received a fixed latency after its
// time plus a jitter of up to a tenth of it (so some arrive behind later-timed ones), handed to
// EpisodeFusion in receipt order as the fusion center's loop does: add() per measurement,
// fuseUpTo(receipt - lag) every millisecond, finish() at the end (the live pass, then the
// real-time cost of what was received by each instant).
//
//   build/bench/fusion_bench                       # 90,000/s and 250,000/s, 200 us latency
//   build/bench/fusion_bench 150000 1000           # one rate, latency in us
//   build/bench/fusion_bench 30000 200 1           # one round (under callgrind)
//
// Prints, per rate, the median over the rounds (5 unless given) of the wall time per measurement of the live part
// (add + fuseUpTo) and of finish(), and the episode's costs, so that a change that is meant to
// be exact can be seen to be. Under `valgrind --tool=callgrind` (instructions, not seconds)
// the figure does not depend on what else the machine is doing:
//
//   valgrind --tool=callgrind --callgrind-out-file=/tmp/cg.out build/bench/fusion_bench 90000
//   callgrind_annotate /tmp/cg.out | head -30

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "sensornet/core/emulated_plant.hpp"
#include "sensornet/core/random.hpp"
#include "sensornet/core/rate_schedule.hpp"
#include "sensornet/core/scenario.hpp"
#include "sensornet/core/surrogate.hpp"
#include "sensornet/emulator/episode_fusion.hpp"
#include "sensornet/emulator/schedule_book.hpp"
#include "sensornet/emulator/sensor_timeline.hpp"
#include "sensornet/io/scenario_file.hpp"

namespace {

using sensornet::emulator::EpisodeFusion;
using sensornet::emulator::FusedMeasurement;

constexpr std::uint64_t kSeed = 1;
constexpr std::uint32_t kEpisode = 0;
constexpr double kLagS = 0.05;  // the fusion center's default --lag

struct Timing {
  double live_us = 0.0;    // add + fuseUpTo, per measurement
  double finish_us = 0.0;  // finish(), per measurement
  sensornet::emulator::EpisodeResult result;
};

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

// Every measurement of the episode, in receipt order: `latency_s` after its time plus a uniform
// jitter of up to a tenth of it (fixed seed), so that some arrive behind later-timed ones, as on
// the wire.
std::vector<FusedMeasurement> drawn(const sensornet::Scenario& scenario,
                                    const sensornet::emulator::ScheduleBook& book,
                                    const sensornet::EmulatedPlant& plant, double latency_s) {
  std::vector<int> sensors(static_cast<std::size_t>(scenario.sensorCount()));
  for (std::size_t j = 0; j < sensors.size(); ++j) sensors[j] = static_cast<int>(j);
  std::vector<std::uint64_t> seq(sensors.size(), 0);
  std::vector<FusedMeasurement> all;
  sensornet::EmulatedPlant::Path path;
  sensornet::Rng jitter(7);
  for (const auto& a :
       sensornet::emulator::sensorTimeline(book, plant, kSeed, kEpisode, sensors,
                                           scenario.horizon_s)) {
    FusedMeasurement m;
    m.sensor = a.sensor;
    m.seq = seq[static_cast<std::size_t>(a.sensor)]++;
    m.time_s = a.time_s;
    m.version = a.version;
    m.z = plant.measure(plant.stateAt(kEpisode, a.tick, path), a.sensor, kEpisode, m.seq);
    m.received_s = a.time_s + latency_s * (1.0 + 0.1 * jitter.uniform());
    const auto ns = [](double s) { return static_cast<std::int64_t>(s * 1e9); };
    m.publish_wall_ns = ns(m.time_s);
    m.receive_wall_ns = ns(m.received_s);
    all.push_back(std::move(m));
  }
  std::stable_sort(all.begin(), all.end(), [](const auto& a, const auto& b) {
    return a.received_s < b.received_s;
  });
  return all;
}

Timing fuseOnce(const sensornet::Scenario& scenario, const sensornet::emulator::ScheduleBook& book,
                const sensornet::EmulatedPlant& plant, const sensornet::CostBracket& bracket,
                const std::vector<FusedMeasurement>& all) {
  using Clock = std::chrono::steady_clock;
  const auto bracketOf = [&bracket](const sensornet::emulator::ScheduleVersion&) {
    return bracket;
  };
  EpisodeFusion fusion(scenario, plant, book, kEpisode, bracketOf, bracketOf);
  const auto start = Clock::now();
  double next_tick = 0.0;
  for (const FusedMeasurement& m : all) {
    if (m.received_s >= next_tick) {
      if (m.received_s - kLagS > 0.0) {
        fusion.fuseUpTo(std::min(m.received_s - kLagS, scenario.horizon_s));
      }
      next_tick = m.received_s + 1e-3;
    }
    (void)fusion.add(m);
  }
  std::vector<std::uint64_t> sent(static_cast<std::size_t>(scenario.sensorCount()), 0);
  for (const FusedMeasurement& m : all) ++sent[static_cast<std::size_t>(m.sensor)];
  for (std::size_t j = 0; j < sent.size(); ++j) {
    fusion.setTally(static_cast<int>(j), {sent[j], 0, 0});
  }
  const auto live_end = Clock::now();
  Timing t;
  t.result = fusion.finish();
  const auto end = Clock::now();
  const auto count = static_cast<double>(all.size());
  t.live_us = std::chrono::duration<double, std::micro>(live_end - start).count() / count;
  t.finish_us = std::chrono::duration<double, std::micro>(end - live_end).count() / count;
  return t;
}

void run(const sensornet::Scenario& scenario, double total_rate_hz, double latency_s, int rounds) {
  const int m = scenario.sensorCount();
  const int intervals = 30;
  sensornet::emulator::ScheduleBook book;
  sensornet::emulator::ScheduleVersion v;
  v.version = 1;
  v.schedule = sensornet::RateSchedule(
      scenario.horizon_s, Eigen::MatrixXd::Constant(intervals, m, total_rate_hz / m));
  const sensornet::CostBracket bracket = sensornet::computeBracket(scenario, v.schedule);
  book.add(std::move(v));
  const sensornet::EmulatedPlant plant(scenario, kSeed);
  const std::vector<FusedMeasurement> all = drawn(scenario, book, plant, latency_s);
  std::vector<double> live, finish;
  Timing last;
  for (int round = 0; round < rounds; ++round) {
    last = fuseOnce(scenario, book, plant, bracket, all);
    live.push_back(last.live_us);
    finish.push_back(last.finish_us);
  }
  std::printf("%9.0f/s  %7zu measurements, latency %4.0f us: live %.2f us, finish %.2f us, "
              "total %.2f us per measurement (medians of %d); realized %.17g, received "
              "real-time %.17g\n",
              total_rate_hz, all.size(), latency_s * 1e6, median(live), median(finish),
              median(live) + median(finish), rounds, last.result.realized_cost,
              last.result.received_realtime_cost);
}

}  // namespace

int main(int argc, char** argv) {
  const sensornet::Scenario scenario =
      sensornet::loadScenarioFile(std::string(SENSORNET_SOURCE_DIR) + "/scenarios/default.yaml");
  const double latency_s = (argc > 2 ? std::atof(argv[2]) : 200.0) * 1e-6;
  std::printf("fusion_bench: default scenario (n = %d, %d sensors), one 3 s episode, received "
              "%g us after its time plus up to a tenth more, fuseUpTo every 1 ms\n",
              static_cast<int>(scenario.stateDim()), scenario.sensorCount(), latency_s * 1e6);
  const int rounds = argc > 3 ? std::max(1, std::atoi(argv[3])) : 5;
  if (argc > 1) {
    run(scenario, std::atof(argv[1]), latency_s, rounds);
  } else {
    for (const double rate : {90000.0, 250000.0}) run(scenario, rate, latency_s, rounds);
  }
  return 0;
}
