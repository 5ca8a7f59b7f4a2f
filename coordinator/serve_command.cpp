#include "serve_command.hpp"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <chrono>
#include <deque>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <thread>

#include "sensornet/core/emulated_plant.hpp"
#include "sensornet/core/input_error.hpp"
#include "sensornet/core/network.hpp"
#include "sensornet/core/planner.hpp"
#include "sensornet/core/surrogate.hpp"
#include "sensornet/dds/participant.hpp"
#include "sensornet/dds/reader.hpp"
#include "sensornet/dds/topics.hpp"
#include "sensornet/dds/waitset.hpp"
#include "sensornet/dds/wire.hpp"
#include "sensornet/dds/writer.hpp"
#include "sensornet/emulator/coordinator_journal.hpp"
#include "sensornet/emulator/messages.hpp"
#include "sensornet/emulator/replanner.hpp"
#include "sensornet/emulator/run_inputs.hpp"
#include "sensornet/emulator/run_options.hpp"
#include "sensornet/emulator/stall_watch.hpp"
#include "sensornet/emulator/stop_signal.hpp"
#include "sensornet/io/scenario_file.hpp"

namespace sensornet::coordinator {
namespace {

using namespace std::chrono_literals;
using emulator::wallNowNs;

// What to do when the launcher reports that sensors died (COMMAND_SENSORS_FAILED).
enum class FailurePolicy { Replan, Continue, Stop };

struct ServeOptions {
  emulator::RunOptions run;
  std::string scenario_path;
  PlanSurrogate surrogate = PlanSurrogate::Covariance;
  std::string schedule_path;
  int episodes = 20;
  double time_scale = 1.0;
  std::uint64_t seed = 1;
  double ready_timeout_s = 30.0;
  double start_lead_s = 0.2;     // wall seconds between announcing the first episode and its start
  double episode_gap_s = 0.002;  // wall seconds between one episode's end and the next's start
  double switch_margin_s = 0.3;  // wall seconds between a re-plan and its effective time
  double report_timeout_s = 30.0;  // wall seconds of fusion-center silence before giving up
  FailurePolicy on_sensor_failure = FailurePolicy::Replan;
  bool network_aware = false;
  std::string arrivals;    // empty: the scenario's `arrivals:`; else poisson or timetable
  std::string state_path;  // the journal (empty: none)
  bool resume = false;     // start from the journal
  bool json = false;
};

std::int64_t toNs(double seconds) { return static_cast<std::int64_t>(1e9 * seconds); }

std::string listed(const std::set<int>& sensors) {
  std::string text;
  for (const int id : sensors) text += (text.empty() ? "" : ", ") + std::to_string(id);
  return text;
}

// The journal's fixed part: which run it belongs to (what --resume checks) and its length.
emulator::CoordinatorJournal journalHeader(const ServeOptions& options,
                                           const emulator::RunScenario& run) {
  emulator::CoordinatorJournal journal;
  journal.run_id = options.run.run_id;
  journal.scenario_digest = run.digest;
  journal.seed = run.seed;
  journal.episodes_planned = static_cast<std::uint32_t>(options.episodes);
  journal.time_scale = options.time_scale;
  return journal;
}

// What the coordinator answers to one command: new versions to publish (and settings to adopt)
// or none, and the reply's reason.
struct Answer {
  std::optional<emulator::Replan> replan;
  std::string reason;
};

// An episode announced and not reported yet.
struct Outstanding {
  std::uint32_t episode = 0;
  emulator::EpisodeClock clock;
};

class Coordinator {
 public:
  // `journal` is where the run stands: a fresh one (version 1, nothing announced) or one read
  // back with --resume.
  Coordinator(const ServeOptions& options, emulator::RunScenario run,
              const emulator::CoordinatorJournal& journal)
      : options_(options),
        run_(std::move(run)),
        plant_(run_.scenario, run_.seed),
        replanner_(run_.scenario, plant_, journal.settings, replannerOptions(options, run_)),
        domain_(options.run.domainConfig()),
        participant_(domain_),
        scenario_topic_(participant_),
        schedule_topic_(participant_),
        control_topic_(participant_),
        command_topic_(participant_),
        reply_topic_(participant_),
        status_topic_(participant_),
        report_topic_(participant_),
        state_topic_(participant_),
        scenario_writer_(participant_, scenario_topic_),
        schedule_writer_(participant_, schedule_topic_),
        control_writer_(participant_, control_topic_),
        reply_writer_(participant_, reply_topic_),
        command_reader_(participant_, command_topic_),
        status_reader_(participant_, status_topic_),
        report_reader_(participant_, report_topic_),
        state_reader_(participant_, state_topic_),
        waitset_(participant_),
        command_ready_(command_reader_),
        status_ready_(status_reader_),
        report_ready_(report_reader_),
        reported_(journal.episodes_reported),
        announced_(journal.announced),
        answered_(journal.answered),
        stopping_(journal.shutdown_requested),
        abort_detail_(journal.abort_detail) {
    waitset_.attach(command_ready_, 1);
    waitset_.attach(status_ready_, 2);
    waitset_.attach(report_ready_, 3);
    for (const emulator::ScheduleVersion& v : journal.versions) book_.add(v);
    if (announced_) {  // resumed: the episode announced last runs on without us
      current_episode_ = announced_->episode;
      next_episode_ = current_episode_ + 1;
      const emulator::EpisodeClock clock{announced_->start_wall_ns, options_.time_scale};
      if (!reported_.count(current_episode_)) outstanding_.push_back({current_episode_, clock});
      last_end_ns_ = clock.wallAt(run_.scenario.horizon_s);
    }
  }

