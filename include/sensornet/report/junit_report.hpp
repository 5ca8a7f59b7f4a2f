#pragma once
// A finished run as JUnit XML (`sensornet launch ... --junit FILE.xml`), for the CI systems
// that read JUnit: one <testsuite> named after the run, one <testcase> "run" that passes only
// when the run completed (its message: the status, the exit code, the faults by kind), and one
// <testcase> per --require criterion, passing or failing as the launcher judged it, with the
// value measured in its message.
//
//   const std::string xml = junitXml({run_id, RunStatus::Degraded, 3, run.faults, checks, 12.5});

#include <string>
#include <vector>

#include "sensornet/report/run_record.hpp"
#include "sensornet/report/run_requirements.hpp"

namespace sensornet::report {

struct JunitRun {
  std::string run_id;
  RunStatus status = RunStatus::Failed;
  int exit_code = 1;
  std::vector<FaultRecord> faults;  // the report's
  std::vector<RequirementCheck> checks;
  double seconds = 0.0;  // wall time of the launch
};

[[nodiscard]] std::string junitXml(const JunitRun& run);

// Any suite of checks as JUnit XML: one <testcase> per case, a <failure> with `failure` as its
// message when it did not pass. (`sensornet conform` writes its rules so.)
struct JunitCase {
  std::string name;
  bool pass = false;
  std::string failure;  // the failure's one-line message
  std::string message;  // the whole story
};
[[nodiscard]] std::string junitSuiteXml(const std::string& suite, const std::string& classname,
                                        const std::vector<JunitCase>& cases, double seconds);

}  // namespace sensornet::report
