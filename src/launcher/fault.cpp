#include "sensornet/launcher/fault.hpp"

#include <algorithm>
#include <optional>
#include <set>

namespace sensornet::launcher {
namespace {

using emulator::FaultKind;
using nlohmann::json;

// The reported entry is of an episode still open at the cause, or later, or of no episode (the
// run's end). The coordinator keeps at most two episodes outstanding, so the one before the
// cause's may still have been owed counts when the cause struck.
bool atOrAfter(const json& entry, const RunPosition& cause) {
  const json episode = entry.is_object() && entry.contains("episode") ? entry["episode"] : json();
  if (!episode.is_number_integer() || !cause.episode) return true;
  return episode.get<std::int64_t>() + 1 >= static_cast<std::int64_t>(*cause.episode);
}

// A kind word of a reported entry, if it is one.
std::optional<FaultKind> kindOf(const json& entry) {
  const json kind = entry.is_object() ? entry.value("kind", json()) : json();
  return kind.is_string() ? lookUpWord<FaultKind>(kind.get<std::string>()) : std::nullopt;
}

bool isConsequenceOf(const json& entry, const Fault& cause) {
  if (!entry.is_object()) return false;
  // The fusion center marks what it saw as the cause (the coordinator's abort); when that
  // followed from the launcher's cause, the launcher names the root instead.
  if (entry.contains(sensornet::report::kCausedByField)) {
    const std::optional<FaultKind> marked = kindOf(entry[sensornet::report::kCausedByField]);
    if (!marked || !followsFromStop(*marked)) return false;
  }
  const std::optional<FaultKind> known = kindOf(entry);
  return known && followsFromStop(*known) && atOrAfter(entry, cause.at);
}

}  // namespace

json Fault::toJson() const {
  json entry = {{"kind", std::string(wordOf(kind))},
                {"process", process},
                {"sensor", sensors.size() == 1 ? json(sensors.front()) : json()},
                {"episode", at.episode ? json(*at.episode) : json()},
                {"emulated_time_s", at.emulated_time_s ? json(*at.emulated_time_s) : json()},
                {"detail", detail}};
  if (!sensors.empty()) entry["sensors"] = sensors;
  entry["survived"] = survived;
  if (schedule_version) entry["schedule_version"] = *schedule_version;
  return entry;
}

const Fault* runEndingCause(const std::vector<Fault>& launcher_faults) {
  const auto it = std::find_if(launcher_faults.begin(), launcher_faults.end(),
                               [](const Fault& f) { return !f.survived; });
  return it == launcher_faults.end() ? nullptr : &*it;
}

bool followsFromStop(FaultKind kind) {
  switch (kind) {
    case FaultKind::Stall:
    case FaultKind::Lost:
    case FaultKind::LateTally:
    case FaultKind::CutShort:
    case FaultKind::RunAborted:
    case FaultKind::MissingEpisodes:
      return true;
    default:
      return false;
  }
}

json faultList(const std::vector<Fault>& launcher_faults, const json& reported) {
  json listed = json::array();
  for (const Fault& fault : launcher_faults) listed.push_back(fault.toJson());
  const Fault* cause = runEndingCause(launcher_faults);
  if (!reported.is_array()) return listed;
  std::set<int> accounted;  // sensors whose process's end the launcher saw itself
  for (const Fault& fault : launcher_faults) {
    accounted.insert(fault.sensors.begin(), fault.sensors.end());
  }
  for (json entry : reported) {
    // The fusion center's sensor_died repeats the coordinator's notice of a death the launcher
    // reported: the launcher's entry says more (the process, how it ended).
    const json& sensor = entry.value("sensor", json());
    if (entry.value("kind", "") == wordOf(emulator::FaultKind::SensorDied) && sensor.is_number() &&
        accounted.contains(sensor.get<int>())) {
      continue;
    }
    if (cause != nullptr && isConsequenceOf(entry, *cause)) {
      entry[sensornet::report::kCausedByField] = {{"kind", std::string(wordOf(cause->kind))},
                                         {"process", cause->process}};
    }
    listed.push_back(std::move(entry));
  }
  return listed;
}

}  // namespace sensornet::launcher
