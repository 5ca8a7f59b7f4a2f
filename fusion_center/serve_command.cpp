#include "serve_command.hpp"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <chrono>
#include <ctime>
#include <deque>
#include <filesystem>
#include <iostream>
#include <iterator>
#include <limits>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <set>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "sensornet/core/emulated_plant.hpp"
#include "sensornet/core/network.hpp"
#include "sensornet/core/input_error.hpp"
#include "sensornet/dds/listener.hpp"
#include "sensornet/dds/participant.hpp"
#include "sensornet/dds/reader.hpp"
#include "sensornet/dds/topics.hpp"
#include "sensornet/dds/waitset.hpp"
#include "sensornet/dds/wire.hpp"
#include "sensornet/dds/writer.hpp"
#include "sensornet/emulator/covariance_trace.hpp"
#include "sensornet/emulator/episode_fusion.hpp"
#include "sensornet/emulator/messages.hpp"
#include "sensornet/emulator/run_inputs.hpp"
#include "sensornet/emulator/run_options.hpp"
#include "sensornet/emulator/run_report.hpp"
#include "sensornet/emulator/stall_watch.hpp"
#include "sensornet/emulator/stop_signal.hpp"
#include "sensornet/emulator/writer_claims.hpp"
#include "sensornet/io/scenario_file.hpp"

namespace sensornet::fusion_center {
namespace {

using namespace std::chrono_literals;
using emulator::wallNowNs;
using nlohmann::json;

constexpr const char* kProcess = "fusion_center";

struct ServeOptions {
  emulator::RunOptions run;
  std::string report_path;
  double lag_s = 0.05;           // wall seconds a measurement may take to arrive before fusion
  double stall_limit_s = 12.0;   // wall seconds a sensor that owes measurements may stay silent
  double keep_up_limit_s = 1.0;  // wall seconds of drain or sensor lag that count as overload
  double state_period_s = 0.05;  // FusionState publication period (wall seconds)
  bool json = false;
  bool resume = false;           // restarted by the launcher: go on from the episode log
};

// A restarted fusion center waits at most this long (wall seconds after it joined) for its
// measurement reader to match every live sensor process before it answers for the episode it
// could not fuse (the coordinator then starts the next one, which must lose nothing).
constexpr double kResumeMatchWaitS = 5.0;

// The report's covariance_traces: the first few episodes, each curve on this many grid times.
constexpr std::size_t kTracedEpisodes = 3;
// The Report instances (one per episode) kept registered for late joiners: the latest ones.
constexpr std::size_t kReportsKept = 64;
constexpr int kTracePoints = 200;

// Now, as an ISO 8601 UTC time ("2026-11-30T18:20:00Z"): when the report was written.
std::string utcNow() {
  const std::time_t now = std::chrono::system_clock::to_time_t(std::chrono::system_clock::now());
  std::tm utc{};
  gmtime_r(&now, &utc);
  char text[32];
  std::strftime(text, sizeof text, "%Y-%m-%dT%H:%M:%SZ", &utc);
  return text;
}

std::int64_t toNs(double seconds) { return static_cast<std::int64_t>(1e9 * seconds); }

// A measurement as it came off the wire, stamped on arrival.
struct Arrival {
  emulator::FusedMeasurement measurement;
  std::uint32_t episode = 0;
  std::optional<std::string> other_run;  // the run id it carries, if not this run's
  emulator::WriterId writer = 0;         // the DDS writer that sent it (publication handle)
};

// Arrivals handed from Cyclone's receive thread (the listener) to the main loop. Buffers are
// swapped, not allocated: after the first few calls neither side allocates for the hand-off.
class Inbox {
 public:
  // Moves `arrivals` in and leaves it empty (its capacity kept for the next call). Returns true
  // if the inbox was empty before: the main loop may be asleep and needs a wake.
  bool push(std::vector<Arrival>& arrivals) {
    std::lock_guard lock(mutex_);
    const bool was_empty = arrivals_.empty();
    if (was_empty) {
      std::swap(arrivals_, arrivals);
    } else {
      std::move(arrivals.begin(), arrivals.end(), std::back_inserter(arrivals_));
    }
    arrivals.clear();
    return was_empty;
  }
  // Everything pushed so far, swapped into `into` (whose old contents are dropped).
  void drainInto(std::vector<Arrival>& into) {
    into.clear();
    std::lock_guard lock(mutex_);
    std::swap(arrivals_, into);
  }

 private:
  std::mutex mutex_;
  std::vector<Arrival> arrivals_;
};

// An episode in progress: its clock, its fusion and what the fusion center heard of it.
struct OpenEpisode {
  emulator::EpisodeClock clock;
  std::unique_ptr<emulator::EpisodeFusion> fusion;
  std::vector<std::int64_t> last_heard_ns;  // per sensor: its last measurement, tally or status
  std::vector<sensornet_EpisodeTally> tallies;  // as received (sent, lag, stalls), per sensor
  std::int64_t last_tally_ns = 0;               // publication wall time of the latest tally
  std::optional<std::int64_t> settled_ns;       // when everything owed was in
  std::uint64_t backlog = 0;
};

class FusionCenter {
 public:
  explicit FusionCenter(const ServeOptions& options)
      : options_(options),
        domain_(options.run.domainConfig()),
        participant_(domain_),
        inputs_(participant_),
        measurement_topic_(participant_),
        tally_topic_(participant_),
        status_topic_(participant_),
        report_topic_(participant_),
        state_topic_(participant_),
        measurement_reader_(participant_, measurement_topic_),
        tally_reader_(participant_, tally_topic_),
        status_reader_(participant_, status_topic_),
        report_writer_(participant_, report_topic_, dds::reportWriterQos()),
        state_writer_(participant_, state_topic_),
        waitset_(participant_),
        tally_ready_(tally_reader_),
        status_ready_(status_reader_),
        arrivals_listener_(measurement_reader_, [this] { onMeasurements(); }) {
    inputs_.attachTo(waitset_);
    waitset_.attach(tally_ready_, 1);
    waitset_.attach(status_ready_, 2);
    const std::int64_t joined_ns = wallNowNs();
    if (!options_.report_path.empty()) {
      const auto log_path = emulator::episodeLogPath(options_.report_path);
      if (options_.resume) {
        resumed_.emplace(emulator::readEpisodeLog(log_path), joined_ns);
        spdlog::info("resuming from {} episodes in the episode log {}",
                     resumed_->entries().size(), log_path.string());
      }
      episode_log_.emplace(log_path, options_.resume ? emulator::EpisodeLog::Mode::Append
                                                     : emulator::EpisodeLog::Mode::Truncate);
      spdlog::info("episode log: {}", log_path.string());
    }
    if (options_.resume && !resumed_) resumed_.emplace(std::vector<json>{}, joined_ns);
  }

