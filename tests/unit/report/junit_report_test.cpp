// The run as JUnit XML (junit_report.hpp): a case for the run, one per criterion, failures where
// the run did not complete or a criterion failed, and every message escaped.
#include "sensornet/report/junit_report.hpp"

#include <gtest/gtest.h>

#include "support/occurrences.hpp"

namespace sensornet::report {
namespace {

using sensornet::testing::occurrences;

RequirementCheck check(const std::string& text, bool pass, const std::string& measured) {
  RequirementCheck c;
  c.requirement.text = text;
  c.requirement.name = text;
  c.pass = pass;
  c.measured = measured;
  return c;
}

TEST(JunitReport, ADegradedRunAndAFailedCriterionAreFailuresWithTheirReasons) {
  JunitRun run;
  run.run_id = "r<1>";
  run.status = RunStatus::Degraded;
  run.exit_code = 3;
  run.faults.resize(3);
  run.faults[0].kind = FaultKind::Stall;
  run.faults[1].kind = FaultKind::Stall;
  run.faults[2].kind = FaultKind::SensorDied;
  run.checks = {check("no-loss", true, "0"), check("latency-p99<=5ms", false, "7.2 ms")};
  run.seconds = 12.5;
  const std::string xml = junitXml(run);
  EXPECT_EQ(occurrences(xml, "<testcase "), 3u);
  EXPECT_EQ(occurrences(xml, "</testcase>"), 3u);
  EXPECT_EQ(occurrences(xml, "<failure "), 2u) << xml;
  EXPECT_NE(xml.find("tests=\"3\" failures=\"2\" errors=\"0\" time=\"12.5\""), std::string::npos)
      << xml;
  EXPECT_NE(xml.find("name=\"sensornet run r&lt;1&gt;\""), std::string::npos) << xml;
  EXPECT_NE(xml.find("status degraded, exit 3, 3 faults: 1 sensor_died, 2 stall"),
            std::string::npos)
      << xml;
  EXPECT_NE(xml.find("name=\"require latency-p99&lt;=5ms\"><failure message=\"measured 7.2 ms\""),
            std::string::npos)
      << xml;
  EXPECT_EQ(xml.find("name=\"require no-loss\"><failure"), std::string::npos) << xml;
  EXPECT_EQ(xml.find("r<1>"), std::string::npos) << "unescaped: " << xml;
}

TEST(JunitReport, ACompletedRunWithoutCriteriaIsOnePassingCase) {
  JunitRun run;
  run.run_id = "clean";
  run.status = RunStatus::Completed;
  run.exit_code = 0;
  const std::string xml = junitXml(run);
  EXPECT_EQ(occurrences(xml, "<testcase "), 1u);
  EXPECT_EQ(occurrences(xml, "<failure"), 0u) << xml;
  EXPECT_NE(xml.find("tests=\"1\" failures=\"0\""), std::string::npos) << xml;
  EXPECT_NE(xml.find("status completed, exit 0, 0 faults"), std::string::npos) << xml;
}

}  // namespace
}  // namespace sensornet::report
