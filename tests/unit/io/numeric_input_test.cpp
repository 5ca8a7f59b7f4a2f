// Numbers in input files that overflow a double, and values whose derived quantities (A T,
// Q T, H' R^-1 H, the largest rate times T) are not finite or beyond what double precision can
// carry, are refused when the file is read: an InputError naming the file, its line and the
// field. Expected lines are counted in the test's own text, the overflows follow from IEEE
// doubles (the largest is about 1.8e308).

#include <gtest/gtest.h>

#include <algorithm>
#include <string>

#include "sensornet/core/input_error.hpp"
#include "sensornet/core/scenario.hpp"
#include "sensornet/io/scenario_file.hpp"

namespace sensornet {
namespace {

// A valid two-state, two-sensor scenario (T = 2 s); each test changes one line of it.
const char* kValid = R"(horizon: 2.0
intervals: 4
plant:
  A: [[0, 1], [0, -1]]
  Q: [[0, 0], [0, 1]]
  P0: [[10, 0], [0, 10]]
sensors:
  - H: [[1, 0]]
    R: [[1]]
  - H: [[1, 0], [0, 1]]
    R: [[2, 0.5], [0.5, 2]]
constraints:
  b: [3]
)";

struct Mutation {
  std::string text;
  int line = 0;  // 1-based line of the changed text
};

Mutation mutated(const std::string& from, const std::string& to) {
  std::string text = kValid;
  const auto at = text.find(from);
  if (at == std::string::npos) throw std::logic_error("fixture has no '" + from + "'");
  text.replace(at, from.size(), to);
  const auto line = static_cast<int>(std::count(text.begin(), text.begin() + at, '\n')) + 1;
  return {text, line};
}

// The InputError that parsing `text` throws; fails the test if none.
InputError scenarioError(const std::string& text) {
  try {
    (void)parseScenarioYaml(text, "bad.yaml");
  } catch (const InputError& e) {
    return e;
  }
  ADD_FAILURE() << "accepted:\n" << text;
  return InputError("", "", "");
}

void expectRefused(const Mutation& m, const std::string& field, const std::string& says) {
  const InputError e = scenarioError(m.text);
  const std::string message = e.what();
  EXPECT_EQ(e.field(), field) << message;
  EXPECT_EQ(message.rfind("bad.yaml:" + std::to_string(m.line) + ": " + field + ": expected ", 0),
            0u)
      << message;
  EXPECT_NE(message.find(says), std::string::npos) << message;
}

TEST(NumericInput, TheFixtureIsValid) {
  EXPECT_NO_THROW((void)parseScenarioYaml(kValid, "ok.yaml"));
}

// --- numbers that overflow a double -------------------------------------------------------

TEST(NumericInput, AnOverflowingYamlNumberNamesItsField) {
  expectRefused(mutated("Q: [[0, 0], [0, 1]]", "Q: [[0, 0], [0, 1e309]]"), "plant.Q[1][1]",
                "the number overflows a double");
  expectRefused(mutated("horizon: 2.0", "horizon: -1e400"), "horizon",
                "the number overflows a double");
  // A 400-digit number is not echoed in full.
  const InputError e = scenarioError(mutated("b: [3]", "b: [" + std::string(400, '9') + "]").text);
  EXPECT_LT(std::string(e.what()).size(), 200u) << e.what();
}

TEST(NumericInput, AnOverflowingJsonNumberNamesTheLineAndField) {
  const std::string text =
      "{\"horizon\": 2,\n \"intervals\": 2,\n \"rates\": [[1, 2],\n  [3, 1e309]]}";
  try {
    (void)parseScheduleJson(text, "plan.json");
    FAIL() << "accepted an overflowing rate";
  } catch (const InputError& e) {
    EXPECT_EQ(e.field(), "rates[1][1]");
    EXPECT_EQ(std::string(e.what()),
              "plan.json:4: rates[1][1]: expected a finite number, got 1e309 (the number "
              "overflows a double)");
  }
}

TEST(NumericInput, AnOverflowingJsonNumberInAnExtraKeyOrAStringIsHandled) {
  // An overflowing number in a key the reader ignores is still not valid input...
  const std::string extra =
      "{\"horizon\": 2, \"intervals\": 1, \"rates\": [[1]],\n \"note\": {\"cost\": -2e999}}";
  try {
    (void)parseScheduleJson(extra, "plan.json");
    FAIL() << "accepted an overflowing number";
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()),
              "plan.json:2: note.cost: expected a finite number, got -2e999 (the number "
              "overflows a double)");
  }
  // ...while the same characters inside a string are text.
  const std::string quoted =
      "{\"horizon\": 2, \"intervals\": 1, \"rates\": [[1]], \"x\": \"1e999\"}";
  EXPECT_NO_THROW((void)parseScheduleJson(quoted, "plan.json"));
}