  int run() {
    spdlog::info("fusion center of run {} waiting for the scenario", options_.run.run_id);
    std::optional<emulator::RunEnd> end;
    while (!end && !emulator::stopRequested()) {
      (void)waitset_.wait(10ms);
      noteOwnStall();
      inbox_.drainInto(drained_);
      for (Arrival& arrival : drained_) accept(std::move(arrival));
      end = follow();
      readTallies();
      readStatuses();
      advance();
    }
    // Finish what is open: an episode still owed measurements is closed incomplete (cut short
    // when a signal stopped the run: the launcher names the process that caused it).
    for (auto& [number, open] : open_) {
      closeUnsettled(number, open, end ? "the run ended" : "the run was stopped",
                     end ? emulator::FaultKind::Stall : emulator::FaultKind::CutShort);
    }
    for (auto& [number, open] : open_) finishEpisode(number, open);
    open_.clear();
    if (resumed_ && end && report_) {
      for (const std::uint32_t e : resumed_->heardEnd(end->episodes_run)) restarted_.emplace(e, 0);
    }
    if (report_) {
      while (!restarted_.empty()) finishRestarted(restarted_.begin()->first);
    }
    const std::string status = decideStatus(end);
    writeReport(status);
    (void)report_writer_.waitForAcks(2s);
    spdlog::info("run {}: {}", options_.run.run_id, status);
    // The report carries the run's status; the exit code says whether this process did its job
    // (followed the run to its end and wrote the report).
    return end && report_ ? kExitOk : kExitFailure;
  }

 private:
  // Takes what the run announced; the run's end on RUN_SHUTDOWN.
  std::optional<emulator::RunEnd> follow() {
    const emulator::RunInputs::Update update = inputs_.poll();
    if (update.scenario_arrived) {
      const Scenario& s = inputs_.scenario();
      std::optional<std::filesystem::path> read_back;  // the report's entries, from the log
      if (episode_log_) read_back = emulator::episodeLogPath(options_.report_path);
      report_.emplace(options_.run.run_id, inputs_.run().digest, s.sensorCount(), s.stateDim(),
                      std::move(read_back));
      if (resumed_) {
        for (const json& entry : resumed_->entries()) report_->add(entry);
      }
    }
    if (update.new_versions > 0) {
      for (auto& [episode, open] : open_) open.fusion->scheduleChanged();
    }
    for (const emulator::EpisodeStart& start : update.starts) startEpisode(start);
    for (const emulator::SensorFailure& failure : update.failures) {
      spdlog::warn("sensors failed in episode {} at {:.3g} s: {}", failure.episode, failure.at_s,
                   failure.detail);
      if (resumed_ && open_.count(failure.episode) == 0 &&
          (!inputs_.lastStarted() || failure.episode > *inputs_.lastStarted())) {
        // Under way, and its start was before this process joined (the durable control sample
        // is this notice now): it cannot be fused; its end is unknown.
        for (const std::uint32_t e : resumed_->heardOfRunning(failure.episode)) {
          restarted_.emplace(e, 0);
        }
      }
      failures_.push_back(failure);
      releaseClaims(failure.sensors);
      for (auto& [number, open] : open_) applyFailure(number, open, failure);
    }
    if (update.shutdown) return update.end;
    return std::nullopt;
  }

  void startEpisode(const emulator::EpisodeStart& start) {
    episodes_planned_ = start.episodes_planned;
    if (resumed_) {
      for (const std::uint32_t e : resumed_->heardStart(start.episode, start.clock.start_wall_ns)) {
        restarted_.emplace(e, e == start.episode ? start.clock.wallAt(inputs_.scenario().horizon_s)
                                                 : 0);
      }
      if (resumed_->ignores(start.episode)) {
        early_.erase(start.episode);
        early_tallies_.erase(start.episode);
        return;
      }
    }
    OpenEpisode open;
    open.clock = start.clock;
    open.fusion = std::make_unique<emulator::EpisodeFusion>(
        inputs_.scenario(), inputs_.plant(), inputs_.book(), start.episode,
        [this](const emulator::ScheduleVersion& v) { return bracketOf(v); },
        [this, episode = start.episode](const emulator::ScheduleVersion& v) {
          return deliveredBracketOf(v, episode);
        });
    const auto sensors = static_cast<std::size_t>(inputs_.scenario().sensorCount());
    open.last_heard_ns.assign(sensors, 0);
    open.tallies.assign(sensors, sensornet_EpisodeTally{});
    auto& slot = open_.emplace(start.episode, std::move(open)).first->second;
    for (const int j : start.failed_sensors) slot.fusion->sensorFailedBefore(j);
    for (const emulator::SensorFailure& failure : failures_) applyFailure(start.episode, slot, failure);
    // Measurements and tallies that came before the episode's control sample.
    if (auto early = early_.find(start.episode); early != early_.end()) {
      for (auto& a : early->second) route(slot, std::move(a.measurement), a.writer);
      early_.erase(early);
    }
    if (auto early = early_tallies_.find(start.episode); early != early_tallies_.end()) {
      for (const auto& t : early->second) applyTally(slot, t);
      early_tallies_.erase(early);
    }
  }

  // A failed sensor is never awaited: in the episode it died in (the episode is incomplete), in
  // the later ones (dead from their start), and in an earlier one still waiting for its count.
  static void applyFailure(std::uint32_t number, OpenEpisode& open,
                           const emulator::SensorFailure& failure) {
    for (const int j : failure.sensors) {
      if (number == failure.episode) {
        open.fusion->sensorFailedAt(j, failure.at_s);
      } else if (number > failure.episode) {
        open.fusion->sensorFailedBefore(j);
      } else if (!open.fusion->settled(j)) {
        open.fusion->sensorFailedAt(j, std::numeric_limits<double>::infinity());
      }
    }
  }

