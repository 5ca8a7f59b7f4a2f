#pragma once
// What a run announces to the processes that follow it, decoded from the wire (RunInputs reads
// them off DDS; the fusion center's core takes them as events): an episode's clock and start, the
// coordinator's sensor-failure notices and the run's end. Free of DDS.

#include <cstdint>
#include <set>
#include <string>

namespace sensornet::emulator {

// Wall clock in nanoseconds (messages.cpp): only for the convenience emulatedNow() below.
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

}  // namespace sensornet::emulator
