#include "sensornet/io/scenario_file.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <unistd.h>

#include <Eigen/Eigenvalues>

#include "sensornet/core/input_error.hpp"
#include "sensornet/core/rate_schedule.hpp"
#include "support/eigen_near.hpp"
#include "support/scratch_dir.hpp"

namespace sensornet {
namespace {

// A valid two-state, two-sensor scenario; each bad-input test breaks one field of it.
const char* kValid = R"(
horizon: 2.0
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
cost:
  W: [[1, 0], [0, 0]]
constraints:
  b: [3]
)";

std::string replaced(const std::string& from, const std::string& to) {
  std::string text = kValid;
  const auto at = text.find(from);
  if (at == std::string::npos) throw std::logic_error("fixture has no '" + from + "'");
  text.replace(at, from.size(), to);
  return text;
}

// Parses `text` and returns the error message, failing the test if it parses.
std::string errorOf(const std::string& text) {
  try {
    (void)parseScenarioYaml(text, "bad.yaml");
  } catch (const InputError& e) {
    return e.what();
  }
  ADD_FAILURE() << "expected an InputError for:\n" << text;
  return {};
}

TEST(ScenarioFile, ParsesTheExplicitFormWithDefaults) {
  const Scenario s = parseScenarioYaml(kValid, "ok.yaml");
  EXPECT_EQ(s.stateDim(), 2);
  EXPECT_EQ(s.sensorCount(), 2);
  EXPECT_DOUBLE_EQ(s.horizon_s, 2.0);
  EXPECT_EQ(s.intervals, 4);
  EXPECT_TRUE(s.cost.WT.isIdentity());                      // default W_T = I
  EXPECT_TRUE(s.constraints.C.isApprox(Eigen::MatrixXd::Ones(1, 2)));  // default C = 1'
  EXPECT_TRUE(s.plant.m0.isZero());                         // default m0 = 0
  EXPECT_DOUBLE_EQ(s.sensors[1].R(0, 1), 0.5);
}

TEST(ScenarioFile, ParsesTheRandomFormReproducibly) {
  const std::string text = "horizon: 3\nintervals: 30\nrandom: {states: 4, sensors: 7, seed: 11}\n";
  const Scenario a = parseScenarioYaml(text, "r.yaml");
  const Scenario b = parseScenarioYaml(text, "r.yaml");
  EXPECT_EQ(a.stateDim(), 4);
  EXPECT_EQ(a.sensorCount(), 7);
  EXPECT_MATRIX_NEAR(a.plant.A, b.plant.A, 0.0);
  EXPECT_DOUBLE_EQ(a.constraints.b(0), 5.0);
  // The paper's protocol: orthonormal sensor rows, R eigenvalues in [1, 10], Q = I, P0 = 100 I.
  for (const auto& sensor : a.sensors) {
    EXPECT_MATRIX_NEAR(sensor.H * sensor.H.transpose(), Eigen::MatrixXd::Identity(1, 1), 1e-12);
    EXPECT_GE(sensor.R(0, 0), 1.0);
    EXPECT_LE(sensor.R(0, 0), 10.0);
  }
  EXPECT_TRUE(a.plant.P0.isApprox(100.0 * Eigen::MatrixXd::Identity(4, 4)));
  // Balanced modes: two unstable, two stable eigenvalues.
  const Eigen::VectorXd eig = Eigen::EigenSolver<Eigen::MatrixXd>(a.plant.A).eigenvalues().real();
  EXPECT_EQ((eig.array() > 0).count(), 2);
  EXPECT_EQ((eig.array() < 0).count(), 2);
}

TEST(ScenarioFile, ShippedScenariosParse) {
  for (const char* name : {"default.yaml", "paper.yaml"}) {
    const std::string path = std::string(SENSORNET_SOURCE_DIR) + "/scenarios/" + name;
    EXPECT_NO_THROW((void)loadScenarioFile(path)) << path;
  }
}

struct BadScenarioCase {
  const char* what;
  std::string text;
  const char* field;     // must appear in the message
  const char* expected;  // must appear in the message
};

// Names the case in test output and in ctest's test list ("loss one", not its bytes).
void PrintTo(const BadScenarioCase& c, std::ostream* os) { *os << c.what; }

class BadScenario : public ::testing::TestWithParam<BadScenarioCase> {};

TEST_P(BadScenario, IsRejectedWithAMessageNamingFileFieldAndExpectation) {
  const BadScenarioCase& c = GetParam();
  const std::string message = errorOf(c.text);
  EXPECT_NE(message.find("bad.yaml"), std::string::npos) << message;
  EXPECT_NE(message.find(c.field), std::string::npos) << c.what << ": " << message;
  EXPECT_NE(message.find(c.expected), std::string::npos) << c.what << ": " << message;
  EXPECT_EQ(message.find('\n'), std::string::npos) << "one line: " << message;
}

INSTANTIATE_TEST_SUITE_P(
    EveryKindOfBadInput, BadScenario,
    ::testing::Values(
        BadScenarioCase{"A not square", replaced("A: [[0, 1], [0, -1]]", "A: [[0, 1]]"),
                        "plant.A", "square"},
        BadScenarioCase{"Q wrong size", replaced("Q: [[0, 0], [0, 1]]", "Q: [[1]]"), "plant.Q",
                        "2 x 2 matrix"},
        BadScenarioCase{"ragged rows", replaced("A: [[0, 1], [0, -1]]", "A: [[0, 1], [0]]"),
                        "plant.A[1]", "2 entries"},
        BadScenarioCase{"H columns", replaced("H: [[1, 0]]", "H: [[1, 0, 0]]"), "sensors[0].H",
                        "1 x 2 matrix"},
        BadScenarioCase{"R shape", replaced("R: [[1]]", "R: [[1, 0], [0, 1]]"), "sensors[0].R",
                        "1 x 1 matrix"},
        BadScenarioCase{"non-symmetric Q", replaced("Q: [[0, 0], [0, 1]]", "Q: [[0, 1], [0, 1]]"),
                        "plant.Q", "symmetric"},
        BadScenarioCase{"P0 not PD", replaced("P0: [[10, 0], [0, 10]]", "P0: [[10, 0], [0, 0]]"),
                        "plant.P0", "positive definite"},
        BadScenarioCase{"R not PD", replaced("R: [[2, 0.5], [0.5, 2]]", "R: [[1, 2], [2, 1]]"),
                        "sensors[1].R", "positive definite"},
        BadScenarioCase{"Q negative eigenvalue",
                        replaced("Q: [[0, 0], [0, 1]]", "Q: [[0, 0], [0, -1]]"), "plant.Q",
                        "positive semidefinite"},
        BadScenarioCase{"W negative eigenvalue", replaced("W: [[1, 0], [0, 0]]", "W: [[1, 0], [0, -0.1]]"),
                        "cost.W", "positive semidefinite"},
        BadScenarioCase{"WT negative eigenvalue",
                        replaced("W: [[1, 0], [0, 0]]", "WT: [[1, 2], [2, 1]]"), "cost.WT",
                        "positive semidefinite"},
        BadScenarioCase{"NaN", replaced("A: [[0, 1], [0, -1]]", "A: [[0, .nan], [0, -1]]"),
                        "plant.A[0][1]", "finite"},
        BadScenarioCase{"infinity", replaced("R: [[1]]", "R: [[.inf]]"), "sensors[0].R[0][0]",
                        "finite"},
        BadScenarioCase{"not a number", replaced("horizon: 2.0", "horizon: soon"), "horizon",
                        "a number"},
        BadScenarioCase{"missing plant", replaced("plant:", "plantt:"), "plantt",
                        "known keys"},
        BadScenarioCase{"missing horizon", replaced("horizon: 2.0", ""), "horizon", "missing"},
        BadScenarioCase{"missing P0", replaced("P0: [[10, 0], [0, 10]]", ""), "plant.P0",
                        "missing"},
        BadScenarioCase{"missing b", replaced("b: [3]", "C: [[1, 1]]"), "constraints.b",
                        "missing"},
        BadScenarioCase{"column without positive entry",
                        replaced("b: [3]", "C: [[1, 0], [1, 0]]\n  b: [3, 3]"), "constraints.C",
                        "column 1"},
        BadScenarioCase{"negative C", replaced("b: [3]", "C: [[1, -1]]\n  b: [3]"),
                        "constraints.C", "nonnegative"},
        BadScenarioCase{"b zero", replaced("b: [3]", "b: [0]"), "constraints.b[0]", "> 0"},
        BadScenarioCase{"b negative", replaced("b: [3]", "b: [-2]"), "constraints.b[0]", "> 0"},
        BadScenarioCase{"b length", replaced("b: [3]", "b: [3, 4]"), "constraints.b",
                        "1 x 1 matrix"},
        BadScenarioCase{"horizon zero", replaced("horizon: 2.0", "horizon: 0"), "horizon",
                        "> 0"},
        BadScenarioCase{"horizon negative", replaced("horizon: 2.0", "horizon: -1"), "horizon",
                        "> 0"},
        BadScenarioCase{"intervals zero", replaced("intervals: 4", "intervals: 0"), "intervals",
                        "integer"},
        BadScenarioCase{"intervals fractional", replaced("intervals: 4", "intervals: 2.5"),
                        "intervals", "an integer"},
        BadScenarioCase{"no sensors",
                        std::string("horizon: 1\nintervals: 1\nplant: {A: [[0]], Q: [[1]], "
                                    "P0: [[1]]}\nsensors: []\nconstraints: {b: [1]}\n"),
                        "sensors", "non-empty"},
        BadScenarioCase{"bad YAML", std::string("horizon: [1, 2\n"), "bad.yaml", "valid YAML"},
        BadScenarioCase{"random form with zero states",
                        std::string("horizon: 1\nintervals: 2\nrandom: {states: 0, sensors: 2, "
                                    "seed: 1}\n"),
                        "random.states", ">= 1"},
        BadScenarioCase{"random and explicit", std::string(kValid) + "random: {states: 1}\n",
                        "plant", "not both"},
        BadScenarioCase{"energy zero", replaced("b: [3]", "b: [3]\n  energy: [2, 0]"),
                        "constraints.energy[1]", "> 0"},
        BadScenarioCase{"energy count", replaced("b: [3]", "b: [3]\n  energy: [2, 3, 4]"),
                        "constraints.energy", "2 budgets (one per sensor) or one for all"},
        BadScenarioCase{"energy not a number", replaced("b: [3]", "b: [3]\n  energy: lots"),
                        "constraints.energy", "a number"},
        BadScenarioCase{"energy NaN", replaced("b: [3]", "b: [3]\n  energy: [.nan, 1]"),
                        "constraints.energy[0]", "finite"},
        BadScenarioCase{"random energy list",
                        std::string("horizon: 1\nintervals: 2\nrandom: {states: 2, sensors: 2, "
                                    "seed: 1, energy: [1, 2]}\n"),
                        "random.energy", "one budget for every sensor"}));

// Energy budgets: one per sensor, .inf for none, or one number for every sensor; the random
// form takes one for every sensor.
TEST(ScenarioFile, EnergyBudgetsPerSensorOrForAll) {
  const Scenario none = parseScenarioYaml(kValid, "ok.yaml");
  EXPECT_EQ(none.constraints.energy.size(), 0);
  EXPECT_FALSE(none.constraints.hasEnergyBudgets());
  const Scenario listed = parseScenarioYaml(replaced("b: [3]", "b: [3]\n  energy: [2.5, .inf]"), "ok.yaml");
  ASSERT_EQ(listed.constraints.energy.size(), 2);
  EXPECT_DOUBLE_EQ(listed.constraints.energy(0), 2.5);
  EXPECT_TRUE(std::isinf(listed.constraints.energy(1)));
  EXPECT_TRUE(listed.constraints.hasEnergyBudgets());
  const Scenario all = parseScenarioYaml(replaced("b: [3]", "b: [3]\n  energy: 4"), "ok.yaml");
  EXPECT_TRUE(all.constraints.energy.isApprox(Eigen::Vector2d(4.0, 4.0)));
  const Scenario random = parseScenarioYaml(
      "horizon: 3\nintervals: 30\nrandom: {states: 4, sensors: 7, seed: 11, energy: 1.5}\n",
      "r.yaml");
  EXPECT_TRUE(random.constraints.energy.isApprox(Eigen::VectorXd::Constant(7, 1.5)));
  const Scenario unlimited = parseScenarioYaml(
      "horizon: 3\nintervals: 30\nrandom: {states: 4, sensors: 7, seed: 11, energy: .inf}\n",
      "r.yaml");
  EXPECT_FALSE(unlimited.constraints.hasEnergyBudgets());
}

// A schedule that overspends a budget is named by its sensor; 1e-9 of slack per second of
// horizon is rounding.
TEST(ScenarioFile, ASchedulePastAnEnergyBudgetIsInfeasible) {
  const Scenario s = parseScenarioYaml(replaced("b: [3]", "b: [3]\n  energy: [2.5, .inf]"), "ok.yaml");
  Eigen::MatrixXd rates = Eigen::MatrixXd::Zero(4, 2);
  rates.col(0).setConstant(1.25);  // 1.25 Hz x 2 s = 2.5: on the budget
  rates.col(1).setConstant(1.5);
  EXPECT_TRUE(checkFeasibility(RateSchedule(2.0, rates), s).feasible);
  rates(3, 0) += 1e-3;  // 0.5 s x 1e-3 Hz over
  const Feasibility f = checkFeasibility(RateSchedule(2.0, rates), s);
  EXPECT_FALSE(f.feasible);
  EXPECT_NEAR(f.max_violation, 0.5e-3, 1e-12);
  EXPECT_NE(f.reason.find("sensor 0"), std::string::npos) << f.reason;
  EXPECT_NE(f.reason.find("energy budget 2.5"), std::string::npos) << f.reason;
  // The uniform baseline: 1.5 Hz each by 1'λ <= 3, sensor 0 capped at 2.5 / 2 s.
  const RateSchedule uniform = uniformSchedule(s);
  EXPECT_DOUBLE_EQ(uniform.rate(2, 0), 1.25);
  EXPECT_DOUBLE_EQ(uniform.rate(2, 1), 1.5);
}

// The valid fixture (horizon 2, intervals 4, two sensors) with a network section and faults.
std::string withNetwork(const std::string& network, const std::string& faults = "") {
  return std::string(kValid) + network + faults;
}

const char* kNetwork = R"(network:
  default: {loss: 0.1, delay: {fixed: 0.005, jitter: exponential, mean: 0.010}, duplicate: 0.0}
  sensors: {1: {loss: 0.5}}
  outages:
    - {sensor: 1, episodes: all, from: 0.5, to: 1.25}
    - {sensor: 0, episodes: [2, 4], from: 0, to: 2}
)";