  CostBracket bracketOf(const emulator::ScheduleVersion& v) {
    auto it = brackets_.find(v.version);
    if (it == brackets_.end()) {
      it = brackets_.emplace(v.version, computeBracket(inputs_.scenario(), v.schedule)).first;
    }
    return it->second;
  }

  // The bracket of what the emulated network delivers of version v in `episode`: the same for
  // every episode with the same outages.
  CostBracket deliveredBracketOf(const emulator::ScheduleVersion& v, std::uint32_t episode) {
    const NetworkSpec& network = *inputs_.scenario().network;
    std::vector<std::size_t> outages;
    for (std::size_t i = 0; i < network.outages.size(); ++i) {
      if (network.outages[i].appliesTo(episode)) outages.push_back(i);
    }
    auto key = std::make_pair(v.version, std::move(outages));
    auto it = delivered_brackets_.find(key);
    if (it == delivered_brackets_.end()) {
      const RateSchedule delivered = deliveredSchedule(v.schedule, network, episode);
      it = delivered_brackets_.emplace(std::move(key), computeBracket(inputs_.scenario(), delivered))
               .first;
    }
    return it->second;
  }

  // In Cyclone's receive thread, as measurements are delivered: takes them, stamps their arrival
  // there (one thread hop after the wire, as in ddsperf) and hands them to the main loop.
  void onMeasurements() {
    // Usually one sample a call: a small batch keeps the loan and its info array small.
    constexpr std::size_t kBatch = 16;
    std::vector<Arrival>& arrivals = taken_;  // Cyclone runs one call of a listener at a time
    for (;;) {
      const std::int64_t received_ns = wallNowNs();
      const std::size_t count = measurement_reader_.takeEach(
          kBatch,
          [&](const sensornet_Measurement& m, const dds::SampleInfo& info) {
            arrivals.push_back(arrivalOf(m, received_ns));
            arrivals.back().writer = info.publication;
          },
          [](const sensornet_Measurement& key, const dds::SampleInfo& info) {
            if (info.instance_state == dds::InstanceState::NoWriters) {
              spdlog::info("sensor {} has no live writer at the moment", key.sensor_id);
            }
          });
      if (count < kBatch) break;
    }
    if (!arrivals.empty() && inbox_.push(arrivals)) waitset_.wake();
  }

  // Reads only what never changes after construction (the run id): safe in the receive thread.
  [[nodiscard]] Arrival arrivalOf(const sensornet_Measurement& m, std::int64_t received_ns) const {
    Arrival a;
    emulator::FusedMeasurement& fused = a.measurement;
    fused.sensor = static_cast<int>(m.sensor_id);
    fused.seq = m.seq;
    fused.time_s = m.emulated_time_s;
    fused.version = m.schedule_version;
    const auto z = dds::viewSequence(m.z);
    fused.z = Eigen::Map<const Eigen::VectorXd>(z.data(), static_cast<Eigen::Index>(z.size()));
    fused.publish_wall_ns = m.publish_wall_time_ns;
    fused.receive_wall_ns = received_ns;
    fused.network_delay_s = m.network_delay_s;
    a.episode = m.episode;
    if (const std::string_view run = dds::viewString(m.run_id); run != options_.run.run_id) {
      a.other_run = std::string(run);
    }
    return a;
  }

  // The scenario's emulated network writes some of this sensor's measurements twice.
  [[nodiscard]] bool duplicatesLink(int sensor) const {
    const auto& network = inputs_.scenario().network;
    return network && sensor >= 0 && static_cast<std::size_t>(sensor) < network->links.size() &&
           network->links[static_cast<std::size_t>(sensor)].duplicate > 0.0;
  }

  // A copy the emulated network made of a measurement of an episode already closed (the copy
  // can trail the tally, which travels on another topic): counted as the network's, not as a
  // sample of a finished episode, while the sensor's tally leaves copies unaccounted for.
  bool networkCopyAfterClose(std::uint32_t episode, int sensor) {
    const auto left = copies_left_.find({episode, sensor});
    if (left == copies_left_.end()) return false;
    ++rejected_outside_[emulator::kNetworkDuplicate];
    if (--left->second == 0) copies_left_.erase(left);
    return true;
  }

  void rejectOutside(const char* reason, const std::string& detail) {
    ++rejected_outside_[reason];
    spdlog::warn("rejected a measurement: {}", detail);
  }

  void accept(Arrival arrival) {
    ++waiting_;
    if (arrival.other_run) {
      rejectOutside("other_run", "of another run '" + *arrival.other_run + "'");
      return;
    }
    const std::uint32_t episode = arrival.episode;
    if (resumed_ && resumed_->ignores(episode)) return;  // logged before, or not fusable here
    auto open = open_.find(episode);
    if (open == open_.end()) {
      if (networkCopyAfterClose(episode, arrival.measurement.sensor)) return;
      if (inputs_.lastStarted() && episode <= *inputs_.lastStarted()) {
        rejectOutside("finished_episode", "of finished episode " + std::to_string(episode) +
                                              " (sensor " +
                                              std::to_string(arrival.measurement.sensor) + ")");
      } else {
        early_[episode].push_back(std::move(arrival));
      }
      return;
    }
    route(open->second, std::move(arrival.measurement), arrival.writer);
  }

  // Without DDS Security anyone on the host can write into the run's partition: a sample of a
  // second writer claiming a sensor whose first writer lives is kept out (writer_claims.hpp),
  // counted as rejected (foreign_writer) and named once per writer in the faults.
  bool refuseForeign(emulator::WriterClaims& claims, const dds::detail::ReaderCore& reader,
                     const char* topic, std::uint32_t sensor, emulator::WriterId writer,
                     std::uint32_t episode) {
    const int j = static_cast<int>(sensor);
    const auto live = [&reader](emulator::WriterId w) { return reader.matchesWriter(w); };
    if (!claims.isForeign(j, writer, live)) return false;
    ++rejected_outside_[emulator::kForeignWriter];
    if (claims.firstRefusalOf(writer)) {
      const std::string detail =
          "a second " + std::string(topic) + " writer (publication " + std::to_string(writer) +
          ") claims sensor " + std::to_string(sensor) + " while its first writer (publication " +
          std::to_string(claims.ownerOf(j)) + ") lives; its samples are kept out";
      spdlog::warn("{}", detail);
      faults_.push_back(emulator::faultEntry(emulator::FaultKind::ForeignWriter, kProcess, j, episode,
                                             std::nullopt, detail));
    }
    return true;
  }

