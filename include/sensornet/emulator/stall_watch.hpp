#pragma once
// Noticing that this process itself was not running: stopped (SIGSTOP, a debugger), paused or
// starved of CPU. docs/ARCHITECTURE.md separates a stall (alive but silent, and back later) from a death;
// a process that knows when it was stalled can keep its own absence out of what it measures
// (how late an episode drained, how far a sensor lagged behind the emulated clock) and out of
// its deadlines.
//
//   StallWatch watch;                       // slack 0.5 s
//   for (;;) {
//     wait(20ms);
//     if (auto stall = watch.tick(wallNowNs())) spdlog::warn("stalled {} s", stall->seconds());
//     ...
//   }
//   watch.stalledBetween(from_ns, to_ns);   // how much of [from, to) this process was stalled
//
// A loop that ticks at least every few tens of milliseconds (each wait, each published sample)
// sees a gap longer than the slack only when it did not run.

#include <chrono>
#include <cstdint>
#include <optional>
#include <vector>

namespace sensornet::emulator {

struct Stall {
  std::int64_t from_ns = 0;  // wall time of the last tick before it
  std::int64_t to_ns = 0;    // wall time of the first tick after it
  [[nodiscard]] double seconds() const { return 1e-9 * static_cast<double>(to_ns - from_ns); }
};

class StallWatch {
 public:
  explicit StallWatch(std::chrono::nanoseconds slack = std::chrono::milliseconds(500))
      : slack_ns_(slack.count()) {}

  // The stall that just ended, when the gap since the previous tick exceeds the slack.
  std::optional<Stall> tick(std::int64_t now_ns);
  // The time since the previous tick was spent working (a long computation), not stalled.
  void busyUntil(std::int64_t now_ns) { last_ns_ = std::max(last_ns_, now_ns); }
  // Wall seconds of [from_ns, to_ns) during which this process was stalled.
  [[nodiscard]] double stalledBetween(std::int64_t from_ns, std::int64_t to_ns) const;
  [[nodiscard]] const std::vector<Stall>& stalls() const { return stalls_; }
  // Forgets the stalls that ended before `before_ns` (what no measurement reaches back to).
  void forgetBefore(std::int64_t before_ns);

 private:
  std::int64_t slack_ns_;
  std::int64_t last_ns_ = 0;
  std::vector<Stall> stalls_;
};

}  // namespace sensornet::emulator