  int run() {
    saveState();
    mustWrite(emulator::publishScenario(scenario_writer_, options_.run.run_id, run_), "scenario");
    for (const emulator::ScheduleVersion& v : book_.versions()) publishVersion(v);
    spdlog::info("run {}: scenario {} and schedule v1..v{} published; waiting for {} sensors "
                 "and the fusion center",
                 options_.run.run_id, run_.digest, book_.latest().version, sensorsInService());
    if (!abort_detail_.empty()) return abort();
    if (!waitUntilReady()) return abort_detail_.empty() ? kExitFailure : abort();
    if (!outstanding_.empty()) {
      spdlog::info("resuming: episode {} was announced before the restart; waiting for its report",
                   current_episode_);
    }
    for (;;) {
      announceAhead();
      if (outstanding_.empty()) break;
      if (!awaitReport(outstanding_.front())) return fail();
      outstanding_.pop_front();
    }
    shutDown("");
    if (emulator::stopRequested()) return kExitFailure;
    if (options_.json) {
      printJson({{"run_id", options_.run.run_id},
                 {"episodes", episodesDone()},
                 {"schedule_versions", book_.latest().version}});
    }
    return kExitOk;
  }

 private:
  static emulator::ReplannerOptions replannerOptions(const ServeOptions& options,
                                                     const emulator::RunScenario& run) {
    emulator::ReplannerOptions r;
    r.switch_margin_s = options.switch_margin_s;
    r.time_scale = options.time_scale;
    if (options.network_aware) r.delivery = deliveryFactors(run.scenario);
    return r;
  }

  static void mustWrite(dds::WriteResult result, const char* what) {
    if (result == dds::WriteResult::TimedOut) {
      throw std::runtime_error(std::string("publishing the ") + what + " timed out");
    }
  }

  // Ends an unfinished run: why, in the RUN_SHUTDOWN detail.
  int fail() {
    if (!abort_detail_.empty()) return abort();
    shutDown(emulator::stopRequested()
                 ? "the coordinator was stopped by a signal"
                 : "no report of episode " + std::to_string(current_episode_));
    return kExitFailure;
  }
  int abort() {
    shutDown(abort_detail_);
    return kExitFailure;
  }

  [[nodiscard]] int episodesDone() const { return static_cast<int>(reported_.size()); }
  [[nodiscard]] int sensorsInService() const {
    return run_.scenario.sensorCount() - static_cast<int>(replanner_.settings().failed.size());
  }
  [[nodiscard]] int readySensorsInService() const {
    const std::set<int>& failed = replanner_.settings().failed;
    return static_cast<int>(std::count_if(ready_sensors_.begin(), ready_sensors_.end(),
                                          [&](int id) { return !failed.count(id); }));
  }

  // Every sensor that has not failed, and the fusion center. At a resume the sensors' durable
  // statuses (READY, RUNNING, EXCLUDED) count.
  bool waitUntilReady() {
    const std::int64_t deadline = wallNowNs() + toNs(options_.ready_timeout_s);
    for (;;) {
      pump(20ms);
      const bool sensors_ready = readySensorsInService() == sensorsInService();
      const bool fusion_ready = report_reader_.matchedWriters() > 0 &&
                                state_reader_.matchedWriters() > 0;
      if (sensors_ready && fusion_ready) {
        spdlog::info("all {} sensors and the fusion center are ready", readySensorsInService());
        std::this_thread::sleep_for(100ms);  // let the last discovery settle
        return true;
      }
      if (emulator::stopRequested() || !abort_detail_.empty()) return false;
      if (wallNowNs() > deadline) {
        spdlog::error("not ready after {} s: {} of {} sensors ready, fusion center {}",
                      options_.ready_timeout_s, readySensorsInService(), sensorsInService(),
                      fusion_ready ? "present" : "missing");
        return false;
      }
    }
  }