  // The sensors' processes were declared failed: whoever takes their place writes anew.
  void releaseClaims(const std::set<int>& sensors) {
    for (const int j : sensors) {
      measurement_claims_.release(j);
      tally_claims_.release(j);
      status_claims_.release(j);
    }
  }

  void route(OpenEpisode& open, emulator::FusedMeasurement m, emulator::WriterId writer) {
    const int sensor = m.sensor;
    m.received_s = open.clock.emulatedAt(m.receive_wall_ns);
    // A foreign writer's sample that is malformed anyway is counted under that more telling
    // reason by the fusion.
    if (!emulator::malformedMeasurement(inputs_.scenario(), m) &&
        refuseForeign(measurement_claims_, measurement_reader_, "Measurement",
                      static_cast<std::uint32_t>(sensor), writer, open.fusion->episode())) {
      return;
    }
    if (auto rejection = open.fusion->add(std::move(m))) {
      // The emulated network's copies are expected; finish() tells them from other duplicates.
      const auto level = rejection->reason == "duplicate" && duplicatesLink(sensor)
                             ? spdlog::level::debug
                             : spdlog::level::warn;
      spdlog::log(level, "rejected a measurement of episode {}: {}", open.fusion->episode(),
                  rejection->detail);
      return;
    }
    measurement_claims_.claim(sensor, writer);  // accepted: well-formed, of this run
    open.last_heard_ns[static_cast<std::size_t>(sensor)] = wallNowNs();
  }

  void readTallies() {
    if (!inputs_.hasScenario()) return;  // kept by the reader (transient local) until then
    for (auto& received : tally_reader_.take(64).samples) {
      const sensornet_EpisodeTally& t = *received.sample;
      if (dds::viewString(t.run_id) != options_.run.run_id) {
        ++rejected_outside_["other_run"];
        continue;
      }
      if (t.sensor_id >= static_cast<std::uint32_t>(inputs_.scenario().sensorCount())) {
        ++rejected_outside_["malformed_tally"];
        continue;
      }
      if (refuseForeign(tally_claims_, tally_reader_, "EpisodeTally", t.sensor_id,
                        received.info.publication, t.episode)) {
        continue;
      }
      tally_claims_.claim(static_cast<int>(t.sensor_id), received.info.publication);
      if (resumed_ && resumed_->ignores(t.episode)) continue;  // no late tally for those
      if (auto open = open_.find(t.episode); open != open_.end()) {
        applyTally(open->second, t);
      } else if (!inputs_.lastStarted() || t.episode > *inputs_.lastStarted()) {
        early_tallies_[t.episode].push_back(t);
      } else {
        lateTally(t);
      }
    }
  }

  void applyTally(OpenEpisode& open, const sensornet_EpisodeTally& t) {
    const auto j = static_cast<std::size_t>(t.sensor_id);
    open.tallies[j] = t;
    open.tallies[j].run_id = nullptr;  // borrowed from the sample; not kept
    open.fusion->setTally(static_cast<int>(t.sensor_id),
                          {t.sent, t.dropped_by_network, t.duplicated_by_network});
    open.last_heard_ns[j] = wallNowNs();
    open.last_tally_ns = std::max(open.last_tally_ns, t.wall_time_ns);
  }

  // A tally of an episode closed before it came (the sensor stalled past the limit): the report
  // names what the episode missed.
  void lateTally(const sensornet_EpisodeTally& t) {
    if (closed_without_.erase({t.episode, static_cast<int>(t.sensor_id)}) == 0) return;
    faults_.push_back(emulator::faultEntry(
        emulator::FaultKind::LateTally, kProcess, static_cast<int>(t.sensor_id), t.episode, std::nullopt,
        "sensor " + std::to_string(t.sensor_id) + " reported " + std::to_string(t.sent) +
            " measurements sent in episode " + std::to_string(t.episode) +
            " after the episode had been closed without them"));
  }

  // Statuses carry each sensor's running count: a lower bound of what it sent, for a sensor
  // whose tally never comes.
  void readStatuses() {
    for (auto& received : status_reader_.take(64).samples) {
      const sensornet_SensorStatus& s = *received.sample;
      if (dds::viewString(s.run_id) != options_.run.run_id) continue;
      if (refuseForeign(status_claims_, status_reader_, "SensorStatus", s.sensor_id,
                        received.info.publication, s.episode)) {
        continue;
      }
      status_claims_.claim(static_cast<int>(s.sensor_id), received.info.publication);
      sensor_processes_[s.sensor_id] = {s.process_id, s.state};
      auto open = open_.find(s.episode);
      if (open == open_.end() || !inputs_.hasScenario() ||
          s.sensor_id >= static_cast<std::uint32_t>(inputs_.scenario().sensorCount())) {
        continue;
      }
      open->second.fusion->noteSentAtLeast(static_cast<int>(s.sensor_id), s.sent_in_episode);
      open->second.last_heard_ns[s.sensor_id] = wallNowNs();
    }
  }

  void noteOwnStall() {
    if (const auto stall = stall_watch_.tick(wallNowNs())) {
      spdlog::warn("the fusion center was stalled for {:.3g} s", stall->seconds());
      stalls_.push_back({{"process", kProcess}, {"seconds", stall->seconds()}});
    }
  }

  // Wall seconds since `from_ns` during which this process ran.
  [[nodiscard]] double awakeSince(std::int64_t from_ns, std::int64_t now_ns) const {
    return 1e-9 * static_cast<double>(now_ns - from_ns) -
           stall_watch_.stalledBetween(from_ns, now_ns);
  }

