#include "sensornet/core/poisson_arrivals.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include "sensornet/core/input_error.hpp"

namespace sensornet {
namespace {

void checkWindow(const RateSchedule& schedule, double t0, double t1, const char* source) {
  if (!(std::isfinite(t0) && std::isfinite(t1) && 0.0 <= t0 && t0 <= t1 &&
        t1 <= schedule.horizon())) {
    throw InputError(source, "t0/t1",
                     "0 <= t0 <= t1 <= horizon " + std::to_string(schedule.horizon()) + ", got [" +
                         std::to_string(t0) + ", " + std::to_string(t1) + ")");
  }
}

void checkRates(const RateSchedule& schedule, const char* source) {
  if (schedule.intervals() < 1 || schedule.sensorCount() < 1 ||
      !(std::isfinite(schedule.horizon()) && schedule.horizon() > 0.0)) {
    throw InputError(source, "schedule",
                     "at least one interval and one sensor over a finite horizon > 0");
  }
  for (int k = 0; k < schedule.intervals(); ++k) {
    for (int j = 0; j < schedule.sensorCount(); ++j) {
      const double rate = schedule.rate(k, j);
      if (!(std::isfinite(rate) && rate >= 0.0)) {
        throw InputError(source,
                         "rates[" + std::to_string(k) + "][" + std::to_string(j) + "]",
                         "a finite rate >= 0, got " + std::to_string(rate));
      }
    }
  }
}

// End of interval k clipped to t1; the last interval ends at the horizon itself, so that
// rounding in N * (T / N) cannot drop or add a sliver at the end.
double clippedIntervalEnd(const RateSchedule& schedule, int k, double t1) {
  const double end =
      (k + 1 == schedule.intervals()) ? schedule.horizon() : schedule.intervalStart(k + 1);
  return std::min(end, t1);
}

// The interval to start scanning from: one before intervalAt(t0), because floor(t0 / h) can
// round up past t0 and the sliver below k h would otherwise be skipped.
int firstInterval(const RateSchedule& schedule, double t0) {
  return std::max(0, schedule.intervalAt(t0) - 1);
}

}  // namespace

ArrivalSampler::ArrivalSampler(const RateSchedule& schedule) : schedule_(schedule) {
  checkRates(schedule_, "arrival sampler");
  const int intervals = schedule_.intervals();
  const int sensors = schedule_.sensorCount();
  total_rate_hz_.assign(intervals, 0.0);
  cumulative_rate_hz_.assign(static_cast<std::size_t>(intervals) * sensors, 0.0);
  last_active_sensor_.assign(intervals, -1);
  for (int k = 0; k < intervals; ++k) {
    double sum = 0.0;
    for (int j = 0; j < sensors; ++j) {
      sum += schedule_.rate(k, j);
      cumulative_rate_hz_[static_cast<std::size_t>(k) * sensors + j] = sum;
      if (schedule_.rate(k, j) > 0.0) last_active_sensor_[k] = j;
    }
    total_rate_hz_[k] = sum;
  }
}

double ArrivalSampler::intervalEnd(int k, double t1) const {
  return clippedIntervalEnd(schedule_, k, t1);
}

int ArrivalSampler::pickSensor(int k, double u) const {
  const int sensors = schedule_.sensorCount();
  const auto row = cumulative_rate_hz_.begin() + static_cast<std::ptrdiff_t>(k) * sensors;
  const double target = u * total_rate_hz_[k];
  // First j with Σ_{i<=j} λ_ki > target: a zero-rate sensor never wins, since its cumulative
  // sum equals its predecessor's. Rounding can leave target at the total; then the last
  // sensor with a positive rate takes it.
  const auto it = std::upper_bound(row, row + sensors, target);
  if (it == row + sensors) return last_active_sensor_[k];
  return static_cast<int>(it - row);
}

void ArrivalSampler::draw(Rng& rng, double t0, double t1, std::vector<Arrival>& out) const {
  checkWindow(schedule_, t0, t1, "drawArrivals");
  out.clear();
  if (t0 >= t1) return;
  for (int k = firstInterval(schedule_, t0); k < schedule_.intervals(); ++k) {
    const double start = std::max(t0, schedule_.intervalStart(k));
    const double end = intervalEnd(k, t1);
    if (start >= t1) break;
    const double rate = total_rate_hz_[k];
    if (rate <= 0.0 || start >= end) continue;
    // Memorylessness: restarting the exponential clock at the interval start is exact.
    for (double t = start + rng.exponential(rate); t < end; t += rng.exponential(rate)) {
      out.push_back(Arrival{t, pickSensor(k, rng.uniform())});
    }
  }
}

std::vector<Arrival> ArrivalSampler::draw(Rng& rng, double t0, double t1) const {
  std::vector<Arrival> out;
  draw(rng, t0, t1, out);
  return out;
}

double ArrivalSampler::expectedCount(double t0, double t1) const {
  return schedule_.expectedCounts(t0, t1).sum();
}

std::vector<Arrival> drawArrivals(const RateSchedule& schedule, Rng& rng, double t0, double t1) {
  return ArrivalSampler(schedule).draw(rng, t0, t1);
}

std::vector<double> drawSensorArrivals(const RateSchedule& schedule, int sensor, Rng& rng,
                                       double t0, double t1) {
  checkRates(schedule, "drawSensorArrivals");
  if (sensor < 0 || sensor >= schedule.sensorCount()) {
    throw InputError("drawSensorArrivals", "sensor",
                     "an index in [0, " + std::to_string(schedule.sensorCount()) + "), got " +
                         std::to_string(sensor));
  }
  checkWindow(schedule, t0, t1, "drawSensorArrivals");
  std::vector<double> out;
  if (t0 >= t1) return out;
  for (int k = firstInterval(schedule, t0); k < schedule.intervals(); ++k) {
    const double start = std::max(t0, schedule.intervalStart(k));
    const double end = clippedIntervalEnd(schedule, k, t1);
    if (start >= t1) break;
    const double rate = schedule.rate(k, sensor);
    if (rate <= 0.0 || start >= end) continue;
    for (double t = start + rng.exponential(rate); t < end; t += rng.exponential(rate)) {
      out.push_back(t);
    }
  }
  return out;
}

}  // namespace sensornet