  // Episodes run back to back: while one runs, the next is announced (its start is the end of
  // this one plus --episode-gap), so the sensors hold it and begin on time. At most two episodes
  // are outstanding (announced, not reported): the next but one is announced only once the
  // report of the oldest is in, so a stalled fusion center holds the run back by one episode.
  void announceAhead() {
    while (outstanding_.size() < 2 && !stopping_ &&
           next_episode_ < static_cast<std::uint32_t>(options_.episodes)) {
      announceEpisode(next_episode_);
    }
  }

  // The first episode of a run starts start_lead_s from now (every process is ready but has not
  // seen a start yet); a later one episode_gap_s after the previous one's end, or from now if
  // that has passed (a report came late).
  [[nodiscard]] std::int64_t nextStartNs() const {
    const std::int64_t now = wallNowNs();
    if (!announced_) return now + toNs(options_.start_lead_s);
    return std::max(last_end_ns_, now) + toNs(options_.episode_gap_s);
  }

  void announceEpisode(std::uint32_t episode) {
    const emulator::EpisodeClock clock{nextStartNs(), options_.time_scale};
    announced_ = emulator::AnnouncedEpisode{episode, clock.start_wall_ns};
    outstanding_.push_back({episode, clock});
    last_end_ns_ = clock.wallAt(run_.scenario.horizon_s);
    next_episode_ = episode + 1;
    saveState();
    const std::vector<std::uint32_t> failed = failedIds();
    sensornet_EpisodeControl c = control(sensornet_EPISODE_START, episode);
    c.start_wall_time_ns = clock.start_wall_ns;
    c.schedule_version = book_.inForce(episode, 0.0)->version;
    dds::borrowSequence(c.failed_sensors, failed);
    mustWrite(control_writer_.write(c), "episode control");
  }

  bool awaitReport(const Outstanding& awaited) {
    const std::uint32_t episode = awaited.episode;
    current_episode_ = episode;
    // The fusion center closes the episode once every sensor's count is in, which after a
    // stall can take a while; it publishes its state meanwhile. Give up only when it has shown
    // no sign of life for report_timeout_s after the episode's end, not counting the time this
    // process was stalled itself.
    const std::int64_t end_ns = awaited.clock.wallAt(run_.scenario.horizon_s);
    fusion_heard_ns_ = end_ns;
    while (!reported_.count(episode)) {
      pump(10ms);
      if (emulator::stopRequested() || !abort_detail_.empty()) return false;
      const std::int64_t now = wallNowNs();
      const std::int64_t from = std::max(end_ns, fusion_heard_ns_);
      if (now > from && 1e-9 * static_cast<double>(now - from) -
                                stall_watch_.stalledBetween(from, now) >
                            options_.report_timeout_s) {
        spdlog::error("no report of episode {} and no sign of the fusion center for {} s",
                      episode, options_.report_timeout_s);
        return false;
      }
    }
    return true;
  }

  [[nodiscard]] sensornet_EpisodeControl control(sensornet_EpisodeCommand command,
                                                 std::uint32_t episode) const {
    sensornet_EpisodeControl c{};
    c.run_id = dds::borrowString(options_.run.run_id);
    c.episode = episode;
    c.command = command;
    c.start_wall_time_ns = wallNowNs();
    c.time_scale = options_.time_scale;
    c.seed = run_.seed;
    c.schedule_version = book_.latest().version;
    c.episodes_planned = static_cast<std::uint32_t>(options_.episodes);
    c.detail = dds::borrowString(kEmpty);
    return c;
  }

  [[nodiscard]] std::vector<std::uint32_t> failedIds() const {
    const std::set<int>& failed = replanner_.settings().failed;
    return {failed.begin(), failed.end()};
  }

  // Ends the run; `failure` empty when every episode ran.
  void shutDown(const std::string& failure) {
    sensornet_EpisodeControl c = control(sensornet_RUN_SHUTDOWN, current_episode_);
    c.episodes_planned = static_cast<std::uint32_t>(episodesDone());
    c.aborted = !failure.empty();
    c.detail = dds::borrowString(failure);
    if (control_writer_.write(c) == dds::WriteResult::TimedOut) {
      spdlog::warn("the shutdown announcement timed out");
    }
    (void)control_writer_.waitForAcks(3s);
    (void)reply_writer_.waitForAcks(1s);
    spdlog::info("run {} shut down after {} episodes{}", options_.run.run_id, episodesDone(),
                 failure.empty() ? "" : ": " + failure);
  }

  // Waits up to `timeout` for something to read, then reads everything.
  void pump(std::chrono::nanoseconds timeout) {
    (void)waitset_.wait(timeout);
    if (const auto stall = stall_watch_.tick(wallNowNs())) {
      spdlog::warn("the coordinator was stalled for {:.3g} s", stall->seconds());
    }
    readStatuses();
    readReports();
    readFusionStates();
    readCommands();
    stall_watch_.busyUntil(wallNowNs());  // planning a live change is work, not a stall
  }

