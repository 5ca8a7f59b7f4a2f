#pragma once
// Running the project's programs from tests: run one to completion and capture its output, with
// a time limit after which it is killed, so that a hung program fails the test instead of
// hanging CTest.
//
//   ProcessResult r = runProcess({coordinator, "timetable", "--help"});
//   EXPECT_EQ(r.exit_code, 0);

#include <chrono>
#include <string>
#include <vector>

namespace sensornet::testing {

struct ProcessResult {
  int exit_code = -1;  // the exit status, or 128 + signal when killed by a signal
  std::string out;     // standard output
  std::string err;     // standard error
  bool timed_out = false;
};

ProcessResult runProcess(const std::vector<std::string>& argv,
                         std::chrono::milliseconds limit = std::chrono::seconds(120));

}  // namespace sensornet::testing
