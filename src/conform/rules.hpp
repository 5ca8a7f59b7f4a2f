#pragma once
// What the rules of every role share (sensor_conformance.cpp, fusion_center_conformance.cpp):
// making a rule that names its section of docs/wire-protocol.md, wording evidence, and the rules
// that judge the run as a whole (its outcome, the NEES band) rather than one role.

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "sensornet/conform/sensor_conformance.hpp"

namespace sensornet::conform::detail {

// A failing rule (its evidence to come) citing docs/wire-protocol.md#<section>.
[[nodiscard]] RuleCheck rule(std::string id, std::string statement, std::string section);
[[nodiscard]] double secondsSince(std::int64_t from_ns, std::int64_t ns);
[[nodiscard]] std::string plural(std::size_t n, const char* one, const char* many);
// The episodes the run started before it shut down, in order.
[[nodiscard]] std::vector<std::uint32_t> startedEpisodes(const RecordedRun& run);
// How the participant's process ended: "exited with status 0", "was killed by signal 9 ...".
[[nodiscard]] std::string programEnding(const RunFacts& facts);
// The run completed: status completed, the launcher's exit 0.
[[nodiscard]] RuleCheck runCompletes(const RunFacts& facts);
// The run's mean NEES lies in its chi-square band.
[[nodiscard]] RuleCheck truth(const RunFacts& facts);

}  // namespace sensornet::conform::detail