  void readStatuses() {
    for (auto& received : status_reader_.take(64).samples) {
      const sensornet_SensorStatus& s = *received.sample;
      const int id = static_cast<int>(s.sensor_id);
      if (id < 0 || id >= run_.scenario.sensorCount()) continue;
      if (s.state == sensornet_SENSOR_READY || s.state == sensornet_SENSOR_EXCLUDED ||
          s.state == sensornet_SENSOR_RUNNING) {
        if (s.schedule_version >= 1) ready_sensors_.insert(id);
      }
      if (s.state == sensornet_SENSOR_FAILED) {
        spdlog::warn("sensor {} failed: {}", id, dds::viewString(s.detail));
      }
    }
  }

  void readReports() {
    for (auto& received : report_reader_.take(16).samples) {
      const sensornet_Report& r = *received.sample;
      fusion_heard_ns_ = std::max(fusion_heard_ns_, wallNowNs());
      if (r.episode >= static_cast<std::uint32_t>(options_.episodes)) continue;
      if (!reported_.insert(r.episode)) continue;
      saveState();
      spdlog::info("[{}/{}] episode {}: realized {:.6g}, bracket [{:.6g}, {:.6g}]; mean {:.6g} "
                   "in [{:.6g}, {:.6g}] (95%)",
                   r.summary.episodes, options_.episodes, r.episode, r.realized_cost,
                   r.bracket_lower, r.bracket_upper, r.summary.realized_mean,
                   r.summary.realized_ci95_low, r.summary.realized_ci95_high);
    }
  }

  void readFusionStates() {
    for (auto& received : state_reader_.take(8).samples) {
      const sensornet_FusionState& s = *received.sample;
      const auto values = dds::viewSequence(s.covariance);
      const auto n = static_cast<std::size_t>(run_.scenario.stateDim());
      if (s.state_dim != n || values.size() != n * n) continue;
      Eigen::MatrixXd P = Eigen::Map<const Eigen::MatrixXd>(values.data(),
                                                            static_cast<Eigen::Index>(n),
                                                            static_cast<Eigen::Index>(n));
      fused_ = emulator::FusedCovariance{s.episode, s.emulated_time_s, 0.5 * (P + P.transpose())};
      fusion_heard_ns_ = std::max(fusion_heard_ns_, wallNowNs());
    }
  }

  void readCommands() {
    for (auto& received : command_reader_.take(8).samples) {
      const sensornet_Command& c = *received.sample;
      if (dds::viewString(c.run_id) != options_.run.run_id) continue;
      // A command that comes again (the launcher resends until it sees a reply) was answered.
      if (const auto it = answered_.find(c.command_id); it != answered_.end()) {
        sendReply(c.command_id, it->second);
        continue;
      }
      emulator::AnsweredCommand reply = answer(c);
      spdlog::info("command {} from '{}': {} ({})", c.command_id, dds::viewString(c.issuer),
                   reply.accepted ? "accepted" : "refused", reply.reason);
      sendReply(c.command_id, reply);
    }
  }

  // Decides, records (journal first) and publishes what command `c` changes; returns the reply.
  emulator::AnsweredCommand answer(const sensornet_Command& c) {
    emulator::AnsweredCommand reply;
    try {
      Answer a = execute(c);
      reply.accepted = true;
      reply.reason = std::move(a.reason);
      if (a.replan) {
        reply.schedule_version = a.replan->replyVersion();
        for (const emulator::ScheduleVersion& v : a.replan->versions) book_.add(v);
        replanner_.adopt(*a.replan);
      }
      answered_[c.command_id] = reply;
      saveState();
      if (a.replan) {
        for (const emulator::ScheduleVersion& v : a.replan->versions) publishVersion(v);
      }
    } catch (const InputError& error) {
      reply = {false, 0, error.what()};
      answered_[c.command_id] = reply;
      saveState();
    } catch (const std::exception& error) {
      // Not recorded: the same command may succeed when it comes again.
      reply = {false, 0, std::string("failed: ") + error.what()};
      answered_.erase(c.command_id);
    }
    return reply;
  }

  void sendReply(std::uint64_t command_id, const emulator::AnsweredCommand& answered) {
    sensornet_CommandReply reply{};
    reply.run_id = dds::borrowString(options_.run.run_id);
    reply.command_id = command_id;
    reply.accepted = answered.accepted;
    reply.schedule_version = answered.schedule_version;
    reply.reason = dds::borrowString(answered.reason);
    if (reply_writer_.write(reply) == dds::WriteResult::TimedOut) {
      spdlog::warn("the reply to command {} timed out", command_id);
    }
  }

