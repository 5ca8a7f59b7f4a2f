#pragma once
// What the sanitizer build changes for a test (scripts/test.sh --sanitize):
//  - AddressSanitizer replaces malloc, and glibc's heap statistics (mallinfo2) see none of its
//    blocks (every count is 0, so a "stays flat" check would pass without measuring anything);
//  - programs run several times slower, so a test of capacity (what rate keeps up) measures
//    the sanitizer, not the program.
//
//   if (sensornet::testing::kAddressSanitizer) GTEST_SKIP() << sensornet::testing::kNoGlibcHeap;

namespace sensornet::testing {

#if defined(__SANITIZE_ADDRESS__)
inline constexpr bool kAddressSanitizer = true;
#else
inline constexpr bool kAddressSanitizer = false;
#endif

inline constexpr const char* kNoGlibcHeap =
    "AddressSanitizer replaces malloc: glibc's heap statistics (mallinfo2) see none of it";
inline constexpr const char* kNoCapacity =
    "a capacity test: under AddressSanitizer it would measure the sanitizer's slowdown";

}  // namespace sensornet::testing
