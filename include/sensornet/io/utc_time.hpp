#pragma once
// The one spelling of every time sensornet writes: ISO 8601 in UTC, to the second with a "Z"
// ("2026-11-30T18:20:00Z": a report's ended_at, run.json's started_at, a recording's metadata),
// to the millisecond (a recording's first and last sample), or without the zone as DDS Security
// documents take it ("2026-11-30T18:20:00", a permissions document's validity).
//
//   const std::string ended_at = utcNow();                                  // "...:00Z"
//   utcText(std::chrono::system_clock::now() + std::chrono::days(365), UtcForm::NoZone);
//   utcText(std::chrono::system_clock::from_time_t(0), UtcForm::Milliseconds);
//   // "1970-01-01T00:00:00.000Z"

#include <chrono>
#include <string>

namespace sensornet {

enum class UtcForm {
  Seconds,       // 2026-11-30T18:20:00Z
  Milliseconds,  // 2026-11-30T18:20:00.123Z
  NoZone,        // 2026-11-30T18:20:00
};

[[nodiscard]] std::string utcText(std::chrono::system_clock::time_point when,
                                  UtcForm form = UtcForm::Seconds);

// The current time as utcText(now, UtcForm::Seconds).
[[nodiscard]] std::string utcNow();

}  // namespace sensornet