namespace sensornet {

TimeChangedArrivals::TimeChangedArrivals(int sensors, std::uint64_t seed, std::uint64_t episode,
                                         double t0)
    : now_(t0) {
  clocks_.reserve(static_cast<std::size_t>(std::max(0, sensors)));
  for (int j = 0; j < sensors; ++j) {
    Clock clock{Rng::keyed(seed, kTimeChangeStream, episode, static_cast<std::uint64_t>(j))};
    clock.next_point = clock.rng.exponential(1.0);
    clocks_.push_back(std::move(clock));
  }
}

void TimeChangedArrivals::drawUntil(const RateSchedule& schedule, double t1,
                                    std::vector<Arrival>& out) {
  checkWindow(schedule, now_, t1, "time-changed arrivals");
  if (schedule.sensorCount() != static_cast<int>(clocks_.size())) {
    throw InputError("time-changed arrivals", "schedule",
                     std::to_string(clocks_.size()) + " sensors, got " +
                         std::to_string(schedule.sensorCount()));
  }
  out.clear();
  for (int k = firstInterval(schedule, now_); k < schedule.intervals(); ++k) {
    const double from = std::max(now_, schedule.intervalStart(k));
    const double to = clippedIntervalEnd(schedule, k, t1);
    if (from >= t1) break;
    if (!(to > from)) continue;
    for (std::size_t j = 0; j < clocks_.size(); ++j) {
      Clock& c = clocks_[j];
      const double rate = schedule.rate(k, static_cast<int>(j));
      if (!(rate >= 0.0) || !std::isfinite(rate)) {
        throw InputError("time-changed arrivals",
                         "rates[" + std::to_string(k) + "][" + std::to_string(j) + "]",
                         "a finite rate >= 0, got " + std::to_string(rate));
      }
      if (rate == 0.0) continue;
      const double top = c.integrated + rate * (to - from);
      while (c.next_point < top) {
        const double t = from + (c.next_point - c.integrated) / rate;
        if (t < to) out.push_back(Arrival{t, static_cast<int>(j)});
        c.next_point += c.rng.exponential(1.0);
      }
      c.integrated = top;
    }
  }
  now_ = t1;
  std::sort(out.begin(), out.end(), [](const Arrival& a, const Arrival& b) {
    return a.time < b.time || (a.time == b.time && a.sensor < b.sensor);
  });
}

}  // namespace sensornet
