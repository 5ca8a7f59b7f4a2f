#pragma once
// One sensor_agent process: emulates a block of sensors of one run. It learns the scenario
// and the schedule versions over DDS, and for every episode the coordinator starts it
// publishes each hosted sensor's measurements z = H_j x(t) + v_j at the Poisson arrival
// instants of the schedule in force (sensor_timeline.hpp), on the emulated clock, then an
// EpisodeTally per sensor: how many it published (seq 0..sent-1), which the fusion center
// checks its receipts against. A stalled agent (SIGSTOP) publishes what fell due meanwhile as
// soon as it runs again; the measurements keep their emulated instants, so nothing changes for
// the filter, and the lag it reports leaves its own stall out.
//
// With a `network:` section in the scenario, every drawn arrival still takes its seq, and the
// emulated network (network_emulation.hpp, keyed by the run seed) drops it (counted in the
// tally's dropped_by_network, never written), holds it back until wall time
// clock.wallAt(t + delay) (Measurement.network_delay_s), or writes it twice with the same seq
// (duplicated_by_network). The tally goes out only once everything held back is written. A
// scripted crash (`faults:`) of a hosted sensor logs one line and kills the process with SIGKILL
// at its emulated instant.

#include <vector>

#include "sensornet/wire/run_options.hpp"

namespace sensornet::sensor_agent {

struct AgentOptions {
  wire::RunOptions run;
  std::vector<int> sensors;
  double status_period_s = 1.0;  // SensorStatus republished at least this often
};

// Runs until RUN_SHUTDOWN (returns kExitOk) or SIGINT/SIGTERM (kExitFailure).
int runSensorAgent(const AgentOptions& options);

}  // namespace sensornet::sensor_agent