  void advance() {
    const std::int64_t now = wallNowNs();
    answerRestarted(now);
    // Measurements handled in this loop turn: how many were waiting for the main loop.
    const std::uint64_t waiting = std::exchange(waiting_, 0);
    for (auto it = open_.begin(); it != open_.end();) {
      const std::uint32_t number = it->first;
      OpenEpisode& open = it->second;
      open.backlog = std::max(open.backlog, waiting);
      const double horizon = inputs_.scenario().horizon_s;
      const double watermark = open.clock.emulatedAt(now - toNs(options_.lag_s));
      if (watermark > 0.0) open.fusion->fuseUpTo(std::min(watermark, horizon));
      if (open.fusion->allSettled()) {
        open.settled_ns = now;
        finishEpisode(number, open);
        it = open_.erase(it);
        continue;
      }
      if (silentTooLong(open, now)) {
        closeUnsettled(number, open,
                       "silent for " + formatSeconds(options_.stall_limit_s) +
                           " s after the episode ended");
        finishEpisode(number, open);
        it = open_.erase(it);
        continue;
      }
      if (now >= next_state_ns_) publishState(number, open);
      ++it;
    }
  }

  // Episodes this restarted process cannot fuse: each answered (logged, reported, its Report
  // published so the coordinator moves on) once its end has passed and the measurement reader
  // has matched every live sensor process, or kResumeMatchWaitS after the join.
  void answerRestarted(std::int64_t now) {
    if (restarted_.empty() || !report_) return;
    const bool waited = awakeSince(resumed_->joinedWallNs(), now) >= kResumeMatchWaitS;
    if (!waited && !matchedEverySensorProcess()) return;
    for (auto it = restarted_.begin(); it != restarted_.end();) {
      const auto [episode, end_ns] = *it;
      ++it;
      if (now >= end_ns) finishRestarted(episode);
    }
  }

  // The Measurement reader has matched a writer per live sensor process (one per sensor_agent),
  // as far as the sensors' statuses tell.
  [[nodiscard]] bool matchedEverySensorProcess() const {
    std::set<std::int32_t> processes;
    for (const auto& [sensor, process] : sensor_processes_) {
      const bool dead = inputs_.failedSensors().count(static_cast<int>(sensor)) > 0 ||
                        process.state == sensornet_SENSOR_FAILED ||
                        process.state == sensornet_SENSOR_STOPPED;
      if (!dead) processes.insert(process.id);
    }
    return !processes.empty() && measurement_reader_.matchedWriters() >= processes.size();
  }

  // The entry and Report of an episode this process could not fuse (it restarted during it).
  void finishRestarted(std::uint32_t episode) {
    restarted_.erase(episode);
    early_.erase(episode);
    early_tallies_.erase(episode);
    const Scenario& scenario = inputs_.scenario();
    emulator::EpisodeResult result = emulator::restartedEpisode(episode, scenario.sensorCount());
    const auto segments = inputs_.book().segments(episode, scenario.horizon_s);
    for (const emulator::ScheduleSegment& segment : segments) {
      result.versions.push_back(segment.version->version);
    }
    if (segments.size() == 1) {  // after a switch the bracket needs the fused P(s): unknown
      result.bracket = bracketOf(*segments.front().version);
      result.delivered_bracket = scenario.network
                                     ? deliveredBracketOf(*segments.front().version, episode)
                                     : result.bracket;
    }
    const json entry = emulator::episodeEntry(result);
    if (episode_log_) episode_log_->append(entry);
    report_->add(entry);
    spdlog::warn(
        "episode {}: not fused (the fusion center restarted during it); answered {:.3g} s after "
        "joining, with {} sensor processes' measurement writers matched",
        episode, 1e-9 * static_cast<double>(wallNowNs() - resumed_->joinedWallNs()),
        measurement_reader_.matchedWriters());
    publishReport(result, report_->summary());
  }

  static std::string formatSeconds(double seconds) {
    char text[32];
    std::snprintf(text, sizeof text, "%.3g", seconds);
    return text;
  }

  // An unsettled sensor silent (no measurement, tally or status) for the stall limit after the
  // episode's end, not counting the fusion center's own stalls.
  [[nodiscard]] bool silentTooLong(const OpenEpisode& open, std::int64_t now) const {
    const std::int64_t end_ns = open.clock.wallAt(inputs_.scenario().horizon_s);
    if (now < end_ns) return false;
    for (const int j : open.fusion->unsettled()) {
      const std::int64_t from = std::max(end_ns, open.last_heard_ns[static_cast<std::size_t>(j)]);
      if (awakeSince(from, now) <= options_.stall_limit_s) return false;
    }
    return true;
  }

  // Names every sensor the episode still waits for in the faults (the episode is incomplete).
  void closeUnsettled(std::uint32_t number, OpenEpisode& open, const std::string& why,
                      emulator::FaultKind silent_kind = emulator::FaultKind::Stall) {
    for (const int j : open.fusion->unsettled()) {
      const emulator::SensorTally& t = open.fusion->tally(j);
      std::string detail;
      if (t.tallied) {
        detail = "sensor " + std::to_string(j) + " sent " + std::to_string(t.sent) +
                 " measurements in episode " + std::to_string(number) + ", " +
                 std::to_string(t.received) + " arrived; the episode was closed when " + why;
      } else {
        detail = "sensor " + std::to_string(j) + " never reported its count for episode " +
                 std::to_string(number) + " (" + std::to_string(t.received) +
                 " measurements arrived); the episode was closed when " + why;
        closed_without_.insert({number, j});
      }
      faults_.push_back(emulator::faultEntry(t.tallied ? emulator::FaultKind::Lost : silent_kind, kProcess, j, number,
                                             open.fusion->fusedTime(), detail));
      spdlog::warn("episode {}: {}", number, detail);
    }
  }

  void publishState(std::uint32_t episode, const OpenEpisode& open) {
    next_state_ns_ = wallNowNs() + toNs(options_.state_period_s);
    const Eigen::MatrixXd& P = open.fusion->covariance();
    std::vector<double> values(P.data(), P.data() + P.size());  // symmetric: order is moot
    const emulator::ScheduleVersion* v = inputs_.book().inForce(episode, open.fusion->fusedTime());
    sensornet_FusionState s{};
    s.run_id = dds::borrowString(options_.run.run_id);
    s.episode = episode;
    s.emulated_time_s = open.fusion->fusedTime();
    s.state_dim = static_cast<std::uint32_t>(P.rows());
    dds::borrowSequence(s.covariance, values);
    s.schedule_version = v != nullptr ? v->version : 0;
    s.wall_time_ns = wallNowNs();
    (void)state_writer_.write(s);  // keep-last 1: a timeout only loses a superseded estimate
  }

