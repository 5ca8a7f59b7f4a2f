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

// Arrivals by time change, the common random numbers of the Monte Carlo planner
// (mc_planner.hpp): sensor j's arrivals are the points of ONE unit-rate Poisson process, keyed by
// (seed, kTimeChangeStream, episode, j), mapped through the inverse of its integrated rate
// Λ_j(t) = ∫_{t0}^t λ_j. That is the exact Poisson law for any rates, and two schedules (or a
// schedule and a closed-loop policy) run on the same keys see the same underlying randomness.
// Drawn piece by piece: the rates of a piece may be chosen after the arrivals before it were
// seen (a closed loop), which the construction allows because the points beyond Λ_j(t) are
// untouched until the clock gets there.
//
//   TimeChangedArrivals arrivals(M, seed, episode, /*t0=*/0.0);
//   arrivals.drawUntil(open_loop, 1.0, buffer);   // [0, 1.0) under the open-loop plan
//   arrivals.drawUntil(replanned, T, buffer);     // [1.0, T) under the re-planned tail
inline constexpr std::uint64_t kTimeChangeStream = 0x6d632d756e697470ULL;  // "mc-unitp"

class TimeChangedArrivals {
 public:
  TimeChangedArrivals(int sensors, std::uint64_t seed, std::uint64_t episode, double t0 = 0.0);

  // Replaces `out` with the arrivals in [now(), t1) under `schedule`'s rates there, sorted by
  // time (then sensor), and moves now() to t1. Requires now() <= t1 <= horizon (InputError).
  void drawUntil(const RateSchedule& schedule, double t1, std::vector<Arrival>& out);
  [[nodiscard]] double now() const { return now_; }

 private:
  struct Clock {
    Rng rng;
    double next_point = 0.0;  // the next unit-rate point, in Λ_j units
    double integrated = 0.0;  // Λ_j(now)
  };
  std::vector<Clock> clocks_;
  double now_;
};

// All sensors' arrivals in [t0, t1), sorted by time (superposition: total rate per interval,
// exponential gaps restarted at interval boundaries, sensor picked with probability λ_j/Σλ).
[[nodiscard]] std::vector<Arrival> drawArrivals(const RateSchedule& schedule, Rng& rng, double t0,
                                                double t1);

// One sensor's arrivals in [t0, t1), sorted (what an emulated sensor process draws for itself).
[[nodiscard]] std::vector<double> drawSensorArrivals(const RateSchedule& schedule, int sensor,
                                                     Rng& rng, double t0, double t1);

}  // namespace sensornet
