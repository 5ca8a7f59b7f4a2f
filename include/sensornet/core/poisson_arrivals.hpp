#pragma once
// Poisson measurement arrivals (Section II of the first paper: sensor j transmits at the events
// of a Poisson process N_j(t) of intensity λ_j(t)), drawn exactly for a piecewise-constant
// RateSchedule: on each rate interval the gaps are exponential, and they restart at interval
// boundaries, which memorylessness makes exact.
//
//   Rng rng = Rng::keyed(seed, kArrivalStream, episode);
//   std::vector<Arrival> all = drawArrivals(schedule, rng, 0.0, schedule.horizon());
//   for (const Arrival& a : all) filter.propagateTo(a.time), filter.update(a.sensor, z);
//
//   // What one emulated sensor draws for itself:
//   std::vector<double> mine = drawSensorArrivals(schedule, /*sensor=*/3, rng, 0.0, 1.5);
//
// In a hot loop, build an ArrivalSampler once and reuse one output buffer:
//
//   const ArrivalSampler sampler(schedule);
//   std::vector<Arrival> buffer;
//   sampler.draw(rng, 0.0, T, buffer);  // no heap allocation once the buffer has grown

#include <vector>

#include "sensornet/core/random.hpp"
#include "sensornet/core/rate_schedule.hpp"

namespace sensornet {

struct Arrival {
  double time = 0.0;  // emulated time in [t0, t1)
  int sensor = 0;     // index into Scenario::sensors
};

// Draws the superposition of all sensors' arrivals: on each interval the merged process has
// rate Λ_k = Σ_j λ_kj, and each of its events belongs to sensor j with probability λ_kj / Λ_k
// (independent thinning in reverse), which gives the same law as M independent processes.
class ArrivalSampler {
 public:
  // Throws InputError when a rate is negative or not finite, or the schedule is empty.
  explicit ArrivalSampler(const RateSchedule& schedule);

  // Replaces the contents of `out` with the arrivals in [t0, t1), sorted by time. Requires
  // 0 <= t0 <= t1 <= horizon (throws InputError otherwise).
  void draw(Rng& rng, double t0, double t1, std::vector<Arrival>& out) const;
  [[nodiscard]] std::vector<Arrival> draw(Rng& rng, double t0, double t1) const;

  // Expected number of arrivals of all sensors together in [t0, t1).
  [[nodiscard]] double expectedCount(double t0, double t1) const;

  [[nodiscard]] const RateSchedule& schedule() const { return schedule_; }

 private:
  // Sensor of one merged event in interval k, from a uniform u in (0, 1).
  [[nodiscard]] int pickSensor(int k, double u) const;
  // Upper end of interval k clipped to t1; the last interval ends exactly at the horizon.
  [[nodiscard]] double intervalEnd(int k, double t1) const;

  RateSchedule schedule_;
  std::vector<double> total_rate_hz_;       // Λ_k per interval
  std::vector<double> cumulative_rate_hz_;  // row-major N x M: Σ_{i<=j} λ_ki
  std::vector<int> last_active_sensor_;     // per interval, the largest j with λ_kj > 0
};

// All sensors' arrivals in [t0, t1), sorted by time (superposition: total rate per interval,
// exponential gaps restarted at interval boundaries, sensor picked with probability λ_j/Σλ).
[[nodiscard]] std::vector<Arrival> drawArrivals(const RateSchedule& schedule, Rng& rng, double t0,
                                                double t1);

// One sensor's arrivals in [t0, t1), sorted (what an emulated sensor process draws for itself).
[[nodiscard]] std::vector<double> drawSensorArrivals(const RateSchedule& schedule, int sensor,
                                                     Rng& rng, double t0, double t1);

}  // namespace sensornet
