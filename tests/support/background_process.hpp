#pragma once
// A program started in the background for an integration test, with its output in a log file.
// Whatever happens in the test (a failed assertion, an exception), the destructor stops it:
// SIGTERM, then SIGKILL after a grace period, then reaps it, so no test leaves a process
// behind.
//
//   BackgroundProcess fusion({fusion_center, "serve", "--run-id", id}, log_dir + "/fc.log");
//   ...
//   std::optional<int> code = fusion.waitForExit(10s);   // nullopt: still running

#include <sys/types.h>

#include <chrono>
#include <optional>
#include <string>
#include <vector>

namespace sensornet::testing {

class BackgroundProcess {
 public:
  // Throws std::runtime_error if the program cannot be started.
  BackgroundProcess(const std::vector<std::string>& argv, const std::string& log_path);
  ~BackgroundProcess();
  BackgroundProcess(BackgroundProcess&& other) noexcept;
  BackgroundProcess& operator=(BackgroundProcess&&) = delete;
  BackgroundProcess(const BackgroundProcess&) = delete;
  BackgroundProcess& operator=(const BackgroundProcess&) = delete;

  [[nodiscard]] pid_t pid() const { return pid_; }
  // The exit status (128 + signal if killed), or nullopt if it still runs after `timeout`.
  std::optional<int> waitForExit(std::chrono::milliseconds timeout);
  // SIGTERM, SIGKILL after `grace`; returns the exit status.
  int stop(std::chrono::milliseconds grace = std::chrono::milliseconds(3000));
  [[nodiscard]] std::string log() const;

 private:
  pid_t pid_ = -1;
  std::optional<int> status_;
  std::string log_path_;
};

// True while a process with this pid exists (and is not a zombie we own).
[[nodiscard]] bool processExists(pid_t pid);

// Tokens shorter than this are refused (std::invalid_argument): every command line contains ""
// (a guard with an empty run id once killed every process on the machine).
inline constexpr std::size_t kMinProcessToken = 8;

// Processes (other than this one) whose command line contains `token` (a run id, say).
[[nodiscard]] std::vector<pid_t> processesMentioning(const std::string& token);

// Kills (SIGKILL) whatever still mentions the token on its command line when the guard goes
// away, pass or fail, so that a failing test never leaves processes for the next one.
class LeftoverGuard {
 public:
  // Throws std::invalid_argument for a token shorter than kMinProcessToken.
  explicit LeftoverGuard(std::string token);
  LeftoverGuard(const LeftoverGuard&) = delete;
  LeftoverGuard& operator=(const LeftoverGuard&) = delete;
  ~LeftoverGuard();

 private:
  std::string token_;
};

}  // namespace sensornet::testing
