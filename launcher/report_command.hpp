#pragma once
// `sensornet report REPORT.json --html OUT.html [--csv DIR]`: the page of a finished run (one
// self-contained HTML file, report_page.hpp) and its CSV tables (DIR/episodes.csv,
// DIR/sensors.csv). Bad input (a missing or malformed report, an output that cannot be written)
// is one line naming the file and the problem, exit 2.
//
// The launcher writes the page beside every report it settles:
//   if (auto problem = writePageBeside(report_path)) spdlog::warn("{}", *problem);

#include <filesystem>
#include <optional>
#include <string>

#include "sensornet/io/command_line.hpp"

namespace sensornet::launcher {

Subcommand addReportCommand(CLI::App& app);

// The page's path beside a report: report.json -> report.html (any other name gets ".html"
// appended).
[[nodiscard]] std::filesystem::path pagePathBeside(const std::filesystem::path& report_path);

// Writes the page beside the report; the problem as one line when it cannot (never throws).
[[nodiscard]] std::optional<std::string> writePageBeside(const std::filesystem::path& report_path);

}  // namespace sensornet::launcher
