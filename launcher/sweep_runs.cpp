#include "sweep_runs.hpp"

#include <unistd.h>

#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <string>
#include <vector>

#include "sensornet/core/words.hpp"
#include "sensornet/io/output_file.hpp"
#include "sensornet/io/scenario_file.hpp"
#include "sensornet/launcher/process_group.hpp"
#include "sensornet/report/report_files.hpp"
#include "sensornet/report/run_record.hpp"

namespace sensornet::launcher {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

std::string number(double value) {
  char text[32];
  std::snprintf(text, sizeof text, "%.17g", value);
  return text;
}

json orNull(const std::optional<double>& value) { return value ? json(*value) : json(nullptr); }

// The `sensornet launch` of the cell.
std::vector<std::string> launchArgv(const SweepCell& cell, const fs::path& dir, double horizon_s) {
  const EmulatedRuns& e = *cell.emulate;
  std::vector<std::string> argv = {
      fs::read_symlink("/proc/self/exe").string(), "launch", (dir / "scenario.yaml").string(),
      "--schedule", (dir / "schedule.json").string(), "--episodes", std::to_string(e.episodes),
      "--time-scale", number(e.time_scale), "--seed", std::to_string(cell.seed), "--run-id",
      "sweep-" + std::to_string(::getpid()) + "-" + cell.id(), "--report",
      (dir / "report.json").string(), "--log-dir", (dir / "logs").string(), "--no-html",
      // A run that hangs is a failed cell, not a stuck sweep: four times its emulated length
      // in wall time, and a minute for the start.
      "--timeout", number(60.0 + 4.0 * e.episodes * (horizon_s / e.time_scale + 1.0))};
  // What re-plans (after a sensor's death; the closed loop's tails) are made with: the cell's.
  if (cell.planner != "schedule") {
    argv.insert(argv.end(), {"--surrogate", std::string(wordOf(cell.surrogate))});
  }
  if (cell.planner == "timetable") argv.insert(argv.end(), {"--arrivals", "timetable"});
  if (cell.planner == "closed_loop") {
    argv.insert(argv.end(), {"--replan-every", number(cell.replan_every_s)});
  }
  if (!e.on_sensor_failure.empty()) {
    argv.insert(argv.end(), {"--on-sensor-failure", e.on_sensor_failure});
  }
  return argv;
}

// Why a run gave no measurement: its status and first fault, else what the launcher said last.
std::string whyFailed(int exit_code, const std::optional<report::RunRecord>& run,
                      const fs::path& dir) {
  std::string why = "the run exited " + std::to_string(exit_code);
  if (run) {
    why += " (" + std::string(wordOf(run->status)) + ")";
    for (const report::FaultRecord& f : run->faults) {
      if (f.isConsequence()) continue;
      return why + ": " + std::string(wordOf(f.kind)) + " in " + f.process + ": " + f.detail;
    }
    if (run->summary.episodes_complete == 0) return why + ": no episode completed";
  }
  if (const auto said = lastErrorLine(dir / "launch.log")) return why + ": " + *said;
  return why + "; see " + (dir / "launch.log").string();
}

void runCell(const fs::path& out, const SweepCell& cell, const RateSchedule& schedule,
             const std::atomic<bool>& stop, json& row) {
  const fs::path dir = out / "runs" / cell.id();
  std::error_code ignored;
  fs::remove_all(dir, ignored);  // an earlier attempt's files are not this run's
  fs::create_directories(dir / "logs");
  replaceFileAtomically(dir / "scenario.yaml", cell.scenarioYaml(), "cell scenario");
  writeScheduleFile((dir / "schedule.json").string(), schedule, {{"cell", cell.key()}});
  row["report"] = (dir / "report.json").string();

  ProcessGroup group;
  // A sweep that dies takes its run with it, as an interrupt: the launcher stops its processes.
  group.start({"launch", launchArgv(cell, dir, schedule.horizon()), dir / "launch.log", SIGTERM});
  std::optional<ChildExit> exit;
  while (!(exit = group.waitFor("launch", std::chrono::milliseconds(100)))) {
    if (stop.load()) {
      (void)group.stopAll(std::chrono::seconds(20));
      throw evaluation::SweepStopped();
    }
  }
  row["exit_code"] = exit->exit_code;

  std::optional<report::RunRecord> run;
  if (const report::ReportFile file = report::readReport(dir / "report.json"); file.ok()) {
    try {
      run = report::decodeRunRecord(file.report);
    } catch (const std::exception&) {
      run.reset();  // no report to read: the reason says what the launcher said
    }
  }
  if (run) {
    const report::SummaryRecord& s = run->summary;
    row["run_status"] = std::string(wordOf(run->status));
    row["mean"] = orNull(s.mean);
    row["ci95"] = orNull(s.ci95);
    row["std"] = orNull(s.std_dev);
    const std::uint64_t episodes = run->finishedEpisodes();
    row["arrivals_mean"] = episodes > 0
                               ? json(static_cast<double>(s.sent) / static_cast<double>(episodes))
                               : json(nullptr);
    row["delivered_bracket_info"] =
        s.delivered_bracket ? orNull(s.delivered_bracket->info) : json(nullptr);
    row["delivered_bracket_cov"] =
        s.delivered_bracket ? orNull(s.delivered_bracket->cov) : json(nullptr);
    row["episodes_complete"] = s.episodes_complete;
    row["sent"] = s.sent;
    row["received"] = s.received;
    row["lost"] = s.lost;
    row["dropped_by_network"] = s.dropped_by_network;
  }
  const bool measured = (exit->exit_code == 0 || exit->exit_code == 3) && exit->signal == 0 &&
                        run && run->summary.mean.has_value();
  if (!measured) throw std::runtime_error(whyFailed(exit->exit_code, run, dir));
}

}  // namespace

evaluation::EmulatedRunner emulatedRunner(fs::path out) {
  return [out = std::move(out)](const SweepCell& cell, const RateSchedule& schedule,
                                const std::atomic<bool>& stop,
                                json& row) { runCell(out, cell, schedule, stop, row); };
}

}  // namespace sensornet::launcher
