#include "sensornet/emulator/coordinator_core.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <exception>
#include <utility>

#include <Eigen/Core>

#include "sensornet/core/input_error.hpp"
#include "sensornet/core/network.hpp"
#include "sensornet/emulator/sensor_ids.hpp"

namespace sensornet::emulator {
namespace {

using spdlog::level::err;
using spdlog::level::info;
using spdlog::level::warn;

std::int64_t toNs(double seconds) { return static_cast<std::int64_t>(1e9 * seconds); }

std::string listed(const std::set<int>& sensors) {
  std::string text;
  for (const int id : sensors) text += (text.empty() ? "" : ", ") + std::to_string(id);
  return text;
}

ReplannerOptions replannerOptions(const CoordinatorConfig& config, const Scenario& scenario) {
  ReplannerOptions r;
  r.switch_margin_s = config.switch_margin_s;
  r.time_scale = config.time_scale;
  if (config.network_aware) r.delivery = deliveryFactors(scenario);
  return r;
}

}  // namespace

CoordinatorJournal journalHeader(const CoordinatorConfig& config,
                                 const std::string& scenario_digest, std::uint64_t seed) {
  CoordinatorJournal journal;
  journal.run_id = config.run_id;
  journal.scenario_digest = scenario_digest;
  journal.seed = seed;
  journal.episodes_planned = static_cast<std::uint32_t>(config.episodes);
  journal.time_scale = config.time_scale;
  return journal;
}

CoordinatorCore::CoordinatorCore(CoordinatorConfig config, CoordinatedRun run,
                                 const CoordinatorJournal& journal, WallClock wall_clock)
    : config_(std::move(config)),
      run_(std::move(run)),
      wall_clock_(std::move(wall_clock)),
      plant_(run_.scenario, run_.seed),
      replanner_(run_.scenario, plant_, journal.settings,
                 replannerOptions(config_, run_.scenario)),
      reported_(journal.episodes_reported),
      announced_(journal.announced),
      answered_(journal.answered),
      stopping_(journal.shutdown_requested),
      abort_detail_(journal.abort_detail) {
  for (const ScheduleVersion& v : journal.versions) book_.add(v);
  if (announced_) {  // resumed: the episodes announced and not reported run on without us
    current_episode_ = announced_->episode;
    next_episode_ = current_episode_ + 1;
    const EpisodeClock clock{announced_->start_wall_ns, config_.time_scale};
    // At most two are outstanding: the one before the last may still owe its report (the fusion
    // center may close them out of order; chaos seed 435 ended a run with it open). Its start
    // is not journaled, but it ended at the latest the gap before the last one's start.
    if (current_episode_ > 0 && !reported_.count(current_episode_ - 1)) {
      const std::int64_t ended_by = announced_->start_wall_ns - toNs(config_.episode_gap_s);
      const double duration_s = run_.scenario.horizon_s / config_.time_scale;
      outstanding_.push_back({current_episode_ - 1,
                              EpisodeClock{ended_by - toNs(duration_s), config_.time_scale}});
    }
    if (!reported_.count(current_episode_)) {
      outstanding_.push_back({current_episode_, clock});
      resumed_with_outstanding_ = true;
    }
    last_end_ns_ = clock.wallAt(run_.scenario.horizon_s);
  }
}

CoordinatorActions CoordinatorCore::take() { return std::exchange(actions_, {}); }

// In place: GCC 12 takes a moved-from temporary variant for uninitialized (maybe-uninitialized).
template <class A>
void CoordinatorCore::act(A action) {
  actions_.emplace_back(std::in_place_type<A>, std::move(action));
}

void CoordinatorCore::log(spdlog::level::level_enum level, std::string text) {
  act(LogLine{level, std::move(text)});
}

// The journal as the run stands now; it goes out before the DDS write it records.
void CoordinatorCore::saveState() {
  if (journal_failed_) return;
  CoordinatorJournal journal = journalHeader(config_, run_.digest, run_.seed);
  journal.settings = replanner_.settings();
  journal.versions = book_.versions();
  journal.episodes_reported = reported_;
  journal.announced = announced_;
  journal.answered = answered_;
  journal.shutdown_requested = stopping_;
  journal.abort_detail = abort_detail_;
  act(WriteJournal{std::move(journal)});
}

void CoordinatorCore::onJournalFailed(const std::string& why) {
  if (journal_failed_) return;
  journal_failed_ = true;
  const std::string detail = "the coordinator cannot write its journal (" + why +
                             "), without which a restart could not resume the run";
  log(err, detail);
  if (abort_detail_.empty()) abort_detail_ = detail;
}

CoordinatorActions CoordinatorCore::start(std::int64_t now_ns) {
  saveState();
  act(PublishScenario{});
  for (const ScheduleVersion& v : book_.versions()) act(PublishVersion{v});
  log(info, fmt::format("run {}: scenario {} and schedule v1..v{} published; waiting for {} "
                        "sensors and the fusion center",
                        config_.run_id, run_.digest, book_.latest().version, sensorsInService()));
  phase_ = Phase::AwaitingPeers;
  ready_deadline_ns_ = now_ns + toNs(config_.ready_timeout_s);
  return take();  // an abort already decided (the journal) ends the run at the first tick
}

std::chrono::nanoseconds CoordinatorCore::waitHint() const {
  using std::chrono::milliseconds;
  return phase_ == Phase::Running ? milliseconds(10) : milliseconds(20);
}

// ---- events -------------------------------------------------------------------------------

CoordinatorActions CoordinatorCore::onSensorStatus(const SensorStatusEvent& s, std::int64_t) {
  if (!s.from_its_sensor) {
    ++rejected_;
    if (impostors_.insert(s.sensor_id).second) {
      log(warn, fmt::format("ignored a status for sensor {} from a writer whose identity does not "
                            "name it (and ignore the next ones)",
                            s.sensor_id));
    }
    return take();
  }
  if (s.sensor_id < 0 || s.sensor_id >= run_.scenario.sensorCount()) {
    ++rejected_;
    log(warn, fmt::format("ignored the status of sensor {}: the scenario has sensors 0 to {} "
                          "({} sample(s) ignored so far)",
                          s.sensor_id, run_.scenario.sensorCount() - 1, rejected_));
    return take();
  }
  const bool has_schedule = s.state == SensorState::Ready || s.state == SensorState::Excluded ||
                            s.state == SensorState::Running;
  if (has_schedule && s.schedule_version >= 1) ready_sensors_.insert(s.sensor_id);
  if (s.state == SensorState::Failed) {
    log(warn, fmt::format("sensor {} failed: {}", s.sensor_id, s.detail));
  }
  return take();
}

CoordinatorActions CoordinatorCore::onReport(const ReportEvent& r, std::int64_t now_ns) {
  fusion_heard_ns_ = std::max(fusion_heard_ns_, now_ns);
  if (r.episode >= static_cast<std::uint32_t>(config_.episodes)) {
    ++rejected_;
    log(warn, fmt::format("ignored a report of episode {}: the run has {} episodes", r.episode,
                          config_.episodes));
    return take();
  }
  if (!reported_.insert(r.episode)) return take();  // durability replays a report
  saveState();
  log(info, fmt::format("[{}/{}] episode {}: realized {:.6g}, bracket [{:.6g}, {:.6g}]; mean "
                        "{:.6g} in [{:.6g}, {:.6g}] (95%)",
                        r.episodes_summarized, config_.episodes, r.episode, r.realized_cost,
                        r.bracket_lower, r.bracket_upper, r.realized_mean, r.realized_ci95_low,
                        r.realized_ci95_high));
  return take();
}

CoordinatorActions CoordinatorCore::onFusionState(const FusionStateEvent& s, std::int64_t now_ns) {
  const auto n = static_cast<std::size_t>(run_.scenario.stateDim());
  if (s.state_dim != n || s.values.size() != n * n) {
    ++rejected_;
    log(warn, fmt::format("ignored a fusion state of episode {}: expected a {} x {} covariance, "
                          "got state_dim {} and {} values",
                          s.episode, n, n, s.state_dim, s.values.size()));
    return take();
  }
  const auto dim = static_cast<Eigen::Index>(n);
  const Eigen::MatrixXd P = Eigen::Map<const Eigen::MatrixXd>(s.values.data(), dim, dim);
  fused_ = FusedCovariance{s.episode, s.emulated_time_s, 0.5 * (P + P.transpose())};
  fusion_heard_ns_ = std::max(fusion_heard_ns_, now_ns);
  return take();
}

CoordinatorActions CoordinatorCore::onCommand(const CommandEvent& c, std::int64_t now_ns) {
  if (c.run_id != config_.run_id || phase_ == Phase::Ended) return take();
  // A command that comes again (the launcher resends until it sees a reply) was answered.
  if (const auto it = answered_.find(c.command_id); it != answered_.end()) {
    act(SendReply{c.command_id, it->second});
    return take();
  }
  if (config_.drop_first_command_copy && dropped_copies_.insert(c.command_id).second) {
    log(info, fmt::format("command {} from the {} ('{}'): its first copy left unanswered "
                          "(--drop-first-command-copy)",
                          c.command_id, commandSenderName(c.sender), c.issuer));
    return take();
  }
  AnsweredCommand reply = answer(c, now_ns);
  log(reply.accepted ? info : warn,
      fmt::format("command {} from the {} ('{}'): {} ({})", c.command_id,
                  commandSenderName(c.sender), c.issuer,
                  reply.accepted ? "accepted" : "refused", reply.reason));
  act(SendReply{c.command_id, std::move(reply)});
  stall_watch_.busyUntil(wall_clock_());  // planning a live change is work, not a stall
  return take();
}

// ---- pacing -------------------------------------------------------------------------------

CoordinatorActions CoordinatorCore::tick(std::int64_t now_ns) {
  if (const auto stall = stall_watch_.tick(now_ns)) {
    log(warn, fmt::format("the coordinator was stalled for {:.3g} s", stall->seconds()));
  }
  if (phase_ == Phase::Starting || phase_ == Phase::Ended) return take();
  if (stop_signal_) {
    endRun("the coordinator was stopped by a signal", kCoordinatorExitDone, now_ns);
  } else if (!abort_detail_.empty()) {
    // The fusion center writes the report: a run that ends before it joined waits for it (up to
    // the readiness deadline), so that the report gets the reason.
    const bool heard = fusion_matched_ || phase_ != Phase::AwaitingPeers;
    if (heard || now_ns > ready_deadline_ns_) endRun(abort_detail_, kCoordinatorExitDone, now_ns);
  } else if (phase_ == Phase::AwaitingPeers) {
    tickAwaitingPeers(now_ns);
  } else if (phase_ == Phase::Settling && now_ns >= settled_ns_) {
    phase_ = Phase::Running;
    if (resumed_with_outstanding_) announceAgain(outstanding_.back(), now_ns);
    tickRunning(now_ns);
  } else if (phase_ == Phase::Running) {
    declareDeaths(now_ns);
    tickRunning(now_ns);
  }
  return take();
}

// Every sensor that has not failed, and the fusion center. At a resume the sensors' durable
// statuses (READY, RUNNING, EXCLUDED) count.
bool CoordinatorCore::peersReady() const {
  return fusion_matched_ && readySensorsInService() == sensorsInService();
}

void CoordinatorCore::tickAwaitingPeers(std::int64_t now_ns) {
  if (peersReady()) {
    log(info, fmt::format("all {} sensors and the fusion center are ready",
                          readySensorsInService()));
    phase_ = Phase::Settling;
    settled_ns_ = now_ns + config_.settle.count();
  } else if (now_ns > ready_deadline_ns_) {
    std::vector<int> silent;
    const std::set<int>& failed = replanner_.settings().failed;
    for (int j = 0; j < run_.scenario.sensorCount(); ++j) {
      if (!failed.count(j) && !ready_sensors_.count(j)) silent.push_back(j);
    }
    log(err, fmt::format("not ready after {} s: {} of {} sensors ready{}, fusion center {}",
                         config_.ready_timeout_s, readySensorsInService(), sensorsInService(),
                         silent.empty() ? std::string()
                                        : " (not ready: sensors " + formatSensorIds(silent) + ")",
                         fusion_matched_ ? "present"
                                         : "missing (not started, or not yet holding every "
                                           "sensor's writers: its log names whose)"));
    phase_ = Phase::Ended;
    exit_code_ = kCoordinatorExitFailed;
    act(ExitProgram{kCoordinatorExitFailed, std::nullopt});
  }
}

// Episodes run back to back: while one runs, the next is announced (its start is the end of
// this one plus --episode-gap), so the sensors hold it and begin on time. At most two episodes
// are outstanding (announced, not reported): the next but one is announced only once the
// report of the oldest is in, so a stalled fusion center holds the run back by one episode.
void CoordinatorCore::tickRunning(std::int64_t now_ns) {
  announceAhead(now_ns);
  replanOnCadence(now_ns);
  while (!outstanding_.empty()) {
    current_episode_ = outstanding_.front().episode;
    if (!reported_.count(current_episode_)) break;
    outstanding_.pop_front();
    announceAhead(now_ns);
  }
  if (outstanding_.empty()) {
    endRun("", kCoordinatorExitDone, now_ns);
  } else if (reportOverdue(outstanding_.front(), now_ns)) {
    log(err, fmt::format("no report of episode {} and no sign of the fusion center for {} s",
                         current_episode_, config_.report_timeout_s));
    endRun("no report of episode " + std::to_string(current_episode_), kCoordinatorExitFailed,
           now_ns);
  }
}

void CoordinatorCore::announceAhead(std::int64_t now_ns) {
  while (outstanding_.size() < 2 && !stopping_ &&
         next_episode_ < static_cast<std::uint32_t>(config_.episodes)) {
    announceEpisode(next_episode_, now_ns);
  }
}

// The first episode of a run starts start_lead_s from now (every process is ready but has not
// seen a start yet); a later one episode_gap_s after the previous one's end, or from now if
// that has passed (a report came late).
std::int64_t CoordinatorCore::nextStartNs(std::int64_t now_ns) const {
  if (!announced_) return now_ns + toNs(config_.start_lead_s);
  return std::max(last_end_ns_, now_ns) + toNs(config_.episode_gap_s);
}

void CoordinatorCore::announceEpisode(std::uint32_t episode, std::int64_t now_ns) {
  const EpisodeClock clock{nextStartNs(now_ns), config_.time_scale};
  announced_ = AnnouncedEpisode{episode, clock.start_wall_ns};
  outstanding_.push_back({episode, clock});
  last_end_ns_ = clock.wallAt(run_.scenario.horizon_s);
  next_episode_ = episode + 1;
  saveState();
  EpisodeControl c = control(ControlKind::EpisodeStart, episode, now_ns);
  c.start_wall_ns = clock.start_wall_ns;
  c.schedule_version = book_.inForce(episode, 0.0)->version;
  c.failed_sensors = failedIds();
  act(PublishControl{std::move(c)});
}

// A resumed coordinator announces the episode its journal says it announced last (the last
// outstanding), as it was:
// it may have died between the journal write and the announcement. Whoever had it already drops
// the repeat (RunInputs keeps each episode's first start).
void CoordinatorCore::announceAgain(const Outstanding& outstanding, std::int64_t now_ns) {
  log(info, fmt::format("resuming: episode {} was announced before the restart; announcing it "
                        "again and waiting for its report",
                        outstanding.episode));
  EpisodeControl c = control(ControlKind::EpisodeStart, outstanding.episode, now_ns);
  c.start_wall_ns = outstanding.clock.start_wall_ns;
  c.schedule_version = book_.inForce(outstanding.episode, 0.0)->version;
  c.failed_sensors = failedIds();
  act(PublishControl{std::move(c)});
}

// The fusion center closes the episode once every sensor's count is in, which after a stall can
// take a while; it publishes its state meanwhile. Give up only when it has shown no sign of life
// for report_timeout_s after the episode's end, not counting the time this process was stalled.
bool CoordinatorCore::reportOverdue(const Outstanding& awaited, std::int64_t now_ns) {
  const std::int64_t end_ns = awaited.clock.wallAt(run_.scenario.horizon_s);
  if (awaited_ != awaited.episode) {  // signs of life before its end do not count for it
    awaited_ = awaited.episode;
    fusion_heard_ns_ = end_ns;
  }
  const std::int64_t from = std::max(end_ns, fusion_heard_ns_);
  if (now_ns <= from) return false;
  const double silent_s = 1e-9 * static_cast<double>(now_ns - from) -
                          stall_watch_.stalledBetween(from, now_ns);
  return silent_s > config_.report_timeout_s;
}

// Ends the run; `failure` empty when every episode ran. RUN_SHUTDOWN goes out unless the run
// never started.
void CoordinatorCore::endRun(const std::string& failure, int exit_code, std::int64_t now_ns) {
  EpisodeControl c = control(ControlKind::RunShutdown, current_episode_, now_ns);
  c.episodes_planned = static_cast<std::uint32_t>(episodesDone());
  c.aborted = !failure.empty();
  c.detail = failure;
  act(ShutDownRun{std::move(c)});
  log(info, fmt::format("run {} shut down after {} episodes{}", config_.run_id, episodesDone(),
                        failure.empty() ? "" : ": " + failure));
  std::optional<CoordinatorSummary> summary;
  if (failure.empty()) summary = CoordinatorSummary{config_.run_id, episodesDone(), book_.latest().version};
  phase_ = Phase::Ended;
  exit_code_ = exit_code;
  act(ExitProgram{exit_code, std::move(summary)});
}

EpisodeControl CoordinatorCore::control(ControlKind kind, std::uint32_t episode,
                                        std::int64_t now_ns) const {
  EpisodeControl c;
  c.kind = kind;
  c.episode = episode;
  c.start_wall_ns = now_ns;
  c.time_scale = config_.time_scale;
  c.seed = run_.seed;
  c.schedule_version = book_.latest().version;
  c.episodes_planned = static_cast<std::uint32_t>(config_.episodes);
  return c;
}

std::vector<std::uint32_t> CoordinatorCore::failedIds() const {
  const std::set<int>& failed = replanner_.settings().failed;
  return {failed.begin(), failed.end()};
}

int CoordinatorCore::sensorsInService() const {
  return run_.scenario.sensorCount() - static_cast<int>(replanner_.settings().failed.size());
}

int CoordinatorCore::readySensorsInService() const {
  const std::set<int>& failed = replanner_.settings().failed;
  return static_cast<int>(std::count_if(ready_sensors_.begin(), ready_sensors_.end(),
                                        [&](int id) { return !failed.count(id); }));
}

// ---- commands -----------------------------------------------------------------------------

// Decides, records (journal first) and publishes what command `c` changes; returns the reply.
// Commands by right: the launcher reports sensors failed (it supervises their processes), an
// operator asks for everything else. Empty when `c`'s sender may send it.
std::string CoordinatorCore::withoutRight(const CommandEvent& c) {
  const bool failure_notice = c.kind == CommandKind::SensorsFailed;
  const CommandSender entitled = failure_notice ? CommandSender::Launcher : CommandSender::Operator;
  if (c.sender == entitled) return {};
  return fmt::format("only the {} may {}; command {} came from the {}", commandSenderName(entitled),
                     failure_notice ? "report sensors failed" : "send this command", c.command_id,
                     commandSenderName(c.sender));
}

AnsweredCommand CoordinatorCore::answer(const CommandEvent& c, std::int64_t now_ns) {
  AnsweredCommand reply;
  if (const std::string why = withoutRight(c); !why.empty()) {
    reply = {false, 0, std::string(kNotPermitted) + why};
    answered_[c.command_id] = reply;
    saveState();
    return reply;
  }
  try {
    Answer a = execute(c, now_ns);
    reply.accepted = true;
    reply.reason = std::move(a.reason);
    if (a.replan) {
      reply.schedule_version = a.replan->replyVersion();
    }
    answered_[c.command_id] = reply;
    if (a.replan) {
      adoptAndPublish(*a.replan);
    } else {
      saveState();
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

// Plans (nothing is published or adopted here); throws InputError to refuse. A change of
// settings (surrogate, excluded sensors, budget) holds only once its plans are published.
CoordinatorCore::Answer CoordinatorCore::execute(const CommandEvent& c, std::int64_t now_ns) {
  const auto replanned = [](Replan r) {
    std::string reason = r.summary;
    return Answer{std::move(r), std::move(reason)};
  };
  switch (c.kind) {
    case CommandKind::Status:
      return {std::nullopt, "running episode " + std::to_string(current_episode_) +
                                ", schedule v" + std::to_string(book_.latest().version)};
    case CommandKind::SensorsFailed:
      return onSensorsFailed(c, now_ns);
    case CommandKind::Shutdown:
      stopping_ = true;
      return {std::nullopt, "the run ends after the episodes already announced"};
    case CommandKind::Replan:
      return replanned(replanner_.changeSurrogate(c.surrogate, book_, moment(now_ns),
                                                  c.command_id));
    case CommandKind::ExcludeSensors:
      return replanned(replanner_.exclude(c.sensor_ids, book_, moment(now_ns), c.command_id));
    case CommandKind::IncludeSensors:
      return replanned(replanner_.include(c.sensor_ids, book_, moment(now_ns), c.command_id));
    case CommandKind::SetBudget:
      return replanned(replanner_.setBudget(c.budget, book_, moment(now_ns), c.command_id));
    case CommandKind::ScheduleFile:
      return replanned(
          replanner_.adoptScheduleFile(c.schedule_json, book_, moment(now_ns), c.command_id));
    case CommandKind::Unknown:
      break;
  }
  throw InputError("command " + std::to_string(c.command_id), "kind", "a known command kind");
}

// The failure policy: the failed sensors are recorded and announced whatever the policy, then
// re-planned without (replan), left alone (continue) or the run ends (stop). When every sensor
// has failed the run ends as failed under any policy: there is nothing left to run.
CoordinatorCore::Answer CoordinatorCore::onSensorsFailed(const CommandEvent& c,
                                                         std::int64_t now_ns) {
  const std::set<int> sensors(c.sensor_ids.begin(), c.sensor_ids.end());
  const std::set<int>& failed = replanner_.settings().failed;
  if (std::includes(failed.begin(), failed.end(), sensors.begin(), sensors.end())) {
    return {std::nullopt, "sensor(s) " + listed(sensors) + " had failed before: nothing new"};
  }
  replanner_.noteFailed(c.sensor_ids, c.command_id);
  log(warn, fmt::format("sensor(s) {} failed ({}); policy {}", listed(sensors), c.detail,
                        wordOf(config_.on_sensor_failure)));
  saveState();
  announceFailure(c.detail, now_ns);
  if (sensorsInService() == 0) {  // nothing left to emulate, whatever the policy
    abort_detail_ = "every sensor has failed (the last: sensor(s) " + listed(sensors) + ")";
    return {std::nullopt, "no policy applies: " + abort_detail_ + "; the run ends"};
  }
  switch (config_.on_sensor_failure) {
    case FailurePolicy::Continue:
      return {std::nullopt, "policy continue: schedule unchanged"};
    case FailurePolicy::Stop:
      abort_detail_ = "sensor(s) " + listed(sensors) + " failed; --on-sensor-failure stop";
      return {std::nullopt, "policy stop: the run ends (" + abort_detail_ + ")"};
    case FailurePolicy::Replan:
      break;
  }
  return replanAmongSurvivors(c, now_ns);
}

CoordinatorCore::Answer CoordinatorCore::replanAmongSurvivors(const CommandEvent& c,
                                                              std::int64_t now_ns) {
  try {
    Replan r = replanner_.replanAsIs(book_, moment(now_ns), c.command_id);
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

// The versions of `replan` go into the book and its settings hold; journal first, then publish.
void CoordinatorCore::adoptAndPublish(const Replan& replan) {
  for (const ScheduleVersion& v : replan.versions) book_.add(v);
  replanner_.adopt(replan);
  saveState();
  for (const ScheduleVersion& v : replan.versions) act(PublishVersion{v});
}

// ---- deaths seen in liveliness (DeathWitness::Liveliness) ----------------------------------

void CoordinatorCore::onSensorLiveliness(int sensor_id, bool alive, std::int64_t now_ns) {
  if (config_.sensor_deaths != DeathWitness::Liveliness) return;
  if (sensor_id < 0 || sensor_id >= run_.scenario.sensorCount()) return;
  if (alive) {
    if (lively_lost_ns_.erase(sensor_id) > 0 && phase_ == Phase::Running) {
      log(info, fmt::format("sensor {} is live again: a stall, not a death", sensor_id));
    }
  } else {
    lively_lost_ns_.try_emplace(sensor_id, now_ns);
  }
}

// The sensors without liveliness for the grace, while episodes run, died: one notice for all
// of them, answered by the failure policy as a launcher's would be.
void CoordinatorCore::declareDeaths(std::int64_t now_ns) {
  if (lively_lost_ns_.empty() || phase_ != Phase::Running || stopping_ ||
      !abort_detail_.empty()) {
    return;
  }
  CommandEvent notice;
  notice.kind = CommandKind::SensorsFailed;
  notice.sender = CommandSender::Launcher;
  const std::int64_t grace = toNs(config_.death_grace_s);
  for (auto it = lively_lost_ns_.begin(); it != lively_lost_ns_.end();) {
    if (now_ns - it->second < grace) {
      ++it;
      continue;
    }
    notice.sensor_ids.push_back(static_cast<std::uint32_t>(it->first));
    it = lively_lost_ns_.erase(it);
  }
  if (notice.sensor_ids.empty()) return;
  notice.detail = fmt::format("the SensorStatus writer lost its liveliness and stayed without "
                              "it for {} s (--sensor-deaths liveliness)",
                              config_.death_grace_s);
  Answer a = onSensorsFailed(notice, now_ns);
  log(info, a.reason);
  if (a.replan) adoptAndPublish(*a.replan);
}

// EPISODE_SENSORS_FAILED: every failed sensor, from now in the running episode (from the start
// of the next one between episodes; episodes announced after it count them dead from their
// start).
void CoordinatorCore::announceFailure(const std::string& detail, std::int64_t now_ns) {
  const Outstanding* running = runningEpisode(now_ns);
  EpisodeControl c = control(ControlKind::SensorsFailed,
                             running ? running->episode : firstNotStarted(now_ns), now_ns);
  c.failed_at_s = running ? std::clamp(running->clock.emulatedAt(now_ns), 0.0,
                                       run_.scenario.horizon_s)
                          : 0.0;
  c.detail = detail;
  c.failed_sensors = failedIds();
  act(PublishControl{std::move(c)});
}

// --replan-every DT: at the first tick at or after each k DT of the running episode at which a
// fused covariance of the episode is known, the rest of it is planned again from that
// covariance (Replanner::replanTail). An instant passed while the coordinator could not act (a
// stall, a resume, no fused covariance yet) is served once, late; the instants it skipped are
// not made up for.
void CoordinatorCore::replanOnCadence(std::int64_t now_ns) {
  if (!config_.replan_every_s || stopping_ || !abort_detail_.empty()) return;
  const Outstanding* running = runningEpisode(now_ns);
  if (running == nullptr) return;
  const double every = *config_.replan_every_s;
  const double t = running->clock.emulatedAt(now_ns);
  if (!cadence_ || cadence_->episode != running->episode) cadence_ = Cadence{running->episode, 1};
  const int reached = static_cast<int>(std::floor(t / every));
  if (reached < cadence_->next || reached * every >= run_.scenario.horizon_s) return;
  if (!(fused_ && fused_->episode == running->episode)) {
    if (!cadence_->waiting_logged) {
      log(info, fmt::format("closed loop: no fused covariance of episode {} yet at {:.3f} s; "
                            "re-planning as soon as one comes",
                            running->episode, t));
      cadence_->waiting_logged = true;
    }
    return;
  }
  cadence_->next = reached + 1;
  const std::string at = fmt::format("closed loop at {:.3f} s of episode {}", t, running->episode);
  try {
    const Replan r = replanner_.replanTail(book_, moment(now_ns), 0);
    if (r.versions.empty()) {
      log(info, at + ": no tail, " + r.summary);
      return;
    }
    for (const ScheduleVersion& v : r.versions) book_.add(v);
    saveState();
    for (const ScheduleVersion& v : r.versions) act(PublishVersion{v});
    log(info, at + ": " + r.summary);
    if (!r.caveat.empty()) log(warn, "closed loop: " + r.caveat);
  } catch (const InputError& error) {
    log(warn, at + ": no tail published (" + error.what() + "); the schedule in force stays");
  }
}

// ---- the switch moment --------------------------------------------------------------------

// The outstanding episode whose clock has started by `now_ns` (the latest such), if any.
const CoordinatorCore::Outstanding* CoordinatorCore::runningEpisode(std::int64_t now_ns) const {
  const Outstanding* running = nullptr;
  for (const Outstanding& o : outstanding_) {
    if (o.clock.start_wall_ns <= now_ns) running = &o;
  }
  return running;
}

// The announced episode not started yet, if any (the last outstanding one).
const CoordinatorCore::Outstanding* CoordinatorCore::pendingEpisode(std::int64_t now_ns) const {
  if (outstanding_.empty() || outstanding_.back().clock.start_wall_ns <= now_ns) return nullptr;
  return &outstanding_.back();
}

std::uint32_t CoordinatorCore::firstNotStarted(std::int64_t now_ns) const {
  const Outstanding* pending = pendingEpisode(now_ns);
  return pending ? pending->episode : next_episode_;
}

// Where a re-plan can take effect. An announced episode that starts within the switch margin
// keeps the version it was announced with (the sensors may begin it before a new version
// reaches them): the new one takes effect from the episode after it, which is not announced
// yet; no episode runs long enough then for a mid-episode switch. Otherwise as before: a switch
// in the running episode and a version from the next one (announced or not, it starts at least
// a margin from now).
RunMoment CoordinatorCore::moment(std::int64_t now_ns) const {
  RunMoment now;
  now.fused = fused_;
  const Outstanding* pending = pendingEpisode(now_ns);
  const Outstanding* running = runningEpisode(now_ns);
  if (pending && pending->clock.start_wall_ns < now_ns + toNs(config_.switch_margin_s)) {
    now.running = false;
    now.episode = pending->episode + 1;
  } else if (running) {
    now.running = true;
    now.episode = running->episode;
    // Read before and after planning: planning takes time, and the switch must stay ahead.
    now.emulated_now = [clock = running->clock, wall = wall_clock_] {
      return clock.emulatedAt(wall());
    };
  } else {
    now.running = false;
    now.episode = pending ? pending->episode : next_episode_;
  }
  return now;
}

}  // namespace sensornet::emulator
