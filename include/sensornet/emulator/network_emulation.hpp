#pragma once
// What the emulated network (the scenario's `network:`, network.hpp) does to one measurement on
// its way from a sensor to the fusion center: drop it (by the link's loss, or because an outage
// of that episode covers its emulated time), hold it back by a delay (fixed + jitter), or deliver
// it twice. Each decision is drawn from its own stream keyed by (run seed, sensor, episode, seq),
// so it depends on nothing else: the same seed gives the same decisions whatever the process
// layout, the order of the calls or the timing. No DDS here; the sensor agent applies it.
//
//   const NetworkDecision d = decideDelivery(*scenario.network, seed, sensor, episode, seq, t);
//   if (d.dropped()) ++tally.dropped_by_network;            // never written
//   else hold(measurement, /*until emulated*/ t + d.delay_s, d.duplicated ? 2 : 1);

#include <cstdint>

#include "sensornet/core/network_spec.hpp"

namespace sensornet::emulator {

inline constexpr std::uint64_t kNetworkStream = 0x6e742d6c696e6b73ULL;  // "nt-links"

enum class DropCause { None, Loss, Outage };

struct NetworkDecision {
  DropCause drop = DropCause::None;
  double delay_s = 0.0;     // emulated seconds it is held back (0 when dropped)
  bool duplicated = false;  // delivered twice (never when dropped)
  [[nodiscard]] bool dropped() const { return drop != DropCause::None; }
};

// The fate of measurement `seq` of `sensor` in `episode`, drawn at emulated time
// `emulated_time_s`. A sensor without a link in `network` (or an empty spec) has a perfect one.
[[nodiscard]] NetworkDecision decideDelivery(const NetworkSpec& network, std::uint64_t seed,
                                             int sensor, std::uint32_t episode, std::uint64_t seq,
                                             double emulated_time_s);

// Whether `network` can change anything at all (a link that is not perfect, or an outage).
[[nodiscard]] bool impairs(const NetworkSpec& network);

}  // namespace sensornet::emulator
