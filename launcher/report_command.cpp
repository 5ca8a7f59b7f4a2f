#include "report_command.hpp"

#include <exception>
#include <memory>
#include <vector>

#include "sensornet/io/output_file.hpp"
#include "sensornet/core/input_error.hpp"
#include "sensornet/report/report_page.hpp"
#include "sensornet/io/output_path.hpp"

namespace sensornet::launcher {
namespace {

namespace fs = std::filesystem;

struct ReportOptions {
  std::string report;
  std::string html;
  std::string csv_dir;
  bool json = false;
};

// Replaces `path` with `text`; an InputError naming the path when it cannot.
void writeOutput(const fs::path& path, const std::string& text, const std::string& option) {
  makeParentFolders(path, option);
  checkOutputFile(path, option);
  try {
    replaceFileAtomically(path, text);
  } catch (const std::exception& e) {
    throw InputError(option + " " + path.string(), "", "a writable file (" + std::string(e.what()) + ")");
  }
}

// Returns the files written.
std::vector<fs::path> writeCsv(const fs::path& dir, const sensornet::report::ReportTables& tables) {
  makeFolders(dir, "--csv");
  writeOutput(dir / "episodes.csv", tables.episodes, "--csv");
  writeOutput(dir / "sensors.csv", tables.sensors, "--csv");
  return {dir / "episodes.csv", dir / "sensors.csv"};
}

int runReport(const ReportOptions& options) {
  const nlohmann::json report = sensornet::report::readReportFile(options.report);
  if (options.html.empty() && options.csv_dir.empty()) {
    throw InputError("sensornet report", "--html / --csv", "at least one output");
  }
  if (!options.html.empty()) {
    writeOutput(options.html, sensornet::report::reportPage(report, options.report), "--html");
  }
  std::vector<fs::path> tables;
  if (!options.csv_dir.empty()) {
    tables = writeCsv(options.csv_dir, sensornet::report::reportTables(report, options.report));
  }
  if (options.json) {
    nlohmann::json csv = nlohmann::json::array();
    for (const fs::path& file : tables) csv.push_back(file.string());
    const nlohmann::json html =
        options.html.empty() ? nlohmann::json(nullptr) : nlohmann::json(options.html);
    printJson({{"report", options.report}, {"html", html}, {"csv", csv}});
  }
  return kExitOk;
}

}  // namespace

Subcommand addReportCommand(CLI::App& app) {
  auto options = std::make_shared<ReportOptions>();
  CLI::App* cmd = app.add_subcommand(
      "report",
      "Make the page of a finished run from its report: one self-contained HTML file (inline "
      "SVG plots: cost per episode against the bracket, schedule heat maps, per-sensor counts, "
      "latency histogram, covariance traces against the surrogates, faults), readable offline "
      "and printable; and CSV tables for spreadsheets. `sensornet launch` writes report.html "
      "beside every report already. Example:\n  sensornet report runs/a/report.json --html "
      "runs/a/report.html --csv runs/a/tables");
  cmd->add_option("REPORT", options->report, "the run report (JSON) of a finished run")->required();
  cmd->add_option("--html", options->html, "write the page here (missing folders are made)");
  cmd->add_option("--csv", options->csv_dir,
                  "write episodes.csv and sensors.csv into this folder (made if missing)");
  cmd->add_flag("--json", options->json,
                "print {\"report\", \"html\", \"csv\": [files]} as one JSON line once written "
                "(without it nothing is printed)");
  return {cmd, [options] { return runReport(*options); }};
}

}  // namespace sensornet::launcher
