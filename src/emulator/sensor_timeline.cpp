#include "sensornet/emulator/sensor_timeline.hpp"

#include <algorithm>
#include <bit>

#include "sensornet/core/arrival_timetable.hpp"
#include "sensornet/core/poisson_arrivals.hpp"
#include "sensornet/core/random.hpp"

namespace sensornet::emulator {
namespace {

void addOnTick(std::vector<TimedArrival>& timeline, const EmulatedPlant& plant, double t,
               int sensor, std::uint32_t version) {
  const std::int64_t tick = plant.tickAt(t);
  timeline.push_back({plant.timeOf(tick), tick, sensor, version});
}

// Each sensor's timetable of the composed intensity: every stretch continues from Λ_j reached
// at its start under the versions before it.
void addTimetables(std::vector<TimedArrival>& timeline,
                   const std::vector<ScheduleSegment>& segments, const EmulatedPlant& plant,
                   const std::vector<int>& sensors) {
  for (const int sensor : sensors) {
    double intensity = 0.0;  // Λ_j at the start of the current stretch
    for (const ScheduleSegment& segment : segments) {
      const RateSchedule& schedule = segment.version->schedule;
      for (const double t :
           sensorTimetable(schedule, sensor, segment.from_s, segment.to_s, intensity)) {
        addOnTick(timeline, plant, t, sensor, segment.version->version);
      }
      intensity += integratedIntensity(schedule, sensor, segment.from_s, segment.to_s);
    }
  }
}

// Poisson arrivals, each stretch of a version from its own keyed stream.
void addPoissonArrivals(std::vector<TimedArrival>& timeline,
                        const std::vector<ScheduleSegment>& segments, const EmulatedPlant& plant,
                        std::uint64_t seed, std::uint32_t episode,
                        const std::vector<int>& sensors) {
  for (const ScheduleSegment& segment : segments) {
    for (const int sensor : sensors) {
      Rng rng = Rng::keyed(seed, kEmulatedArrivalStream, episode, sensor, segment.version->version,
                           std::bit_cast<std::uint64_t>(segment.from_s));
      for (const double t : drawSensorArrivals(segment.version->schedule, sensor, rng,
                                               segment.from_s, segment.to_s)) {
        addOnTick(timeline, plant, t, sensor, segment.version->version);
      }
    }
  }
}

}  // namespace

std::vector<TimedArrival> sensorTimeline(const ScheduleBook& book, const EmulatedPlant& plant,
                                         std::uint64_t seed, std::uint32_t episode,
                                         const std::vector<int>& sensors, double horizon_s,
                                         ArrivalMode mode) {
  std::vector<TimedArrival> timeline;
  const std::vector<ScheduleSegment> segments = book.segments(episode, horizon_s);
  if (mode == ArrivalMode::Timetable) {
    addTimetables(timeline, segments, plant, sensors);
  } else {
    addPoissonArrivals(timeline, segments, plant, seed, episode, sensors);
  }
  std::sort(timeline.begin(), timeline.end(), [](const TimedArrival& a, const TimedArrival& b) {
    return a.time_s != b.time_s ? a.time_s < b.time_s : a.sensor < b.sensor;
  });
  return timeline;
}

}  // namespace sensornet::emulator
