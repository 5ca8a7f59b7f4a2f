#pragma once
// When the sensors of one agent transmit in an episode: Poisson arrivals drawn exactly from
// the schedule versions in force (poisson_arrivals.hpp), each stretch of a version from a stream
// keyed by (seed, episode, sensor, version, stretch start), then put on the emulated plant's
// ticks. Because each stream is consumed in time order, the timeline recomputed after a new
// version arrives is identical up to the new version's effective time: an agent just recomputes
// it and carries on from where it was.
//
// With ArrivalMode::Timetable the instants are deterministic (arrival_timetable.hpp) and use no
// randomness (seed and episode play no part): sensor j's k-th instant is where the composed
// intensity of the versions in force, the old version's rates before a switch at s and the new
// one's after it, integrates to k - 1/2. So a switch continues the count from Λ_j(s) of the old
// version (it neither restarts at 0 nor jumps to the new version's own Λ_j(s)), the instants
// before s are unchanged, and without a switch every episode has the same instants. Example: a
// sensor at 2 Hz switched at s = 1.2 s to 5 Hz has Λ(s) = 2.4: instants 0.25 and 0.75 (Λ = 0.5,
// 1.5) under the old version, then 1.2 + (2.5 - 2.4) / 5 = 1.22, 1.42, ... under the new one.
//
//   std::vector<TimedArrival> plan = sensorTimeline(book, plant, seed, episode, {0, 1}, T);
//   std::vector<TimedArrival> fixed =
//       sensorTimeline(book, plant, seed, episode, {0, 1}, T, ArrivalMode::Timetable);

#include <cstdint>
#include <vector>

#include "sensornet/core/arrival_mode.hpp"
#include "sensornet/core/emulated_plant.hpp"
#include "sensornet/emulator/schedule_book.hpp"

namespace sensornet::emulator {

inline constexpr std::uint64_t kEmulatedArrivalStream = 0x656d2d6172726976ULL;  // "em-arriv"

struct TimedArrival {
  double time_s = 0.0;  // on a tick
  std::int64_t tick = 0;
  int sensor = 0;
  std::uint32_t version = 0;  // the version whose rates drew it
};

// Sorted by (time, sensor); empty when no version is in force at the episode's start.
[[nodiscard]] std::vector<TimedArrival> sensorTimeline(const ScheduleBook& book,
                                                       const EmulatedPlant& plant,
                                                       std::uint64_t seed, std::uint32_t episode,
                                                       const std::vector<int>& sensors,
                                                       double horizon_s,
                                                       ArrivalMode mode = ArrivalMode::Poisson);

}  // namespace sensornet::emulator
