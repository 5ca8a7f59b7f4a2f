// `sensornet conform sensor` (issue 48): a launched run with a participant of the user's in a
// sensor's role, judged rule by rule. The participant is the C example (examples/c/
// external_sensor.c): measuring the truth through the world library it keeps every rule; sending
// z = 0 while claiming the truth it fails the NEES rule alone; killed mid-run it fails leaving
// and the run's outcome. The test reads the verdicts from the table and the JUnit file, and
// checks the counts the accounting rule judged against the report the run wrote.

#include <gtest/gtest.h>

#include <chrono>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "launch_fixture.hpp"
#include "sensornet/io/command_line.hpp"

namespace sensornet {
namespace {

#ifdef SENSORNET_EXTERNAL_SENSOR_EXAMPLE

using namespace std::chrono_literals;
using testing::LeftoverGuard;
using testing::ProcessResult;
using testing::runProcess;

// The rule -> "ok" / "FAIL" lines of the table conform prints.
std::map<std::string, std::string> verdicts(const std::string& table) {
  std::map<std::string, std::string> out;
  std::istringstream lines(table);
  std::string line;
  while (std::getline(lines, line)) {
    std::istringstream words(line);
    std::string rule, verdict;
    words >> rule >> verdict;
    if (!line.empty() && line[0] != ' ' && (verdict == "ok" || verdict == "FAIL"))
      out[rule] = verdict;
  }
  return out;
}

std::size_t count(const std::string& text, const std::string& what) {
  std::size_t n = 0;
  for (std::size_t at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++n;
  return n;
}

class ConformSensor : public testing::LaunchTest {
 protected:
  ProcessResult conform(std::vector<std::string> options, std::vector<std::string> program,
                        const std::string& time_scale = "4", const std::string& sensor = "1") {
    std::vector<std::string> argv = {testing::kLauncher,
                                     "conform",
                                     "sensor",
                                     "--sensor",
                                     sensor,
                                     "--scenario",
                                     testing::kDefaultScenario,
                                     "--episodes",
                                     "3",
                                     "--time-scale",
                                     time_scale,
                                     "--run-id",
                                     run_id_,
                                     "--dir",
                                     (dir_ / "conform").string()};
    argv.insert(argv.end(), options.begin(), options.end());
    argv.emplace_back("--");
    argv.insert(argv.end(), program.begin(), program.end());
    return runProcess(argv, 300s);
  }
  // `sensornet conform ROLE` of `program` on `scenario`, at time scale 2.
  ProcessResult conformAs(const std::string& role, const std::string& scenario,
                          const std::string& episodes, const std::vector<std::string>& program) {
    std::vector<std::string> argv = {testing::kLauncher, "conform",  role,
                                     "--scenario",       scenario,   "--episodes",
                                     episodes,           "--time-scale", "2",
                                     "--run-id",         run_id_,    "--dir",
                                     (dir_ / "conform").string(), "--"};
    argv.insert(argv.end(), program.begin(), program.end());
    return runProcess(argv, 300s);
  }
  std::vector<std::string> example(const std::string& measure) const {
    return {SENSORNET_EXTERNAL_SENSOR_EXAMPLE,
            "--run-id",
            "{run_id}",
            "--domain-id",
            "{domain_id}",
            "--sensor",
            "{sensor}",
            "--dim",
            "{dim}",
            "--measure",
            measure};
  }
};

TEST_F(ConformSensor, TheCExampleMeasuringTheTruthKeepsEveryRule) {
  const LeftoverGuard guard(run_id_);
  const ProcessResult r =
      conform({"--measures-truth", "--junit", (dir_ / "rules.xml").string()}, example("truth"));
  EXPECT_EQ(r.exit_code, 0) << r.out << r.err;
  const auto rules = verdicts(r.out);
  EXPECT_EQ(rules.size(), 12u) << r.out;
  for (const auto& [rule, verdict] : rules) EXPECT_EQ(verdict, "ok") << rule << "\n" << r.out;
  // The C example draws its arrivals as our agents do (without --seed).
  EXPECT_NE(r.out.find("3 of 3 drawn exactly as our agents draw"), std::string::npos) << r.out;
  const std::string junit = testing::readText(dir_ / "rules.xml");
  EXPECT_EQ(count(junit, "<testcase "), 12u) << junit;
  EXPECT_EQ(count(junit, "<failure "), 0u) << junit;
  // What the accounting rule judged, from the report itself: every sample of sensor 1 arrived.
  const nlohmann::json report = testing::readJson(dir_ / "conform" / "report.json");
  std::uint64_t sent = 0, received = 0;
  for (const nlohmann::json& e : report.at("per_episode")) {
    sent += e.at("sent").at(1).get<std::uint64_t>();
    received += e.at("received").at(1).get<std::uint64_t>();
  }
  EXPECT_GT(sent, 0u);
  EXPECT_EQ(sent, received);
  EXPECT_NE(r.out.find("sent " + std::to_string(sent) + ", received " + std::to_string(received) +
                       ", lost 0, refused 0"),
            std::string::npos)
      << r.out;
}

// Our own sensor_agent in the role: every rule holds, its arrivals are ours to the instant.
TEST_F(ConformSensor, OurOwnAgentKeepsEveryRule) {
  const LeftoverGuard guard(run_id_);
  const ProcessResult r = conform({"--measures-truth"},
                                  {SENSORNET_SENSOR_AGENT, "--run-id", "{run_id}", "--domain-id",
                                   "{domain_id}", "--sensors", "{sensor}"},
                                  "4", "3");
  EXPECT_EQ(r.exit_code, 0) << r.out << r.err;
  const auto rules = verdicts(r.out);
  EXPECT_EQ(rules.size(), 12u) << r.out;
  for (const auto& [rule, verdict] : rules) EXPECT_EQ(verdict, "ok") << rule << "\n" << r.out;
  EXPECT_NE(r.out.find("3 of 3 drawn exactly as our agents draw"), std::string::npos) << r.out;
}

// Its own arrivals (--seed: a stream of its own, as valid a Poisson draw) and z = 0 while
// claiming the truth: the protocol holds, the measurements do not (nor, then, the NEES).
TEST_F(ConformSensor, ASensorSendingZerosFailsOnlyTheTruth) {
  const LeftoverGuard guard(run_id_);
  std::vector<std::string> program = example("zero");
  program.insert(program.end(), {"--seed", "7"});
  const ProcessResult r = conform({"--measures-truth"}, program);
  EXPECT_EQ(r.exit_code, 1) << r.out << r.err;
  const auto rules = verdicts(r.out);
  EXPECT_EQ(rules.size(), 12u) << r.out;
  for (const auto& [rule, verdict] : rules) {
    const bool judged_by_truth = rule == "truth" || rule == "measurement-noise";
    EXPECT_EQ(verdict, judged_by_truth ? "FAIL" : "ok") << rule << "\n" << r.out;
  }
  EXPECT_NE(r.out.find("KS D = "), std::string::npos) << r.out;  // its own draw: the law tested
  EXPECT_NE(r.out.find("OUTSIDE"), std::string::npos) << r.out;
}

// Killed (SIGKILL) four seconds in, in real time (3 episodes of 3 s): it neither says STOPPED
// nor leaves by itself, and the run does not complete.
TEST_F(ConformSensor, ASensorKilledMidRunFailsLeavingAndTheRun) {
  const LeftoverGuard guard(run_id_);
  std::vector<std::string> program = {"/usr/bin/timeout", "-s", "KILL", "4"};
  const std::vector<std::string> sensor = example("truth");
  program.insert(program.end(), sensor.begin(), sensor.end());
  const ProcessResult r = conform({}, program, "1");
  EXPECT_EQ(r.exit_code, 1) << r.out << r.err;
  const auto rules = verdicts(r.out);
  ASSERT_TRUE(rules.contains("leaving") && rules.contains("run")) << r.out;
  EXPECT_EQ(rules.at("leaving"), "FAIL") << r.out;
  EXPECT_EQ(rules.at("run"), "FAIL") << r.out;
  EXPECT_EQ(rules.at("readiness"), "ok") << r.out;
  // timeout(1) passes the SIGKILL on to itself.
  EXPECT_NE(r.out.find("it was killed by signal 9"), std::string::npos) << r.out;
}

#ifdef SENSORNET_EXTERNAL_FUSION_CENTER_EXAMPLE
// `conform fusion-center`: ours beside it (--reference-fusion) is the yardstick. Our own
// fusion_center and the C example (the scalar plant's CD-KF in closed form) keep every rule; the
// C example given a wrong process noise (q 0.6 for the scenario's 0.5) fails the costs alone.
class ConformFusionCenter : public ConformSensor {
 protected:
  ProcessResult conformFusionCenter(const std::string& scenario,
                                    const std::vector<std::string>& program) {
    return conformAs("fusion-center", scenario, "3", program);
  }
  std::vector<std::string> example(double q) const {
    std::vector<std::string> argv = {SENSORNET_EXTERNAL_FUSION_CENTER_EXAMPLE, "--run-id",
                                     "{run_id}", "--domain-id", "{domain_id}"};
    for (std::string a : testing::scalarModelArgs(kScalar)) {
      argv.push_back(a == "0.5" && argv.back() == "--q" ? formatNumber(q) : a);
    }
    return argv;
  }
  const std::string kScalar = std::string(SENSORNET_SOURCE_DIR) + "/examples/c/scalar.yaml";
};

TEST_F(ConformFusionCenter, OursAndTheCExampleKeepEveryRule) {
  const LeftoverGuard guard(run_id_);
  const ProcessResult ours = conformFusionCenter(
      kScalar, {SENSORNET_FUSION_CENTER, "serve", "--run-id", "{run_id}", "--domain-id",
                "{domain_id}", "--report", (dir_ / "users.json").string()});
  EXPECT_EQ(ours.exit_code, 0) << ours.out << ours.err;
  auto rules = verdicts(ours.out);
  EXPECT_EQ(rules.size(), 7u) << ours.out;
  for (const auto& [rule, verdict] : rules) EXPECT_EQ(verdict, "ok") << rule << "\n" << ours.out;
  const ProcessResult c = conformFusionCenter(kScalar, example(0.5));
  EXPECT_EQ(c.exit_code, 0) << c.out << c.err;
  rules = verdicts(c.out);
  EXPECT_EQ(rules.size(), 7u) << c.out;
  for (const auto& [rule, verdict] : rules) EXPECT_EQ(verdict, "ok") << rule << "\n" << c.out;
}

TEST_F(ConformFusionCenter, AWrongModelFailsTheCostsAlone) {
  const LeftoverGuard guard(run_id_);
  const ProcessResult r = conformFusionCenter(kScalar, example(0.6));
  EXPECT_EQ(r.exit_code, 1) << r.out << r.err;
  const auto rules = verdicts(r.out);
  EXPECT_EQ(rules.size(), 7u) << r.out;
  for (const auto& [rule, verdict] : rules) {
    EXPECT_EQ(verdict, rule == "costs" ? "FAIL" : "ok") << rule << "\n" << r.out;
  }
}
#endif

// `conform scheduler`: the coordinator leaves each command's first copy unanswered. Our own
// `sensornet replan` and a scheduler written with the Python participant
// (python_scheduler.py) keep every rule; that scheduler broken on purpose fails exactly the rule
// it breaks (and writing in the launcher's partition also the run's: a refusal by right is a
// command_refused fault, and the run is degraded).
class ConformScheduler : public ConformSensor {
 protected:
  ProcessResult conformScheduler(const std::vector<std::string>& program) {
    return conformAs("scheduler", testing::kDefaultScenario, "10", program);
  }
  // The rules that failed, by name.
  static std::vector<std::string> failing(const std::string& table) {
    std::vector<std::string> out;
    for (const auto& [rule, verdict] : verdicts(table)) {
      if (verdict == "FAIL") out.push_back(rule);
    }
    return out;
  }
};

TEST_F(ConformScheduler, SensornetReplanKeepsEveryRule) {
  const LeftoverGuard guard(run_id_);
  const ProcessResult r =
      conformScheduler({testing::kLauncher, "replan", "--run-id", "{run_id}", "--domain-id",
                        "{domain_id}", "--surrogate", "info"});
  EXPECT_EQ(r.exit_code, 0) << r.out << r.err;
  const auto rules = verdicts(r.out);
  EXPECT_EQ(rules.size(), 8u) << r.out;
  EXPECT_EQ(failing(r.out), std::vector<std::string>{}) << r.out;
  // The reply names the first version the report records as asked by a command.
  const nlohmann::json report = testing::readJson(dir_ / "conform" / "report.json");
  std::uint32_t commanded = 0;
  for (const nlohmann::json& v : report.at("schedule_versions")) {
    if (v.value("command_id", std::uint64_t{0}) != 0 && commanded == 0) commanded = v.at("version");
  }
  ASSERT_GT(commanded, 1u) << report.at("schedule_versions").dump();
  EXPECT_NE(r.out.find("versions " + std::to_string(commanded)), std::string::npos) << r.out;
}

#ifdef SENSORNET_PYTHON
class ConformPythonScheduler : public ConformScheduler,
                               public ::testing::WithParamInterface<
                                   std::pair<std::string, std::vector<std::string>>> {
 protected:
  std::vector<std::string> pythonScheduler(const std::string& broken) const {
    return {"/usr/bin/env",
            std::string("PYTHONPATH=") + SENSORNET_PYTHON_PATH,
            SENSORNET_PYTHON,
            std::string(SENSORNET_SOURCE_DIR) + "/tests/integration/emulation/python_scheduler.py",
            "--run-id",
            "{run_id}",
            "--domain-id",
            "{domain_id}",
            "--break",
            broken};
  }
};

TEST_P(ConformPythonScheduler, FailsExactlyTheRuleItBreaks) {
  const LeftoverGuard guard(run_id_);
  const auto& [broken, expected] = GetParam();
  const ProcessResult r = conformScheduler(pythonScheduler(broken));
  EXPECT_EQ(r.exit_code, expected.empty() ? 0 : 1) << r.out << r.err;
  EXPECT_EQ(verdicts(r.out).size(), 8u) << r.out;
  EXPECT_EQ(failing(r.out), expected)
      << r.out << testing::readText(dir_ / "conform" / "participant.log");
}

INSTANTIATE_TEST_SUITE_P(
    Breaks, ConformPythonScheduler,
    ::testing::Values(std::pair{std::string("none"), std::vector<std::string>{}},
                      std::pair{std::string("no-retry"), std::vector<std::string>{"retries"}},
                      // A refusal by right is a fault of the run (command_refused): degraded.
                      std::pair{std::string("launcher"), std::vector<std::string>{"by-right", "run"}},
                      std::pair{std::string("reuse-id"), std::vector<std::string>{"command-ids"}},
                      std::pair{std::string("deaf"), std::vector<std::string>{"replies-read"}},
                      std::pair{std::string("refused"), std::vector<std::string>{"accepted"}},
                      std::pair{std::string("stay"), std::vector<std::string>{"leaving"}}),
    [](const auto& param_info) {
      std::string name = param_info.param.first;
      std::erase(name, '-');
      return name;
    });
#endif

TEST_F(ConformSensor, BadInputIsOneLineAndExitTwo) {
  const ProcessResult r = conform({}, example("truth"), "4", "99");
  EXPECT_EQ(r.exit_code, 2) << r.out << r.err;
  EXPECT_NE(r.err.find("--sensor"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("0 to "), std::string::npos) << r.err;
  const ProcessResult role = runProcess({testing::kLauncher, "conform", "router", "--", "true"});
  EXPECT_EQ(role.exit_code, 2) << role.err;
  EXPECT_NE(role.err.find("the role `sensor`, `fusion-center` or `scheduler`"), std::string::npos)
      << role.err;
}

#endif

}  // namespace
}  // namespace sensornet
