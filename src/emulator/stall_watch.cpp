#include "sensornet/emulator/stall_watch.hpp"

#include <algorithm>

namespace sensornet::emulator {

std::optional<Stall> StallWatch::tick(std::int64_t now_ns) {
  const std::int64_t last = last_ns_;
  last_ns_ = std::max(last_ns_, now_ns);
  if (last == 0 || now_ns - last <= slack_ns_) return std::nullopt;
  stalls_.push_back({last, now_ns});
  return stalls_.back();
}

double StallWatch::stalledBetween(std::int64_t from_ns, std::int64_t to_ns) const {
  std::int64_t total = 0;
  for (const Stall& s : stalls_) {
    const std::int64_t overlap = std::min(to_ns, s.to_ns) - std::max(from_ns, s.from_ns);
    if (overlap > 0) total += overlap;
  }
  return 1e-9 * static_cast<double>(total);
}

void StallWatch::forgetBefore(std::int64_t before_ns) {
  std::erase_if(stalls_, [before_ns](const Stall& s) { return s.to_ns < before_ns; });
}

}  // namespace sensornet::emulator
