#include "sensornet/emulator/clock_offsets.hpp"

#include <algorithm>
#include <cmath>

namespace sensornet::emulator {

bool ClockOffset::surelyBeyond(double bound_s) const {
  return std::abs(offset_s) - uncertainty_s > bound_s;
}

std::optional<ClockOffset> offsetOf(const ClockExchange& x) {
  const std::int64_t outward = x.probe_taken_ns - x.probe_sent_ns;  // d1 + offset
  const std::int64_t back = x.answered_ns - x.answer_taken_ns;      // offset - d2
  const std::int64_t held = x.answered_ns - x.probe_taken_ns;       // in the process
  const std::int64_t round_trip = (x.answer_taken_ns - x.probe_sent_ns) - held;
  if (held < 0 || round_trip < 0) return std::nullopt;
  // Halves in floating point: the sum of two int64 differences of times near each other.
  return ClockOffset{0.5e-9 * (static_cast<double>(outward) + static_cast<double>(back)),
                     0.5e-9 * static_cast<double>(round_trip)};
}

bool ClockOffsets::add(const std::string& process, const std::vector<int>& sensors,
                       const ClockExchange& x) {
  const std::optional<ClockOffset> offset = offsetOf(x);
  if (!offset) {
    ++refused_;
    return false;
  }
  auto it = std::find_if(processes_.begin(), processes_.end(),
                         [&process](const Process& p) { return p.name == process; });
  if (it == processes_.end()) {
    processes_.push_back(Process{process, sensors, 0, *offset, *offset, {}});
    it = std::prev(processes_.end());
  }
  Process& p = *it;
  p.sensors = sensors;
  ++p.exchanges;
  p.window.push_back(*offset);
  if (p.window.size() > kWindow) p.window.pop_front();
  p.best = *std::min_element(p.window.begin(), p.window.end(),
                             [](const ClockOffset& a, const ClockOffset& b) {
                               return a.uncertainty_s < b.uncertainty_s;
                             });
  const auto sureness = [](const ClockOffset& o) { return std::abs(o.offset_s) - o.uncertainty_s; };
  if (sureness(p.best) > sureness(p.farthest)) p.farthest = p.best;
  return true;
}

bool ClockOffsets::measured(int sensor) const {
  return std::any_of(processes_.begin(), processes_.end(), [sensor](const Process& p) {
    return std::find(p.sensors.begin(), p.sensors.end(), sensor) != p.sensors.end();
  });
}

}  // namespace sensornet::emulator
