#pragma once
// `sensornet record [--run-id ID] RUN.mcap`: joins a running emulation and records it, as
// `sensornet launch --record` does from the start (recording::RunRecorder: every sample of every
// topic in every partition of the run, into an MCAP file). It only reads. What was sent before
// it joined is in the file only where the topic keeps it for late joiners (the scenario, the
// schedule versions, the episode controls, the latest reports); measurements and tallies from
// the moment it joined. It stops when the run ends (or on Ctrl-C), and closes the file with its
// summary and a `run-end` metadata record (status as seen: ended, or interrupted). Exit 0 when
// the file holds everything it took, 1 when the run never answered within --wait or the disk
// refused part of the recording, 2 on bad input (the path).

#include "sensornet/io/command_line.hpp"

namespace sensornet::launcher {

Subcommand addRecordCommand(CLI::App& app);

}  // namespace sensornet::launcher
