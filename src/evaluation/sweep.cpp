#include "sensornet/evaluation/sweep.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstring>
#include <exception>
#include <fstream>
#include <sstream>
#include <string>
#include <utility>

#include "sensornet/core/input_error.hpp"
#include "sensornet/core/plan_status.hpp"
#include "sensornet/core/surrogate.hpp"
#include "sensornet/io/scenario_file.hpp"
#include "sensornet/evaluation/schedule_evaluation.hpp"
#include "sensornet/io/output_file.hpp"
#include "sensornet/io/plan_request.hpp"
#include "sensornet/planning/planner.hpp"

namespace sensornet::evaluation {
namespace {

using nlohmann::json;

json numberOrNull(double value) { return std::isfinite(value) ? json(value) : json(nullptr); }

// The cell's axes as columns.
json axesOf(const SweepCell& cell) {
  json row = {{"key", cell.key()}};
  if (cell.scenario.random) {
    const RandomPlantSpec& r = *cell.scenario.random;
    row["scenario"] = "random";
    row["states"] = r.state_dim;
    row["sensors"] = r.sensor_count;
    row["scenario_seed"] = r.seed;
    row["noise_scale"] = r.noise_scale;
    row["budget"] = cell.scenario.budget.value_or(r.budget);
  } else {
    row["scenario"] = cell.scenario.file;
    row["budget"] = cell.scenario.budget ? json(*cell.scenario.budget) : json(nullptr);
  }
  row["energy"] = cell.scenario.energy ? json(*cell.scenario.energy) : json(nullptr);
  row["planner"] = cell.planner;
  row["surrogate"] =
      cell.planner == "schedule" ? json(nullptr) : json(std::string(wordOf(cell.surrogate)));
  row["schedule"] = cell.planner == "schedule" ? json(cell.schedule_file) : json(nullptr);
  row["replan_every"] = cell.planner == "closed_loop" ? json(cell.replan_every_s) : json(nullptr);
  row["seed"] = cell.seed;
  if (cell.emulate) {  // the run's --seed; whole runs, not a Monte Carlo
    const EmulatedRuns& e = *cell.emulate;
    row["runs"] = nullptr;
    row["episodes"] = e.episodes;
    row["time_scale"] = e.time_scale;
    row["network"] = e.network_name.empty() ? json("scenario") : json(e.network_name);
    row["faults"] = e.faults_name.empty() ? json("scenario") : json(e.faults_name);
  } else {
    row["runs"] = cell.runs;
  }
  return row;
}

// Progress callbacks that stop the work when the sweep is stopped.
auto stopper(const std::atomic<bool>& stop) {
  return [&stop](int, int) {
    if (stop.load()) throw SweepStopped();
  };
}

std::string csvField(const json& value) {
  if (value.is_null()) return "";
  std::string text = value.is_string() ? value.get<std::string>() : value.dump();
  if (text.find_first_of(",\"\n") == std::string::npos) return text;
  std::string quoted = "\"";
  for (const char c : text) quoted += c == '"' ? std::string("\"\"") : std::string(1, c);
  return quoted + "\"";
}

}  // namespace

json runSweepCell(const SweepCell& cell, int threads, const std::atomic<bool>& stop,
                  const EmulatedRunner& emulate) {
  json row = axesOf(cell);
  const auto began = std::chrono::steady_clock::now();
  try {
    // An emulated cell's scenario is the file its run reads (with its network and faults), and
    // its plan is the one `sensornet launch` would make of it: for what the network delivers.
    const Scenario scenario = cell.emulate ? parseScenarioYaml(cell.scenarioYaml(), cell.key())
                                           : cell.scenario.load(cell.key());
    // The schedule measured: a fixed file, or the open-loop plan (the closed loop's plan at
    // every episode start), planned as `coordinator plan` plans it.
    RateSchedule schedule;
    if (cell.planner == "schedule") {
      schedule = loadScheduleFile(cell.schedule_file, scenario);
      const CostBracket bracket = computeBracket(scenario, schedule);
      row["plan_status"] = "file";
      row["plan_seconds"] = 0.0;
      row["objective"] = nullptr;
      row["bracket_info"] = numberOrNull(bracket.info);
      row["bracket_cov"] = numberOrNull(bracket.cov);
    } else {
      PlanChoices choices;
      choices.surrogate = cell.surrogate;
      choices.network_aware = cell.emulate && scenario.network.has_value();
      PlanRequest request = planRequest(scenario, cell.key(), choices);
      request.realized.seed = cell.seed;
      request.realized.threads = threads;
      request.progress = [&stop](const PlanProgress&) { return !stop.load(); };
      const PlanResult plan = planSchedule(scenario, request);
      if (stop.load()) throw SweepStopped();
      schedule = plan.schedule;
      row["plan_status"] = statusText(plan.status, plan.failure);
      row["plan_seconds"] = plan.solve_seconds;
      row["objective"] = numberOrNull(plan.objective);
      row["bracket_info"] = numberOrNull(plan.bracket.info);
      row["bracket_cov"] = numberOrNull(plan.bracket.cov);
    }
    if (cell.emulate) {
      if (!emulate) throw std::runtime_error("an emulated cell, and no launcher to run it");
      emulate(cell, schedule, stop, row);
    } else if (cell.planner == "closed_loop") {
      ClosedLoopOptions loop;
      loop.replan_every_s = cell.replan_every_s;
      loop.surrogate = cell.surrogate;
      loop.runs = cell.runs;
      loop.seed = cell.seed;
      loop.threads = threads;
      loop.progress = stopper(stop);
      const ClosedLoopRun run = runClosedLoop(scenario, schedule, loop);
      row["mean"] = run.closed.mean;
      row["ci95"] = run.closed.ci95;
      row["std"] = run.closed.std_dev;
      row["arrivals_mean"] = run.closed.arrivals_mean;
      row["open_mean"] = run.open_mean;
      row["gain_mean"] = run.gain.mean;
      row["gain_ci95"] = run.gain.ci95;
    } else {
      MonteCarloOptions mc;
      mc.runs = cell.runs;
      mc.seed = cell.seed;
      mc.threads = threads;
      mc.progress = stopper(stop);
      const bool timetable = cell.planner == "timetable";
      const OpenLoopRun run = runOpenLoop(scenario, schedule, mc,
                                          timetable ? ArrivalMode::Timetable : scenario.arrivals);
      // A timetable cell's cost is the timetable's, the Poisson mean beside it.
      const MonteCarloResult& measured = timetable ? *run.timetable : run.mc;
      row["mean"] = measured.mean;
      row["ci95"] = measured.ci95;
      row["std"] = measured.std_dev;
      row["arrivals_mean"] = measured.arrivals_mean;
      if (timetable) {
        row["poisson_mean"] = run.mc.mean;
        row["poisson_ci95"] = run.mc.ci95;
      }
    }
    row["status"] = "ok";
  } catch (const SweepStopped&) {
    throw;
  } catch (const std::exception& e) {
    if (stop.load()) throw SweepStopped();
    row["status"] = "failed";
    row["reason"] = e.what();
  }
  row["seconds"] = std::chrono::duration<double>(std::chrono::steady_clock::now() - began).count();
  return row;
}

const std::vector<std::string>& sweepColumns() {
  // clang-format off
  static const std::vector<std::string> columns = {
      "scenario", "states", "sensors", "scenario_seed", "noise_scale", "budget", "energy",
      "planner", "surrogate", "replan_every", "schedule", "seed", "runs", "episodes", "time_scale",
      "network", "faults", "status", "reason", "plan_status", "plan_seconds", "objective",
      "bracket_info", "bracket_cov", "mean", "ci95", "std", "arrivals_mean", "open_mean",
      "gain_mean", "gain_ci95", "poisson_mean", "poisson_ci95", "run_status", "exit_code",
      "delivered_bracket_info", "delivered_bracket_cov", "episodes_complete", "sent", "received",
      "lost", "dropped_by_network", "report", "seconds", "key"};
  // clang-format on
  return columns;
}

SweepResults::SweepResults(std::string path) : path_(std::move(path)) {
  std::ifstream in(path_, std::ios::binary);
  if (!in) return;  // no results yet
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  // A torn last line (no newline: the run died while writing it) is cut off the file.
  const std::size_t whole = text.rfind('\n') == std::string::npos ? 0 : text.rfind('\n') + 1;
  if (whole < text.size()) {
    if (::truncate(path_.c_str(), static_cast<off_t>(whole)) != 0) {
      throw InputError(
          path_, "",
          std::string("a results file this sweep can mend (") + std::strerror(errno) + ")");
    }
    text.resize(whole);
  }
  std::istringstream lines(text);
  std::string line;
  for (int number = 1; std::getline(lines, line); ++number) {
    if (line.empty()) continue;
    json row = json::parse(line, nullptr, false);
    if (!row.is_object() || !row.contains("key") || !row["key"].is_string() ||
        !row.contains("status")) {
      throw InputError(
          path_ + ":" + std::to_string(number), "",
          "a sweep's result row (a JSON object with key and status); is this another file?");
    }
    std::string key = row["key"].get<std::string>();  // before the row is moved from
    rows_[std::move(key)] = std::move(row);
  }
}

std::size_t SweepResults::failed() const {
  std::size_t n = 0;
  for (const auto& [key, row] : rows_) n += row.value("status", "") != "ok";
  return n;
}

void SweepResults::forgetFailed() {
  std::erase_if(rows_, [](const auto& entry) { return entry.second.value("status", "") != "ok"; });
}

void SweepResults::append(const json& row) {
  const std::string line = row.dump() + "\n";
  const int fd = ::open(path_.c_str(), O_WRONLY | O_CREAT | O_APPEND | O_CLOEXEC, 0644);
  if (fd < 0) throw std::runtime_error("cannot open " + path_ + ": " + std::strerror(errno));
  std::size_t written = 0;
  while (written < line.size()) {
    const ssize_t n = ::write(fd, line.data() + written, line.size() - written);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      const int error = errno;
      // Leave no torn line behind: cut the file back to where this row began.
      if (written > 0) {
        const off_t end = ::lseek(fd, 0, SEEK_END);
        if (end >= static_cast<off_t>(written))
          (void)::ftruncate(fd, end - static_cast<off_t>(written));
      }
      ::close(fd);
      throw std::runtime_error("cannot write " + path_ + ": " + std::strerror(error));
    }
    written += static_cast<std::size_t>(n);
  }
  const bool synced = ::fsync(fd) == 0;
  const int error = errno;
  ::close(fd);
  if (!synced) throw std::runtime_error("cannot write " + path_ + ": " + std::strerror(error));
  rows_[row.at("key").get<std::string>()] = row;
}

std::vector<json> SweepResults::rows(const std::vector<std::string>& keys) const {
  std::vector<json> out;
  for (const std::string& key : keys) {
    const auto found = rows_.find(key);
    if (found != rows_.end()) out.push_back(found->second);
  }
  return out;
}

void SweepResults::writeCsv(const std::string& path, const std::vector<std::string>& keys) const {
  std::string text;
  for (const std::string& column : sweepColumns()) text += (text.empty() ? "" : ",") + column;
  text += "\n";
  for (const json& row : rows(keys)) {
    std::string line;
    bool first = true;
    for (const std::string& column : sweepColumns()) {
      if (!first) line += ",";
      first = false;
      line += row.contains(column) ? csvField(row[column]) : "";
    }
    text += line + "\n";
  }
  replaceFileAtomically(path, text, "sweep table");
}

}  // namespace sensornet::evaluation
