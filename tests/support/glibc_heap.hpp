#pragma once
// Tests that read glibc's heap statistics (mallinfo2) skip in the sanitizer build: there
// AddressSanitizer replaces malloc, and mallinfo2 sees none of its blocks (every count is 0, so
// a "stays flat" check would pass without measuring anything).
//
//   if (!sensornet::testing::kGlibcHeap) GTEST_SKIP() << sensornet::testing::kNoGlibcHeap;

namespace sensornet::testing {

#if defined(__SANITIZE_ADDRESS__)
inline constexpr bool kGlibcHeap = false;
#else
inline constexpr bool kGlibcHeap = true;
#endif

inline constexpr const char* kNoGlibcHeap =
    "AddressSanitizer replaces malloc: glibc's heap statistics (mallinfo2) see none of it";

}  // namespace sensornet::testing