  // Plans (nothing is published or adopted here); throws InputError to refuse. A change of
  // settings (surrogate, excluded sensors, budget) holds only once its plans are published.
  Answer execute(const sensornet_Command& c) {
    const emulator::RunMoment now = moment();
    const emulator::ScheduleBook& book = book_;
    const auto replanned = [](emulator::Replan r) {
      std::string reason = r.summary;
      return Answer{std::move(r), std::move(reason)};
    };
    switch (c.kind) {
      case sensornet_COMMAND_STATUS:
        return {std::nullopt, "running episode " + std::to_string(current_episode_) +
                                  ", schedule v" + std::to_string(book_.latest().version)};
      case sensornet_COMMAND_SENSORS_FAILED:
        return onSensorsFailed(c);
      case sensornet_COMMAND_SHUTDOWN:
        stopping_ = true;
        return {std::nullopt, "the run ends after the episodes already announced"};
      case sensornet_COMMAND_REPLAN:
        return replanned(replanner_.changeSurrogate(dds::viewString(c.surrogate), book, now,
                                                    c.command_id));
      case sensornet_COMMAND_EXCLUDE_SENSORS:
        return replanned(replanner_.exclude(dds::viewSequence(c.sensor_ids), book, now,
                                            c.command_id));
      case sensornet_COMMAND_SET_BUDGET:
        return replanned(
            replanner_.setBudget(dds::viewSequence(c.budget), book, now, c.command_id));
      case sensornet_COMMAND_SCHEDULE_FILE:
        return replanned(replanner_.adoptScheduleFile(std::string(dds::viewString(c.schedule_json)),
                                                      book, now, c.command_id));
    }
    throw InputError("command " + std::to_string(c.command_id), "kind", "a known command kind");
  }

  // The failure policy: the failed sensors are recorded and announced whatever the policy,
  // then re-planned without (replan), left alone (continue) or the run ends (stop). When every
  // sensor has failed the run ends as failed under any policy: there is nothing left to run.
  Answer onSensorsFailed(const sensornet_Command& c) {
    std::set<int> sensors;
    for (const std::uint32_t id : dds::viewSequence(c.sensor_ids)) {
      sensors.insert(static_cast<int>(id));
    }
    if (std::includes(replanner_.settings().failed.begin(), replanner_.settings().failed.end(),
                      sensors.begin(), sensors.end())) {
      return {std::nullopt, "sensor(s) " + listed(sensors) + " had failed before: nothing new"};
    }
    replanner_.noteFailed(dds::viewSequence(c.sensor_ids), c.command_id);
    const std::string detail(dds::viewString(c.detail));
    spdlog::warn("sensor(s) {} failed ({}); policy {}", listed(sensors), detail,
                 policyName(options_.on_sensor_failure));
    saveState();
    announceFailure(detail);
    if (sensorsInService() == 0) {  // nothing left to emulate, whatever the policy
      abort_detail_ = "every sensor has failed (the last: sensor(s) " + listed(sensors) + ")";
      return {std::nullopt, "no policy applies: " + abort_detail_ + "; the run ends"};
    }
    switch (options_.on_sensor_failure) {
      case FailurePolicy::Continue:
        return {std::nullopt, "policy continue: schedule unchanged"};
      case FailurePolicy::Stop:
        abort_detail_ = "sensor(s) " + listed(sensors) + " failed; --on-sensor-failure stop";
        return {std::nullopt, "policy stop: the run ends (" + abort_detail_ + ")"};
      case FailurePolicy::Replan:
        break;
    }
    try {
      emulator::Replan r = replanner_.replanAsIs(book_, moment(), c.command_id);
      std::string reason = "policy replan: " + r.versionsInBrief();
      return {std::move(r), std::move(reason)};
    } catch (const std::exception& refused) {  // not optimal, or no sensor left to plan for
      const bool none_left = static_cast<int>(replanner_.settings().outOfService().size()) ==
                             run_.scenario.sensorCount();
      return {std::nullopt, "policy replan fell back to continue (" +
                                (none_left ? std::string("no sensor left in service")
                                           : std::string(refused.what())) +
                                "): schedule unchanged"};
    }
  }

  static const char* policyName(FailurePolicy policy) {
    switch (policy) {
      case FailurePolicy::Replan: return "replan";
      case FailurePolicy::Continue: return "continue";
      case FailurePolicy::Stop: return "stop";
    }
    return "?";
  }

