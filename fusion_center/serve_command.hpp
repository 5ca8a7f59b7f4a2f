#pragma once
// `fusion_center serve`: the fusion center of a running emulation. It runs the exact CD-KF on
// the measurements of every sensor in timestamp order, publishes a Report per episode (realized
// cost against the bracket of the schedule in force, counts, latency, running summary) and the
// fused covariance for re-planning, and on RUN_SHUTDOWN writes the final report (JSON).

#include "sensornet/io/command_line.hpp"

namespace sensornet::fusion_center {

Subcommand addServeCommand(CLI::App& app);

}  // namespace sensornet::fusion_center
