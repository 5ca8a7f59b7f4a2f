#include "sweep_command.hpp"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "interrupts.hpp"
#include "sweep_runs.hpp"
#include "sensornet/core/input_error.hpp"
#include "sensornet/evaluation/sweep.hpp"
#include "sensornet/io/command_line.hpp"
#include "sensornet/io/experiment_file.hpp"
#include "sensornet/io/output_file.hpp"
#include "sensornet/io/output_path.hpp"
#include "sensornet/report/sweep_page.hpp"

namespace sensornet::launcher {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

struct SweepOptions {
  std::string experiment;
  std::string out;  // empty: sweeps/<experiment name>
  int jobs = 0;     // 0: one per core
  bool retry_failed = false;
  bool json = false;
};

std::string duration(double seconds) {
  const long s = std::lround(seconds);
  char text[32];
  if (s >= 3600) {
    std::snprintf(text, sizeof text, "%ldh%02ldm", s / 3600, (s / 60) % 60);
  } else {
    std::snprintf(text, sizeof text, "%ldm%02lds", s / 60, s % 60);
  }
  return text;
}

int runSweep(const SweepOptions& options) {
  const Experiment experiment = loadExperimentFile(options.experiment);
  const fs::path out =
      options.out.empty() ? fs::path("sweeps") / experiment.name : fs::path(options.out);
  makeFolders(out, "--out");
  const fs::path jsonl = out / "results.jsonl";
  const fs::path csv = out / "results.csv";
  const fs::path page = out / "results.html";
  evaluation::SweepResults results(jsonl.string());
  if (options.retry_failed) results.forgetFailed();

  std::vector<const SweepCell*> todo;
  std::vector<std::string> keys;
  for (const SweepCell& cell : experiment.cells) {
    keys.push_back(cell.key());
    if (!results.has(cell.key())) todo.push_back(&cell);
  }
  const std::size_t total = experiment.cells.size();
  const std::size_t already = total - todo.size();
  const unsigned cores = std::max(1u, std::thread::hardware_concurrency());
  // An emulated cell is a whole run of several processes that keep time: one at a time unless
  // asked, so that runs do not slow one another past their deadlines.
  const bool emulated = std::any_of(experiment.cells.begin(), experiment.cells.end(),
                                    [](const SweepCell& c) { return c.emulate.has_value(); });
  const std::size_t jobs = std::min<std::size_t>(
      std::max<std::size_t>(1, todo.size()),
      options.jobs > 0 ? static_cast<std::size_t>(options.jobs) : emulated ? 1 : cores);
  const evaluation::EmulatedRunner runner = emulatedRunner(out);
  const int threads = static_cast<int>(std::max<std::size_t>(1, cores / jobs));
  std::fprintf(stderr, "sweep %s: %zu cells, %zu done before, %zu to run, %zu at a time -> %s\n",
               experiment.name.c_str(), total, already, todo.size(), jobs, jsonl.c_str());

  installInterruptHandlers();
  std::atomic<bool> stop{false};
  std::atomic<std::size_t> next{0};
  std::mutex lock;  // the results file, the counts, the progress line
  std::size_t finished = 0;
  double last_line_s = -1.0;
  std::string write_error;
  const auto began = Clock::now();
  const auto worker = [&] {
    for (;;) {
      const std::size_t i = next.fetch_add(1);
      if (i >= todo.size() || stop.load()) return;
      nlohmann::json row;
      try {
        row = evaluation::runSweepCell(*todo[i], threads, stop, runner);
      } catch (const evaluation::SweepStopped&) {
        return;  // not a result: the cell runs again next time
      }
      const std::lock_guard<std::mutex> held(lock);
      try {
        results.append(row);
      } catch (const std::exception& e) {
        write_error = e.what();
        stop = true;
        return;
      }
      ++finished;
      const bool ok = row.value("status", "") == "ok";
      const double elapsed = std::chrono::duration<double>(Clock::now() - began).count();
      // A line a second at most, and for the last cell and every failure.
      if (ok && finished < todo.size() && elapsed - last_line_s < 1.0) continue;
      last_line_s = elapsed;
      const double left =
          elapsed / static_cast<double>(finished) * static_cast<double>(todo.size() - finished);
      std::fprintf(stderr, "sweep: %zu/%zu cells (%zu failed), %s elapsed, about %s left%s%s\n",
                   already + finished, total, results.failed(), duration(elapsed).c_str(),
                   duration(left).c_str(),
                   ok ? "" : "; failed: ", ok ? "" : row.value("reason", std::string("?")).c_str());
    }
  };
  std::atomic<std::size_t> working{jobs};
  std::vector<std::thread> pool;
  for (std::size_t j = 0; j < jobs; ++j) {
    pool.emplace_back([&] {
      worker();
      --working;
    });
  }
  // The main thread watches for Ctrl-C and tells the workers, which stop within a plan
  // iteration or a Monte Carlo batch; the cells under way are not results.
  while (working.load() > 0) {
    if (pendingInterrupt() != 0) stop = true;
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  for (std::thread& t : pool) t.join();

  if (!write_error.empty()) {
    std::fprintf(stderr, "sweep: stopped: %s (the cells written before are kept)\n",
                 write_error.c_str());
  }
  try {
    results.writeCsv(csv.string(), keys);
    replaceFileAtomically(page, report::sweepPage(experiment.name, results.rows(keys)),
                          "sweep page");
  } catch (const std::exception& e) {  // a full disk: the rows written stay, say what did not
    std::fprintf(stderr, "sweep: %s (the results in %s are whole)\n", e.what(), jsonl.c_str());
    return kExitFailure;
  }
  const std::size_t done =
      std::count_if(keys.begin(), keys.end(), [&](const std::string& k) { return results.has(k); });
  const std::size_t failed = results.failed();
  if (options.json) {
    printJson({{"experiment", options.experiment},
               {"cells", total},
               {"done", done},
               {"failed", failed},
               {"results", jsonl.string()},
               {"table", csv.string()},
               {"page", page.string()},
               {"interrupted", pendingInterrupt() != 0}});
  }
  if (!write_error.empty()) return kExitFailure;
  if (done < total) {
    std::fprintf(stderr,
                 "sweep: interrupted: %zu of %zu cells done; the same command goes on from there\n",
                 done, total);
    return kExitFailure;
  }
  std::fprintf(stderr, "sweep: %zu cells, %zu failed; table %s, page %s\n", total, failed,
               csv.c_str(), page.c_str());
  return failed == 0 ? kExitOk : kExitFailure;
}

}  // namespace

Subcommand addSweepCommand(CLI::App& app) {
  auto options = std::make_shared<SweepOptions>();
  CLI::App* cmd = app.add_subcommand(
      "sweep",
      "Run an experiment: every cell (one value of each axis: scenario files or random plants "
      "and their budgets, planners, seeds) planned as `coordinator plan` plans and measured by "
      "the Monte Carlo of `fusion_center evaluate` (the same numbers for the same inputs), "
      "several cells at a time; with the experiment's emulate: section, by a whole `sensornet "
      "launch` of the cell instead (its network and faults, time scale, episodes; the run's "
      "files in OUT/runs/ID, one run at a time by default). Each finished cell is a line of "
      "OUT/results.jsonl at once; "
      "after a Ctrl-C or a crash the same command runs only the cells not yet there. "
      "OUT/results.csv is the table and OUT/results.html the page (cost against each axis per "
      "planner, with intervals and brackets). Exit 0 when every cell is ok, 1 when one failed (its "
      "row "
      "says why) or the sweep was stopped, 2 for bad input. Example:\n  sensornet sweep "
      "examples/experiments/planners-vs-budget.yaml --jobs 2");
  cmd->add_option(
         "EXPERIMENT", options->experiment,
         "the experiment file (YAML; docs/reference/file-formats.md, \"Experiment files\")")
      ->required();
  cmd->add_option("--out", options->out,
                  "the results folder (made if missing; default sweeps/NAME, NAME the experiment's "
                  "name: or its file's stem)");
  cmd->add_option("--jobs", options->jobs,
                  "cells at a time (0: one per core, or 1 for emulated cells); each cell's Monte "
                  "Carlo gets the cores divided among them")
      ->capture_default_str()
      ->check(integerRange(0, 1024));
  cmd->add_flag("--retry-failed", options->retry_failed,
                "run the cells whose earlier row says failed again (default: a cell in the "
                "results is done, failed or not)");
  cmd->add_flag(
      "--json", options->json,
      "print {\"cells\", \"done\", \"failed\", \"results\", \"table\", \"page\", \"interrupted\"} "
      "as one JSON line at the end");
  return {cmd, [options] { return runSweep(*options); }};
}

}  // namespace sensornet::launcher