const char* kFaults = R"(faults:
  - {kind: crash, sensor: 1, episode: 2, at: 1.0}
)";

TEST(ScenarioFileNetwork, ParsesLinksOverridesOutagesAndFaults) {
  const Scenario s = parseScenarioYaml(withNetwork(kNetwork, kFaults), "net.yaml");
  ASSERT_TRUE(s.network.has_value());
  ASSERT_EQ(s.network->links.size(), 2U);
  const LinkSpec& first = s.network->links[0];
  EXPECT_DOUBLE_EQ(first.loss, 0.1);
  EXPECT_DOUBLE_EQ(first.delay_fixed_s, 0.005);
  EXPECT_EQ(first.jitter, Jitter::Exponential);
  EXPECT_DOUBLE_EQ(first.jitter_mean_s, 0.010);
  EXPECT_DOUBLE_EQ(first.duplicate, 0.0);
  // The override replaces the loss only; the delay is the default's.
  const LinkSpec& second = s.network->links[1];
  EXPECT_DOUBLE_EQ(second.loss, 0.5);
  EXPECT_DOUBLE_EQ(second.delay_fixed_s, 0.005);
  EXPECT_EQ(second.jitter, Jitter::Exponential);
  EXPECT_DOUBLE_EQ(second.jitter_mean_s, 0.010);
  ASSERT_EQ(s.network->outages.size(), 2U);
  EXPECT_EQ(s.network->outages[0].sensor, 1);
  EXPECT_TRUE(s.network->outages[0].episodes.empty());  // all
  EXPECT_DOUBLE_EQ(s.network->outages[0].from_s, 0.5);
  EXPECT_DOUBLE_EQ(s.network->outages[0].to_s, 1.25);
  EXPECT_EQ(s.network->outages[1].episodes, (std::vector<std::uint32_t>{2, 4}));
  ASSERT_EQ(s.faults.size(), 1U);
  EXPECT_EQ(s.faults[0].sensor, 1);
  EXPECT_EQ(s.faults[0].episode, 2U);
  EXPECT_DOUBLE_EQ(s.faults[0].at_s, 1.0);
}

