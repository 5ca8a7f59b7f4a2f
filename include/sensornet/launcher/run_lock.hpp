#pragma once
// One launch per run id on this host: the launcher holds an exclusive lock (flock) on
// <log dir>/launch.lock for the whole launch. The kernel releases it however the launcher ends,
// even by SIGKILL, so a stale lock never blocks a later launch; a second launch of the same run
// (same log folder) cannot take it and is refused before it changes anything.
//
//   const RunLock lock(log_dir, run_id);   // InputError naming the run id when held elsewhere

#include <filesystem>
#include <string>

namespace sensornet::launcher {

class RunLock {
 public:
  // Creates the lock file if needed (never through a symbolic link), takes the lock without
  // waiting and writes this process's id into it. Throws InputError naming `run_id` and the
  // holder's pid when another launch holds it, std::runtime_error when the file cannot be used.
  RunLock(const std::filesystem::path& log_dir, const std::string& run_id);
  RunLock(const RunLock&) = delete;
  RunLock& operator=(const RunLock&) = delete;
  ~RunLock();

  [[nodiscard]] const std::filesystem::path& path() const noexcept { return path_; }

 private:
  std::filesystem::path path_;
  int fd_ = -1;
};

}  // namespace sensornet::launcher
