// `sensornet sweep`: an experiment's cells equal what `coordinator plan` and `fusion_center
// evaluate` print for the same inputs, a sweep stopped by Ctrl-C goes on where it stopped
// without running a cell twice, a failed cell is not run again unless asked, and a bad
// experiment file is one line and exit 2.

#include <gtest/gtest.h>
#include <signal.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <set>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "support/background_process.hpp"
#include "support/process.hpp"
#include "support/scratch_dir.hpp"

namespace sensornet {
namespace {

using nlohmann::json;
using sensornet::testing::ProcessResult;
using sensornet::testing::runProcess;

const std::string kLauncher = SENSORNET_LAUNCHER;
const std::string kCoordinator = SENSORNET_COORDINATOR;
const std::string kFusionCenter = SENSORNET_FUSION_CENTER;

// A random plant of the first paper, small: 2 budgets x 2 planners x 2 seeds = 8 cells.
std::string experiment(int runs, const std::string& seeds) {
  return "name: small\n"
         "scenarios:\n"
         "  - random: {states: 3, sensors: 5, seed: 4, budget: [2, 4]}\n"
         "    horizon: 2\n"
         "    intervals: 6\n"
         "planners: [info, cov]\n"
         "runs: " +
         std::to_string(runs) +
         "\n"
         "seeds: " +
         seeds + "\n";
}

std::vector<json> rowsOf(const std::string& path) {
  std::ifstream in(path);
  std::vector<json> rows;
  for (std::string line; std::getline(in, line);) rows.push_back(json::parse(line));
  return rows;
}

std::vector<std::string> linesOf(const std::string& path) {
  std::ifstream in(path);
  std::vector<std::string> lines;
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  return lines;
}

TEST(SweepCli, EveryCellIsWhatThePlannerAndTheEvaluatorPrint) {
  const sensornet::testing::ScratchDir dir;
  const std::string file = dir.write("small.yaml", experiment(300, "[1, 2]"));
  const ProcessResult r =
      runProcess({kLauncher, "sweep", file, "--out", dir.file("out"), "--jobs", "2", "--json"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const json summary = json::parse(r.out);
  EXPECT_EQ(summary.at("cells"), 8);
  EXPECT_EQ(summary.at("done"), 8);
  EXPECT_EQ(summary.at("failed"), 0);
  const std::vector<json> rows = rowsOf(dir.file("out/results.jsonl"));
  ASSERT_EQ(rows.size(), 8u);
  std::set<std::string> cells;
  for (const json& row : rows) {
    cells.insert(row.at("planner").get<std::string>() + "/" + row.at("budget").dump() + "/" +
                 row.at("seed").dump());
  }
  EXPECT_EQ(cells.size(), 8u);  // each cell once

  // Every cell again through the programs, from a scenario file of the same plant and budget.
  for (const json& row : rows) {
    const std::string budget = row.at("budget").dump();
    const std::string scenario =
        dir.write("plant-" + budget + ".yaml",
                  "horizon: 2\nintervals: 6\nrandom:\n  states: 3\n  sensors: 5\n"
                  "  seed: 4\n  budget: " +
                      budget + "\n");
    const std::string plan = dir.file("plan.json");
    const ProcessResult p =
        runProcess({kCoordinator, "plan", "--scenario", scenario, "--surrogate",
                    row.at("planner").get<std::string>(), "--out", plan, "--json"});
    ASSERT_EQ(p.exit_code, 0) << p.err;
    const json planned = json::parse(p.out);
    EXPECT_EQ(row.at("objective"), planned.at("objective")) << row.dump();
    EXPECT_EQ(row.at("bracket_info"), planned.at("bracket").at("info"));
    EXPECT_EQ(row.at("bracket_cov"), planned.at("bracket").at("cov"));
    const ProcessResult e =
        runProcess({kFusionCenter, "evaluate", "--scenario", scenario, "--schedule", plan, "--runs",
                    "300", "--seed", row.at("seed").dump(), "--json"});
    ASSERT_EQ(e.exit_code, 0) << e.err;
    const json evaluated = json::parse(e.out);
    EXPECT_EQ(row.at("mean"), evaluated.at("mc").at("mean")) << row.dump();
    EXPECT_EQ(row.at("ci95"), evaluated.at("mc").at("ci95"));
  }

  // The table: a header and one line per cell; the page plots cost against the budget.
  EXPECT_EQ(linesOf(dir.file("out/results.csv")).size(), 9u);
  std::ifstream page(dir.file("out/results.html"));
  std::stringstream html;
  html << page.rdbuf();
  EXPECT_NE(html.str().find("id=\"fig-budget\""), std::string::npos);
  EXPECT_EQ(summary.at("page"), dir.file("out/results.html"));
}

// Energy budgets as an axis, the timetable planner and a fixed schedule file: each cell is what
// the programs print for a scenario file with the same budget (a timetable cell: `fusion_center
// evaluate --arrivals timetable`; a schedule cell: `fusion_center evaluate --schedule` of that
// file), and its schedule spends at most the budget of every sensor (recomputed here from the
// schedule file: Σ_k λ_kj T / N).
TEST(SweepCli, EnergyAndTimetableCellsAreWhatTheProgramsPrintAndMeetTheirBudgets) {
  const sensornet::testing::ScratchDir dir;
  // 0.25 Hz for 2 s, 0.5 expected measurements of each sensor, and an uneven row.
  const std::string fixed = dir.write(
      "fixed.json",
      "{\"horizon\": 2, \"intervals\": 6, \"rates\": [[0.25, 0.25, 0.25, 0.25, 0.25], "
      "[0.25, 0.25, 0.25, 0.25, 0.25], [0.25, 0.25, 0.25, 0.25, 0.25], "
      "[0.25, 0.25, 0.25, 0.25, 0.25], [0.25, 0.25, 0.25, 0.25, 0.25], "
      "[0.05, 0.45, 0.25, 0.25, 0.25]]}");
  const std::string file = dir.write(
      "energy.yaml",
      "scenarios:\n  - random: {states: 3, sensors: 5, seed: 4, budget: 4}\n"
      "    horizon: 2\n    intervals: 6\n    energy: [0.8, 3]\n"
      "planners: [info, cov, uniform, {timetable: info}, {schedule: fixed.json}]\nruns: 200\n");
  const ProcessResult r = runProcess({kLauncher, "sweep", file, "--out", dir.file("out"), "--json"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const std::vector<json> rows = rowsOf(dir.file("out/results.jsonl"));
  ASSERT_EQ(rows.size(), 10u);
  for (const json& row : rows) {
    const double energy = row.at("energy").get<double>();
    const std::string scenario = dir.write(
        "plant.yaml", "horizon: 2\nintervals: 6\nrandom:\n  states: 3\n  sensors: 5\n"
                      "  seed: 4\n  budget: 4\n  energy: " + row.at("energy").dump() + "\n");
    const bool fixed_schedule = row.at("planner") == "schedule";
    const std::string plan = fixed_schedule ? fixed : dir.file("plan.json");
    if (fixed_schedule) {
      EXPECT_EQ(row.at("schedule"), fixed);
      EXPECT_EQ(row.at("plan_status"), "file");
    } else {
      const ProcessResult p =
          runProcess({kCoordinator, "plan", "--scenario", scenario, "--surrogate",
                      row.at("surrogate").get<std::string>(), "--out", plan, "--json"});
      ASSERT_EQ(p.exit_code, 0) << p.err;
      const json planned = json::parse(p.out);
      EXPECT_EQ(row.at("objective"), planned.at("objective")) << row.dump();
      EXPECT_EQ(row.at("bracket_cov"), planned.at("bracket").at("cov"));
    }
    std::ifstream in(plan);
    const json schedule = json::parse(in);
    std::vector<double> used(5, 0.0);
    for (const json& interval : schedule.at("rates")) {
      for (std::size_t j = 0; j < 5; ++j) used[j] += interval.at(j).get<double>() * 2.0 / 6.0;
    }
    EXPECT_LE(*std::max_element(used.begin(), used.end()), energy * (1.0 + 1e-9)) << row.dump();
    if (energy == 0.8 && row.at("planner") != "uniform" && !fixed_schedule) {
      // 4 Hz x 2 s = 8 measurements to share against 5 x 0.8 = 4: every budget binds.
      EXPECT_GE(*std::min_element(used.begin(), used.end()), 0.8 * (1.0 - 1e-4)) << row.dump();
    }
    const bool timetable = row.at("planner") == "timetable";
    const ProcessResult e = runProcess(
        {kFusionCenter, "evaluate", "--scenario", scenario, "--schedule", plan, "--runs", "200",
         "--seed", row.at("seed").dump(), "--arrivals", timetable ? "timetable" : "poisson",
         "--json"});
    ASSERT_EQ(e.exit_code, 0) << e.err;
    const json evaluated = json::parse(e.out);
    if (timetable) {
      EXPECT_EQ(row.at("mean"), evaluated.at("timetable").at("cost")) << row.dump();
      EXPECT_EQ(row.at("poisson_mean"), evaluated.at("mc").at("mean")) << row.dump();
    } else {
      EXPECT_EQ(row.at("mean"), evaluated.at("mc").at("mean")) << row.dump();
    }
    EXPECT_EQ(row.at("bracket_info"), evaluated.at("bracket").at("info")) << row.dump();
  }
}

TEST(SweepCli, CtrlCKeepsTheCellsDoneAndTheSameCommandGoesOn) {
  const sensornet::testing::ScratchDir dir;
  const std::string file = dir.write("small.yaml", experiment(20000, "[1, 2, 3, 4, 5, 6]"));
  const std::string results = dir.file("out/results.jsonl");
  const std::vector<std::string> argv = {kLauncher,       "sweep",  file, "--out",
                                         dir.file("out"), "--jobs", "1"};
  {
    sensornet::testing::BackgroundProcess sweep(argv, dir.file("first.log"));
    // Ctrl-C once some cells are done (the 24 cells take tens of seconds).
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(60);
    while (linesOf(results).size() < 2 && std::chrono::steady_clock::now() < deadline) {
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    ::kill(sweep.pid(), SIGINT);
    EXPECT_EQ(sweep.waitForExit(std::chrono::seconds(30)), std::optional<int>(1));
  }
  const std::vector<std::string> before = linesOf(results);
  ASSERT_GE(before.size(), 2u);
  ASSERT_LT(before.size(), 24u) << "the sweep ended before Ctrl-C";
  std::ifstream log(dir.file("first.log"));
  std::stringstream said;
  said << log.rdbuf();
  EXPECT_NE(said.str().find("interrupted: " + std::to_string(before.size()) + " of 24 cells done"),
            std::string::npos)
      << said.str();

  const ProcessResult r = runProcess(argv, std::chrono::minutes(5));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find(std::to_string(before.size()) + " done before, " +
                       std::to_string(24 - before.size()) + " to run"),
            std::string::npos)
      << r.err;
  const std::vector<std::string> after = linesOf(results);
  ASSERT_EQ(after.size(), 24u);
  for (std::size_t i = 0; i < before.size(); ++i) EXPECT_EQ(after[i], before[i]);  // untouched
  std::set<std::string> keys;
  for (const std::string& line : after) keys.insert(json::parse(line).at("key").get<std::string>());
  EXPECT_EQ(keys.size(), 24u);  // no cell twice
}

TEST(SweepCli, AFailedCellRunsAgainOnlyWhenAsked) {
  const sensornet::testing::ScratchDir dir;
  const std::string file = dir.write("small.yaml", experiment(100, "[1]"));
  const std::vector<std::string> argv = {kLauncher, "sweep", file, "--out", dir.file("out")};
  ASSERT_EQ(runProcess(argv).exit_code, 0);
  // As if the first cell had failed in an earlier run.
  std::vector<json> rows = rowsOf(dir.file("out/results.jsonl"));
  ASSERT_EQ(rows.size(), 4u);
  json failed = rows[0];
  failed["status"] = "failed";
  failed["reason"] = "the machine ran out of memory";
  std::ofstream(dir.file("out/results.jsonl")) << failed.dump() << "\n";

  ProcessResult r = runProcess(argv);
  EXPECT_EQ(r.exit_code, 1) << r.err;  // a cell failed
  EXPECT_NE(r.err.find("4 cells, 1 failed"), std::string::npos) << r.err;
  EXPECT_EQ(rowsOf(dir.file("out/results.jsonl")).size(), 4u);  // the failed one was not run

  r = runProcess({kLauncher, "sweep", file, "--out", dir.file("out"), "--retry-failed"});
  EXPECT_EQ(r.exit_code, 0) << r.err;
  rows = rowsOf(dir.file("out/results.jsonl"));
  ASSERT_EQ(rows.size(), 5u);
  EXPECT_EQ(rows.back().at("key"), failed.at("key"));
  EXPECT_EQ(rows.back().at("status"), "ok");
  // The table has the cell's last row only.
  const std::vector<std::string> csv = linesOf(dir.file("out/results.csv"));
  ASSERT_EQ(csv.size(), 5u);
  for (const std::string& line : csv) EXPECT_EQ(line.find("out of memory"), std::string::npos);
}

// Emulated cells (`emulate:`): each is a whole `sensornet launch` of its scenario and plan.
// 2 planners x 2 networks x 2 fault sets = 8 cells, a run of 2 episodes each. Checked against
// what is recomputed here, not the rows' own word:
// - each row's mean and interval are the report's complete episodes' costs (Student t, 95%);
// - the run outcome follows the table (docs/ARCHITECTURE.md): loss the network section asks for
//   degrades nothing (exit 0, completed); a scripted crash under --on-sensor-failure stop fails
//   the run (exit 1), so the cell is failed, naming the crash, and the others still run;
// - every measurement sent is accounted for: sent = received + lost + dropped_by_network;
// - a timetable cell on a perfect network costs what `fusion_center evaluate --arrivals
//   timetable` computes offline, to 1e-4 relative (the emulation puts each instant on the
//   plant's tick, T / 2^20, the offline evaluation does not);
// - a lossy cov cell's plan is `coordinator plan --network-aware` of a scenario file written
//   here, and a native `sensornet launch` of it with the same seed gives the same cost in every
//   episode, bit for bit;
// - Ctrl-C stops the run under way and leaves none of its processes; the same command then
//   runs the cells not yet done, and those done are untouched.
TEST(SweepCli, EmulatedCellsAreTheRunsOfSensornetLaunch) {
  const sensornet::testing::ScratchDir dir;
  const std::string file =
      dir.write("emulated.yaml",
                "scenarios:\n  - random: {states: 3, sensors: 4, seed: 6, budget: 5}\n"
                "    horizon: 2\n    intervals: 8\n"
                "planners: [cov, {timetable: info}]\n"
                "seeds: [7]\n"
                "emulate:\n"
                "  episodes: 2\n  time_scale: 4\n  on_sensor_failure: stop\n"
                "  network: {perfect: ~, lossy: {default: {loss: 0.3}}}\n"
                "  faults: {none: [], crash: [{kind: crash, sensor: 2, episode: 1, at: 0.5}]}\n");
  const std::string results = dir.file("out/results.jsonl");
  const std::vector<std::string> argv = {kLauncher, "sweep", file, "--out", dir.file("out")};
  {
    sensornet::testing::BackgroundProcess sweep(argv, dir.file("first.log"));
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(120);
    while (linesOf(results).size() < 1 && std::chrono::steady_clock::now() < deadline) {
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(1500));  // the next run under way
    const std::string runs = "sweep-" + std::to_string(sweep.pid()) + "-";
    EXPECT_FALSE(sensornet::testing::processesMentioning(runs).empty()) << "no run under way";
    ::kill(sweep.pid(), SIGINT);
    EXPECT_EQ(sweep.waitForExit(std::chrono::seconds(60)), std::optional<int>(1));
    EXPECT_EQ(sensornet::testing::processesMentioning(runs), std::vector<pid_t>{});
  }
  const std::vector<std::string> before = linesOf(results);
  ASSERT_GE(before.size(), 1u);
  ASSERT_LT(before.size(), 8u) << "the sweep ended before Ctrl-C";

  const ProcessResult r = runProcess(argv, std::chrono::minutes(5));
  EXPECT_EQ(r.exit_code, 1) << r.err;  // the crash cells failed
  EXPECT_NE(r.err.find("8 cells, 4 failed"), std::string::npos) << r.err;
  const std::vector<std::string> after = linesOf(results);
  ASSERT_EQ(after.size(), 8u);
  for (std::size_t i = 0; i < before.size(); ++i) EXPECT_EQ(after[i], before[i]);

  int checked_timetable = 0, checked_native = 0;
  for (const std::string& line : after) {
    const json row = json::parse(line);
    SCOPED_TRACE(row.at("key").get<std::string>());
    const bool crash = row.at("faults") == "crash";
    const bool lossy = row.at("network") == "lossy";
    std::ifstream in(row.at("report").get<std::string>());
    const json report = json::parse(in);
    EXPECT_EQ(row.at("exit_code"), crash ? 1 : 0);
    EXPECT_EQ(row.at("run_status"), crash ? "failed" : "completed");
    EXPECT_EQ(row.at("status"), crash ? "failed" : "ok");
    if (crash) {
      EXPECT_NE(row.at("reason").get<std::string>().find("crash in sensor_agent-2"),
                std::string::npos);
      continue;
    }
    // The mean and its interval from the episodes' costs.
    std::vector<double> costs;
    std::uint64_t sent = 0, accounted = 0;
    for (const json& e : report.at("per_episode")) {
      if (e.at("complete").get<bool>()) costs.push_back(e.at("realized_cost").get<double>());
      for (std::size_t j = 0; j < e.at("sent").size(); ++j) {
        sent += e.at("sent")[j].get<std::uint64_t>();
        accounted += e.at("received")[j].get<std::uint64_t>() +
                     e.at("lost")[j].get<std::uint64_t>() +
                     e.at("dropped_by_network")[j].get<std::uint64_t>();
      }
    }
    ASSERT_EQ(costs.size(), 2u);
    const double mean = (costs[0] + costs[1]) / 2.0;
    const double sd = std::abs(costs[0] - costs[1]) / std::sqrt(2.0);
    EXPECT_NEAR(row.at("mean").get<double>(), mean, 1e-12 * mean);
    EXPECT_NEAR(row.at("ci95").get<double>(), 12.7062047361747 * sd / std::sqrt(2.0), 1e-9 * mean);
    EXPECT_EQ(row.at("sent"), sent);
    EXPECT_EQ(sent, accounted);
    EXPECT_GT(sent, 0u);
    EXPECT_EQ(row.at("dropped_by_network").get<std::uint64_t>() > 0, lossy);

    const std::string scenario = dir.write(
        "plant-" + row.at("network").get<std::string>() + ".yaml",
        "horizon: 2\nintervals: 8\nrandom: {states: 3, sensors: 4, seed: 6, budget: 5}\n" +
            std::string(lossy ? "network: {default: {loss: 0.3}}\n" : ""));
    const std::string schedule = std::filesystem::path(row.at("report").get<std::string>())
                                     .replace_filename("schedule.json")
                                     .string();
    if (row.at("planner") == "timetable" && !lossy) {
      const ProcessResult e =
          runProcess({kFusionCenter, "evaluate", "--scenario", scenario, "--schedule", schedule,
                      "--runs", "10", "--seed", "7", "--arrivals", "timetable", "--json"});
      ASSERT_EQ(e.exit_code, 0) << e.err;
      const double offline = json::parse(e.out).at("timetable").at("cost").get<double>();
      EXPECT_NEAR(costs[0], offline, 1e-4 * offline);
      EXPECT_EQ(costs[0], costs[1]);  // the same instants in every episode, no noise in the cost
      ++checked_timetable;
    }
    if (row.at("planner") == "cov" && lossy) {
      const std::string plan = dir.file("native-plan.json");
      const ProcessResult p =
          runProcess({kCoordinator, "plan", "--scenario", scenario, "--surrogate", "cov",
                      "--network-aware", "--out", plan, "--json"});
      ASSERT_EQ(p.exit_code, 0) << p.err;
      EXPECT_EQ(row.at("objective"), json::parse(p.out).at("objective"));
      std::ifstream planned(plan), used(schedule);
      EXPECT_EQ(json::parse(planned).at("rates"), json::parse(used).at("rates"));
      const ProcessResult native = runProcess(
          {kLauncher, "launch", scenario, "--schedule", plan, "--episodes", "2", "--time-scale",
           "4", "--seed", "7", "--run-id", "native-" + std::to_string(::getpid()), "--report",
           dir.file("native/report.json"), "--log-dir", dir.file("native/logs"), "--no-html"},
          std::chrono::minutes(2));
      ASSERT_EQ(native.exit_code, 0) << native.err;
      std::ifstream native_in(dir.file("native/report.json"));
      const json native_report = json::parse(native_in);
      for (std::size_t k = 0; k < 2; ++k) {
        EXPECT_EQ(native_report.at("per_episode")[k].at("realized_cost").get<double>(), costs[k]);
      }
      ++checked_native;
    }
  }
  EXPECT_EQ(checked_timetable, 1);
  EXPECT_EQ(checked_native, 1);
}

TEST(SweepCli, ABadExperimentIsOneLineAndExitTwo) {
  const sensornet::testing::ScratchDir dir;
  const std::string file = dir.write(
      "bad.yaml", "scenarios:\n  - random: {states: 3, sensors: 5, seed: 1}\nplanners: [inf]\n");
  const ProcessResult r = runProcess({kLauncher, "sweep", file, "--out", dir.file("out")});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("bad.yaml:3: planners[0]: expected info, cov"), std::string::npos) << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  EXPECT_FALSE(std::filesystem::exists(dir.file("out/results.jsonl")));
}

}  // namespace
}  // namespace sensornet
