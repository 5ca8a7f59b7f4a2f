#include "sensornet/launcher/fault.hpp"

#include <algorithm>
#include <optional>
#include <set>

namespace sensornet::launcher {
namespace {

using emulator::FaultKind;
using report::FaultRecord;

// The reported entry is of an episode still open at the cause, or later, or of no episode (the
// run's end). The coordinator keeps at most two episodes outstanding, so the one before the
// cause's may still have been owed counts when the cause struck.
bool atOrAfter(const FaultRecord& entry, const RunPosition& cause) {
  if (!entry.episode || !cause.episode) return true;
  return *entry.episode + 1 >= *cause.episode;
}

bool isConsequenceOf(const FaultRecord& entry, const Fault& cause) {
  // The fusion center marks what it saw as the cause (the coordinator's abort); when that
  // followed from the launcher's cause, the launcher names the root instead.
  if (entry.caused_by && !followsFromStop(entry.caused_by->kind)) return false;
  return followsFromStop(entry.kind) && atOrAfter(entry, cause.at);
}

}  // namespace

FaultRecord Fault::toRecord() const {
  FaultRecord record;
  record.kind = kind;
  record.process = process;
  if (sensors.size() == 1) record.sensor = sensors.front();
  if (!sensors.empty()) record.sensors = sensors;
  record.episode = at.episode;
  record.emulated_time_s = at.emulated_time_s;
  record.detail = detail;
  record.survived = survived;
  record.schedule_version = schedule_version;
  return record;
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

std::vector<FaultRecord> faultList(const std::vector<Fault>& launcher_faults,
                                   const std::vector<FaultRecord>& reported) {
  std::vector<FaultRecord> listed;
  for (const Fault& fault : launcher_faults) listed.push_back(fault.toRecord());
  const Fault* cause = runEndingCause(launcher_faults);
  std::set<int> accounted;  // sensors whose process's end the launcher saw itself
  for (const Fault& fault : launcher_faults) {
    accounted.insert(fault.sensors.begin(), fault.sensors.end());
  }
  for (FaultRecord entry : reported) {
    // The fusion center's sensor_died repeats the coordinator's notice of a death the launcher
    // reported: the launcher's entry says more (the process, how it ended).
    if (entry.kind == FaultKind::SensorDied && entry.sensor && accounted.contains(*entry.sensor)) {
      continue;
    }
    if (cause != nullptr && isConsequenceOf(entry, *cause)) {
      entry.caused_by = report::FaultCause{cause->kind, cause->process};
    }
    listed.push_back(std::move(entry));
  }
  return listed;
}

}  // namespace sensornet::launcher