  void finishEpisode(std::uint32_t number, OpenEpisode& open) {
    emulator::EpisodeResult result = open.fusion->finish();
    result.backlog = open.backlog;
    for (std::size_t j = 0; j < result.sensors.size(); ++j) {
      const emulator::SensorTally& t = result.sensors[j];
      if (t.duplicated_by_network > t.duplicates) {
        copies_left_[{number, static_cast<int>(j)}] = t.duplicated_by_network - t.duplicates;
      }
    }
    checkKeepingUp(number, open, result);
    traceCovariance(*open.fusion, result);
    report_->addLatencies(result.latencies_s);
    const json entry = emulator::episodeEntry(result);
    if (episode_log_) episode_log_->append(entry);
    report_->add(entry);
    if (resumed_) resumed_->noteFused(number);
    const emulator::RunSummary s = report_->summary();
    spdlog::info(
        "episode {}{}: realized {:.6g}, bracket [{:.6g}, {:.6g}]; mean {:.6g} over {} complete "
        "episodes",
        result.episode, result.complete ? "" : " (incomplete)", result.realized_cost,
        result.bracket.info, result.bracket.cov, s.mean, s.episodes_complete);
    publishReport(result, s);
  }

  // The weighted covariance trace of one of the first kTracedEpisodes episodes (its measurements
  // are gone once it is closed), for the report's page; the surrogate curves of the version in
  // force at its start are computed when the report is written, not while the run goes on.
  void traceCovariance(const emulator::EpisodeFusion& fusion, const emulator::EpisodeResult& r) {
    if (traced_episodes_.size() >= kTracedEpisodes || r.versions.empty()) return;
    const Scenario& scenario = inputs_.scenario();
    const emulator::TraceWeight weight = emulator::traceWeight(scenario);
    const std::uint32_t version = r.versions.front();
    json curve = emulator::traceJson(
        emulator::fusedCovarianceTrace(scenario, fusion.measurements(), weight, kTracePoints));
    curve["episode"] = r.episode;
    curve["version"] = version;
    curve["complete"] = r.complete;
    traced_episodes_.push_back(std::move(curve));
    traced_versions_.insert(version);
  }

  [[nodiscard]] json covarianceTraces() const {
    const Scenario& scenario = inputs_.scenario();
    const emulator::TraceWeight weight = emulator::traceWeight(scenario);
    json surrogates = json::array();
    for (const emulator::ScheduleVersion& v : inputs_.book().versions()) {
      if (traced_versions_.count(v.version) == 0) continue;
      try {  // a curve of the page must never cost the report
        const emulator::SurrogateTraces s =
            emulator::surrogateTraces(scenario, v.schedule, weight, kTracePoints);
        surrogates.push_back({{"version", v.version},
                              {"info", emulator::traceJson(s.info)},
                              {"cov", emulator::traceJson(s.cov)}});
      } catch (const std::exception& e) {
        spdlog::warn("no surrogate curves of version {} for the report: {}", v.version, e.what());
      }
    }
    return {{"weight", weight.name},
            {"episodes", traced_episodes_},
            {"surrogates", surrogates}};
  }

  // Overload: the fusion center drained an episode late (not counting its own stalls), or a
  // sensor published far behind the emulated clock (not counting the sensor's stalls).
  void checkKeepingUp(std::uint32_t number, const OpenEpisode& open,
                      emulator::EpisodeResult& result) {
    if (open.settled_ns) {
      const std::int64_t from =
          std::max(open.clock.wallAt(inputs_.scenario().horizon_s), open.last_tally_ns);
      if (*open.settled_ns > from) result.drain_s = awakeSince(from, *open.settled_ns);
    }
    if (result.drain_s > options_.keep_up_limit_s) {
      faults_.push_back(emulator::faultEntry(
          emulator::FaultKind::Overload, kProcess, std::nullopt, number, std::nullopt,
          "the fusion center had all of episode " + std::to_string(number) + " only " +
              formatSeconds(result.drain_s) + " s after its last tally (up to " +
              std::to_string(open.backlog) + " measurements waiting)"));
    }
    for (std::size_t j = 0; j < open.tallies.size(); ++j) {
      const sensornet_EpisodeTally& t = open.tallies[j];
      if (t.stalled_s > 0.0) {
        stalls_.push_back({{"process", "sensor " + std::to_string(j)},
                           {"episode", number},
                           {"seconds", t.stalled_s}});
      }
      if (t.max_lag_s > options_.keep_up_limit_s) {
        faults_.push_back(emulator::faultEntry(
            emulator::FaultKind::SensorLag, "sensor_agent", static_cast<int>(j), number, std::nullopt,
            "sensor " + std::to_string(j) + " published up to " + formatSeconds(t.max_lag_s) +
                " s behind the emulated clock in episode " + std::to_string(number)));
      }
    }
  }

