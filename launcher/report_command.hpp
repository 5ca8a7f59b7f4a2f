#pragma once
// `sensornet report REPORT.json --html OUT.html [--csv DIR]`: the page of a finished run (one
// self-contained HTML file, report_page.hpp) and its CSV tables (DIR/episodes.csv,
// DIR/sensors.csv). Bad input (a missing or malformed report, an output that cannot be written)
// is one line naming the file and the problem, exit 2.
//
// The launcher writes the page beside every report it settles (sensornet::report::writePageBeside).

#include "sensornet/io/command_line.hpp"

namespace sensornet::launcher {

Subcommand addReportCommand(CLI::App& app);

}  // namespace sensornet::launcher