  // EPISODE_SENSORS_FAILED: every failed sensor, from now in the running episode (from the
  // start of the next one between episodes; episodes announced after it count them dead from
  // their start).
  void announceFailure(const std::string& detail) {
    const std::vector<std::uint32_t> failed = failedIds();
    const Outstanding* running = runningEpisode(wallNowNs());
    sensornet_EpisodeControl c = control(sensornet_EPISODE_SENSORS_FAILED,
                                         running ? running->episode : firstNotStarted());
    c.failed_at_s =
        running ? std::clamp(running->clock.emulatedNow(), 0.0, run_.scenario.horizon_s) : 0.0;
    c.detail = dds::borrowString(detail);
    dds::borrowSequence(c.failed_sensors, failed);
    mustWrite(control_writer_.write(c), "failure notice");
  }

  // The outstanding episode whose clock has started by `now_ns` (the latest such), if any.
  [[nodiscard]] const Outstanding* runningEpisode(std::int64_t now_ns) const {
    const Outstanding* running = nullptr;
    for (const Outstanding& o : outstanding_) {
      if (o.clock.start_wall_ns <= now_ns) running = &o;
    }
    return running;
  }
  // The announced episode not started yet, if any (the last outstanding one).
  [[nodiscard]] const Outstanding* pendingEpisode(std::int64_t now_ns) const {
    if (outstanding_.empty() || outstanding_.back().clock.start_wall_ns <= now_ns) return nullptr;
    return &outstanding_.back();
  }
  [[nodiscard]] std::uint32_t firstNotStarted() const {
    const Outstanding* pending = pendingEpisode(wallNowNs());
    return pending ? pending->episode : next_episode_;
  }

  // Where a re-plan can take effect. An announced episode that starts within the switch margin
  // keeps the version it was announced with (the sensors may begin it before a new version
  // reaches them): the new one takes effect from the episode after it, which is not announced
  // yet; no episode runs long enough then for a mid-episode switch. Otherwise as before: a
  // switch in the running episode and a version from the next one (announced or not, it starts
  // at least a margin from now).
  [[nodiscard]] emulator::RunMoment moment() const {
    const std::int64_t now_ns = wallNowNs();
    emulator::RunMoment now;
    now.fused = fused_;
    const Outstanding* pending = pendingEpisode(now_ns);
    const Outstanding* running = runningEpisode(now_ns);
    if (pending && pending->clock.start_wall_ns < now_ns + toNs(options_.switch_margin_s)) {
      now.running = false;
      now.episode = pending->episode + 1;
    } else if (running) {
      now.running = true;
      now.episode = running->episode;
      const emulator::EpisodeClock clock = running->clock;
      now.emulated_now = [clock] { return clock.emulatedNow(); };
    } else {
      now.running = false;
      now.episode = pending ? pending->episode : next_episode_;
    }
    return now;
  }

  void publishVersion(const emulator::ScheduleVersion& v) {
    mustWrite(emulator::publishSchedule(schedule_writer_, options_.run.run_id, run_.digest, v),
              "schedule");
  }

  // Writes the journal (--state) as the run stands now; before the DDS write it records.
  void saveState() const {
    if (options_.state_path.empty()) return;
    emulator::CoordinatorJournal journal = journalHeader(options_, run_);
    journal.settings = replanner_.settings();
    journal.versions = book_.versions();
    journal.episodes_reported = reported_;
    journal.announced = announced_;
    journal.answered = answered_;
    journal.shutdown_requested = stopping_;
    journal.abort_detail = abort_detail_;
    emulator::saveJournal(options_.state_path, journal);
  }

  static inline const std::string kEmpty;

  ServeOptions options_;
  emulator::RunScenario run_;
  EmulatedPlant plant_;  // only for its tick grid: effective times fall on ticks
  emulator::Replanner replanner_;
  emulator::ScheduleBook book_;

  dds::Domain domain_;
  dds::Participant participant_;
  dds::Topic<sensornet_Scenario> scenario_topic_;
  dds::Topic<sensornet_Schedule> schedule_topic_;
  dds::Topic<sensornet_EpisodeControl> control_topic_;
  dds::Topic<sensornet_Command> command_topic_;
  dds::Topic<sensornet_CommandReply> reply_topic_;
  dds::Topic<sensornet_SensorStatus> status_topic_;
  dds::Topic<sensornet_Report> report_topic_;
  dds::Topic<sensornet_FusionState> state_topic_;
  dds::Writer<sensornet_Scenario> scenario_writer_;
  dds::Writer<sensornet_Schedule> schedule_writer_;
  dds::Writer<sensornet_EpisodeControl> control_writer_;
  dds::Writer<sensornet_CommandReply> reply_writer_;
  dds::Reader<sensornet_Command> command_reader_;
  dds::Reader<sensornet_SensorStatus> status_reader_;
  dds::Reader<sensornet_Report> report_reader_;
  dds::Reader<sensornet_FusionState> state_reader_;
  dds::WaitSet waitset_;
  dds::ReadCondition command_ready_;
  dds::ReadCondition status_ready_;
  dds::ReadCondition report_ready_;

