#pragma once
// `sensornet replay RUN.mcap`: re-fuses a recording (`sensornet launch --record`) offline
// (recording/recording_replay.hpp), prints per episode the replayed cost beside the recorded one
// and writes the replay's report; exit 0 when every episode equals the recording to the bit.
// `--info`: what a recording holds, like `mcap info`: its run metadata, the time span, and per
// channel (topic and writer partition) the schema and the message count, with the summary's
// statistics checked against the messages read. A file that is not a complete MCAP (damaged,
// cut short) is one line naming the file and what is wrong, exit 2. `--live --run-id NEW`:
// republishes the recording into a new run for its fusion center (recording/live_replay.hpp).

#include "sensornet/io/command_line.hpp"

namespace sensornet::launcher {

Subcommand addReplayCommand(CLI::App& app);

}  // namespace sensornet::launcher
