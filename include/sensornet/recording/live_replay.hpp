#pragma once
// Republishing a recording into a new run (`sensornet replay RUN.mcap --live --run-id NEW`): the
// recorded traffic of the run's own side (Scenario, Schedule, EpisodeControl, and every sensor
// writer's Measurement, EpisodeTally, SensorStatus) written again, sample for sample, in the new
// run's partitions (each writer in its recorded partition, renamed: sensornet/OLD/sensors/2 ->
// sensornet/NEW/sensors/2), at the recorded timing scaled by `time_scale` (2: twice as fast), so
// that a fusion center of the new run (ours, or a user's) sees exactly the recorded run. Every
// sample's run id becomes NEW; every wall time moves with the timeline (an episode's start,
// publication times), and each EpisodeControl's time scale is multiplied by `time_scale`, so the
// emulated clock keeps pace. Nothing the fusion center wrote (Report, FusionState) is replayed.
//
// It waits (up to `ready_timeout_s`) until every Measurement writer has matched a reader (the
// fusion center), since the topic is volatile, then plays; returns how many samples it wrote.

#include <cstdint>
#include <string>

#include "sensornet/wire/run_options.hpp"
#include "sensornet/io/mcap.hpp"

namespace sensornet::recording {

struct LiveReplayResult {
  std::uint64_t written = 0;
  double wall_s = 0.0;
};

[[nodiscard]] LiveReplayResult replayLive(const McapReader& file, const std::string& source,
                                          const wire::RunOptions& new_run, double time_scale,
                                          double ready_timeout_s);

}  // namespace sensornet::recording
