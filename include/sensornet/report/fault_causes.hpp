#pragma once
// Causes and consequences in a report's `faults`: an entry that followed from another (the run's
// one cause: a stop, a death under --on-sensor-failure stop) carries `caused_by: {kind,
// process}` of that cause and is counted with it, never as a fault of its own (docs/guide/faults.md,
// "One cause, one fault"). The launcher marks them (sensornet/launcher/fault.hpp: faultList); every
// count of faults (`--require no-faults`, the report page, the launcher's summary) counts causes:
//
//   causeCount(report["faults"]);              // 1 for an interrupt and its 13 consequences
//   isConsequence(fault);                      // fault.contains("caused_by")
//
// The word of `--on-sensor-failure`, which decides whether a death ends the run, is
// FailurePolicy in vocabulary.hpp.

#include <array>
#include <cstddef>
#include <nlohmann/json.hpp>

#include "sensornet/emulator/vocabulary.hpp"

namespace sensornet::report {

inline constexpr const char* kCausedByField = "caused_by";

[[nodiscard]] inline bool isConsequence(const nlohmann::json& fault) {
  return fault.is_object() && fault.contains(kCausedByField);
}

// The entries of `faults` that are not another's consequence.
[[nodiscard]] inline std::size_t causeCount(const nlohmann::json& faults) {
  std::size_t causes = 0;
  if (!faults.is_array()) return causes;
  for (const nlohmann::json& fault : faults) causes += isConsequence(fault) ? 0 : 1;
  return causes;
}

}  // namespace sensornet::report