TEST(ScenarioFileNetwork, WithoutTheSectionThereIsNoNetworkAndNoFault) {
  const Scenario s = parseScenarioYaml(kValid, "ok.yaml");
  EXPECT_FALSE(s.network.has_value());
  EXPECT_TRUE(s.faults.empty());
}

TEST(ScenarioFileNetwork, LognormalSigmaDefaultsToOneHalfAndOverridesApplyFieldByField) {
  const Scenario s = parseScenarioYaml(withNetwork(R"(network:
  default: {delay: {jitter: lognormal, mean: 0.02}}
  sensors:
    0: {delay: {jitter: none}, duplicate: 0.25}
    1: {delay: {sigma: 1.5}}
)"),
                                       "net.yaml");
  const LinkSpec& zero = s.network->links[0];
  EXPECT_EQ(zero.jitter, Jitter::None);
  EXPECT_DOUBLE_EQ(zero.jitter_mean_s, 0.0);
  EXPECT_DOUBLE_EQ(zero.duplicate, 0.25);
  EXPECT_DOUBLE_EQ(zero.loss, 0.0);
  const LinkSpec& one = s.network->links[1];
  EXPECT_EQ(one.jitter, Jitter::Lognormal);
  EXPECT_DOUBLE_EQ(one.jitter_mean_s, 0.02);
  EXPECT_DOUBLE_EQ(one.jitter_sigma, 1.5);
  const Scenario defaults = parseScenarioYaml(
      withNetwork("network: {default: {delay: {jitter: lognormal, mean: 0.02}}}\n"), "n.yaml");
  EXPECT_DOUBLE_EQ(defaults.network->links[0].jitter_sigma, 0.5);
}

