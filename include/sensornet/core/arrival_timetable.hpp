#pragma once
// Deterministic measurement instants beside the Poisson ones (issue 14, part 3): a sensor's
// rate schedule is quantized into a timetable. With Λ_j(t) = ∫_0^t λ_j the integrated
// intensity, sensor j's k-th instant is the first t with Λ_j(t) = k - 1/2 (k = 1, 2, ...), for
// as long as it stays within the horizon. Over any window the count differs from the Poisson
// mean Λ_j(t1) - Λ_j(t0) by at most one, and it never varies: the covariance path, and so
// J(P), is the same in every episode.
//
//   const ArrivalMode mode = parseArrivalMode("timetable", "scenario.yaml:4", "arrivals");
//   std::vector<Arrival> all = timetableArrivals(schedule);           // every sensor, sorted
//   std::vector<double> mine = sensorTimetable(schedule, 3, 0.0, T);  // one sensor
//
//   // A schedule switch at s: continue the second schedule's instants from Λ of the first.
//   const double at_s = integratedIntensity(first, 3, 0.0, s);
//   std::vector<double> rest = sensorTimetable(second, 3, s, T, at_s);

#include <vector>

#include "sensornet/core/arrival_mode.hpp"
#include "sensornet/core/poisson_arrivals.hpp"
#include "sensornet/core/rate_schedule.hpp"

namespace sensornet {

// Λ_j(t1) - Λ_j(t0) = ∫_{t0}^{t1} λ_j for 0 <= t0 <= t1 <= horizon (throws InputError
// otherwise, or for a negative or non-finite rate or a sensor out of range).
[[nodiscard]] double integratedIntensity(const RateSchedule& schedule, int sensor, double t0,
                                         double t1);

// Sensor j's instants in [t0, t1), sorted: the first t at which intensity_at_t0 + ∫_{t0}^t λ_j
// reaches each half-integer k - 1/2 >= intensity_at_t0. intensity_at_t0 is Λ_j(t0) of the
// intensity in force before t0; by default that of this schedule, so that a window of one
// schedule gives exactly the instants of [0, T) that fall in it.
[[nodiscard]] std::vector<double> sensorTimetable(const RateSchedule& schedule, int sensor,
                                                  double t0, double t1,
                                                  double intensity_at_t0);
[[nodiscard]] std::vector<double> sensorTimetable(const RateSchedule& schedule, int sensor,
                                                  double t0, double t1);

// Every sensor's instants over [0, T), sorted by (time, sensor).
[[nodiscard]] std::vector<Arrival> timetableArrivals(const RateSchedule& schedule);

}  // namespace sensornet
