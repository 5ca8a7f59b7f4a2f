#pragma once
// A stable 64-bit hash of a text (FNV-1a), and its 16 hex digits as a digest: what processes
// compare to agree on a scenario, what a sweep's cell key holds, what a run id maps to a domain
// by. Fast and the same on every machine; not a cryptographic hash.

#include <cstdint>
#include <cstdio>
#include <string>
#include <string_view>

namespace sensornet {

[[nodiscard]] constexpr std::uint64_t fnv1a64(std::string_view text) noexcept {
  std::uint64_t hash = 0xcbf29ce484222325ULL;
  for (const char c : text) {
    hash ^= static_cast<unsigned char>(c);
    hash *= 0x100000001b3ULL;
  }
  return hash;
}

// The 16 lower-case hex digits of fnv1a64(text).
[[nodiscard]] inline std::string digestOf(std::string_view text) {
  char hex[17];
  std::snprintf(hex, sizeof hex, "%016llx", static_cast<unsigned long long>(fnv1a64(text)));
  return hex;
}

}  // namespace sensornet
