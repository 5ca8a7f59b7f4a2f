#pragma once
// libfaketime (Debian: faketime) for tests that put a process's wall clock off.
//
// Tests preload the library themselves rather than run the `faketime` wrapper: the wrapper
// shares its time through /dev/shm/faketime_shm_<pid> and sem.faketime_sem_<pid>, which a killed
// wrapper leaves behind, and a later wrapper that is given the same pid fails ("sem_open: File
// exists"). Preloaded without FAKETIME_SHARED, the library makes no such files.
//
//   if (const auto library = faketimeLibrary())
//     exec = "env " + faketimeEnvironment(*library, "FAKETIME=+2s") + " " + exec;

#include <filesystem>
#include <optional>
#include <string>

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

}  // namespace sensornet::testing
