#include "sensornet/emulator/fusion_center_core.hpp"

#include <algorithm>
#include <cstdio>
#include <iterator>
#include <limits>

#include "sensornet/core/network.hpp"
#include "sensornet/emulator/covariance_trace.hpp"
#include "sensornet/report/fault_causes.hpp"
#include "sensornet/emulator/sensor_ids.hpp"

namespace sensornet::emulator {

using nlohmann::json;

namespace {

constexpr const char* kProcess = "fusion_center";
// The report's covariance_traces: the first few episodes, each curve on this many grid times.
constexpr std::size_t kTracedEpisodes = 3;
constexpr int kTracePoints = 200;
// Wall seconds a measurement or tally may take from its publication to this process (less this
// process's own stalls) before the link that carried it counts as having stalled: the slack a
// StallWatch allows a process (a loaded machine delays a sample by tens of milliseconds).
constexpr double kHeldBackS = 0.5;
// "sensor 3", "sensors 3, 4, 5": the sensors a fault's detail names, each by its number.
std::string sensorList(const std::vector<int>& sensors) {
  std::string names;
  for (const int j : sensors) names += (names.empty() ? "" : ", ") + std::to_string(j);
  return (sensors.size() > 1 ? "sensors " : "sensor ") + names;
}

// closed_without_: an episode cut short at the run's end, not closed by the stall limit.
constexpr std::int64_t kClosedAtRunEnd = std::numeric_limits<std::int64_t>::min();

std::int64_t toNs(double seconds) { return static_cast<std::int64_t>(1e9 * seconds); }

std::string formatSeconds(double seconds) {
  char text[32];
  std::snprintf(text, sizeof text, "%.3g", seconds);
  return text;
}

// A clock's offset: to the microsecond up to 1000 s ("2.00018").
std::string formatOffset(double seconds) {
  char text[32];
  std::snprintf(text, sizeof text, "%.6g", seconds);
  return text;
}

template <class Numbers>
std::string listed(const Numbers& numbers) {
  std::string out;
  for (const auto n : numbers) out += (out.empty() ? "" : ", ") + std::to_string(n);
  return out;
}

}  // namespace

// An episode in progress: its clock, its fusion and what the fusion center heard of it.
struct FusionCenterCore::OpenEpisode {
  EpisodeClock clock;
  std::unique_ptr<EpisodeFusion> fusion;
  std::vector<std::int64_t> last_heard_ns;  // per sensor: its last measurement, tally or status
  std::vector<EpisodeTally> tallies;        // as received (sent, lag, stalls), per sensor
  std::vector<double> held_back_s;          // per sensor: the longest a sample of it was in transit
  std::int64_t last_tally_ns = 0;           // publication wall time of the latest tally
  // When the latest failure notice that applied to it came: until then the dead sensors' counts
  // were owed, and waiting for them is not the fusion center's backlog.
  std::int64_t last_failure_notice_ns = 0;
  std::int64_t last_arrival_ns = 0;         // receipt of the latest measurement or tally
  std::optional<std::int64_t> settled_ns;   // when everything owed was in
  std::uint64_t backlog = 0;
};

FusionCenterCore::FusionCenterCore(FusionCenterConfig config, const WriterFacts& writers,
                                   std::int64_t joined_ns)
    : config_(std::move(config)), writers_(writers) {
  // The faults of the process's earlier lives; one this version cannot read is said in the log.
  for (const json& fault : config_.resumed_faults) {
    try {
      faults_.push_back(report::decodeFault(fault));
    } catch (const report::RecordError& e) {
      log(spdlog::level::warn, "a fault of an earlier life is not kept: " + std::string(e.what()));
    }
  }
  config_.resumed_faults.clear();
  if (config_.resumed_log) {
    resumed_.emplace(*config_.resumed_log, joined_ns);
    // Recorded now, so that a life killed before its end still leaves its restart in the fault
    // log, as the next life reads it; noteRestart says what it could not fuse when this one ends.
    restart_fault_ = faults_.size();
    recordFault(faultEntry(FaultKind::Restarted, kProcess, std::nullopt, std::nullopt,
                           std::nullopt,
                           "the fusion center was restarted and resumed from " +
                               std::to_string(resumed_->entries().size()) +
                               " logged episodes, and was stopped again before the run's end "
                               "(what it could not fuse is incomplete in the episode log)"));
  }
}

FusionCenterCore::~FusionCenterCore() = default;

std::vector<FusionAction> FusionCenterCore::takeActions() { return std::exchange(actions_, {}); }

void FusionCenterCore::log(spdlog::level::level_enum level, std::string text) {
  emit<LogLine>(level, std::move(text));
}

void FusionCenterCore::recordFault(report::FaultRecord fault) {
  faults_.push_back(fault);
  emit<RecordFault>(std::move(fault));
}

void FusionCenterCore::countOutside(RejectionReason reason, std::uint64_t count) {
  rejected_outside_[reason] += count;
}

void FusionCenterCore::onScenario(ScenarioAnnounced announced, std::int64_t /*now*/) {
  if (announced_) return;  // one scenario per run
  announced_ = std::move(announced);
  plant_.emplace(announced_->scenario, announced_->seed);
  std::optional<std::filesystem::path> read_back;  // the report's entries, from the log
  if (config_.episode_log) read_back = config_.episode_log_path;
  report_.emplace(config_.run_id, announced_->digest, scenario().sensorCount(),
                  scenario().stateDim(), std::move(read_back));
  if (resumed_) {
    for (const json& entry : resumed_->entries()) report_->add(entry);
  }
}

void FusionCenterCore::onScheduleVersions(const std::vector<ScheduleVersion>& versions,
                                          std::int64_t /*now*/) {
  std::size_t added = 0;
  for (const ScheduleVersion& v : versions) {
    if (book_.add(v) == ScheduleBook::Outcome::Accepted) ++added;
  }
  if (added == 0) return;
  for (auto& [episode, open] : open_) open->fusion->scheduleChanged();
}

void FusionCenterCore::onEpisodeStart(const EpisodeStart& start, std::int64_t now) {
  if (last_started_ && start.episode <= *last_started_) return;  // RunInputs hands each out once
  last_started_ = start.episode;
  failed_sensors_.insert(start.failed_sensors.begin(), start.failed_sensors.end());
  startEpisode(start, now);
}

void FusionCenterCore::startEpisode(const EpisodeStart& start, std::int64_t now) {
  episodes_planned_ = start.episodes_planned;
  if (resumed_) {
    for (const std::uint32_t e : resumed_->heardStart(start.episode, start.clock.start_wall_ns)) {
      restarted_.emplace(e, e == start.episode ? start.clock.wallAt(scenario().horizon_s) : 0);
    }
    if (resumed_->ignores(start.episode)) {
      early_.erase(start.episode);
      early_tallies_.erase(start.episode);
      return;
    }
  }
  auto open = std::make_unique<OpenEpisode>();
  open->clock = start.clock;
  open->fusion = std::make_unique<EpisodeFusion>(
      scenario(), *plant_, book_, start.episode,
      [this](const ScheduleVersion& v) { return bracketOf(v); },
      [this, episode = start.episode](const ScheduleVersion& v) {
        return deliveredBracketOf(v, episode);
      });
  const auto sensors = static_cast<std::size_t>(scenario().sensorCount());
  open->last_heard_ns.assign(sensors, 0);
  open->tallies.assign(sensors, EpisodeTally{});
  open->held_back_s.assign(sensors, 0.0);
  OpenEpisode& slot = *open_.emplace(start.episode, std::move(open)).first->second;
  for (const int j : start.failed_sensors) slot.fusion->sensorFailedBefore(j);
  for (const SensorFailure& failure : failures_) applyFailure(start.episode, slot, failure);
  // Measurements and tallies that came before the episode's control sample.
  if (auto early = early_.find(start.episode); early != early_.end()) {
    for (auto& a : early->second) route(slot, std::move(a.measurement), a.writer, now);
    early_.erase(early);
  }
  if (auto early = early_tallies_.find(start.episode); early != early_tallies_.end()) {
    for (const auto& t : early->second) applyTally(slot, t, now);
    early_tallies_.erase(early);
  }
}

void FusionCenterCore::onSensorFailure(const SensorFailure& failure, std::int64_t now) {
  log(spdlog::level::warn, "sensors failed in episode " + std::to_string(failure.episode) +
                               " at " + formatSeconds(failure.at_s) + " s: " + failure.detail);
  if (resumed_ && open_.count(failure.episode) == 0 &&
      (!last_started_ || failure.episode > *last_started_)) {
    // Under way, and its start was before this process joined (the durable control sample
    // is this notice now): it cannot be fused; its end is unknown.
    for (const std::uint32_t e : resumed_->heardOfRunning(failure.episode)) restarted_.emplace(e, 0);
  }
  for (const int j : failure.sensors) {
    const auto heard = heard_ns_.find(j);
    if (heard == heard_ns_.end() || silent_from_ns_.count(j) > 0) continue;
    // It still owes an earlier episode its count: it died there, whenever the notice came.
    const bool owes_earlier = std::any_of(open_.begin(), open_.end(), [&](const auto& open) {
      return open.first < failure.episode && !open.second->fusion->settled(j);
    });
    if (owes_earlier || awakeSince(heard->second, now) > kLateFailureNoticeS) {
      silent_from_ns_[j] = heard->second;
    }
  }
  recordDeaths(failure);
  failed_sensors_.insert(failure.sensors.begin(), failure.sensors.end());
  failures_.push_back(failure);
  releaseClaims(failure.sensors);
  for (auto& [number, open] : open_) {
    applyFailure(number, *open, failure);
    open->last_failure_notice_ns = now;
  }
}

// One sensor_died per sensor, the first time a notice names it (every notice names every sensor
// failed so far, and a resumed process has the entries of its predecessor): the report of a run
// that no launcher supervised says so too (coordinator serve --sensor-deaths liveliness).
void FusionCenterCore::recordDeaths(const SensorFailure& failure) {
  for (const int j : failure.sensors) {
    const bool known = std::any_of(faults_.begin(), faults_.end(), [&](const report::FaultRecord& f) {
      return f.kind == FaultKind::SensorDied && f.sensor == j;
    });
    if (known) continue;
    // Which process (and so which host) it lived in, as that process answered the clock probes:
    // across machines, which machine went.
    std::string hosted_by;
    for (const ClockOffsets::Process& p : clocks_.processes()) {
      if (std::find(p.sensors.begin(), p.sensors.end(), j) != p.sensors.end()) {
        hosted_by = " (hosted by " + p.name + ")";
      }
    }
    recordFault(faultEntry(FaultKind::SensorDied, "sensor_agent", j, failure.episode, failure.at_s,
                           "the coordinator announced it failed: " + failure.detail + hosted_by));
  }
}

// A failed sensor is never awaited: in the episode it died in (the episode is incomplete), in
// the later ones (dead from their start), and in an earlier one still waiting for its count.
// A notice that came late is not when it died: its silence says so (applySilentFailure).
void FusionCenterCore::applyFailure(std::uint32_t number, OpenEpisode& open,
                                    const SensorFailure& failure) {
  for (const int j : failure.sensors) {
    const auto silent = silent_from_ns_.find(j);
    if (number <= failure.episode && silent != silent_from_ns_.end()) {
      if (number == failure.episode || !open.fusion->settled(j)) {
        applySilentFailure(open, j, silent->second);
      }
    } else if (number == failure.episode) {
      open.fusion->sensorFailedAt(j, failure.at_s);
    } else if (number > failure.episode) {
      open.fusion->sensorFailedBefore(j);
    } else if (!open.fusion->settled(j)) {
      open.fusion->sensorFailedAt(j, std::numeric_limits<double>::infinity());
    }
  }
}

// A sensor last heard at `last_heard_ns`, long before the notice: dead from the start of an
// episode it was silent throughout (which it then leaves complete, as any later one), else
// failed after it was last heard in it.
void FusionCenterCore::applySilentFailure(OpenEpisode& open, int sensor,
                                          std::int64_t last_heard_ns) {
  const std::int64_t start_ns = open.clock.wallAt(0.0);
  if (open.last_heard_ns[static_cast<std::size_t>(sensor)] == 0 && last_heard_ns <= start_ns) {
    open.fusion->sensorFailedBefore(sensor);
    return;
  }
  open.fusion->sensorFellSilentAt(sensor, open.clock.emulatedAt(std::max(last_heard_ns, start_ns)));
}

void FusionCenterCore::heard(std::uint32_t sensor, std::int64_t now) {
  std::int64_t& last = heard_ns_[static_cast<int>(sensor)];
  last = std::max(last, now);
}

CostBracket FusionCenterCore::bracketOf(const ScheduleVersion& v) {
  auto it = brackets_.find(v.version);
  if (it == brackets_.end()) {
    it = brackets_.emplace(v.version, computeBracket(scenario(), v.schedule)).first;
  }
  return it->second;
}

// The bracket of what the emulated network delivers of version v in `episode`: the same for
// every episode with the same outages.
CostBracket FusionCenterCore::deliveredBracketOf(const ScheduleVersion& v, std::uint32_t episode) {
  const NetworkSpec& network = *scenario().network;
  std::vector<std::size_t> outages;
  for (std::size_t i = 0; i < network.outages.size(); ++i) {
    if (network.outages[i].appliesTo(episode)) outages.push_back(i);
  }
  auto key = std::make_pair(v.version, std::move(outages));
  auto it = delivered_brackets_.find(key);
  if (it == delivered_brackets_.end()) {
    const RateSchedule delivered = deliveredSchedule(v.schedule, network, episode);
    it = delivered_brackets_.emplace(std::move(key), computeBracket(scenario(), delivered)).first;
  }
  return it->second;
}

// The scenario's emulated network writes some of this sensor's measurements twice.
bool FusionCenterCore::duplicatesLink(int sensor) const {
  const auto& network = scenario().network;
  return network && sensor >= 0 && static_cast<std::size_t>(sensor) < network->links.size() &&
         network->links[static_cast<std::size_t>(sensor)].duplicate > 0.0;
}

// A copy the emulated network made of a measurement of an episode already closed (the copy
// can trail the tally, which travels on another topic): counted as the network's, not as a
// sample of a finished episode, while the sensor's tally leaves copies unaccounted for.
bool FusionCenterCore::networkCopyAfterClose(std::uint32_t episode, int sensor) {
  const auto left = copies_left_.find({episode, sensor});
  if (left == copies_left_.end()) return false;
  countOutside(RejectionReason::NetworkDuplicate);
  if (--left->second == 0) copies_left_.erase(left);
  return true;
}

void FusionCenterCore::rejectOutside(RejectionReason reason, const std::string& detail) {
  countOutside(reason);
  log(spdlog::level::warn, "rejected a measurement: " + detail);
}

void FusionCenterCore::onMeasurement(MeasurementArrival arrival, std::int64_t now) {
  ++waiting_;
  if (arrival.other_run) {
    rejectOutside(RejectionReason::OtherRun, "of another run '" + *arrival.other_run + "'");
    return;
  }
  const std::uint32_t episode = arrival.episode;
  if (resumed_ && resumed_->ignores(episode)) return;  // logged before, or not fusable here
  auto open = open_.find(episode);
  if (open == open_.end()) {
    const int sensor = arrival.measurement.sensor;
    if (hasScenario() && networkCopyAfterClose(episode, sensor)) return;
    if (last_started_ && episode <= *last_started_) {
      if (closed_without_.count({episode, sensor}) + held_back_.count({episode, sensor}) > 0) {
        ++after_close_[{episode, sensor}];
      }
      rejectOutside(RejectionReason::FinishedEpisode,
                    "of finished episode " + std::to_string(episode) + " (sensor " +
                        std::to_string(sensor) + ")");
    } else {
      early_[episode].push_back(std::move(arrival));
    }
    return;
  }
  route(*open->second, std::move(arrival.measurement), arrival.writer, now);
}

// Who may speak for a sensor. First its writer's identity: the partition it writes in names
// the sensors it speaks for (run_partitions.hpp; in a secured run DDS Security lets an identity
// write in its own partition only), and a sample for any other sensor is kept out, counted as
// wrong_identity and named once per writer with the sensors it does speak for. Then, as
// without security anyone on the host can write in any partition, the one-writer rule: a
// sample of a second writer claiming a sensor whose first writer lives is kept out
// (writer_claims.hpp), counted as rejected (foreign_writer) and named once per writer.
bool FusionCenterCore::refuseWriter(WriterClaims& claims, SensorTopic topic, std::uint32_t sensor,
                                    WriterId writer, std::uint32_t episode) {
  static constexpr const char* kTopicNames[] = {"Measurement", "EpisodeTally", "SensorStatus"};
  const std::string topic_name = kTopicNames[static_cast<int>(topic)];
  const int j = static_cast<int>(sensor);
  const std::vector<int>& speaks_for = writers_.sensorsOf(topic, writer);
  if (!std::binary_search(speaks_for.begin(), speaks_for.end(), j)) {
    countOutside(RejectionReason::WrongIdentity);
    if (claims.firstRefusalOf(writer)) {
      const std::string detail =
          "a " + topic_name + " writer (publication " + std::to_string(writer) +
          ") whose identity speaks for " +
          (speaks_for.empty() ? std::string("no sensor")
                              : "sensors " + formatSensorIds(speaks_for)) +
          " wrote for sensor " + std::to_string(sensor) + "; its samples are kept out";
      log(spdlog::level::warn, detail);
      recordFault(faultEntry(FaultKind::WrongIdentity, kProcess, j, episode, std::nullopt, detail));
    }
    return true;
  }
  const auto live = [this, topic](WriterId w) { return writers_.live(topic, w); };
  if (!claims.isForeign(j, writer, live)) return false;
  countOutside(RejectionReason::ForeignWriter);
  if (claims.firstRefusalOf(writer)) {
    const std::string detail =
        "a second " + topic_name +
        " writer (publication " + std::to_string(writer) + ") claims sensor " +
        std::to_string(sensor) + " while its first writer (publication " +
        std::to_string(claims.ownerOf(j)) + ") lives; its samples are kept out";
    log(spdlog::level::warn, detail);
    recordFault(faultEntry(FaultKind::ForeignWriter, kProcess, j, episode, std::nullopt, detail));
  }
  return true;
}

// The sensors' processes were declared failed: whoever takes their place writes anew.
void FusionCenterCore::releaseClaims(const std::set<int>& sensors) {
  for (const int j : sensors) {
    measurement_claims_.release(j);
    tally_claims_.release(j);
    status_claims_.release(j);
  }
}

void FusionCenterCore::route(OpenEpisode& open, FusedMeasurement m, WriterId writer,
                             std::int64_t now) {
  const int sensor = m.sensor;
  // A sensor declared dead before this episode that publishes again (its process started anew,
  // or an outside one that ignores failed_sensors) is refused and counted: no rejoin.
  if (open.fusion->failedBefore(sensor)) {
    countOutside(RejectionReason::FailedSensor);
    if (returned_.insert(sensor).second) {
      log(spdlog::level::warn,
          "sensor " + std::to_string(sensor) + " was declared failed, and a writer (publication " +
              std::to_string(writer) + ") publishes for it again in episode " +
              std::to_string(open.fusion->episode()) +
              ": its measurements are refused (failed_sensor), a dead sensor does not rejoin");
    }
    return;
  }
  m.received_s = open.clock.emulatedAt(m.receive_wall_ns);
  // A foreign writer's sample that is malformed anyway is counted under that more telling
  // reason by the fusion.
  if (!malformedMeasurement(scenario(), m) &&
      refuseWriter(measurement_claims_, SensorTopic::Measurement,
                    static_cast<std::uint32_t>(sensor), writer, open.fusion->episode())) {
    return;
  }
  const std::int64_t published_ns = m.publish_wall_ns;
  const std::int64_t received_ns = m.receive_wall_ns;
  if (auto rejection = open.fusion->add(std::move(m))) {
    // The emulated network's copies are expected; finish() tells them from other duplicates.
    const auto level = rejection->reason == wordOf(RejectionReason::Duplicate) &&
                               duplicatesLink(sensor)
                           ? spdlog::level::debug
                           : spdlog::level::warn;
    log(level, "rejected a measurement of episode " + std::to_string(open.fusion->episode()) +
                   ": " + rejection->detail);
    if (rejection->reason == wordOf(RejectionReason::Malformed)) {
      Refusals& refusals = refusals_[{sensor, open.fusion->episode()}];
      if (refusals.samples++ == 0) refusals.first_detail = rejection->detail;
    }
    return;
  }
  measurement_claims_.claim(sensor, writer);  // accepted: well-formed, of this run
  const auto j = static_cast<std::size_t>(sensor);
  open.last_heard_ns[j] = now;
  heard(static_cast<std::uint32_t>(sensor), now);
  open.last_arrival_ns = std::max(open.last_arrival_ns, received_ns);
  if (published_ns > 0 && received_ns > published_ns) {
    open.held_back_s[j] = std::max(open.held_back_s[j], awakeSince(published_ns, received_ns));
  }
}

void FusionCenterCore::onTally(const EpisodeTally& t, std::int64_t now) {
  if (!hasScenario()) return;  // the wiring keeps tallies (transient local) until the scenario
  if (t.run_id != config_.run_id) {
    countOutside(RejectionReason::OtherRun);
    return;
  }
  if (t.sensor >= static_cast<std::uint32_t>(scenario().sensorCount())) {
    countOutside(RejectionReason::MalformedTally);
    return;
  }
  if (refuseWriter(tally_claims_, SensorTopic::Tally, t.sensor, t.writer, t.episode)) return;
  tally_claims_.claim(static_cast<int>(t.sensor), t.writer);
  if (resumed_ && resumed_->ignores(t.episode)) return;  // no late tally for those
  if (auto open = open_.find(t.episode); open != open_.end()) {
    applyTally(*open->second, t, now);
  } else if (!last_started_ || t.episode > *last_started_) {
    early_tallies_[t.episode].push_back(t);
  } else {
    lateTally(t);
  }
}

void FusionCenterCore::applyTally(OpenEpisode& open, const EpisodeTally& t, std::int64_t now) {
  const auto j = static_cast<std::size_t>(t.sensor);
  open.tallies[j] = t;
  open.fusion->setTally(static_cast<int>(t.sensor), t.count);
  open.last_heard_ns[j] = now;
  heard(t.sensor, now);
  open.last_tally_ns = std::max(open.last_tally_ns, t.wall_time_ns);
  open.last_arrival_ns = std::max(open.last_arrival_ns, now);
  if (t.wall_time_ns > 0 && now > t.wall_time_ns) {
    open.held_back_s[j] = std::max(open.held_back_s[j], awakeSince(t.wall_time_ns, now));
  }
}

// A tally of an episode closed before it came (the sensor or the network stalled past the
// limit): the report names what the episode missed, and who held it back.
void FusionCenterCore::lateTally(const EpisodeTally& t) {
  const auto closed = closed_without_.find({t.episode, static_cast<int>(t.sensor)});
  if (closed == closed_without_.end()) return;
  const std::int64_t closed_at = closed->second;
  closed_without_.erase(closed);
  report::FaultRecord fault =
      faultEntry(FaultKind::LateTally, kProcess, static_cast<int>(t.sensor), t.episode, std::nullopt,
                 "sensor " + std::to_string(t.sensor) + " reported " + std::to_string(t.count.sent) +
                     " measurements sent in episode " + std::to_string(t.episode) +
                     " after the episode had been closed without them");
  // Written before the close, arrived after: the sensor was on time, the network was not. (A
  // stalled sensor writes its count late.) Clocks of different hosts agree to milliseconds
  // under NTP, far within the stall limit this compares against.
  if (t.wall_time_ns > 0 && t.wall_time_ns <= closed_at) {
    blameNetwork(t);
    fault.caused_by = report::FaultCause{FaultKind::NetworkPartition, "network"};
  }
  recordFault(std::move(fault));
}

// One network_partition fault per episode, naming every sensor whose count the network held
// back past the stall limit; their stall faults become its consequences.
void FusionCenterCore::blameNetwork(const EpisodeTally& t) {
  const int j = static_cast<int>(t.sensor);
  held_back_.insert({t.episode, j});
  for (report::FaultRecord& f : faults_) {
    if (f.kind == FaultKind::Stall && f.episode == t.episode && f.sensor == j && !f.caused_by) {
      f.caused_by = report::FaultCause{FaultKind::NetworkPartition, "network"};
    }
  }
  const auto partition = std::find_if(faults_.begin(), faults_.end(), [&](const report::FaultRecord& f) {
    return f.kind == FaultKind::NetworkPartition && f.episode == t.episode;
  });
  std::vector<int> sensors = partition == faults_.end() ? std::vector<int>{} : *partition->sensors;
  if (std::find(sensors.begin(), sensors.end(), j) == sensors.end()) sensors.push_back(j);
  std::sort(sensors.begin(), sensors.end());
  const std::string detail =
      "the network held back " + sensorList(sensors) + " past the stall limit: " + (sensors.size() > 1 ? "their counts" : "its count") +
      " of episode " + std::to_string(t.episode) +
      ", written before the episode was closed without them, arrived after it (a cut link or a "
      "partition between them and the fusion center)";
  log(spdlog::level::warn, "episode " + std::to_string(t.episode) + ": " + detail);
  if (partition != faults_.end()) {
    partition->sensors = std::move(sensors);
    partition->detail = detail;
    return;
  }
  report::FaultRecord fault =
      faultEntry(FaultKind::NetworkPartition, "network", std::nullopt, t.episode, std::nullopt, detail);
  fault.sensors = std::move(sensors);
  recordFault(std::move(fault));
}

// A process's answer to a clock probe: its sensors must be the run's, and its times possible.
void FusionCenterCore::onClockEcho(const ClockEcho& echo, std::int64_t now) {
  if (echo.run_id != config_.run_id) return;
  const int sensors = hasScenario() ? scenario().sensorCount() : 0;
  const bool known = !echo.sensors.empty() &&
                     std::all_of(echo.sensors.begin(), echo.sensors.end(),
                                 [sensors](int j) { return j >= 0 && j < sensors; });
  if (!known) {
    if (++clock_echoes_refused_ == 1) {
      log(spdlog::level::warn, "a clock echo of \"" + echo.process + "\" names sensors " +
                                   listed(echo.sensors) + ", not sensors of this run: refused");
    }
    return;
  }
  const ClockExchange x{echo.probe_sent_ns, echo.probe_taken_ns, echo.answered_ns, now};
  if (!clocks_.add(echo.process, echo.sensors, x) && clocks_.refused() == 1) {
    log(spdlog::level::warn, "a clock echo of \"" + echo.process +
                                 "\" has times that cannot be (answered before it took the "
                                 "probe, or came back before it was sent): refused");
  }
}

// Latencies across clocks. Where a process answered the clock probes, its offset is measured
// both ways (clock_offsets.hpp): one surely beyond kClockBoundS either way is a clock_offset
// fault naming its sensors and the offset, and the latency figures are not known. Where none
// did, one way only: a measurement stamped after it was received cannot be, unless the sender's
// clock is ahead of this one (beyond kClockBoundS, a fault too); a clock behind then looks like
// a slow network. Any such makes the latency figures not known (never negative, never silently
// wrong). One fault however often it is called; each call says what is known by then.
void FusionCenterCore::noteClocks() {
  std::vector<int> named;  // by the fault
  std::vector<std::string> parts;
  for (const ClockOffsets::Process& p : clocks_.processes()) {
    if (!p.farthest.surelyBeyond(kClockBoundS)) continue;
    named.insert(named.end(), p.sensors.begin(), p.sensors.end());
    parts.push_back("the clock of the host of " + sensorList(p.sensors) + " is " +
                    (p.farthest.offset_s > 0.0 ? "ahead of" : "behind") + " the fusion center's by " +
                    formatOffset(std::abs(p.farthest.offset_s)) + " s (+/- " +
                    formatSeconds(p.farthest.uncertainty_s) + " s, measured both ways)");
  }
  std::vector<int> ahead;   // one way: stamped after they were received
  std::vector<int> beyond;  // ... by more than the bound, with no measurement both ways
  double most = 0.0;
  for (std::size_t j = 0; j < earliest_latency_s_.size(); ++j) {
    if (earliest_latency_s_[j] >= 0.0) continue;
    const int sensor = static_cast<int>(j);
    ahead.push_back(sensor);
    most = std::max(most, -earliest_latency_s_[j]);
    if (-earliest_latency_s_[j] > kClockBoundS && !clocks_.measured(sensor)) beyond.push_back(sensor);
  }
  if (!beyond.empty()) {
    double least = std::numeric_limits<double>::infinity();  // true of each of them
    for (const int j : beyond) least = std::min(least, -earliest_latency_s_[static_cast<std::size_t>(j)]);
    named.insert(named.end(), beyond.begin(), beyond.end());
    parts.push_back("the clock of the host of " + sensorList(beyond) +
                    " is ahead of the fusion center's by at least " + formatSeconds(least) +
                    " s (a measurement stamped that much after it was received)");
  }
  if (!ahead.empty()) {
    report_->setLatencyUnknown("the clocks disagree: " + sensorList(ahead) +
                               " stamped measurements up to " + formatSeconds(most) +
                               " s after the fusion center received them");
  } else if (!named.empty()) {
    report_->setLatencyUnknown("the clocks disagree: " + parts.front());
  }
  if (named.empty()) return;
  std::string detail;
  for (const std::string& part : parts) detail += (detail.empty() ? "" : "; ") + part;
  detail += "; the bound is " + formatSeconds(kClockBoundS) +
            " s: latencies and real-time costs across them are not known";
  std::sort(named.begin(), named.end());
  const auto known = std::find_if(faults_.begin(), faults_.end(), [](const report::FaultRecord& f) {
    return f.kind == FaultKind::ClockOffset;
  });
  if (known != faults_.end()) {  // called again: says what is known now
    known->sensors = std::move(named);
    known->detail = detail;
    return;
  }
  log(spdlog::level::warn, detail);
  report::FaultRecord fault =
      faultEntry(FaultKind::ClockOffset, "sensor_agent", std::nullopt, std::nullopt, std::nullopt, detail);
  fault.sensors = std::move(named);
  recordFault(std::move(fault));
}

// Whether an episode's latencies compare clocks that disagree: a measurement of it stamped after
// it arrived, or a process whose latest measured offset is surely beyond kClockBoundS.
bool FusionCenterCore::clocksDisagree(const EpisodeResult& r) const {
  const auto stamped_late = [](double latency_s) { return latency_s < 0.0; };
  const auto beyond = [](const ClockOffsets::Process& p) { return p.best.surelyBeyond(kClockBoundS); };
  return std::any_of(r.earliest_latency_s.begin(), r.earliest_latency_s.end(), stamped_late) ||
         std::any_of(clocks_.processes().begin(), clocks_.processes().end(), beyond);
}

// The report's `clocks`: every process's measured offset from the fusion center's clock, by
// first sensor.
nlohmann::json FusionCenterCore::clocksJson() const {
  std::vector<const ClockOffsets::Process*> by_sensor;  // in the order of their first sensors
  for (const ClockOffsets::Process& p : clocks_.processes()) by_sensor.push_back(&p);
  std::stable_sort(by_sensor.begin(), by_sensor.end(), [](const auto* a, const auto* b) {
    return a->sensors.front() < b->sensors.front();
  });
  json processes = json::array();
  for (const ClockOffsets::Process* process : by_sensor) {
    const ClockOffsets::Process& p = *process;
    processes.push_back({{"process", p.name},
                         {"sensors", p.sensors},
                         {"offset_s", p.best.offset_s},
                         {"uncertainty_s", p.best.uncertainty_s},
                         {"farthest_offset_s", p.farthest.offset_s},
                         {"farthest_uncertainty_s", p.farthest.uncertainty_s},
                         {"exchanges", p.exchanges}});
  }
  return {{"bound_s", kClockBoundS},
          {"processes", std::move(processes)},
          {"echoes_refused", clocks_.refused() + clock_echoes_refused_}};
}

void FusionCenterCore::onCommandRefused(std::uint64_t command_id, const std::string& reason,
                                        std::int64_t /*now*/) {
  if (!refused_commands_.insert(command_id).second) return;  // a reply comes again on a resend
  const std::string detail = "command " + std::to_string(command_id) + " refused: " + reason;
  log(spdlog::level::warn, detail);
  recordFault(faultEntry(FaultKind::CommandRefused, "coordinator", std::nullopt, last_started_,
                         std::nullopt, detail));
}

// Statuses carry each sensor's running count: a lower bound of what it sent, for a sensor
// whose tally never comes.
void FusionCenterCore::onStatus(const SensorStatus& s, std::int64_t now) {
  if (s.run_id != config_.run_id) return;
  if (refuseWriter(status_claims_, SensorTopic::Status, s.sensor, s.writer, s.episode)) return;
  status_claims_.claim(static_cast<int>(s.sensor), s.writer);
  SensorProcess& process = sensor_processes_[s.sensor];
  process.id = s.process_id;
  process.state = s.state;
  process.status_writer = s.writer;
  heard(s.sensor, now);
  auto open = open_.find(s.episode);
  if (open == open_.end() || !hasScenario() ||
      s.sensor >= static_cast<std::uint32_t>(scenario().sensorCount())) {
    return;
  }
  open->second->fusion->noteSentAtLeast(static_cast<int>(s.sensor), s.sent_in_episode);
  // Hearing for the stall limit: a sensor still publishing the episode (running it, its count
  // not yet in). One that says it is done with it (ready, its count written) is waited for no
  // longer than the limit: its statuses naming the episode it ran last come every second for as
  // long as it lives, and would keep an episode whose measurements or count the network lost
  // open for ever (chaos seed 214: a restarted fusion center never matched one sensor's writer).
  if (s.state == SensorState::Running && !open->second->fusion->tally(static_cast<int>(s.sensor)).tallied) {
    open->second->last_heard_ns[s.sensor] = now;
  }
}

// Wall seconds since `from_ns` during which this process ran.
double FusionCenterCore::awakeSince(std::int64_t from_ns, std::int64_t now_ns) const {
  return 1e-9 * static_cast<double>(now_ns - from_ns) - stall_watch_.stalledBetween(from_ns, now_ns);
}

void FusionCenterCore::tick(std::int64_t now) {
  if (const auto stall = stall_watch_.tick(now)) {
    log(spdlog::level::warn, "the fusion center was stalled for " + formatSeconds(stall->seconds()) +
                                 " s");
    stalls_.push_back({{"process", kProcess}, {"seconds", stall->seconds()}});
  }
  if (!hasScenario()) return;
  giveUpUnheldStarts(now);
  answerRestarted(now);
  // Measurements handled since the last tick: how many were waiting for the main loop.
  const std::uint64_t waiting = std::exchange(waiting_, 0);
  const double horizon = scenario().horizon_s;
  for (auto it = open_.begin(); it != open_.end();) {
    const std::uint32_t number = it->first;
    OpenEpisode& open = *it->second;
    open.backlog = std::max(open.backlog, waiting);
    const double watermark = open.clock.emulatedAt(now - toNs(config_.lag_s));
    if (watermark > 0.0) open.fusion->fuseUpTo(std::min(watermark, horizon));
    bool close = false;
    if (open.fusion->allSettled()) {
      open.settled_ns = now;
      close = true;
    } else if (silentTooLong(open, now)) {
      closeUnsettled(number, open,
                     "silent for " + formatSeconds(config_.stall_limit_s) +
                         " s after the episode ended",
                     now);
      close = true;
    }
    if (close) {
      finishEpisode(number, open);
      it = open_.erase(it);
      continue;
    }
    if (now >= next_state_ns_) publishState(number, open, now);
    ++it;
  }
}

// Episodes this restarted process cannot fuse: each answered (logged, reported, its Report
// published so the coordinator moves on) once its end has passed and this process holds the
// Measurement writers of every live sensor process, or kResumeMatchWaitS after the join.
void FusionCenterCore::answerRestarted(std::int64_t now) {
  if (restarted_.empty() || !report_) return;
  const bool waited = awakeSince(resumed_->joinedWallNs(), now) >= kResumeMatchWaitS;
  if (!waited && !holdsEverySensorProcess()) return;
  for (auto it = restarted_.begin(); it != restarted_.end();) {
    const auto [episode, end_ns] = *it;
    ++it;
    if (now >= end_ns) finishRestarted(episode, now);
  }
}

// A restarted process that does not yet hold every live sensor process's Measurement writer when
// an episode begins cannot fuse it whole: a volatile writer delivers to a reader only what it
// writes after it matched it, so the first measurements of the episode never come. Such an
// episode is answered as restarted (the restart's consequence), not held open for the stall
// limit and reported as lost. Once every writer is held, or kResumeMatchWaitS has passed, every
// episode is fused.
void FusionCenterCore::giveUpUnheldStarts(std::int64_t now) {
  if (!resumed_ || holds_writers_) return;
  if (holdsEverySensorProcess() || awakeSince(resumed_->joinedWallNs(), now) >= kResumeMatchWaitS) {
    holds_writers_ = true;
    return;
  }
  for (auto it = open_.begin(); it != open_.end();) {
    const std::uint32_t number = it->first;
    const EpisodeClock clock = it->second->clock;
    if (clock.start_wall_ns > now) {
      ++it;
      continue;
    }
    for (const std::uint32_t e : resumed_->heardOfRunning(number)) {
      restarted_.emplace(e, e == number ? clock.wallAt(scenario().horizon_s) : 0);
    }
    began_unheld_.insert(number);
    log(spdlog::level::warn, "episode " + std::to_string(number) +
                                 " began before this restarted fusion center held the measurement "
                                 "writers of sensors " + listed(sensorsLackingWriters()) +
                                 ": not fused");
    it = open_.erase(it);
  }
}

bool FusionCenterCore::holdsEverySensorProcess() const {
  return hasScenario() && sensorsLackingWriters().empty();
}

// A live sensor (not declared failed, not failed nor stopped by its own word) whose process this
// fusion center does not hold: no status of it came to this process (its status writer has not
// matched this process's reader, or the process is stalled), or the Measurement or EpisodeTally
// reader has not matched a writer of the process that wrote its status. That is this side of the
// match; the process's READY says only that its writers matched these readers on its side.
std::vector<int> FusionCenterCore::sensorsLackingWriters() const {
  std::vector<int> lacking;
  if (!hasScenario()) return lacking;
  for (int j = 0; j < scenario().sensorCount(); ++j) {
    if (failed_sensors_.count(j) > 0) continue;
    const auto process = sensor_processes_.find(static_cast<std::uint32_t>(j));
    if (process == sensor_processes_.end()) {
      lacking.push_back(j);
      continue;
    }
    const SensorState state = process->second.state;
    if (state == SensorState::Failed || state == SensorState::Stopped) continue;
    if (!writers_.writersMatchedWith(process->second.status_writer)) lacking.push_back(j);
  }
  return lacking;
}

void FusionCenterCore::onCoordinatorProcesses(std::size_t seen, std::int64_t /*now*/) {
  for (; coordinators_seen_ < seen; ++coordinators_seen_) {
    if (coordinators_seen_ == 0) continue;  // the first is the run's own
    const std::optional<std::uint32_t> episode =
        open_.empty() ? std::nullopt : std::optional<std::uint32_t>(open_.begin()->first);
    report::FaultRecord fault = faultEntry(
        FaultKind::Restarted, "coordinator", std::nullopt, episode, std::nullopt,
        "coordinator process " + std::to_string(coordinators_seen_ + 1) +
            " of the run took over (its EpisodeControl writer matched): the coordinator was "
            "restarted, by a restart policy or by hand (no launcher supervises this run), and "
            "resumed from its journal or started the run again");
    fault.survived = true;
    log(spdlog::level::warn, fault.detail);
    recordFault(std::move(fault));
  }
}

// The entry and Report of an episode this process could not fuse (it restarted during it).
void FusionCenterCore::finishRestarted(std::uint32_t episode, std::int64_t now) {
  restarted_.erase(episode);
  early_.erase(episode);
  early_tallies_.erase(episode);
  EpisodeResult result = restartedEpisode(episode, scenario().sensorCount());
  const auto segments = book_.segments(episode, scenario().horizon_s);
  for (const ScheduleSegment& segment : segments) result.versions.push_back(segment.version->version);
  if (segments.size() == 1) {  // after a switch the bracket needs the fused P(s): unknown
    result.bracket = bracketOf(*segments.front().version);
    result.delivered_bracket = scenario().network
                                   ? deliveredBracketOf(*segments.front().version, episode)
                                   : result.bracket;
  }
  const json entry = episodeEntry(result);
  if (!episode_log_refused_) emit<AppendEpisodeLog>(entry);
  report_->add(entry);
  const std::vector<int> lacking = sensorsLackingWriters();
  answered_without_.insert(lacking.begin(), lacking.end());
  log(spdlog::level::warn,
      "episode " + std::to_string(episode) +
          ": not fused (the fusion center restarted during it); answered " +
          formatSeconds(1e-9 * static_cast<double>(now - resumed_->joinedWallNs())) +
          " s after joining, with " + std::to_string(writers_.matchedMeasurementWriters()) +
          " measurement writers matched" +
          (lacking.empty() ? std::string(", every live sensor process's among them")
                           : "; lacking the writers of sensors " + listed(lacking)));
  publishReport(result, lacking);
}

// An unsettled sensor silent (no measurement, tally or status) for the stall limit after the
// episode's end, not counting the fusion center's own stalls.
bool FusionCenterCore::silentTooLong(const OpenEpisode& open, std::int64_t now) const {
  const std::int64_t end_ns = open.clock.wallAt(scenario().horizon_s);
  if (now < end_ns) return false;
  for (const int j : open.fusion->unsettled()) {
    const std::int64_t from = std::max(end_ns, open.last_heard_ns[static_cast<std::size_t>(j)]);
    if (awakeSince(from, now) <= config_.stall_limit_s) return false;
  }
  return true;
}

// Names every sensor the episode still waits for in the faults (the episode is incomplete).
void FusionCenterCore::closeUnsettled(std::uint32_t number, OpenEpisode& open,
                                      const std::string& why, std::int64_t now) {
  for (const int j : open.fusion->unsettled()) {
    const SensorTally& t = open.fusion->tally(j);
    std::string detail;
    if (t.tallied) {
      detail = "sensor " + std::to_string(j) + " sent " + std::to_string(t.sent) +
               " measurements in episode " + std::to_string(number) + ", " +
               std::to_string(t.received) + " arrived; the episode was closed when " + why;
    } else {
      detail = "sensor " + std::to_string(j) + " never reported its count for episode " +
               std::to_string(number) + " (" + std::to_string(t.received) +
               " measurements arrived); the episode was closed when " + why;
      closed_without_[{number, j}] = now;
    }
    recordFault(faultEntry(t.tallied ? FaultKind::Lost : FaultKind::Stall, kProcess, j, number,
                           open.fusion->fusedTime(), detail));
    log(spdlog::level::warn, "episode " + std::to_string(number) + ": " + detail);
  }
}

void FusionCenterCore::publishState(std::uint32_t episode, const OpenEpisode& open,
                                    std::int64_t now) {
  next_state_ns_ = now + toNs(config_.state_period_s);
  const ScheduleVersion* v = book_.inForce(episode, open.fusion->fusedTime());
  emit<PublishState>(episode, open.fusion->fusedTime(), open.fusion->covariance(),
                     v != nullptr ? v->version : 0);
}

void FusionCenterCore::finishEpisode(std::uint32_t number, OpenEpisode& open,
                                     const std::string* cut_short) {
  EpisodeResult result = open.fusion->finish();
  result.backlog = open.backlog;
  if (cut_short != nullptr && !result.complete) {
    result.incomplete_reason = "cut short (" + *cut_short + "): " + result.incomplete_reason;
  }
  for (std::size_t j = 0; j < result.sensors.size(); ++j) {
    const SensorTally& t = result.sensors[j];
    if (t.duplicated_by_network > t.duplicates) {
      copies_left_[{number, static_cast<int>(j)}] = t.duplicated_by_network - t.duplicates;
    }
  }
  checkKeepingUp(number, open, result);
  noteHeldBack(number, open);
  traceCovariance(*open.fusion, result);
  earliest_latency_s_.resize(result.earliest_latency_s.size(), std::numeric_limits<double>::infinity());
  for (std::size_t j = 0; j < result.earliest_latency_s.size(); ++j) {
    earliest_latency_s_[j] = std::min(earliest_latency_s_[j], result.earliest_latency_s[j]);
  }
  // Latencies across clocks that disagree by now are no figures (noteClocks): this episode's
  // are left out of the run's and its entry has none (null), as an episode without arrivals.
  if (clocksDisagree(result)) result.latencies_s.clear();
  report_->addLatencies(result.latencies_s);
  const json entry = episodeEntry(result);
  if (!episode_log_refused_) emit<AppendEpisodeLog>(entry);
  report_->add(entry);
  if (resumed_) resumed_->noteFused(number);
  const RunSummary s = report_->summary();
  char line[256];
  std::snprintf(line, sizeof line,
                "episode %u%s: realized %.6g, bracket [%.6g, %.6g]; mean %.6g over %u complete "
                "episodes",
                result.episode, result.complete ? "" : " (incomplete)", result.realized_cost,
                result.bracket.info, result.bracket.cov, s.mean, s.episodes_complete);
  log(spdlog::level::info, line);
  publishReport(result);
}

// The weighted covariance trace of one of the first kTracedEpisodes episodes (its measurements
// are gone once it is closed), for the report's page; the surrogate curves of the version in
// force at its start are computed when the report is written, not while the run goes on.
void FusionCenterCore::traceCovariance(const EpisodeFusion& fusion, const EpisodeResult& r) {
  if (traced_episodes_.size() >= kTracedEpisodes || r.versions.empty()) return;
  const TraceWeight weight = traceWeight(scenario());
  const std::uint32_t version = r.versions.front();
  json curve =
      traceJson(fusedCovarianceTrace(scenario(), fusion.measurements(), weight, kTracePoints));
  curve["episode"] = r.episode;
  curve["version"] = version;
  curve["complete"] = r.complete;
  traced_episodes_.push_back(std::move(curve));
  traced_versions_.insert(version);
}

json FusionCenterCore::covarianceTraces() {
  const TraceWeight weight = traceWeight(scenario());
  json surrogates = json::array();
  for (const ScheduleVersion& v : book_.versions()) {
    if (traced_versions_.count(v.version) == 0) continue;
    try {  // a curve of the page must never cost the report
      const SurrogateTraces s = surrogateTraces(scenario(), v.schedule, weight, kTracePoints);
      surrogates.push_back(
          {{"version", v.version}, {"info", traceJson(s.info)}, {"cov", traceJson(s.cov)}});
    } catch (const std::exception& e) {
      log(spdlog::level::warn, "no surrogate curves of version " + std::to_string(v.version) +
                                   " for the report: " + e.what());
    }
  }
  return {{"weight", weight.name}, {"episodes", traced_episodes_}, {"surrogates", surrogates}};
}

// Overload: the fusion center settled an episode late after the last of what it owed had
// arrived or the last failure notice that released it came (not counting its own stalls), or a sensor published far behind the emulated clock
// (not counting the sensor's stalls). Samples that arrived late (a cut link, a stalled sender)
// are not the fusion center's backlog: noteHeldBack lists them as stalls.
void FusionCenterCore::checkKeepingUp(std::uint32_t number, const OpenEpisode& open,
                                      EpisodeResult& result) {
  if (open.settled_ns) {
    const std::int64_t from =
        std::max({open.clock.wallAt(scenario().horizon_s), open.last_tally_ns,
                  open.last_arrival_ns, open.last_failure_notice_ns});
    if (*open.settled_ns > from) result.drain_s = awakeSince(from, *open.settled_ns);
  }
  if (result.drain_s > config_.keep_up_limit_s) {
    recordFault(faultEntry(FaultKind::Overload, kProcess, std::nullopt, number, std::nullopt,
                           "the fusion center had all of episode " + std::to_string(number) +
                               " only " + formatSeconds(result.drain_s) +
                               " s after the last of it arrived (up to " +
                               std::to_string(open.backlog) + " measurements waiting)"));
  }
  for (std::size_t j = 0; j < open.tallies.size(); ++j) {
    const EpisodeTally& t = open.tallies[j];
    if (t.stalled_s > 0.0) {
      stalls_.push_back(
          {{"process", "sensor " + std::to_string(j)}, {"episode", number}, {"seconds", t.stalled_s}});
    }
    if (t.max_lag_s > config_.keep_up_limit_s) {
      recordFault(faultEntry(FaultKind::SensorLag, "sensor_agent", static_cast<int>(j), number,
                             std::nullopt,
                             "sensor " + std::to_string(j) + " published up to " +
                                 formatSeconds(t.max_lag_s) +
                                 " s behind the emulated clock in episode " +
                                 std::to_string(number)));
    }
  }
}

// A stall of the network between sensors and this process (a cut link, a partition): samples
// that spent longer than kHeldBackS in transit, not counting this process's own stalls nor the
// sensor's (a stopped sensor publishes late, not slowly). Listed under `stalls` with the sensors
// it held back; absorbed, not a fault, when nothing was lost.
void FusionCenterCore::noteHeldBack(std::uint32_t number, const OpenEpisode& open) {
  json sensors = json::array();
  double longest = 0.0;
  for (std::size_t j = 0; j < open.held_back_s.size(); ++j) {
    if (open.held_back_s[j] <= kHeldBackS) continue;
    sensors.push_back(j);
    longest = std::max(longest, open.held_back_s[j]);
  }
  if (sensors.empty()) return;
  log(spdlog::level::warn, "episode " + std::to_string(number) + ": the network held back sensors " +
                               sensors.dump() + " for up to " + formatSeconds(longest) + " s");
  stalls_.push_back(
      {{"process", "network"}, {"episode", number}, {"seconds", longest}, {"sensors", sensors}});
}

void FusionCenterCore::publishReport(const EpisodeResult& e, std::vector<int> lacking_writers) {
  emit<PublishReport>(e, report_->summary(), std::move(lacking_writers));
}

// The launcher's death as a cause: {kind, process} as the launcher names its own faults.
static report::FaultCause launcherDeath() { return {FaultKind::Interrupted, "sensornet"}; }

void FusionCenterCore::onLauncherGone(const std::string& detail, std::int64_t /*now*/) {
  if (launcher_gone_) return;
  launcher_gone_ = true;
  log(spdlog::level::warn, detail);
  recordFault(faultEntry(FaultKind::Interrupted, launcherDeath().process, std::nullopt,
                         std::nullopt, std::nullopt, detail));
}

RunStatus FusionCenterCore::finish(const std::optional<RunEnd>& end,
                                   const std::map<std::string, std::uint64_t>& rejected_by_inputs,
                                   const std::string& written_at, std::int64_t now) {
  if (!report_) {
    log(spdlog::level::err, "no scenario ever arrived; no report");
    const RunStatus status = end ? RunStatus::Failed : RunStatus::Interrupted;
    return end && end->aborted ? report::decideRunStatus(gatherStatusEvidence(end, rejected_by_inputs))
                                : status;
  }
  // Finish what is open: an episode still owed measurements is closed incomplete, its cause
  // named once (cutShort), not as a fault of every sensor it waited for.
  if (!open_.empty()) {
    if (!end) {
      cutShort(launcher_gone_ ? "the launcher died" : "the run was stopped by a signal",
               FaultKind::Interrupted);
    } else if (end->aborted) {
      cutShort("the coordinator ended the run: " + end->detail, FaultKind::RunAborted);
    } else {
      cutShort("the coordinator ended the run", std::nullopt);
    }
  }
  if (resumed_ && end) {
    for (const std::uint32_t e : resumed_->heardEnd(end->episodes_run)) restarted_.emplace(e, 0);
  }
  while (!restarted_.empty()) finishRestarted(restarted_.begin()->first, now);
  const RunStatus status = report::decideRunStatus(gatherStatusEvidence(end, rejected_by_inputs));
  emit<WriteFinalReport>(status, finalReport(status, written_at), written_at);
  return status;
}

void FusionCenterCore::onEpisodeLogRefused(const json& entry, const std::string& why) {
  if (episode_log_refused_ || !report_) return;
  episode_log_refused_ = true;
  report_->holdFrom(entry);
  const auto episode = entry.value("episode", std::uint32_t{0});
  const std::string detail =
      why + "; episode " + std::to_string(episode) +
      " and later ones are in the report only (a restarted fusion center would not resume them)";
  log(spdlog::level::err, detail);
  recordFault(
      faultEntry(FaultKind::WriteFailed, kProcess, std::nullopt, episode, std::nullopt, detail));
}

WriteFinalReport FusionCenterCore::reportRefused(const WriteFinalReport& refused,
                                                 const std::string& why,
                                                 const std::filesystem::path& elsewhere) {
  const std::string detail = why + "; the report is at " + elsewhere.string();
  log(spdlog::level::err, detail);
  report::FaultRecord fault =
      faultEntry(FaultKind::WriteFailed, kProcess, std::nullopt, std::nullopt, std::nullopt, detail);
  if (report_refused_fault_) {  // a fallback refused it too: one fault, saying where it went
    faults_[*report_refused_fault_] = std::move(fault);
  } else {
    report_refused_fault_ = faults_.size();
    recordFault(std::move(fault));
  }
  report::StatusEvidence evidence;
  evidence.earlier = refused.status;
  evidence.faults = faults_.size();
  const RunStatus status = report::decideRunStatus(evidence);
  return {status, finalReport(status, refused.written_at), refused.written_at};
}

// The one fault of episodes still open at the run's end: which episodes, which sensors they
// waited for, and what ended the run (`ended_by`: a fault kind, when a signal or the
// coordinator's abort did).
// A sensor whose tally says it sent more than arrived really lost measurements: `lost`.
void FusionCenterCore::cutShort(const std::string& why, std::optional<FaultKind> cause) {
  std::vector<std::uint32_t> episodes;
  std::string awaited;
  for (auto& [number, open] : open_) {
    episodes.push_back(number);
    std::vector<int> silent;
    for (const int j : open->fusion->unsettled()) {
      const SensorTally& t = open->fusion->tally(j);
      if (!t.tallied) {
        silent.push_back(j);
        closed_without_[{number, j}] = kClosedAtRunEnd;
        continue;
      }
      recordFault(faultEntry(FaultKind::Lost, kProcess, j, number, open->fusion->fusedTime(),
                             "sensor " + std::to_string(j) + " sent " + std::to_string(t.sent) +
                                 " measurements in episode " + std::to_string(number) + ", " +
                                 std::to_string(t.received) + " arrived by the run's end"));
    }
    if (!silent.empty()) {
      awaited += (awaited.empty() ? "" : "; ") + std::string("episode ") + std::to_string(number) +
                 ": sensors " + listed(silent);
    }
  }
  report::FaultRecord fault = faultEntry(FaultKind::CutShort, kProcess, std::nullopt, episodes.front(),
                          std::nullopt,
                          (episodes.size() == 1 ? "episode " + listed(episodes) + " was"
                                                : "episodes " + listed(episodes) + " were") +
                              " open when " + why +
                              (awaited.empty() ? "" : " (their counts not in: " + awaited + ")"));
  fault.episodes = episodes;
  // What ended the run as the fusion center saw it; the launcher, which knows the run's one cause,
  // marks this entry as that cause's consequence (caused_by, fault_causes.hpp).
  fault.ended_by = cause;
  // A cause the fusion center records itself is named here: the launcher's death, or the
  // coordinator's abort (gatherStatusEvidence's run_aborted entry).
  if (launcher_gone_) {
    fault.caused_by = launcherDeath();
  } else if (cause == FaultKind::RunAborted) {
    fault.caused_by = report::FaultCause{FaultKind::RunAborted, "coordinator"};
  }
  log(spdlog::level::warn, fault.detail);
  recordFault(std::move(fault));
  for (auto& [number, open] : open_) finishEpisode(number, *open, &why);
  open_.clear();
}

// The run as far as the fusion center saw it (the launcher adds what it saw of the processes):
// no end from the coordinator is a signal, its abort or no scenario a failure; missing
// episodes, rejections and the faults, losses and incomplete episodes of the report the rest.
report::StatusEvidence FusionCenterCore::gatherStatusEvidence(
    const std::optional<RunEnd>& end, const std::map<std::string, std::uint64_t>& rejected_by_inputs) {
  if (resumed_ && report_) noteRestart();
  if (report_) noteClocks();  // however the run ended
  report::StatusEvidence seen;
  if (!end) {
    seen.interrupted = true;
    return seen;
  }
  if (end->aborted) {
    recordFault(faultEntry(FaultKind::RunAborted, "coordinator", std::nullopt, std::nullopt,
                           std::nullopt, end->detail));
    seen.failed = true;
    return seen;
  }
  if (!report_) {
    seen.failed = true;
    return seen;
  }
  for (const auto& [reason, count] : rejected_by_inputs) report_->countRejected(reason, count);
  for (const auto& [reason, count] : rejected_outside_) {
    report_->countRejected(std::string(wordOf(reason)), count);
  }
  for (const auto& [episode, held] : early_) {
    report_->countRejected(std::string(wordOf(RejectionReason::UnknownEpisode)), held.size());
  }
  const RunSummary s = report_->summary();
  if (s.episodes < end->episodes_run) {
    recordFault(faultEntry(FaultKind::MissingEpisodes, kProcess, std::nullopt, std::nullopt,
                           std::nullopt,
                           "the coordinator ran " + std::to_string(end->episodes_run) +
                               " episodes, " + std::to_string(s.episodes) + " were fused"));
  }
  // Malformed samples of a sensor in an episode: a fault naming both, with the first reason;
  // the rest of the rejections (of no one episode or sensor) in one fault.
  std::uint64_t named = 0;
  for (const auto& [where, refusals] : refusals_) {
    named += refusals.samples;
    recordFault(faultEntry(FaultKind::Rejected, kProcess, where.first, where.second, std::nullopt,
                           std::to_string(refusals.samples) +
                               (refusals.samples == 1 ? " sample" : " samples") +
                               " refused as malformed (" + refusals.first_detail + ")"));
  }
  // Samples the network held back past the stall limit, refused because their episode had been
  // closed without them: a consequence of the network_partition that names them.
  std::map<std::uint32_t, std::uint64_t> held_by_episode;
  for (const auto& [where, count] : after_close_) {
    if (held_back_.count(where) > 0) held_by_episode[where.first] += count;
  }
  std::uint64_t held_total = 0;
  for (const auto& [episode, count] : held_by_episode) {
    held_total += count;
    report::FaultRecord fault = faultEntry(
        FaultKind::Rejected, kProcess, std::nullopt, episode, std::nullopt,
        std::to_string(count) + (count == 1 ? " sample" : " samples") + " of episode " +
            std::to_string(episode) +
            " held back by the network arrived after the episode was closed without them "
            "(refused as finished_episode)");
    fault.caused_by = report::FaultCause{FaultKind::NetworkPartition, "network"};
    recordFault(std::move(fault));
  }
  std::string reasons;
  for (const auto& [reason, count] : s.rejected) {
    if (reason == kNetworkDuplicate) continue;  // scripted, not a fault
    const std::uint64_t rest =
        reason == wordOf(RejectionReason::Malformed)        ? count - std::min(count, named)
        : reason == wordOf(RejectionReason::FinishedEpisode) ? count - std::min(count, held_total)
                                                            : count;
    if (rest > 0) reasons += (reasons.empty() ? "" : ", ") + std::to_string(rest) + " " + reason;
  }
  if (!reasons.empty()) {
    recordFault(faultEntry(FaultKind::Rejected, kProcess, std::nullopt, std::nullopt, std::nullopt,
                           "samples refused on the wire: " + reasons));
  }
  seen.faults = faults_.size();
  seen.lost = s.lost;
  seen.episodes = s.episodes;
  seen.episodes_complete = s.episodes_complete;
  return seen;
}

// The restart in the report's faults: the process, the episodes it could not fuse. Replaces
// the entry the constructor recorded (in the report; the fault log keeps the first version, read
// only by a later life, which a life that ends has none of).
void FusionCenterCore::noteRestart() { faults_[restart_fault_] = restartFault(); }

report::FaultRecord FusionCenterCore::restartFault() const {
  const std::set<std::uint32_t>& lost = resumed_->restarted();
  return faultEntry(
      FaultKind::Restarted, kProcess, std::nullopt,
      lost.empty() ? std::nullopt : std::optional<std::uint32_t>(*lost.rbegin()), std::nullopt,
      "the fusion center was restarted and resumed from " +
          std::to_string(resumed_->entries().size()) + " logged episodes; " +
          (lost.empty() ? std::string("no episode was lost")
                        : "not fused (incomplete, " + std::string(kRestartedReason) +
                              "): episode " + listed(lost)) +
          (began_unheld_.empty()
               ? std::string()
               : "; episode " + listed(began_unheld_) +
                     " began before it held every live sensor process's measurement writer") +
          (answered_without_.empty()
               ? std::string()
               : "; answered without the measurement writers of sensors " +
                     listed(answered_without_) + " (their next measurements could be lost)"));
}

// The arrival mode of the run, and what the bracket [info, cov] says under it.
static json arrivalsJson(ArrivalMode mode) {
  const char* note =
      mode == ArrivalMode::Timetable
          ? "timetable: every sensor sends at the deterministic instants where its integrated "
            "rate is k - 1/2, the same in every episode, so the realized cost varies only "
            "through the network; the bracket [info, cov] bounds the Poisson mean of the same "
            "schedule (Corollary 1), not the timetable's cost, and meets_bracket only says "
            "whether the timetable's cost lies in it"
          : "poisson: the bracket [info, cov] bounds the mean realized cost (Corollary 1)";
  return {{"mode", std::string(arrivalModeName(mode))}, {"bracket_note", note}};
}

json FusionCenterCore::finalReport(RunStatus status, const std::string& written_at) {
  const json extra = {{"episodes_planned", episodes_planned_},
                      {"seed", announced_->seed},
                      {"stalls", stalls_},
                      {"written_at", written_at},
                      {"covariance_traces", covarianceTraces()},
                      {"arrivals", arrivalsJson(scenario().arrivals)},
                      {"clocks", clocksJson()}};
  // per_episode is streamed in from the episode log, never held whole.
  return report_->toJsonWithoutEpisodes(std::string(wordOf(status)), report::encode(faults_),
                                        scheduleVersionsJson(book_), extra);
}

}  // namespace sensornet::emulator