  void publishReport(const emulator::EpisodeResult& e, const emulator::RunSummary& s) {
    std::vector<sensornet_SensorCounts> counts;
    for (std::size_t j = 0; j < e.sensors.size(); ++j) {
      const emulator::SensorTally& t = e.sensors[j];
      counts.push_back({static_cast<std::uint32_t>(j), t.received, t.expected, t.lost, t.late,
                        t.sent, t.dropped_by_network});
    }
    sensornet_Report r{};
    r.run_id = dds::borrowString(options_.run.run_id);
    r.episode = e.episode;
    r.realized_cost = e.realized_cost;
    r.realtime_cost = e.realtime_cost;
    r.bracket_lower = e.bracket.info;
    r.bracket_upper = e.bracket.cov;
    r.delivered_bracket_lower = e.delivered_bracket.info;
    r.delivered_bracket_upper = e.delivered_bracket.cov;
    dds::borrowSequence(r.schedule_versions, e.versions);
    r.nees = e.nees;
    dds::borrowSequence(r.counts, counts);
    r.latency_median_s = s.latency_median_s;
    r.latency_p99_s = s.latency_p99_s;
    r.summary.episodes = s.episodes;
    r.summary.episodes_complete = s.episodes_complete;
    r.summary.realized_mean = s.mean;
    r.summary.realized_ci95_low = s.ci95_low;
    r.summary.realized_ci95_high = s.ci95_high;
    r.summary.realtime_mean = s.realtime_mean;
    r.summary.bracket_lower_mean = s.bracket_mean.info;
    r.summary.bracket_upper_mean = s.bracket_mean.cov;
    r.summary.meets_bracket = s.meets_bracket.value_or(false);
    r.summary.delivered_lower_mean = s.delivered_bracket_mean.info;
    r.summary.delivered_upper_mean = s.delivered_bracket_mean.cov;
    r.summary.meets_delivered_bracket = s.meets_delivered_bracket.value_or(false);
    r.summary.nees_mean = s.nees_mean;
    r.summary.sent = s.sent;
    r.summary.received = s.received;
    r.summary.lost = s.lost;
    r.summary.dropped_by_network = s.dropped_by_network;
    r.summary.latency_median_s = s.latency_median_s;
    r.summary.latency_p99_s = s.latency_p99_s;
    r.complete = e.complete;
    if (report_writer_.write(r) == dds::WriteResult::TimedOut) {
      spdlog::warn("the report of episode {} timed out on the wire (kept in the file)", e.episode);
    }
    forgetOldReports(e.episode);
  }

  // The Report topic keeps the last report of each episode for late joiners: an instance per
  // episode, held by this writer and by every reader until it is unregistered. Only the latest
  // kReportsKept stay registered (a restarted coordinator needs the last one), so that memory
  // does not grow with the number of episodes (with Cyclone 0.10 only if the unregistration also
  // gives back the key Cyclone keeps of every instance written: unregisterWrittenInstance).
  void forgetOldReports(std::uint32_t episode) {
    reports_registered_.push_back(episode);
    if (reports_registered_.size() <= kReportsKept) return;
    sensornet_Report key{};
    key.run_id = dds::borrowString(options_.run.run_id);
    key.episode = reports_registered_.front();
    reports_registered_.pop_front();
    (void)report_writer_.unregisterWrittenInstance(key);  // a timeout keeps the report longer
  }

  // DESIGN.md's run outcome, as far as the fusion center saw it (the launcher adds what it saw
  // of the processes): failed when the coordinator gave up, interrupted on a signal, degraded
  // when an episode is missing or incomplete, something was lost or rejected, or it overloaded.
  std::string decideStatus(const std::optional<emulator::RunEnd>& end) {
    if (resumed_) noteRestart();
    if (!end) return "interrupted";
    if (end->aborted) {
      faults_.push_back(emulator::faultEntry(emulator::FaultKind::RunAborted, "coordinator", std::nullopt,
                                             std::nullopt, std::nullopt, end->detail));
      return "failed";
    }
    if (!report_) return "failed";
    for (const auto& [reason, count] : inputs_.rejected()) rejected_outside_[reason] += count;
    for (const auto& [reason, count] : rejected_outside_) report_->countRejected(reason, count);
    for (const auto& [episode, held] : early_) {
      report_->countRejected("unknown_episode", held.size());
    }
    const emulator::RunSummary s = report_->summary();
    if (s.episodes < end->episodes_run) {
      faults_.push_back(emulator::faultEntry(
          emulator::FaultKind::MissingEpisodes, kProcess, std::nullopt, std::nullopt, std::nullopt,
          "the coordinator ran " + std::to_string(end->episodes_run) + " episodes, " +
              std::to_string(s.episodes) + " were fused"));
    }
    if (emulator::faultyRejections(s.rejected) > 0) {
      std::string reasons;
      for (const auto& [reason, count] : s.rejected) {
        if (reason == emulator::kNetworkDuplicate) continue;  // scripted, not a fault
        reasons += (reasons.empty() ? "" : ", ") + std::to_string(count) + " " + reason;
      }
      faults_.push_back(emulator::faultEntry(emulator::FaultKind::Rejected, kProcess, std::nullopt, std::nullopt,
                                             std::nullopt,
                                             "samples refused on the wire: " + reasons));
    }
    const bool clean = faults_.empty() && s.lost == 0 && s.episodes == s.episodes_complete;
    return clean ? "completed" : "degraded";
  }

