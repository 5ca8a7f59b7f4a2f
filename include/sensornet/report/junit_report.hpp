#pragma once
// A finished run as JUnit XML (`sensornet launch ... --junit FILE.xml`), for the CI systems
// that read JUnit: one <testsuite> named after the run, one <testcase> "run" that passes only
// when the run completed (its message: the status, the exit code, the faults by kind), and one
// <testcase> per --require criterion, passing or failing as the launcher judged it, with the
// value measured in its message.
//
//   const std::string xml = junitXml({run_id, "degraded", 3, faults, checks, 12.5});

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "sensornet/report/run_requirements.hpp"

namespace sensornet::report {

struct JunitRun {
  std::string run_id;
  std::string status;  // the report's status word
  int exit_code = 1;
  nlohmann::json faults = nlohmann::json::array();  // the report's faults
  std::vector<RequirementCheck> checks;
  double seconds = 0.0;  // wall time of the launch
};

[[nodiscard]] std::string junitXml(const JunitRun& run);

}  // namespace sensornet::report