  std::set<int> ready_sensors_;
  emulator::EpisodeSet reported_;  // as ranges: small over millions of episodes
  std::optional<emulator::AnnouncedEpisode> announced_;
  std::map<std::uint64_t, emulator::AnsweredCommand> answered_;
  std::int64_t fusion_heard_ns_ = 0;  // the fusion center's latest state or report
  emulator::StallWatch stall_watch_;
  std::optional<emulator::FusedCovariance> fused_;
  std::uint32_t current_episode_ = 0;  // whose report is awaited
  std::uint32_t next_episode_ = 0;     // to announce next
  std::deque<Outstanding> outstanding_;  // announced, not reported, in order (at most two)
  std::int64_t last_end_ns_ = 0;         // wall time of the end of the episode announced last
  bool stopping_ = false;
  std::string abort_detail_;  // the run ends as failed (--on-sensor-failure stop)
};

// Plans version 1 (or adopts --schedule), as a fresh journal.
emulator::CoordinatorJournal freshJournal(const ServeOptions& options,
                                          const emulator::RunScenario& run) {
  emulator::ScheduleVersion initial;
  initial.version = 1;
  if (!options.schedule_path.empty()) {
    initial.schedule = loadScheduleFile(options.schedule_path, run.scenario);
    initial.surrogate = "file";
  } else {
    PlanRequest request;
    request.surrogate = options.surrogate;
    if (options.network_aware) request.delivery = deliveryFactors(run.scenario);
    const PlanResult plan = planSchedule(run.scenario, request);
    spdlog::info("initial {}{} schedule: {} after {} iterations in {:.3f} s",
                 describe(options.surrogate), options.network_aware ? " network-aware" : "",
                 plan.status, plan.iterations, plan.solve_seconds);
    initial.schedule = plan.schedule;
    initial.surrogate = std::string(describe(options.surrogate));
  }
  initial.bracket = computeBracket(run.scenario, initial.schedule);
  spdlog::info("bracket of schedule v1: [{:.6g}, {:.6g}]", initial.bracket.info,
               initial.bracket.cov);
  emulator::CoordinatorJournal journal = journalHeader(options, run);
  journal.settings = emulator::initialSettings(run.scenario, options.surrogate);
  journal.versions.push_back(std::move(initial));
  return journal;
}

// The journal of --state, checked against this run (exit 2 when it belongs to another).
emulator::CoordinatorJournal resumedJournal(ServeOptions& options,
                                            const emulator::RunScenario& run) {
  emulator::CoordinatorJournal journal = emulator::loadJournal(options.state_path, run.scenario);
  const auto mismatch = [&](const char* field, const std::string& journal_value,
                            const std::string& ours) {
    throw InputError(options.state_path, field,
                     "the journal's " + journal_value + ", got " + ours +
                         " (resume with the run's own --scenario and --seed)");
  };
  if (journal.scenario_digest != run.digest) {
    mismatch("scenario_digest", journal.scenario_digest,
             run.digest + " from --scenario " + options.scenario_path);
  }
  if (journal.seed != run.seed) {
    mismatch("seed", std::to_string(journal.seed), "--seed " + std::to_string(run.seed));
  }
  if (journal.run_id != options.run.run_id) {
    spdlog::warn("resuming run {} from the journal of run {}", options.run.run_id,
                 journal.run_id);
  }
  // The run's own episode count and time scale, whatever the command line says.
  options.episodes = static_cast<int>(journal.episodes_planned);
  options.time_scale = journal.time_scale;
  spdlog::info("resuming from {}: schedule v{}, {} episodes reported, {} failed sensor(s)",
               options.state_path, journal.versions.back().version,
               journal.episodes_reported.size(), journal.settings.failed.size());
  return journal;
}

int runServe(ServeOptions options) {
  emulator::RunScenario run;
  run.yaml = readTextFile(options.scenario_path, "scenario");  // read once: parsed and sent
  run.scenario = parseScenarioYaml(run.yaml, options.scenario_path);
  run.digest = emulator::digestOf(run.yaml);
  run.seed = options.seed;
  if (!options.arrivals.empty()) {
    run.scenario.arrivals = parseArrivalMode(options.arrivals, "--arrivals", "arrivals");
  }
  (void)options.run.domainConfig();  // bad run or domain id: exit 2 before any planning
  if (options.network_aware && !run.scenario.network) {
    throw InputError(options.scenario_path, "network",
                     "a network: section (--network-aware plans for the rates it delivers)");
  }
  const emulator::CoordinatorJournal journal =
      options.resume ? resumedJournal(options, run) : freshJournal(options, run);
  emulator::installStopSignals();
  Coordinator coordinator(options, std::move(run), journal);
  return coordinator.run();
}

}  // namespace

Subcommand addServeCommand(CLI::App& app) {
  auto options = std::make_shared<ServeOptions>();
  CLI::App* cmd = app.add_subcommand(
      "serve",
      "Coordinate one emulation run over DDS: publish the scenario and the planned schedule, "
      "wait for every sensor and the fusion center, run the episodes on the emulated clock, "
      "re-plan live on command (sensornet replan) and when sensors die, then shut the run "
      "down. Example:\n"
      "  coordinator serve --scenario scenarios/default.yaml --run-id demo --episodes 20\n"
      "After a crash, the same command with --state FILE --resume carries the run on.");
  emulator::addRunOptions(*cmd, options->run);
  options->run.security_role = dds::SecurityRole::Coordinator;
  cmd->add_option("--scenario", options->scenario_path, "scenario file (YAML)")->required();
  const std::map<std::string, PlanSurrogate> surrogates = wordMap<PlanSurrogate>();
  cmd->add_option("--surrogate", options->surrogate,
                  "how to plan the initial schedule: info, cov, uniform or mc (the expected "
                  "realized cost by Monte Carlo; up to a minute)")
      ->transform(CLI::CheckedTransformer(surrogates, CLI::ignore_case))
      ->option_text("info|cov|uniform|mc [cov]");
  cmd->add_option("--schedule", options->schedule_path,
                  "use this schedule file (JSON) instead of planning");
  cmd->add_option("--episodes", options->episodes, "episodes to run")
      ->capture_default_str()
      ->check(integerRange(emulator::kMinEpisodes, emulator::kMaxEpisodes));
  cmd->add_option("--time-scale", options->time_scale,
                  "emulated seconds per wall second (1 = real time, 10 = ten times faster)")
      ->capture_default_str()
      ->check(numberRange(emulator::kMinTimeScale, emulator::kMaxTimeScale));
  cmd->add_option("--seed", options->seed,
                  "run seed: keys the plant truth, the arrivals and the sensor noise")
      ->capture_default_str();
  cmd->add_option("--ready-timeout", options->ready_timeout_s,
                  "seconds to wait for every sensor and the fusion center")
      ->capture_default_str()
      ->check(positiveNumber(emulator::kMaxWallSeconds));
  cmd->add_option("--switch-margin", options->switch_margin_s,
                  "wall seconds between a live re-plan and the time it takes effect")
      ->capture_default_str()
      ->check(positiveNumber(emulator::kMaxWallSeconds));
  cmd->add_option("--episode-gap", options->episode_gap_s,
                  "wall seconds between one episode's end and the next one's start (the next "
                  "episode is announced while the current one runs)")
      ->capture_default_str()
      ->check(positiveNumber(emulator::kMaxWallSeconds));
  const std::map<std::string, FailurePolicy> policies = {{"replan", FailurePolicy::Replan},
                                                          {"continue", FailurePolicy::Continue},
                                                          {"stop", FailurePolicy::Stop}};
  cmd->add_option("--on-sensor-failure", options->on_sensor_failure,
                  "when the launcher reports that sensors died: replan = re-plan the rest of "
                  "the horizon among the survivors (rate zero for the dead from a switch tick "
                  "on, a full-horizon version from the next episode), continue = keep the "
                  "schedule, stop = end the run as failed (exit 1). Either way the dead "
                  "sensors are announced and nobody waits for them")
      ->transform(CLI::CheckedTransformer(policies, CLI::ignore_case))
      ->default_str("replan");
  cmd->add_flag("--network-aware", options->network_aware,
                "plan the initial schedule and every re-plan for the rates the scenario's "
                "network: section delivers (loss thins them, outages of every episode zero "
                "them), with C lambda <= b on the planned rates; needs a network: section");
  cmd->add_option("--arrivals", options->arrivals,
                  "poisson or timetable: how every sensor's instants follow from its rates "
                  "(timetable: deterministic, where the integrated rate is k - 1/2); overrides "
                  "the scenario's arrivals: and is announced with the scenario")
      ->check(CLI::IsMember({"poisson", "timetable"}));
  CLI::Option* state =
      cmd->add_option("--state", options->state_path,
                      "keep a journal of the run in FILE (JSON, replaced atomically after every "
                      "change, before the change goes out): settings, schedule versions, "
                      "episodes reported and announced, commands answered");
  cmd->add_flag("--resume", options->resume,
                "start from the journal in --state instead of planning (after a crash): the "
                "scenario and --seed must be the run's; republishes the scenario and every "
                "version, waits for the report of the episode announced last, then goes on")
      ->needs(state);
  cmd->add_flag("--json", options->json, "print a one-line JSON summary at the end");
  return {cmd, [options] { return runServe(*options); }};
}

}  // namespace sensornet::coordinator
