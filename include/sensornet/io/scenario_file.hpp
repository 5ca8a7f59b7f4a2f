#pragma once
// Reading and writing the file contracts of docs/ARCHITECTURE.md ("File contracts"): scenario
// files (YAML, explicit or random-plant form) and schedule files (JSON). Every malformed input throws InputError naming
// the file, the field and what was expected.
//
//   Scenario s = loadScenarioFile("scenarios/default.yaml");
//   RateSchedule r = loadScheduleFile("plan.json", s);
//   writeScheduleFile("plan.json", r, {{"surrogate", "info"}});

#include <nlohmann/json.hpp>
#include <functional>
#include <ostream>
#include <string>

#include "sensornet/core/rate_schedule.hpp"
#include "sensornet/core/scenario.hpp"

namespace sensornet {

// Parses and validates; `source` names the input in error messages.
// The whole file as text; throws InputError naming the path when it cannot be read. `what`
// names the file's role ("scenario", "schedule").
[[nodiscard]] std::string readTextFile(const std::string& path, const std::string& what);
[[nodiscard]] Scenario parseScenarioYaml(const std::string& text, const std::string& source);
[[nodiscard]] Scenario loadScenarioFile(const std::string& path);

// Parses {"horizon": T, "intervals": N, "rates": [[...] x N]}; extra keys are allowed. When a
// scenario is given, the shape and feasibility are checked against it.
[[nodiscard]] RateSchedule parseScheduleJson(const std::string& text, const std::string& source);
[[nodiscard]] RateSchedule loadScheduleFile(const std::string& path);
[[nodiscard]] RateSchedule loadScheduleFile(const std::string& path, const Scenario& scenario);
[[nodiscard]] nlohmann::json scheduleToJson(const RateSchedule& schedule);
// Writes `doc` (indented) to path atomically: a temporary file beside it, then a rename.
// Throws InputError naming the path when it cannot be written there (a missing folder, no
// permission); std::runtime_error with the system's reason when the disk or a file size limit
// refuses the bytes (no temporary file is left). `what` names the file's role.
void writeJsonFile(const std::string& path, const nlohmann::json& doc, const std::string& what);
// The same, with the text written by `write` (a document too large to hold: streamed).
void writeJsonFile(const std::string& path, const std::string& what,
                   const std::function<void(std::ostream&)>& write);
// Writes scheduleToJson(schedule) merged with `extra` keys.
void writeScheduleFile(const std::string& path, const RateSchedule& schedule,
                       const nlohmann::json& extra = nlohmann::json::object());

}  // namespace sensornet
