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

}  // namespace sensornet::report
