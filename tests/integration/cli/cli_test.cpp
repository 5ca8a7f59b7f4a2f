// The command-line contracts of the issue: exact flags and JSON keys, one-line errors with a
// non-zero exit on bad input. Runs the real programs.

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <unistd.h>

#include "support/process.hpp"
#include "support/scratch_dir.hpp"

namespace sensornet {
namespace {

using sensornet::testing::ProcessResult;
using sensornet::testing::runProcess;
using sensornet::testing::ScratchDir;

const std::string kCoordinator = SENSORNET_COORDINATOR;
const std::string kFusionCenter = SENSORNET_FUSION_CENTER;
const std::string kDefaultScenario = std::string(SENSORNET_SOURCE_DIR) + "/scenarios/default.yaml";

void expectOneLineError(const ProcessResult& r, const std::string& must_contain) {
  EXPECT_NE(r.exit_code, 0) << r.out;
  EXPECT_FALSE(r.timed_out);
  EXPECT_NE(r.err.find(must_contain), std::string::npos) << r.err;
  // One line: the message ends with the only newline.
  EXPECT_EQ(r.err.find('\n'), r.err.size() - 1) << r.err;
  EXPECT_TRUE(r.out.empty()) << r.out;
}

// Eq. (14) of the Brownian paper, minimized by brute force (independent of the closed form).
double bruteForceSingleInstant(double s2, double T, double v0, double v1) {
  auto cost = [&](double t) {
    return s2 * t * t / 2 + v0 * t + s2 * (T - t) * (T - t) / 2 +
           (s2 * t + v0) * v1 * (T - t) / (s2 * t + v0 + v1);
  };
  double best_t = 0.0;
  for (int i = 0; i <= 200000; ++i) {
    const double t = T * i / 200000.0;
    if (cost(t) < cost(best_t)) best_t = t;
  }
  return best_t;
}

TEST(CoordinatorTimetable, OneMeasureMatchesABruteForceMinimum) {
  const ProcessResult r = runProcess({kCoordinator, "timetable", "--sigma2", "1.5", "--horizon",
                                      "2", "--v0", "0.3", "--variances", "0.7", "--json"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto doc = nlohmann::json::parse(r.out);
  ASSERT_EQ(doc["instants"].size(), 1u);
  EXPECT_NEAR(doc["instants"][0].get<double>(), bruteForceSingleInstant(1.5, 2, 0.3, 0.7), 2e-5);
  EXPECT_LE(doc["cost"].get<double>(), doc["regular_cost"].get<double>());
  EXPECT_EQ(doc["regime"].get<int>(), 2);
}

TEST(CoordinatorTimetable, TwoMeasuresReproduceThePapersTable) {
  // Fig. 7, row b): σ² = 1, v = (1, 1, 1), T = 71/18 -> (1.0401, 2.4092), regime 3.
  const ProcessResult r =
      runProcess({kCoordinator, "timetable", "--sigma2", "1", "--horizon", std::to_string(71.0 / 18),
                  "--v0", "1", "--variances", "1,1", "--json"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto doc = nlohmann::json::parse(r.out);
  EXPECT_NEAR(doc["instants"][0].get<double>(), 1.0401, 1e-4);
  EXPECT_NEAR(doc["instants"][1].get<double>(), 2.4092, 1e-4);
  EXPECT_EQ(doc["regime"].get<int>(), 3);
}

TEST(CoordinatorTimetable, ThreeMeasuresHaveNoRegime) {
  const ProcessResult r = runProcess({kCoordinator, "timetable", "--sigma2", "1", "--horizon", "3",
                                      "--v0", "1", "--variances", "1,2,3", "--json"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto doc = nlohmann::json::parse(r.out);
  EXPECT_EQ(doc["instants"].size(), 3u);
  EXPECT_FALSE(doc.contains("regime"));
}

TEST(CoordinatorTimetable, BadInputGivesOneLineAndNonZeroExit) {
  expectOneLineError(runProcess({kCoordinator, "timetable", "--sigma2", "-1", "--horizon", "1",
                                 "--v0", "1", "--variances", "1"}),
                     "sigma2");
  expectOneLineError(runProcess({kCoordinator, "timetable", "--sigma2", "1", "--horizon", "0",
                                 "--v0", "1", "--variances", "1"}),
                     "horizon");
  expectOneLineError(runProcess({kCoordinator, "timetable", "--sigma2", "1", "--horizon", "1",
                                 "--v0", "1", "--variances", "1,abc"}),
                     "variances");
  expectOneLineError(runProcess({kCoordinator, "timetable", "--sigma2", "1", "--horizon", "1",
                                 "--v0", "1", "--variances", "1,-2"}),
                     "variances");
  expectOneLineError(
      runProcess({kCoordinator, "timetable", "--sigma2", "1", "--v0", "1", "--variances", "1"}),
      "--horizon");
  expectOneLineError(runProcess({kCoordinator, "frobnicate"}),
                     "unknown subcommand 'frobnicate' (expected one of: plan, serve, timetable");
  expectOneLineError(runProcess({kFusionCenter}), "subcommand is required");
}

TEST(FusionCenterEvaluate, PrintsTheContractedJson) {
  const ProcessResult r = runProcess({kFusionCenter, "evaluate", "--scenario", kDefaultScenario,
                                      "--runs", "400", "--seed", "3", "--json"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto doc = nlohmann::json::parse(r.out);
  const double info = doc.at("bracket").at("info").get<double>();
  const double cov = doc.at("bracket").at("cov").get<double>();
  EXPECT_LE(info, cov);
  EXPECT_GT(doc.at("mc").at("mean").get<double>(), 0.0);
  EXPECT_GT(doc.at("mc").at("std").get<double>(), 0.0);
  EXPECT_NEAR(doc.at("mc").at("ci95").get<double>(),
              1.96 * doc["mc"]["std"].get<double>() / std::sqrt(400.0), 1e-9);
  EXPECT_EQ(doc.at("mc").at("runs").get<int>(), 400);
  EXPECT_TRUE(doc.at("nees").is_number());

  // Same seed, same answer; the thread count does not matter.
  const ProcessResult again =
      runProcess({kFusionCenter, "evaluate", "--scenario", kDefaultScenario, "--runs", "400",
                  "--seed", "3", "--threads", "1", "--json"});
  ASSERT_EQ(again.exit_code, 0) << again.err;
  EXPECT_EQ(nlohmann::json::parse(again.out)["mc"], doc["mc"]);
}

TEST(FusionCenterEvaluate, EvaluatesAGivenScheduleFile) {
  ScratchDir dir;
  // All budget on the precise radars; feasible for the default scenario (C rows: total <= 12,
  // camera*2 + doppler <= 6).
  std::string rates = "[";
  for (int k = 0; k < 30; ++k) rates += std::string(k ? "," : "") + "[6, 6, 0, 0, 0, 0]";
  rates += "]";
  const std::string schedule =
      dir.write("s.json", R"({"horizon": 3.0, "intervals": 30, "note": "extra keys are fine", "rates": )" +
                              rates + "}");
  const ProcessResult r = runProcess({kFusionCenter, "evaluate", "--scenario", kDefaultScenario,
                                      "--schedule", schedule, "--runs", "200", "--json"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(nlohmann::json::parse(r.out)["schedule"], schedule);
}

TEST(FusionCenterEvaluate, BadInputGivesOneLineAndNonZeroExit) {
  ScratchDir dir;
  expectOneLineError(runProcess({kFusionCenter, "evaluate", "--scenario", "/no/such.yaml"}),
                     "/no/such.yaml");
  const std::string bad_scenario =
      dir.write("bad.yaml", "horizon: 1\nintervals: 2\nplant:\n  A: [[0]]\n  Q: [[1]]\n"
                            "  P0: [[-1]]\nsensors:\n  - {H: [[1]], R: [[1]]}\n"
                            "constraints: {b: [1]}\n");
  expectOneLineError(runProcess({kFusionCenter, "evaluate", "--scenario", bad_scenario}),
                     "plant.P0");
  const std::string infeasible = dir.write(
      "s.json", R"({"horizon": 3.0, "intervals": 1, "rates": [[1, 1, 1, 1, 1, 1]]})");
  expectOneLineError(runProcess({kFusionCenter, "evaluate", "--scenario", kDefaultScenario,
                                 "--schedule", infeasible}),
                     "rates");
  expectOneLineError(runProcess({kFusionCenter, "evaluate", "--scenario", kDefaultScenario,
                                 "--runs", "0"}),
                     "--runs");
  expectOneLineError(runProcess({kFusionCenter, "evaluate"}), "--scenario");
}

// `coordinator plan` writes a schedule that `fusion_center evaluate` accepts, and its JSON agrees
// with an independent evaluation of that file: the bracket `evaluate` computes for the written
// schedule is the one `plan` printed, and the planned surrogate beats the uniform schedule's.
TEST(CoordinatorPlan, WritesAScheduleWhoseBracketEvaluateConfirms) {
  ScratchDir dir;
  const ProcessResult uniform = runProcess({kFusionCenter, "evaluate", "--scenario",
                                            kDefaultScenario, "--runs", "2", "--json"});
  ASSERT_EQ(uniform.exit_code, 0) << uniform.err;
  const auto uniform_bracket = nlohmann::json::parse(uniform.out)["bracket"];
  for (const std::string surrogate : {"info", "cov"}) {
    const std::string out = dir.write(surrogate + ".json", "");
    const ProcessResult r = runProcess({kCoordinator, "plan", "--scenario", kDefaultScenario,
                                        "--surrogate", surrogate, "--out", out, "--json"});
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const auto doc = nlohmann::json::parse(r.out);
    EXPECT_EQ(doc.at("surrogate"), surrogate);
    EXPECT_EQ(doc.at("status"), "optimal");
    EXPECT_GT(doc.at("iterations").get<int>(), 0);
    EXPECT_GE(doc.at("solve_seconds").get<double>(), 0.0);
    const double objective = doc.at("objective").get<double>();
    EXPECT_DOUBLE_EQ(objective, doc.at("bracket").at(surrogate).get<double>());
    EXPECT_LT(objective, uniform_bracket.at(surrogate).get<double>());

    const ProcessResult check = runProcess({kFusionCenter, "evaluate", "--scenario",
                                            kDefaultScenario, "--schedule", out, "--runs", "2",
                                            "--json"});
    ASSERT_EQ(check.exit_code, 0) << check.err;
    const auto bracket = nlohmann::json::parse(check.out)["bracket"];
    for (const char* side : {"info", "cov"}) {
      EXPECT_NEAR(bracket.at(side).get<double>(), doc["bracket"][side].get<double>(),
                  1e-9 * bracket.at(side).get<double>())
          << side;
    }
  }
}

TEST(CoordinatorPlan, BadInputGivesOneLineAndNonZeroExit) {
  ScratchDir dir;
  const std::string out = dir.write("p.json", "");
  expectOneLineError(runProcess({kCoordinator, "plan", "--scenario", kDefaultScenario,
                                 "--surrogate", "best", "--out", out}),
                     "--surrogate");
  expectOneLineError(runProcess({kCoordinator, "plan", "--scenario", kDefaultScenario,
                                 "--exclude", "6", "--out", out}),
                     "--exclude");
  expectOneLineError(runProcess({kCoordinator, "plan", "--scenario", "/no/such.yaml", "--out",
                                 out}),
                     "/no/such.yaml");
  expectOneLineError(runProcess({kCoordinator, "plan", "--scenario", kDefaultScenario}), "--out");
}

}  // namespace
}  // namespace sensornet
