#pragma once
// What the sanitizer build changes for a test (scripts/test.sh --sanitize):
//  - AddressSanitizer replaces malloc, and glibc's heap statistics (mallinfo2) see none of its
//    blocks (every count is 0, so a "stays flat" check would pass without measuring anything);
//  - programs run several times slower, so a test of capacity (what rate keeps up) measures
//    the sanitizer, not the program.
//
//   if (sensornet::testing::kAddressSanitizer) GTEST_SKIP() << sensornet::testing::kNoGlibcHeap;
//   runProcess(argv, 60s);   // waits up to 60 s, or 240 s in the sanitizer build

#include <string>

namespace sensornet::testing {

#if defined(__SANITIZE_ADDRESS__)
inline constexpr bool kAddressSanitizer = true;
#else
inline constexpr bool kAddressSanitizer = false;
#endif

// The one factor every time limit of a test's processes is scaled by (runProcess,
// RunningProgram, BackgroundProcess::waitForExit): the sanitizer build runs programs several
// times slower, and a whole run that needs 20 s there is not a hung one. A limit is scaled, a
// test is never skipped for being slow.
inline constexpr int kTimeFactor = kAddressSanitizer ? 4 : 1;

template <class Duration>
[[nodiscard]] constexpr Duration scaledLimit(Duration limit) {
  return limit * kTimeFactor;
}

// A limit in seconds that a test passes to a program (`replan --timeout 60`), scaled alike.
[[nodiscard]] inline std::string scaledSeconds(int seconds) {
  return std::to_string(seconds * kTimeFactor);
}

inline constexpr const char* kNoGlibcHeap =
    "AddressSanitizer replaces malloc: glibc's heap statistics (mallinfo2) see none of it";
inline constexpr const char* kNoCapacity =
    "a capacity test: under AddressSanitizer it would measure the sanitizer's slowdown";

}  // namespace sensornet::testing
