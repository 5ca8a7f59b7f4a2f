#pragma once
// libfaketime (Debian: faketime) for tests that put a process's wall clock off.
//
// Tests preload the library themselves rather than run the `faketime` wrapper. Both make
// /dev/shm/faketime_shm_<pid> and sem.faketime_sem_<pid> for each process and remove them at its
// exit, so a killed process leaves them behind; a later wrapper given the same pid then fails
// ("sem_open: File exists"), while the preloaded library goes on (measured with libfaketime
// 0.9.10 in a pid namespace). Tests that kill such processes call removeStaleFaketimeFiles().
//
//   if (const auto library = faketimeLibrary())
//     exec = "env " + faketimeEnvironment(*library, "FAKETIME=+2s") + " " + exec;
//   ...
//   removeStaleFaketimeFiles();   // after the run: those of processes no longer alive

#include <signal.h>

#include <cerrno>
#include <filesystem>
#include <optional>
#include <string>
#include <system_error>

namespace sensornet::testing {

// The library's path, if it is installed.
inline std::optional<std::string> faketimeLibrary() {
  for (const char* path : {"/usr/lib/x86_64-linux-gnu/faketime/libfaketime.so.1",
                           "/usr/lib/aarch64-linux-gnu/faketime/libfaketime.so.1",
                           "/usr/lib/faketime/libfaketime.so.1"}) {
    if (std::filesystem::exists(path)) return path;
  }
  return std::nullopt;
}

// `env` assignments that preload the library with `how` (FAKETIME=+2s, or
// FAKETIME_TIMESTAMP_FILE=... to read the offset from a file), leaving the monotonic clock alone
// as NTP leaves it.
inline std::string faketimeEnvironment(const std::string& library, const std::string& how) {
  return "LD_PRELOAD=" + library + " " + how + " FAKETIME_DONT_FAKE_MONOTONIC=1";
}

// Removes libfaketime's files in /dev/shm whose process is no longer alive; returns how many.
inline int removeStaleFaketimeFiles() {
  int removed = 0;
  std::error_code ec;
  for (const auto& entry : std::filesystem::directory_iterator("/dev/shm", ec)) {
    const std::string name = entry.path().filename().string();
    std::string pid;
    for (const char* prefix : {"faketime_shm_", "sem.faketime_sem_"}) {
      if (name.rfind(prefix, 0) == 0) pid = name.substr(std::string(prefix).size());
    }
    if (pid.empty() || pid.find_first_not_of("0123456789") != std::string::npos || pid.size() > 9)
      continue;
    if (::kill(static_cast<pid_t>(std::stol(pid)), 0) == 0 || errno != ESRCH) continue;  // alive
    std::error_code gone;
    if (std::filesystem::remove(entry.path(), gone)) ++removed;
  }
  return removed;
}

}  // namespace sensornet::testing