  // The restart in the report's faults: the process, the episodes it could not fuse.
  void noteRestart() {
    const std::set<std::uint32_t>& lost = resumed_->restarted();
    std::string episodes;
    for (const std::uint32_t e : lost) episodes += (episodes.empty() ? "" : ", ") + std::to_string(e);
    faults_.insert(faults_.begin(),
                   emulator::faultEntry(
                       emulator::FaultKind::Restarted, kProcess, std::nullopt,
                       lost.empty() ? std::nullopt : std::optional<std::uint32_t>(*lost.rbegin()),
                       std::nullopt,
                       "the fusion center was restarted and resumed from " +
                           std::to_string(resumed_->entries().size()) + " logged episodes; " +
                           (lost.empty() ? std::string("no episode was lost")
                                         : "not fused (incomplete, " +
                                               std::string(emulator::kRestartedReason) +
                                               "): episode " + episodes)));
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

  void writeReport(const std::string& status) {
    if (!report_) {
      spdlog::error("no scenario ever arrived; no report");
      return;
    }
    const json extra = {{"episodes_planned", episodes_planned_},
                        {"seed", inputs_.run().seed},
                        {"stalls", stalls_},
                        {"written_at", utcNow()},
                        {"covariance_traces", covarianceTraces()},
                        {"arrivals", arrivalsJson(inputs_.scenario().arrivals)}};
    // per_episode is streamed in from the episode log, never held whole.
    const json doc = report_->toJsonWithoutEpisodes(
        status, faults_, emulator::scheduleVersionsJson(inputs_.book()), extra);
    if (!options_.report_path.empty()) {
      writeJsonFile(options_.report_path, "run report", [&](std::ostream& out) {
        report_->write(out, doc, 2);
        out << '\n';
      });
      spdlog::info("report written to {}", options_.report_path);
    }
    if (options_.json) {
      report_->write(std::cout, doc, -1);
      std::cout << std::endl;
    }
  }

  ServeOptions options_;
  dds::Domain domain_;
  dds::Participant participant_;
  emulator::RunInputs inputs_;
  dds::Topic<sensornet_Measurement> measurement_topic_;
  dds::Topic<sensornet_EpisodeTally> tally_topic_;
  dds::Topic<sensornet_SensorStatus> status_topic_;
  dds::Topic<sensornet_Report> report_topic_;
  dds::Topic<sensornet_FusionState> state_topic_;
  dds::Reader<sensornet_Measurement> measurement_reader_;
  dds::Reader<sensornet_EpisodeTally> tally_reader_;
  dds::Reader<sensornet_SensorStatus> status_reader_;
  dds::Writer<sensornet_Report> report_writer_;
  dds::Writer<sensornet_FusionState> state_writer_;
  dds::WaitSet waitset_;
  dds::ReadCondition tally_ready_;
  dds::ReadCondition status_ready_;
  Inbox inbox_;
  std::vector<Arrival> taken_;    // the listener's batch (receive thread only)
  std::vector<Arrival> drained_;  // the main loop's (main thread only)
  // After what its callback touches (reader, waitset, inbox): it is destroyed before them, and
  // its destructor waits for a callback in progress.
  dds::DataAvailableListener arrivals_listener_;

  std::optional<emulator::EpisodeLog> episode_log_;
  std::optional<emulator::RunReport> report_;
  std::map<std::uint32_t, CostBracket> brackets_;
  // (version, the outages of an episode) -> the bracket of what the network delivers
  std::map<std::pair<std::uint32_t, std::vector<std::size_t>>, CostBracket> delivered_brackets_;
  std::map<std::uint32_t, OpenEpisode> open_;
  std::map<std::uint32_t, std::vector<Arrival>> early_;
  std::map<std::uint32_t, std::vector<sensornet_EpisodeTally>> early_tallies_;
  std::vector<emulator::SensorFailure> failures_;  // the coordinator's notices, in order
  std::optional<emulator::ResumedRun> resumed_;    // with --resume
  std::map<std::uint32_t, std::int64_t> restarted_;  // not fusable here -> end wall time (0: past)
  struct SensorProcess {
    std::int32_t id = 0;
    sensornet_SensorState state = sensornet_SENSOR_STARTING;
  };
  std::map<std::uint32_t, SensorProcess> sensor_processes_;  // by sensor, from their statuses
  std::set<std::pair<std::uint32_t, int>> closed_without_;  // (episode, sensor) with no tally
  // (episode, sensor) of a closed episode: copies its tally says the network made, not yet seen.
  std::map<std::pair<std::uint32_t, int>, std::uint64_t> copies_left_;
  emulator::RejectionCounts rejected_outside_;  // samples refused before reaching an episode
  // Which writer speaks for each sensor, per topic (first live writer wins).
  emulator::WriterClaims measurement_claims_, tally_claims_, status_claims_;
  json faults_ = json::array();
  json traced_episodes_ = json::array();      // covariance_traces: the first episodes' curves
  std::set<std::uint32_t> traced_versions_;   // ... and the versions in force at their start
  json stalls_ = json::array();  // stalls absorbed (own and the sensors'), for the report
  emulator::StallWatch stall_watch_;
  std::uint32_t episodes_planned_ = 0;
  std::deque<std::uint32_t> reports_registered_;  // episodes whose Report instance is registered
  std::uint64_t waiting_ = 0;  // measurements taken off the inbox in this loop turn
  std::int64_t next_state_ns_ = 0;
};

}  // namespace

Subcommand addServeCommand(CLI::App& app) {
  auto options = std::make_shared<ServeOptions>();
  CLI::App* cmd = app.add_subcommand(
      "serve",
      "Fuse a running emulation: the exact CD-KF over every sensor's measurements in timestamp "
      "order, a Report per episode (realized cost against the bracket of the schedule in "
      "force), and the final report on shutdown. An episode closes when every sensor's "
      "end-of-episode tally is in and every measurement it counts has arrived; a sensor that "
      "owes measurements and stays silent past --stall-limit is named in the report's faults. "
      "Each finished episode is appended at once to the JSON Lines log beside the report "
      "(report.jsonl beside report.json). Example:\n  fusion_center serve --run-id demo "
      "--report report.json");
  emulator::addRunOptions(*cmd, options->run);
  options->run.security_role = dds::SecurityRole::FusionCenter;
  cmd->add_option("--report", options->report_path,
                  "final report (JSON) written when the run shuts down; the episode log goes "
                  "beside it");
  cmd->add_option("--lag", options->lag_s,
                  "wall seconds a measurement may take to arrive before it is fused (a later "
                  "one is still fused in order: the episode is re-fused at its end)")
      ->capture_default_str()
      ->check(nonNegativeNumber(emulator::kMaxWallSeconds));
  cmd->add_option("--stall-limit", options->stall_limit_s,
                  "wall seconds a sensor that still owes measurements may stay silent after an "
                  "episode's end before the episode is closed incomplete (longer than the 10 s "
                  "stalls a run absorbs)")
      ->capture_default_str()
      ->check(positiveNumber(emulator::kMaxWallSeconds));
  cmd->add_option("--keep-up-limit", options->keep_up_limit_s,
                  "wall seconds of drain after an episode's end, or of a sensor's lag behind the "
                  "emulated clock, past which the run is reported as overloaded (degraded)")
      ->capture_default_str()
      ->check(positiveNumber(emulator::kMaxWallSeconds));
  cmd->add_flag("--json", options->json, "also print the final report as one JSON line");
  cmd->add_flag("--resume", options->resume,
                "restarted after a death (the launcher adds it): start the report from the "
                "episode log beside --report and append to it; an episode that began before this "
                "process and is not in the log is recorded incomplete (fusion_center_restarted)");
  return {cmd, [options] {
            (void)options->run.domainConfig();
            emulator::installStopSignals();
            FusionCenter center(*options);
            return center.run();
          }};
}

}  // namespace sensornet::fusion_center