TEST(ScenarioFileNetwork, TheRandomFormTakesANetworkToo) {
  const Scenario s = parseScenarioYaml(
      "horizon: 3\nintervals: 30\nrandom: {states: 2, sensors: 3, seed: 1}\n"
      "network: {sensors: {2: {loss: 0.3}}}\n",
      "r.yaml");
  ASSERT_TRUE(s.network.has_value());
  ASSERT_EQ(s.network->links.size(), 3U);
  EXPECT_TRUE(s.network->links[0].perfect());
  EXPECT_DOUBLE_EQ(s.network->links[2].loss, 0.3);
}

TEST(ScenarioFileNetwork, ShippedLossyScenarioParsesWithANetwork) {
  const Scenario s =
      loadScenarioFile(std::string(SENSORNET_SOURCE_DIR) + "/scenarios/lossy.yaml");
  ASSERT_TRUE(s.network.has_value());
  EXPECT_EQ(s.network->links.size(), s.sensors.size());
}

INSTANTIATE_TEST_SUITE_P(
    NetworkAndFaults, BadScenario,
    ::testing::Values(
        BadScenarioCase{"loss one", withNetwork("network: {default: {loss: 1}}\n"),
                        "network.default.loss", "[0, 1), got 1"},
        BadScenarioCase{"loss negative", withNetwork("network: {sensors: {0: {loss: -0.1}}}\n"),
                        "network.sensors.0.loss", "[0, 1)"},
        BadScenarioCase{"duplicate too big", withNetwork("network: {default: {duplicate: 1.5}}\n"),
                        "network.default.duplicate", "[0, 1)"},
        BadScenarioCase{"loss not a number", withNetwork("network: {default: {loss: lots}}\n"),
                        "network.default.loss", "a number"},
        BadScenarioCase{"fixed delay beyond horizon",
                        withNetwork("network: {default: {delay: {fixed: 2.5}}}\n"),
                        "network.default.delay.fixed", "at most the horizon"},
        BadScenarioCase{"negative delay",
                        withNetwork("network: {default: {delay: {fixed: -0.1}}}\n"),
                        "network.default.delay.fixed", "[0, 2]"},
        BadScenarioCase{"infinite delay",
                        withNetwork("network: {default: {delay: {fixed: .inf}}}\n"),
                        "network.default.delay.fixed", "finite"},
        BadScenarioCase{"unknown jitter",
                        withNetwork("network: {default: {delay: {jitter: pareto, mean: 1}}}\n"),
                        "network.default.delay.jitter", "none, exponential, lognormal"},
        BadScenarioCase{"exponential without mean",
                        withNetwork("network: {default: {delay: {jitter: exponential}}}\n"),
                        "network.default.delay.mean", "required for jitter"},
        BadScenarioCase{"override switches on a jitter without mean",
                        withNetwork("network: {sensors: {1: {delay: {jitter: lognormal}}}}\n"),
                        "network.sensors.1.delay.mean", "required"},
        BadScenarioCase{"zero jitter mean",
                        withNetwork("network: {default: {delay: {jitter: exponential, "
                                    "mean: 0}}}\n"),
                        "network.default.delay.mean", "(0, 2]"},
        BadScenarioCase{"mean without jitter",
                        withNetwork("network: {default: {delay: {mean: 0.1}}}\n"),
                        "network.default.delay.mean", "jitter: none"},
        BadScenarioCase{"sigma with exponential",
                        withNetwork("network: {default: {delay: {jitter: exponential, mean: 0.1, "
                                    "sigma: 1}}}\n"),
                        "network.default.delay.sigma", "lognormal"},
        BadScenarioCase{"sigma zero",
                        withNetwork("network: {default: {delay: {jitter: lognormal, mean: 0.1, "
                                    "sigma: 0}}}\n"),
                        "network.default.delay.sigma", "(0, 10]"},
        BadScenarioCase{"unknown link key", withNetwork("network: {default: {los: 0.1}}\n"),
                        "network.default.los", "known keys (loss, delay, duplicate)"},
        BadScenarioCase{"unknown delay key",
                        withNetwork("network: {default: {delay: {fix: 0.1}}}\n"),
                        "network.default.delay.fix", "known keys"},
        BadScenarioCase{"unknown network key", withNetwork("network: {defaults: {}}\n"),
                        "network.defaults", "known keys (default, sensors, outages)"},
        BadScenarioCase{"override sensor out of range",
                        withNetwork("network: {sensors: {2: {loss: 0.1}}}\n"), "network.sensors.2",
                        "sensor index from 0 to 1, got 2"},
        BadScenarioCase{"override sensor not an index",
                        withNetwork("network: {sensors: {x: {loss: 0.1}}}\n"), "network.sensors.x",
                        "a number"},
        BadScenarioCase{"outage sensor out of range",
                        withNetwork("network: {outages: [{sensor: 5, from: 0, to: 1}]}\n"),
                        "network.outages[0].sensor", "from 0 to 1, got 5"},
        BadScenarioCase{"outage from negative",
                        withNetwork("network: {outages: [{sensor: 0, from: -0.5, to: 1}]}\n"),
                        "network.outages[0].from", "[0, 2)"},
        BadScenarioCase{"outage to before from",
                        withNetwork("network: {outages: [{sensor: 0, from: 1, to: 0.5}]}\n"),
                        "network.outages[0].to", "(from, T]"},
        BadScenarioCase{"outage beyond horizon",
                        withNetwork("network: {outages: [{sensor: 0, from: 1, to: 2.5}]}\n"),
                        "network.outages[0].to", "(1, 2]"},
        BadScenarioCase{"outage off the refined grid",
                        withNetwork("network: {outages: [{sensor: 0, from: 0.1234567, to: 1}]}\n"),
                        "network.outages[0]", "at most 1000 equal steps"},
        BadScenarioCase{"outage without to",
                        withNetwork("network: {outages: [{sensor: 0, from: 0.5}]}\n"),
                        "network.outages[0].to", "missing"},
        BadScenarioCase{"outage episodes empty",
                        withNetwork("network: {outages: [{sensor: 0, episodes: [], from: 0, to: "
                                    "1}]}\n"),
                        "network.outages[0].episodes", "all or a non-empty list"},
        BadScenarioCase{"outage episodes word",
                        withNetwork("network: {outages: [{sensor: 0, episodes: some, from: 0, "
                                    "to: 1}]}\n"),
                        "network.outages[0].episodes", "all or a non-empty list"},
        BadScenarioCase{"outage episode negative",
                        withNetwork("network: {outages: [{sensor: 0, episodes: [1, -2], from: 0, "
                                    "to: 1}]}\n"),
                        "network.outages[0].episodes[1]", "episode number"},
        BadScenarioCase{"outage unknown key",
                        withNetwork("network: {outages: [{sensor: 0, from: 0, to: 1, link: 2}]}\n"),
                        "network.outages[0].link", "known keys"},
        BadScenarioCase{"outages not a list",
                        withNetwork("network: {outages: {sensor: 0}}\n"), "network.outages",
                        "a list of outages"},
        BadScenarioCase{"network empty", withNetwork("network:\n"), "network", "a mapping"},
        BadScenarioCase{"fault kind unknown",
                        withNetwork("", "faults: [{kind: partition, sensor: 0, episode: 0, at: "
                                        "1}]\n"),
                        "faults[0].kind", "known kinds (crash), got 'partition'"},
        BadScenarioCase{"fault kind missing",
                        withNetwork("", "faults: [{sensor: 0, episode: 0, at: 1}]\n"),
                        "faults[0].kind", "missing"},
        BadScenarioCase{"fault sensor out of range",
                        withNetwork("", "faults: [{kind: crash, sensor: 2, episode: 0, at: 1}]\n"),
                        "faults[0].sensor", "from 0 to 1, got 2"},
        BadScenarioCase{"fault after the horizon",
                        withNetwork("", "faults: [{kind: crash, sensor: 0, episode: 0, at: 3}]\n"),
                        "faults[0].at", "[0, 2]"},
        BadScenarioCase{"fault before zero",
                        withNetwork("", "faults: [{kind: crash, sensor: 0, episode: 0, at: "
                                        "-1}]\n"),
                        "faults[0].at", "[0, 2]"},
        BadScenarioCase{"fault episode fractional",
                        withNetwork("", "faults: [{kind: crash, sensor: 0, episode: 0.5, at: "
                                        "1}]\n"),
                        "faults[0].episode", "an integer"},
        BadScenarioCase{"fault unknown key",
                        withNetwork("", "faults: [{kind: crash, sensor: 0, episode: 0, at: 1, "
                                        "signal: 9}]\n"),
                        "faults[0].signal", "known keys (kind, sensor, episode, at)"},
        BadScenarioCase{"faults not a list",
                        withNetwork("", "faults: {kind: crash}\n"), "faults", "a list of faults"}));