// --- derived quantities ---------------------------------------------------------------------

TEST(NumericInput, HugeHIsRefusedBecauseItsInformationOverflows) {
  // (1e308)^2 overflows: H' R^-1 H is infinite.
  expectRefused(mutated("- H: [[1, 0]]", "- H: [[1e308, 0]]"), "sensors[0].H",
                "information H' R^-1 H is finite");
}

TEST(NumericInput, HWhoseInformationDwarfsThePriorIsRefused) {
  // H = 1e10: H' R^-1 H = 1e20, already 1e21 times the prior information P0^-1 = I/10.
  expectRefused(mutated("- H: [[1, 0]]", "- H: [[1e10, 0]]"), "sensors[0].H",
                "times as informative as the prior");
  // H = 100: relative information 1e5 (and below 1e12 at T too): a precise but valid sensor.
  EXPECT_NO_THROW((void)parseScenarioYaml(mutated("- H: [[1, 0]]", "- H: [[100, 0]]").text, "ok"));
}

TEST(NumericInput, AWithHugeEntriesIsRefused) {
  // 1e308 x T = 2e308 overflows.
  expectRefused(mutated("A: [[0, 1], [0, -1]]", "A: [[0, 1e308], [0, -1]]"), "plant.A",
                "|A| T finite");
  // Finite A T = 2e200, but far faster than anything a rollout can resolve.
  expectRefused(mutated("A: [[0, 1], [0, -1]]", "A: [[0, 1e200], [0, -1]]"), "plant.A",
                "||A||_2 T <= 100000");
}

TEST(NumericInput, APlantThatGrowsBeyondADoubleOverTheHorizonIsRefused) {
  // Re eig = 200 over T = 2: the covariance grows like exp(800), beyond the largest double.
  expectRefused(mutated("A: [[0, 1], [0, -1]]", "A: [[200, 1], [0, -1]]"), "plant.A",
                "max Re eig(A) T <= 350");
  // A fast oscillation (|A| T = 2000) that neither grows nor decays is fine.
  EXPECT_NO_THROW((void)parseScenarioYaml(
      mutated("A: [[0, 1], [0, -1]]", "A: [[0, 1000], [-1000, 0]]").text, "ok"));
}

TEST(NumericInput, HugeProcessNoiseIsRefused) {
  // 1e308 x T = 2e308 overflows.
  expectRefused(mutated("Q: [[0, 0], [0, 1]]", "Q: [[0, 0], [0, 1e308]]"), "plant.Q",
                "|Q| T finite");
}

TEST(NumericInput, ABudgetAllowingAbsurdRatesIsRefused) {
  // One row of ones: the largest rate of each sensor is b = 1e300 Hz, times T = 2 s.
  expectRefused(mutated("b: [3]", "b: [1e300]"), "constraints.b",
                "at most 1e+09 expected measurements per sensor in one horizon");
  // 1e8 Hz x 2 s = 2e8 measurements: large, but representable and allowed.
  EXPECT_NO_THROW((void)parseScenarioYaml(mutated("b: [3]", "b: [1e8]").text, "ok"));
}

TEST(NumericInput, TheBoundsAreTheDocumentedConstants) {
  EXPECT_EQ(kMaxGrowthExponent, 350.0);
  EXPECT_LT(2 * kMaxGrowthExponent, 709.78);  // log of the largest double
  EXPECT_EQ(kMaxMeasurementsPerHorizon, 1e9);
}

}  // namespace
}  // namespace sensornet
