#include "sensornet/emulator/sensor_timeline.hpp"

#include <algorithm>
#include <bit>

#include "sensornet/core/poisson_arrivals.hpp"
#include "sensornet/core/random.hpp"

namespace sensornet::emulator {

std::vector<TimedArrival> sensorTimeline(const ScheduleBook& book, const EmulatedPlant& plant,
                                         std::uint64_t seed, std::uint32_t episode,
                                         const std::vector<int>& sensors, double horizon_s) {
  std::vector<TimedArrival> timeline;
  for (const ScheduleSegment& segment : book.segments(episode, horizon_s)) {
    for (const int sensor : sensors) {
      Rng rng = Rng::keyed(seed, kEmulatedArrivalStream, episode, sensor,
                           segment.version->version, std::bit_cast<std::uint64_t>(segment.from_s));
      for (const double t : drawSensorArrivals(segment.version->schedule, sensor, rng,
                                               segment.from_s, segment.to_s)) {
        const std::int64_t tick = plant.tickAt(t);
        timeline.push_back({plant.timeOf(tick), tick, sensor, segment.version->version});
      }
    }
  }
  std::sort(timeline.begin(), timeline.end(), [](const TimedArrival& a, const TimedArrival& b) {
    return a.time_s != b.time_s ? a.time_s < b.time_s : a.sensor < b.sensor;
  });
  return timeline;
}

}  // namespace sensornet::emulator
