#pragma once
// `sensornet replay RUN.mcap --info`: what a recording (`sensornet launch --record`) holds, like
// `mcap info`: its run metadata, the time span, and per channel (topic and partition) the schema
// and the message count, with the summary's statistics checked against the messages read. A file
// that is not a complete MCAP (damaged, cut short) is one line naming the file and what is
// wrong, exit 2. Re-fusing a recording (offline and live replay) is not built yet.

#include "sensornet/io/command_line.hpp"

namespace sensornet::launcher {

Subcommand addReplayCommand(CLI::App& app);

}  // namespace sensornet::launcher
