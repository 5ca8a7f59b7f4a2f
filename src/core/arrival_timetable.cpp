#include "sensornet/core/arrival_timetable.hpp"

#include <algorithm>
#include <cmath>

#include "sensornet/core/input_error.hpp"

namespace sensornet {
namespace {

constexpr const char* kSource = "arrival timetable";

void checkSensorWindow(const RateSchedule& schedule, int sensor, double t0, double t1) {
  if (schedule.intervals() < 1 || !(std::isfinite(schedule.horizon()) && schedule.horizon() > 0)) {
    throw InputError(kSource, "schedule", "at least one interval over a finite horizon > 0");
  }
  if (sensor < 0 || sensor >= schedule.sensorCount()) {
    throw InputError(kSource, "sensor",
                     "an index in [0, " + std::to_string(schedule.sensorCount()) + "), got " +
                         std::to_string(sensor));
  }
  if (!(std::isfinite(t0) && std::isfinite(t1) && 0.0 <= t0 && t0 <= t1 &&
        t1 <= schedule.horizon())) {
    throw InputError(kSource, "t0/t1",
                     "0 <= t0 <= t1 <= horizon " + std::to_string(schedule.horizon()) + ", got [" +
                         std::to_string(t0) + ", " + std::to_string(t1) + ")");
  }
  for (int k = 0; k < schedule.intervals(); ++k) {
    const double rate = schedule.rate(k, sensor);
    if (!(std::isfinite(rate) && rate >= 0.0)) {
      throw InputError(kSource, "rates[" + std::to_string(k) + "][" + std::to_string(sensor) + "]",
                       "a finite rate >= 0, got " + std::to_string(rate));
    }
  }
}

// The stretch of interval k inside [t0, t1); the last interval ends at the horizon itself.
struct Stretch {
  double from = 0.0;
  double to = 0.0;
  double rate = 0.0;
};

template <typename Visit>
void forEachStretch(const RateSchedule& schedule, int sensor, double t0, double t1, Visit visit) {
  // One interval early: floor(t0 / h) can round up past t0.
  for (int k = std::max(0, schedule.intervalAt(t0) - 1); k < schedule.intervals(); ++k) {
    const double end =
        (k + 1 == schedule.intervals()) ? schedule.horizon() : schedule.intervalStart(k + 1);
    const double from = std::max(t0, schedule.intervalStart(k));
    const double to = std::min(end, t1);
    if (from >= t1) break;
    if (from < to) visit(Stretch{from, to, schedule.rate(k, sensor)});
  }
}

}  // namespace

std::string_view arrivalModeName(ArrivalMode mode) { return wordOf(mode); }

ArrivalMode parseArrivalMode(std::string_view text, const std::string& source,
                             const std::string& field) {
  return parseWord<ArrivalMode>(text, source, field);
}

double integratedIntensity(const RateSchedule& schedule, int sensor, double t0, double t1) {
  checkSensorWindow(schedule, sensor, t0, t1);
  double total = 0.0;
  forEachStretch(schedule, sensor, t0, t1,
                 [&](const Stretch& s) { total += s.rate * (s.to - s.from); });
  return total;
}

std::vector<double> sensorTimetable(const RateSchedule& schedule, int sensor, double t0,
                                    double t1, double intensity_at_t0) {
  checkSensorWindow(schedule, sensor, t0, t1);
  if (!(std::isfinite(intensity_at_t0) && intensity_at_t0 >= 0.0)) {
    throw InputError(kSource, "intensity_at_t0",
                     "a finite value >= 0, got " + std::to_string(intensity_at_t0));
  }
  std::vector<double> out;
  double at_start = intensity_at_t0;  // Λ at the start of the current stretch
  forEachStretch(schedule, sensor, t0, t1, [&](const Stretch& s) {
    if (s.rate > 0.0) {
      // The smallest half-integer >= Λ(from); each instant is solved from the stretch start,
      // not accumulated, so that rounding does not build up along a long timetable.
      for (double target = std::ceil(at_start - 0.5) + 0.5;; target += 1.0) {
        const double t = s.from + (target - at_start) / s.rate;
        if (!(t < s.to)) break;
        out.push_back(t);
      }
    }
    at_start += s.rate * (s.to - s.from);
  });
  return out;
}

std::vector<double> sensorTimetable(const RateSchedule& schedule, int sensor, double t0,
                                    double t1) {
  return sensorTimetable(schedule, sensor, t0, t1, integratedIntensity(schedule, sensor, 0.0, t0));
}

std::vector<Arrival> timetableArrivals(const RateSchedule& schedule) {
  std::vector<Arrival> all;
  for (int j = 0; j < schedule.sensorCount(); ++j) {
    for (const double t : sensorTimetable(schedule, j, 0.0, schedule.horizon())) {
      all.push_back(Arrival{t, j});
    }
  }
  std::sort(all.begin(), all.end(), [](const Arrival& a, const Arrival& b) {
    return a.time != b.time ? a.time < b.time : a.sensor < b.sensor;
  });
  return all;
}

}  // namespace sensornet
