#pragma once
// Running the project's programs from tests: run one to completion and capture its output, with
// a time limit after which it is killed, so that a hung program fails the test instead of
// hanging CTest.
//
//   ProcessResult r = runProcess({coordinator, "timetable", "--help"});
//   EXPECT_EQ(r.exit_code, 0);

#include <atomic>
#include <chrono>
#include <string>
#include <thread>
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

// A program running on a thread of its own (runProcess with a time limit), for the tests that
// act on a run while it goes on.
//   RunningProgram launcher({sensornet, "launch", ...}, std::chrono::seconds(60));
//   ...                                   // act on the run meanwhile
//   EXPECT_EQ(launcher.result().exit_code, 0);
class RunningProgram {
 public:
  RunningProgram(std::vector<std::string> argv, std::chrono::milliseconds limit)
      : thread_([this, argv = std::move(argv), limit] {
          result_ = runProcess(argv, limit);
          done_ = true;
        }) {}
  // Blocks until the program ended.
  const ProcessResult& result() {
    if (thread_.joinable()) thread_.join();
    return result_;
  }
  [[nodiscard]] bool done() const { return done_; }

 private:
  ProcessResult result_;
  std::atomic<bool> done_{false};
  std::jthread thread_;
};

}  // namespace sensornet::testing