TEST(ScenarioFileNetwork, ErrorsNameTheLineOfTheField) {
  // Line 19 of the fixture plus network section: the outage list entry.
  const std::string text = withNetwork(R"(network:
  outages:
    - {sensor: 0, from: 0.5, to: 1}
    - {sensor: 1, from: 1.5, to: 9}
)");
  const std::string message = errorOf(text);
  const int expected_line = 1 + static_cast<int>(std::count(text.begin(), text.end(), '\n')) - 1;
  EXPECT_NE(message.find("bad.yaml:" + std::to_string(expected_line) + ": network.outages[1].to"),
            std::string::npos)
      << message;
  const std::string loss = withNetwork("network:\n  default:\n    loss: 2\n");
  const int loss_line = static_cast<int>(std::count(loss.begin(), loss.end(), '\n'));
  EXPECT_NE(errorOf(loss).find("bad.yaml:" + std::to_string(loss_line) + ": network.default.loss"),
            std::string::npos)
      << errorOf(loss);
}

TEST(ScenarioFile, ErrorsNameTheLine) {
  const std::string message = errorOf(replaced("P0: [[10, 0], [0, 10]]", "P0: [[10, 0], [0, -3]]"));
  // The plant block starts on line 4 of the fixture, P0 is on line 7; either line is helpful,
  // but the message must carry one.
  const auto at = message.find("bad.yaml:");
  ASSERT_NE(at, std::string::npos) << message;
  EXPECT_TRUE(std::isdigit(static_cast<unsigned char>(message[at + 9]))) << message;
}

