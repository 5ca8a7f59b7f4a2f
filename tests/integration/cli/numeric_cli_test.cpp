// Bad numbers end the programs at once: exit status 2 and exactly one line on standard error
// that names the file (and its line) and the field, or the option and its range in readable
// numbers. Runs the real programs on mutated copies of the shipped default scenario.

#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <utility>

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

std::string defaultScenarioText() {
  std::ifstream in(kDefaultScenario);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

// The default scenario with the first `from` replaced by `to`, and the 1-based line where the
// replacement starts.
std::pair<std::string, int> mutatedDefault(const std::string& from, const std::string& to) {
  std::string text = defaultScenarioText();
  const auto at = text.find(from);
  if (at == std::string::npos) throw std::logic_error("default.yaml has no '" + from + "'");
  text.replace(at, from.size(), to);
  return {text, static_cast<int>(std::count(text.begin(), text.begin() + at, '\n')) + 1};
}

// Exit 2, nothing on standard output, exactly one line on standard error containing every
// string of `parts`.
void expectBadInput(const ProcessResult& r, std::initializer_list<std::string> parts) {
  EXPECT_FALSE(r.timed_out);
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_TRUE(r.out.empty()) << r.out;
  ASSERT_FALSE(r.err.empty());
  EXPECT_EQ(r.err.find('\n'), r.err.size() - 1) << "not exactly one line:\n" << r.err;
  for (const std::string& part : parts) {
    EXPECT_NE(r.err.find(part), std::string::npos) << "no '" << part << "' in: " << r.err;
  }
}

ProcessResult planWith(const ScratchDir& dir, const std::string& scenario_text) {
  const std::string scenario = dir.write("scenario.yaml", scenario_text);
  return runProcess({kCoordinator, "plan", "--scenario", scenario, "--surrogate", "info", "--out",
                     dir.write("plan.json", "")});
}

TEST(NumericCli, PlanRefusesAnHWhoseInformationOverflows) {
  const ScratchDir dir;
  // The first sensor (x-radar): H = [1e308, 0, 0, 0], so H' R^-1 H holds 1e616.
  const auto [text, line] = mutatedDefault("H: [[1, 0, 0, 0]]", "H: [[1e308, 0, 0, 0]]");
  const ProcessResult r = planWith(dir, text);
  expectBadInput(
      r, {"scenario.yaml:" + std::to_string(line) + ": sensors[0].H: expected", "H' R^-1 H"});
}

TEST(NumericCli, PlanRefusesAnAWithHugeEntries) {
  const ScratchDir dir;
  const auto [text, line] = mutatedDefault("[0, 0, -0.5, 0],", "[0, 0, 1e308, 0],");
  const ProcessResult r = planWith(dir, text);
  // The field's line is the line where A starts, two lines above the changed row.
  expectBadInput(
      r, {"scenario.yaml:" + std::to_string(line - 2) + ": plant.A: expected", "|A| T finite"});
}

TEST(NumericCli, PlanRefusesAnOverflowingYamlNumber) {
  const ScratchDir dir;
  const auto [text, line] = mutatedDefault("b: [12, 6]", "b: [12, 1e309]");
  const ProcessResult r = planWith(dir, text);
  expectBadInput(r, {"scenario.yaml:" + std::to_string(line) + ": constraints.b[1]: expected",
                     "overflows a double"});
}

TEST(NumericCli, PlanRefusesAnOverflowingJsonWarmStart) {
  const ScratchDir dir;
  const std::string warm = dir.write(
      "warm.json", "{\"horizon\": 3, \"intervals\": 1,\n \"rates\": [[1, 1, 1, 1, 1, 1e309]]}\n");
  const ProcessResult r = runProcess({kCoordinator, "plan", "--scenario", kDefaultScenario,
                                      "--warm-start", warm, "--out", dir.write("plan.json", "")});
  expectBadInput(r, {"warm.json:2: rates[0][5]: expected a finite number", "overflows a double"});
}

TEST(NumericCli, EvaluateRefusesAnOverflowingJsonSchedule) {
  const ScratchDir dir;
  const std::string schedule =
      dir.write("s.json", "{\"horizon\": 3,\n \"intervals\": 1e999, \"rates\": []}\n");
  const ProcessResult r = runProcess({kFusionCenter, "evaluate", "--scenario", kDefaultScenario,
                                      "--schedule", schedule, "--runs", "10"});
  expectBadInput(r, {"s.json:2: intervals: expected a finite number", "overflows a double"});
}

TEST(NumericCli, ServeRefusesAnAbsurdTimeScaleAtOnceInReadableNumbers) {
  const auto start = std::chrono::steady_clock::now();
  const ProcessResult r =
      runProcess({kCoordinator, "serve", "--scenario", kDefaultScenario, "--run-id",
                  "numeric-cli-" + std::to_string(::getpid()), "--time-scale", "1e308"},
                 std::chrono::seconds(20));
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  expectBadInput(r, {"--time-scale", "0.001 to 10000", "1e+308"});
  EXPECT_LT(seconds, 5.0) << "refused only after " << seconds << " s";
  // No number spelled out in 300 digits (or anything like it).
  EXPECT_EQ(r.err.find("00000000000000000000"), std::string::npos) << r.err;
}

TEST(NumericCli, RangeErrorsNeverSpellOutTheLargestDouble) {
  // CLI::PositiveNumber printed its upper bound, DBL_MAX, with std::to_string: 309 digits.
  const ProcessResult r =
      runProcess({kFusionCenter, "serve", "--run-id", "numeric-cli", "--lag", "-1"});
  expectBadInput(r, {"--lag", "got -1"});
  EXPECT_LT(r.err.size(), 200u) << r.err;
}

}  // namespace
}  // namespace sensornet
