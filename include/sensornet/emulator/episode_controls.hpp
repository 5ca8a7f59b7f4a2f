#pragma once
// What a run's episode controls say, as plain values without DDS: the emulated clock of an
// episode, an episode's start, sensors that died, the end of the run, and the control itself.
// The wire reads them off the EpisodeControl topic (wire/run_inputs.hpp); the process cores
// take and make them.
//
//   const EpisodeClock clock{start_wall_ns, time_scale};
//   clock.emulatedAt(now_ns);          // emulated seconds into the episode at wall time now_ns
//   clock.wallAt(horizon_s);           // the wall time the episode ends

#include <cstdint>
#include <set>
#include <string>
#include <vector>

namespace sensornet::emulator {

// CLOCK_REALTIME in nanoseconds since the epoch (a core takes the time as an argument and never
// calls this).
[[nodiscard]] std::int64_t wallNowNs();

// The emulated clock of one episode: emulated time 0 at start_wall_ns, time_scale emulated
// seconds per wall second.
struct EpisodeClock {
  std::int64_t start_wall_ns = 0;
  double time_scale = 1.0;

  [[nodiscard]] double emulatedAt(std::int64_t wall_ns) const {
    return 1e-9 * static_cast<double>(wall_ns - start_wall_ns) * time_scale;
  }
  [[nodiscard]] double emulatedNow() const { return emulatedAt(wallNowNs()); }
  [[nodiscard]] std::int64_t wallAt(double emulated_s) const {
    return start_wall_ns + static_cast<std::int64_t>(1e9 * emulated_s / time_scale);
  }
};

struct EpisodeStart {
  std::uint32_t episode = 0;
  EpisodeClock clock;
  std::uint32_t episodes_planned = 0;  // how many episodes the run has
  std::set<int> failed_sensors;        // dead before this episode (publish nothing, no tally)
};

// The coordinator's word that sensors died (EPISODE_SENSORS_FAILED): `sensors` (all that died
// so far in the run) publish nothing from emulated time `at_s` of `episode` on.
struct SensorFailure {
  std::uint32_t episode = 0;
  double at_s = 0.0;
  std::set<int> sensors;
  std::string detail;
};

// How the coordinator ended the run (RUN_SHUTDOWN).
struct RunEnd {
  std::uint32_t episodes_run = 0;
  bool aborted = false;  // the run could not finish; `detail` says why
  std::string detail;
};

// An EpisodeControl sample as a plain value, without the run id: what the coordinator core
// decides to send (the executable adds the run id) and what RunInputState takes (the wire
// decodes it: wire/coordinator_wire.hpp, both directions).
enum class ControlKind { EpisodeStart, EpisodeStop, SensorsFailed, RunShutdown };

struct EpisodeControl {
  ControlKind kind = ControlKind::EpisodeStart;
  std::uint32_t episode = 0;
  std::int64_t start_wall_ns = 0;  // EpisodeStart: emulated time 0; else when it was sent
  double time_scale = 1.0;
  std::uint64_t seed = 0;
  std::uint32_t schedule_version = 0;
  std::uint32_t episodes_planned = 0;  // EpisodeStart: the run's; RunShutdown: how many ran
  std::vector<std::uint32_t> failed_sensors;
  double failed_at_s = 0.0;  // SensorsFailed
  bool aborted = false;      // RunShutdown: the run could not finish
  std::string detail;
};

}  // namespace sensornet::emulator
