#pragma once
// How far each sensor process's wall clock is from the fusion center's, measured NTP's way
// (docs/wire-protocol.md, "Clocks"): the fusion center sends a probe at t1 (its clock), the
// process takes it at t2 and answers at t3 (its clock), the answer comes at t4 (the fusion
// center's clock). Whatever the two one-way delays are (each at least 0), the process's clock
// minus the fusion center's lies within half the round trip of ((t2 - t1) + (t3 - t4)) / 2.
//
//   ClockOffsets clocks;
//   clocks.add("sensor_agent 4711@edge-1", {3, 4, 5}, {t1, t2, t3, t4});
//   for (const ClockOffsets::Process& p : clocks.processes()) {
//     // p.best: the offset of least round trip among the latest kWindow exchanges
//   }
//
// Free of DDS and of clocks: the fusion center feeds it the times it read.

#include <cstddef>
#include <cstdint>
#include <deque>
#include <optional>
#include <string>
#include <vector>

namespace sensornet::emulator {

// One probe and its answer: wall nanoseconds, t1 and t4 on the fusion center's clock, t2 and t3
// on the answering process's.
struct ClockExchange {
  std::int64_t probe_sent_ns = 0;     // t1
  std::int64_t probe_taken_ns = 0;    // t2
  std::int64_t answered_ns = 0;       // t3
  std::int64_t answer_taken_ns = 0;   // t4
};

// The process's clock minus the fusion center's: the true offset lies in
// [offset_s - uncertainty_s, offset_s + uncertainty_s].
struct ClockOffset {
  double offset_s = 0.0;
  double uncertainty_s = 0.0;  // half the round trip
  // Beyond `bound_s` either way for certain: |offset| - uncertainty > bound.
  [[nodiscard]] bool surelyBeyond(double bound_s) const;
};

// The offset one exchange shows; none when its times cannot be (an answer before its probe, a
// process that answered before it took the probe): a clock stepped between, or a bad sample.
[[nodiscard]] std::optional<ClockOffset> offsetOf(const ClockExchange& x);

class ClockOffsets {
 public:
  // Exchanges per process the estimate is taken from: the latest 8 (at a probe every 0.5 s, a
  // clock stepped mid-run shows within 4 s).
  static constexpr std::size_t kWindow = 8;

  struct Process {
    std::string name;
    std::vector<int> sensors;
    std::uint64_t exchanges = 0;  // taken (not refused)
    ClockOffset best;             // of least round trip in the window: the latest estimate
    // Of every estimate so far, the one farthest from zero for certain (largest
    // |offset| - uncertainty): what a fault names.
    ClockOffset farthest;
    std::deque<ClockOffset> window;
  };

  // Takes one exchange of `process` (speaking for `sensors`); false (and counted in refused())
  // when its times cannot be.
  bool add(const std::string& process, const std::vector<int>& sensors, const ClockExchange& x);

  [[nodiscard]] const std::vector<Process>& processes() const { return processes_; }
  [[nodiscard]] std::uint64_t refused() const { return refused_; }
  // Whether any answer of a process hosting `sensor` was taken.
  [[nodiscard]] bool measured(int sensor) const;

 private:
  std::vector<Process> processes_;  // in the order they first answered
  std::uint64_t refused_ = 0;
};

}  // namespace sensornet::emulator
