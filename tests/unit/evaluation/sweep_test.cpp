// The cells of `sensornet sweep` and their results file (sweep.hpp): a finished cell is a whole
// line at once, a torn last line is cut off, another file is refused, a failing cell is a row
// that says why, and a stopped cell is no row at all.

#include "sensornet/evaluation/sweep.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "sensornet/core/input_error.hpp"
#include "support/scratch_dir.hpp"

namespace sensornet::evaluation {
namespace {

using nlohmann::json;

std::string readAll(const std::string& path) {
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

SweepCell smallCell(const std::string& planner, std::uint64_t seed) {
  SweepCell cell;
  RandomPlantSpec spec;
  spec.state_dim = 2;
  spec.sensor_count = 3;
  spec.intervals = 4;
  spec.horizon_s = 1.0;
  cell.scenario.random = spec;
  cell.planner = planner;
  cell.surrogate = planner == "cov" ? PlanSurrogate::Covariance : PlanSurrogate::Information;
  cell.seed = seed;
  cell.runs = 50;
  return cell;
}

TEST(SweepResults, KeepsWholeRowsAndCutsATornLastLine) {
  testing::ScratchDir dir;
  const std::string path = dir.file("results.jsonl");
  {
    SweepResults results(path);
    EXPECT_EQ(results.size(), 0u);
    results.append({{"key", "a"}, {"status", "ok"}, {"mean", 1.5}});
    results.append({{"key", "b"}, {"status", "failed"}, {"reason", "x, \"quoted\""}});
  }
  std::ofstream(path, std::ios::app) << R"({"key": "c", "sta)";  // a crash mid-write
  SweepResults again(path);
  EXPECT_TRUE(again.has("a"));
  EXPECT_TRUE(again.has("b"));
  EXPECT_FALSE(again.has("c"));
  EXPECT_EQ(again.failed(), 1u);
  EXPECT_EQ(readAll(path).back(), '\n');  // the torn line is gone from the file too
  again.append({{"key", "c"}, {"status", "ok"}});
  EXPECT_TRUE(SweepResults(path).has("c"));

  again.writeCsv(dir.file("results.csv"), {"b", "a", "not-run"});
  const std::string csv = readAll(dir.file("results.csv"));
  EXPECT_EQ(csv.substr(0, csv.find('\n')).substr(0, 16), "scenario,states,");
  // Rows in the order asked, a field with a comma or a quote quoted, a cell not run left out.
  EXPECT_LT(csv.find("\"x, \"\"quoted\"\"\""), csv.find(",1.5,"));
  EXPECT_EQ(std::count(csv.begin(), csv.end(), '\n'), 3);

  again.forgetFailed();
  EXPECT_FALSE(again.has("b"));
}

TEST(SweepResults, AnotherFileIsRefusedByLine) {
  testing::ScratchDir dir;
  const std::string path =
      dir.write("results.jsonl", "{\"key\": \"a\", \"status\": \"ok\"}\nnot json\n");
  try {
    SweepResults results(path);
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("results.jsonl:2"), std::string::npos) << e.what();
  }
}

TEST(SweepCell, AScenarioThatFailsIsAFailedRowWithItsReason) {
  SweepCell cell = smallCell("info", 1);
  cell.scenario.random.reset();
  cell.scenario.file = "/nonexistent/scenario.yaml";
  const std::atomic<bool> stop{false};
  const json row = runSweepCell(cell, 1, stop);
  EXPECT_EQ(row.at("status"), "failed");
  EXPECT_NE(row.at("reason").get<std::string>().find("/nonexistent/scenario.yaml"),
            std::string::npos);
  EXPECT_EQ(row.at("key"), cell.key());
}

TEST(SweepCell, AStoppedCellIsNoResult) {
  const std::atomic<bool> stop{true};
  EXPECT_THROW((void)runSweepCell(smallCell("info", 1), 1, stop), SweepStopped);
}

TEST(SweepCell, TheRowHoldsThePlanItsBracketAndTheMonteCarlo) {
  const std::atomic<bool> stop{false};
  const json info = runSweepCell(smallCell("info", 3), 1, stop);
  ASSERT_EQ(info.at("status"), "ok") << info.dump();
  EXPECT_LE(info.at("bracket_info").get<double>(), info.at("bracket_cov").get<double>());
  EXPECT_EQ(info.at("objective").get<double>(), info.at("bracket_info").get<double>());
  EXPECT_EQ(info.at("runs"), 50);
  // The same cell on more threads: the same numbers (the Monte Carlo is keyed by episode).
  const json again = runSweepCell(smallCell("info", 3), 3, stop);
  EXPECT_EQ(again.at("mean"), info.at("mean"));
  // Another seed, another sample.
  EXPECT_NE(runSweepCell(smallCell("info", 4), 1, stop).at("mean"), info.at("mean"));
}

}  // namespace
}  // namespace sensornet::evaluation
