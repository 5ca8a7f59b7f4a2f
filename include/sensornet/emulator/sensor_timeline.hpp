#pragma once
// When the sensors of one agent transmit in an episode: Poisson arrivals drawn exactly from
// the schedule versions in force (poisson_arrivals.hpp), each stretch of a version from a stream
// keyed by (seed, episode, sensor, version, stretch start), then put on the emulated plant's
// ticks. Because each stream is consumed in time order, the timeline recomputed after a new
// version arrives is identical up to the new version's effective time: an agent just recomputes
// it and carries on from where it was.
//
//   std::vector<TimedArrival> plan = sensorTimeline(book, plant, seed, episode, {0, 1}, T);

#include <cstdint>
#include <vector>

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
                                                       double horizon_s);

}  // namespace sensornet::emulator