TEST(ScenarioFile, MissingFileIsAnInputError) {
  EXPECT_THROW((void)loadScenarioFile("/nonexistent/scenario.yaml"), InputError);
}

TEST(ScheduleFile, RoundTripsAndRejectsMalformedSchedules) {
  const Scenario s = parseScenarioYaml(kValid, "ok.yaml");
  const RateSchedule uniform = uniformSchedule(s);
  const sensornet::testing::ScratchDir dir;
  const std::string path = dir.file("sched.json");
  writeScheduleFile(path, uniform, {{"surrogate", "uniform"}});
  const RateSchedule back = loadScheduleFile(path, s);
  EXPECT_MATRIX_NEAR(back.rates(), uniform.rates(), 0.0);

  auto bad = [](const std::string& text, const char* field) {
    try {
      (void)parseScheduleJson(text, "s.json");
      ADD_FAILURE() << "accepted " << text;
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(field), std::string::npos) << e.what();
    }
  };
  bad("{\"horizon\": 2, \"intervals\": 2, \"rates\": [[1, 1]]}", "rates");
  bad("{\"horizon\": 2, \"intervals\": 2, \"rates\": [[1, 1], [1]]}", "rates[1]");
  bad("{\"horizon\": 2, \"intervals\": 1, \"rates\": [[1, -1]]}", "rates[0][1]");
  bad("{\"horizon\": 2, \"intervals\": 1, \"rates\": [[1, \"x\"]]}", "rates[0][1]");
  bad("{\"horizon\": -2, \"intervals\": 1, \"rates\": [[1]]}", "horizon");
  bad("{\"intervals\": 1, \"rates\": [[1]]}", "horizon");
  bad("{\"horizon\": 2, \"intervals\": 1, \"rates\": [[1]]", "valid JSON");

  // Shape and feasibility against the scenario.
  const std::string infeasible =
      dir.write("sched.json.bad", R"({"horizon": 2, "intervals": 4, "rates": [[1,1],[1,1],[3,1],[1,1]]})");
  try {
    (void)loadScheduleFile(infeasible, s);
    ADD_FAILURE() << "accepted an infeasible schedule";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("interval 2"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace sensornet

namespace sensornet {
namespace {

TEST(ScenarioFileArrivals, PoissonByDefaultAndTimetableWhenAsked) {
  EXPECT_EQ(parseScenarioYaml(kValid, "ok.yaml").arrivals, ArrivalMode::Poisson);
  EXPECT_EQ(parseScenarioYaml(std::string(kValid) + "arrivals: poisson\n", "ok.yaml").arrivals,
            ArrivalMode::Poisson);
  EXPECT_EQ(parseScenarioYaml(std::string(kValid) + "arrivals: timetable\n", "ok.yaml").arrivals,
            ArrivalMode::Timetable);
}

TEST(ScenarioFileArrivals, ABadModeNamesFileLineFieldAndTheChoices) {
  const std::string text = std::string(kValid) + "arrivals: periodic\n";
  const int line = static_cast<int>(std::count(text.begin(), text.end(), '\n'));
  const std::string message = errorOf(text);
  EXPECT_NE(message.find("bad.yaml:" + std::to_string(line) + ": arrivals"), std::string::npos)
      << message;
  EXPECT_NE(message.find("poisson or timetable, got 'periodic'"), std::string::npos) << message;
  EXPECT_EQ(message.find('\n'), std::string::npos) << message;
  const std::string listed = errorOf(std::string(kValid) + "arrivals: [timetable]\n");
  EXPECT_NE(listed.find("arrivals"), std::string::npos) << listed;
  EXPECT_NE(listed.find("poisson or timetable"), std::string::npos) << listed;
}

}  // namespace
}  // namespace sensornet
