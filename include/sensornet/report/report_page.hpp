#pragma once
// The report page of a run: one self-contained HTML file made from a run report (run_report.hpp)
// with inline SVG plots (svg_plot.hpp), no fetched scripts, fonts or styles, readable offline and
// printable; and the same report as CSV tables for spreadsheets and pandas.
//
//   const nlohmann::json report = readReportFile("runs/a/report.json");  // InputError if bad
//   writeTextFile("runs/a/report.html", reportPage(report, "runs/a/report.json"));
//   const ReportTables tables = reportTables(report, "runs/a/report.json");
//   // tables.episodes: "episode,complete,realized_cost,..." one row per episode
//
// Both read the run's typed record (run_record.hpp), decoded once by the one codec; a caller that
// holds the record already passes it (reportPage(run, source)), one with the document has it
// decoded (decodeReport).
//
// The plots (each drawn only when the report carries what it needs; a note says what is missing):
//   1. realized cost per episode, the bracket in force as a band, the running mean of the complete
//      episodes with its 95% Student-t interval, schedule switches as rules;
//   2. each schedule version as a sensor x time heat map of its rates, its switch point marked;
//   3. per sensor: expected, sent, received, lost (and dropped by the emulated network);
//   4. the publish-to-fusion latency histogram (log-spaced bins) with median and p99;
//   5. <W, P(t)> of the first episodes beside the two surrogate curves of their schedule;
//   6. a faults timeline (and table), when there were faults.
// A small inline script (no network) counts each plot's drawn marks into data-marks and any
// script error into the body's data-errors: what the browser test reads from the dumped DOM.

#include <filesystem>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>

#include "sensornet/report/run_record.hpp"

namespace sensornet::report {

// Reads a run report: InputError("<path>", ...) when the file cannot be read, is not JSON, or
// lacks what a report has (run_id, status, per_episode, sensors, summary) or does not decode
// (checkReport).
[[nodiscard]] nlohmann::json readReportFile(const std::filesystem::path& path);

// The record the page and the tables read: the report decoded (decodeRunRecord), its
// run_id, status, per_episode, sensors and summary required; InputError(source, field,
// expected) naming the first field that is missing or of the wrong type
// ("per_episode[2].complete").
[[nodiscard]] RunRecord decodeReport(const nlohmann::json& report, const std::string& source);
// The same check, the record dropped.
void checkReport(const nlohmann::json& report, const std::string& source);

// The HTML page. `source` names the report in errors; a record without its episode entries
// (read with EpisodeEntries::Skipped) is InputError(source, "per_episode", ...).
[[nodiscard]] std::string reportPage(const RunRecord& run, const std::string& source);
[[nodiscard]] std::string reportPage(const nlohmann::json& report, const std::string& source);

// The page's path beside a report: report.json -> report.html (any other name gets ".html"
// appended).
[[nodiscard]] std::filesystem::path pagePathBeside(const std::filesystem::path& report_path);

// Writes the page beside the report (atomically, as every report file); the problem as one
// line when it cannot (never throws). The launcher and a fusion center with --page use it:
//   if (auto problem = writePageBeside(report_path)) spdlog::warn("{}", *problem);
[[nodiscard]] std::optional<std::string> writePageBeside(const std::filesystem::path& report_path);

// The CSV tables (header row, one row per episode / per sensor, plain numbers, empty for none):
//   episodes.csv: episode, complete (1/0), realized_cost, realtime_cost, bracket_info,
//     bracket_cov, delivered_bracket_info, delivered_bracket_cov, nees, schedule_version (the
//     last in force), switch_time_s, and the episode's sums over sensors: sent, received, lost,
//     dropped_by_network, late, expected; latency_median_s, latency_p99_s.
//   sensors.csv: sensor_id, sent, received, lost, dropped_by_network, late, expected,
//     wrong_version (over every episode: the report's `sensors`).
struct ReportTables {
  std::string episodes;
  std::string sensors;
};
[[nodiscard]] ReportTables reportTables(const RunRecord& run, const std::string& source);
[[nodiscard]] ReportTables reportTables(const nlohmann::json& report, const std::string& source);

}  // namespace sensornet::report
