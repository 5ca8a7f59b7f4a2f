// `coordinator plan --surrogate mc`: the Monte Carlo planner from the command line (its JSON
// keys, the schedule file's record, bad values refused with one line and a non-zero exit).

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>
#include <unistd.h>

#include "support/process.hpp"
#include "support/scratch_dir.hpp"

namespace sensornet {
namespace {

using sensornet::testing::ProcessResult;
using sensornet::testing::runProcess;

const std::string kCoordinator = SENSORNET_COORDINATOR;
const std::string kDefaultScenario = std::string(SENSORNET_SOURCE_DIR) + "/scenarios/default.yaml";

// The planned E[J] with its half-width sits in the schedule's own bracket (Corollary 1 of the
// first paper: J(P_info) <= E[J] <= J(P_cov), computed by the surrogate rollouts, independently
// of the Monte Carlo), and the file records objective, half-width and episodes.
TEST(CoordinatorPlanMc, ReportsMeanHalfWidthAndEpisodesInsideTheBracket) {
  const sensornet::testing::ScratchDir dir;
  const std::string out = dir.file("plan.json");
  const ProcessResult r =
      runProcess({kCoordinator, "plan", "--scenario", kDefaultScenario, "--surrogate", "mc",
                  "--max-seconds", "8", "--out", out, "--json"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto doc = nlohmann::json::parse(r.out);
  EXPECT_EQ(doc.at("surrogate"), "mc");
  EXPECT_TRUE(doc.at("status") == "improved" || doc.at("status") == "kept_start") << doc;
  const double objective = doc.at("objective").get<double>();
  const double half = doc.at("objective_half_width").get<double>();
  EXPECT_GT(half, 0.0);
  EXPECT_GT(doc.at("episodes").get<long long>(), 0);
  EXPECT_GE(objective + half, doc.at("bracket").at("info").get<double>());
  EXPECT_LE(objective - half, doc.at("bracket").at("cov").get<double>());
  std::ifstream file(out);
  const auto written = nlohmann::json::parse(file);
  std::filesystem::remove(out);
  EXPECT_EQ(written.dump().find("\"objective_half_width\"") != std::string::npos, true)
      << written.dump();
  EXPECT_NE(written.dump().find("\"episodes\""), std::string::npos) << written.dump();
}

TEST(CoordinatorPlanMc, BadValuesGiveOneLineAndNonZeroExit) {
  const sensornet::testing::ScratchDir dir;
  const std::string out = dir.file("bad.json");
  for (const auto& args : {std::vector<std::string>{"--surrogate", "montecarlo"},
                           std::vector<std::string>{"--surrogate", "mc", "--max-seconds", "0"}}) {
    std::vector<std::string> command = {kCoordinator, "plan", "--scenario", kDefaultScenario,
                                        "--out", out};
    command.insert(command.end(), args.begin(), args.end());
    const ProcessResult r = runProcess(command);
    EXPECT_NE(r.exit_code, 0) << r.out;
    EXPECT_NE(r.err.find(args[args.size() - 2]), std::string::npos) << r.err;
    EXPECT_EQ(r.err.find('\n'), r.err.size() - 1) << r.err;
  }
}

}  // namespace
}  // namespace sensornet
