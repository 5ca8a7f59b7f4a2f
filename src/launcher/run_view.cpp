#include "sensornet/launcher/run_view.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <iterator>
#include <utility>

#include "sensornet/core/bracket_differs.hpp"

namespace sensornet::launcher {
namespace {

using emulator::SensorState;

// How many announced episodes the view keeps: the one running, the one announced ahead, and a
// couple more for starts replayed out of order.
constexpr std::size_t kAnnouncedKept = 4;

std::string format(const char* pattern, auto... values) {
  char text[512];
  std::snprintf(text, sizeof text, pattern, values...);
  return text;
}

std::string listed(const std::set<std::uint32_t>& ids) {
  std::string text;
  for (const std::uint32_t id : ids) text += (text.empty() ? "" : ", ") + std::to_string(id);
  return text;
}

std::string stateWord(const std::optional<emulator::SensorState>& state) {
  return state ? std::string(wordOf(*state)) : std::string("unknown");
}

double seconds(std::int64_t ns) { return 1e-9 * static_cast<double>(ns); }

// The latency a Report carries (the run's so far); 0 when the fusion center has none: nothing
// measured yet, or every figure across clocks it found apart (the final report says which).
std::string latencyText(const EpisodeReportSeen& r) {
  if (!(r.latency_median_s > 0.0)) return "latency not known";
  return format("latency median %.3g ms, p99 %.3g ms", 1e3 * r.latency_median_s,
                1e3 * r.latency_p99_s);
}

}  // namespace

std::string formatProgress(const EpisodeReportSeen& report,
                           std::optional<std::uint32_t> episodes_planned) {
  const std::string place =
      "[" + std::to_string(report.episode + 1) + "/" +
      (episodes_planned ? std::to_string(*episodes_planned) : std::string("?")) + "] episode " +
      std::to_string(report.episode);
  if (!std::isfinite(report.realized_cost)) {
    // No cost at all: the fusion center was not there to fuse it (it died and was restarted).
    return place +
           ": NOT FUSED (the fusion center restarted during it; left out of the statistics)";
  }
  const RunningSummary& s = report.summary;
  std::string text = place + format(": realized %.4g", report.realized_cost);
  if (s.episodes_complete == 0) {
    text += ", no complete episode yet";
  } else {
    text += format(", mean %.4g over %u complete", s.realized_mean, s.episodes_complete);
    // The interval needs two complete episodes; it is Student's t, clipped at zero below.
    if (s.episodes_complete >= 2) {
      text += format(" (95%%: [%.4g, %.4g])", s.ci95_low, s.ci95_high);
    }
    text += format(", bracket [%.4g, %.4g]", s.bracket_lower_mean, s.bracket_upper_mean);
    // Beside the plan, what it could deliver: a dead sensor's share, the network's losses.
    if (bracketsDiffer(s.bracket_lower_mean, s.bracket_upper_mean, s.delivered_lower_mean,
                       s.delivered_upper_mean)) {
      text += format(" (delivered [%.4g, %.4g])", s.delivered_lower_mean, s.delivered_upper_mean);
    }
  }
  const std::vector<std::uint32_t>& versions = report.schedule_versions;
  if (!versions.empty() && (versions.size() > 1 || versions.front() != 1)) {
    text += ", schedule ";
    for (std::size_t i = 0; i < versions.size(); ++i) {
      text += (i == 0 ? "v" : "\u2192v") + std::to_string(versions[i]);
    }
  }
  if (!report.complete) {
    std::uint64_t sent = 0, received = 0;
    for (const SensorCountsSeen& c : report.counts) {
      sent += c.sent;
      received += c.received;
    }
    text += "; INCOMPLETE";
    if (!report.incomplete_reason.empty()) text += " (" + report.incomplete_reason + ")";
    text += ": " + std::to_string(received) + " of " + std::to_string(sent) +
            " sent measurements received (left out of the statistics)";
  }
  return text;
}

RunView::RunView(RunViewConfig config)
    : config_(std::move(config)), planned_(config_.episodes_planned) {}

void RunView::onScenario(const ScenarioSeen& scenario, std::int64_t now_ns) {
  answered_ = true;
  if (scenario_) return;
  scenario_ = scenario;
  // First of all lines: what was said before it waited for it.
  if (config_.keep_lines)
    lines_.insert(lines_.begin(),
                  format("run %s: scenario %s, %u sensors, %u states, T = %g s, seed %llu",
                         config_.run_id.c_str(), scenario.digest.substr(0, 12).c_str(),
                         scenario.sensor_count, scenario.state_dim, scenario.horizon_s,
                         static_cast<unsigned long long>(scenario.seed)));
  releaseReports();
  // The starts that came before it: news only if their episode is not over by now.
  for (const EpisodeAnnounced& start : std::exchange(starts_before_scenario_, {})) {
    sayStart(start, now_ns);
  }
}

void RunView::onSchedule(const ScheduleSeen& s, std::int64_t /*now_ns*/) {
  answered_ = true;
  if (!versions_.insert(s.version).second) return;
  say(format("schedule v%u (%s) from episode %u at t = %g s, bracket [%.4g, %.4g]", s.version,
             s.surrogate.c_str(), s.effective_episode, s.effective_time_s, s.bracket_lower,
             s.bracket_upper));
  if (!newest_schedule_ || s.version > newest_schedule_->version) newest_schedule_ = s;
}

void RunView::onEpisodeStart(const EpisodeAnnounced& start, std::int64_t now_ns) {
  answered_ = true;
  if (coordinator_gone_ && !run_end_ && !end_said_) {
    // A restarted coordinator (the launcher restarts a killed one): the run goes on.
    coordinator_gone_ = false;
    end_ns_.reset();
    say("the run's coordinator is back");
  }
  if (announced_.contains(start.episode) || reportedAlready(start.episode)) return;
  if (!announced_.empty() && start.episode < announced_.begin()->first) return;  // replayed
  announced_[start.episode] = start;
  while (announced_.size() > kAnnouncedKept) announced_.erase(announced_.begin());
  if (!planned_) planned_ = start.episodes_planned;
  releaseReports();
  if (!scenario_) {
    starts_before_scenario_.push_back(start);
    return;
  }
  sayStart(start, now_ns);
}

// A replayed start of an episode that is over by now is history, not news.
void RunView::sayStart(const EpisodeAnnounced& start, std::int64_t now_ns) {
  if (reportedAlready(start.episode) || now_ns > start.clock.wallAt(scenario_->horizon_s)) return;
  say(format("%s episode %u started (schedule v%u, time scale %g)", place(start.episode).c_str(),
             start.episode, start.schedule_version, start.clock.time_scale));
}

void RunView::onEpisodeStop(std::uint32_t episode, std::int64_t /*now_ns*/) {
  answered_ = true;
  say(format("episode %u stopped", episode));
}

void RunView::onSensorsFailed(const emulator::SensorFailure& failure, std::int64_t /*now_ns*/) {
  answered_ = true;
  std::set<std::uint32_t> fresh;
  for (const int sensor : failure.sensors) {
    const auto id = static_cast<std::uint32_t>(sensor);
    if (failed_.insert(id).second) fresh.insert(id);
    sensors_[id].failed = true;
  }
  if (fresh.empty()) return;
  say(format("%s %s failed (episode %u, t = %g s)%s%s", fresh.size() == 1 ? "sensor" : "sensors",
             listed(fresh).c_str(), failure.episode, failure.at_s,
             failure.detail.empty() ? "" : ": ", failure.detail.c_str()));
}

void RunView::onRunEnd(const emulator::RunEnd& end, std::int64_t now_ns) {
  answered_ = true;
  if (run_end_) return;
  run_end_ = end;
  if (!planned_) planned_ = end.episodes_run;
  markEnded(now_ns);
}

void RunView::onSensorStatus(const SensorStatusSeen& s, std::int64_t now_ns) {
  answered_ = true;
  SensorView& view = sensors_[s.sensor_id];
  if (s.wall_time_ns < view.status_wall_ns) return;  // an older sample of another writer
  // A sensor that stopped or failed is expected to leave: its process going is no news then.
  const bool said_last = s.state == SensorState::Stopped || s.state == SensorState::Failed;
  const bool changed = !view.state || s.state != *view.state ||
                       s.schedule_version != view.schedule_version ||
                       (s.alive != view.alive && !said_last);
  view.state = s.state;
  view.episode = s.episode;
  view.schedule_version = s.schedule_version;
  view.rate_hz = s.rate_hz;
  view.sent_in_episode = s.sent_in_episode;
  view.sent_total = s.sent_total;
  view.write_timeouts = s.write_timeouts;
  view.process_id = s.process_id;
  view.status_wall_ns = s.wall_time_ns;
  view.detail = s.detail;
  view.alive = s.alive;
  if (!changed) return;
  saySensor(s.sensor_id,
            format("%s under schedule v%u%s%s", stateWord(view.state).c_str(), s.schedule_version,
                   s.alive ? "" : " (its process is gone)",
                   view.detail.empty() ? "" : (": " + view.detail).c_str()),
            now_ns);
}

void RunView::onSensorGone(std::uint32_t sensor, std::int64_t now_ns) {
  auto found = sensors_.find(sensor);
  if (found == sensors_.end() || !found->second.alive) return;
  found->second.alive = false;
  const auto& state = found->second.state;
  if (state == SensorState::Stopped || state == SensorState::Failed) return;
  saySensor(sensor, "its process is gone (" + stateWord(found->second.state) + " before)", now_ns);
}

void RunView::onReport(const EpisodeReportSeen& report, std::int64_t /*now_ns*/) {
  answered_ = true;
  if (reportedAlready(report.episode) || held_reports_.contains(report.episode)) return;
  for (const SensorCountsSeen& c : report.counts) {
    SensorView& view = sensors_[c.sensor_id];
    view.sent += c.sent;
    view.received += c.received;
    view.lost += c.lost;
  }
  held_reports_[report.episode] = report;
  releaseReports();
}

void RunView::onCoordinatorGone(std::int64_t now_ns) {
  if (ended()) return;
  coordinator_gone_ = true;
  say("the run's coordinator left without shutting the run down");
  markEnded(now_ns);
}

EpisodeProgress RunView::progressAt(std::int64_t now_ns) const {
  EpisodeProgress at;
  at.horizon_s = scenario_ ? scenario_->horizon_s : 0.0;
  // Without its coordinator the episode's clock still runs (the sensors go on publishing).
  if (run_end_) {
    at.phase = EpisodePhase::Ended;
    return at;
  }
  if (announced_.empty()) return at;
  // The next episode is announced while the current one runs: the one that runs is the latest
  // whose start has come.
  auto current = announced_.end();
  for (auto it = announced_.begin(); it != announced_.end(); ++it) {
    if (it->second.clock.start_wall_ns <= now_ns) current = it;
  }
  if (current == announced_.end()) {
    if (coordinator_gone_) return at;
    const EpisodeAnnounced& first = announced_.begin()->second;
    at.phase = EpisodePhase::StartsSoon;
    at.episode = first.episode;
    at.schedule_version = first.schedule_version;
    at.starts_in_s = seconds(first.clock.start_wall_ns - now_ns);
    return at;
  }
  const EpisodeAnnounced& e = current->second;
  at.episode = e.episode;
  at.schedule_version = e.schedule_version;
  at.t_s = std::max(0.0, e.clock.emulatedAt(now_ns));
  at.phase = EpisodePhase::Running;
  if (scenario_ && at.t_s > at.horizon_s) {
    at.phase = EpisodePhase::Closing;
    at.t_s = at.horizon_s;
    if (const auto next = std::next(current); next != announced_.end()) {
      at.starts_in_s = seconds(next->second.clock.start_wall_ns - now_ns);
    }
  }
  return at;
}

RunPosition RunView::positionAt(std::int64_t now_ns) const {
  const EpisodeProgress at = progressAt(now_ns);
  RunPosition position;
  if (at.phase == EpisodePhase::NotStarted || at.phase == EpisodePhase::Ended) return position;
  position.episode = at.episode;
  if (at.phase == EpisodePhase::Running) position.emulated_time_s = at.t_s;
  return position;
}

std::size_t RunView::sensorsReady() const {
  return static_cast<std::size_t>(std::count_if(
      sensors_.begin(), sensors_.end(),
      [](const auto& s) { return s.second.state.has_value() && s.second.schedule_version >= 1; }));
}

bool RunView::gone(std::uint32_t sensor) const {
  const auto found = sensors_.find(sensor);
  return found != sensors_.end() && found->second.state.has_value() && !found->second.alive &&
         found->second.state != emulator::SensorState::Stopped;
}

bool RunView::heardFrom(std::uint32_t sensor) const {
  const auto found = sensors_.find(sensor);
  return found != sensors_.end() && found->second.state.has_value();
}

bool RunView::allSensorsAccounted() const {
  if (!scenario_) return false;
  for (std::uint32_t id = 0; id < scenario_->sensor_count; ++id) {
    const auto found = sensors_.find(id);
    const bool answered = found != sensors_.end() && found->second.state.has_value();
    if (!answered && !failed_.contains(id)) return false;
  }
  return true;
}

bool RunView::finished(std::int64_t now_ns) const {
  if (!end_ns_) return false;
  if (now_ns - *end_ns_ >= config_.end_grace_ns) return true;
  const bool all_reported =
      run_end_ && reported_count_ + held_reports_.size() >= run_end_->episodes_run;
  const bool all_final = std::all_of(sensors_.begin(), sensors_.end(), [](const auto& s) {
    return !s.second.state.has_value() || s.second.final();
  });
  return (all_reported || coordinator_gone_) && all_final;
}

std::vector<std::string> RunView::takeLines(std::int64_t now_ns) {
  const bool done = finished(now_ns);
  // After the run's end the sensors' last words wait for each other: one line says them all.
  const bool batch_due = !ended() && sensor_lines_since_ns_ &&
                         now_ns - *sensor_lines_since_ns_ >= config_.sensor_batch_ns;
  if (sensor_lines_since_ns_ && (done || batch_due)) {
    flushSensorLines();
  }
  if (done && !end_said_) {
    end_said_ = true;
    releaseReports(/*even_unplaced=*/true);
    if (run_end_) {
      say(run_end_->aborted ? format("run aborted after %u episode(s): %s", run_end_->episodes_run,
                                     run_end_->detail.c_str())
                            : format("run ended: %u episode(s), %zu reported",
                                     run_end_->episodes_run, reported_count_));
    }
  }
  if (!scenario_ && !done) return {};  // the scenario's line comes first
  return std::exchange(lines_, {});
}

void RunView::say(std::string line) {
  if (config_.keep_lines) lines_.push_back(std::move(line));
}

std::vector<EpisodeReportSeen> RunView::takeReports() { return std::exchange(released_, {}); }

void RunView::saySensor(std::uint32_t sensor, const std::string& change, std::int64_t now_ns) {
  // A sensor says one thing at a time: a newer change replaces one not yet printed.
  for (auto it = sensor_lines_.begin(); it != sensor_lines_.end();) {
    it->second.erase(sensor);
    it = it->second.empty() ? sensor_lines_.erase(it) : std::next(it);
  }
  sensor_lines_[change].insert(sensor);
  if (!sensor_lines_since_ns_) sensor_lines_since_ns_ = now_ns;
}

void RunView::flushSensorLines() {
  for (const auto& [change, ids] : sensor_lines_) {
    say((ids.size() == 1 ? "sensor " : "sensors ") + listed(ids) + ": " + change);
  }
  sensor_lines_.clear();
  sensor_lines_since_ns_.reset();
}

// Reports wait for the scenario's line and the planned count ("[3/20]"), then go in order.
void RunView::releaseReports(bool even_unplaced) {
  // The launcher knows N from the start and prints no scenario line.
  const bool placed = planned_ && (scenario_ || config_.episodes_planned);
  if (!even_unplaced && !placed) return;
  for (auto& [episode, report] : held_reports_) {
    noteReported(episode);
    if (!last_report_ || episode >= last_report_->episode) last_report_ = report;
    sayReport(report);
    if (config_.keep_reports) released_.push_back(report);
  }
  held_reports_.clear();
}

void RunView::sayReport(const EpisodeReportSeen& r) {
  say(formatProgress(r, planned_) + "; " + latencyText(r));
}

void RunView::markEnded(std::int64_t now_ns) {
  if (!end_ns_) end_ns_ = now_ns;
}

bool RunView::reportedAlready(std::uint32_t episode) const {
  return episode < reported_below_ || reported_above_.contains(episode);
}

void RunView::noteReported(std::uint32_t episode) {
  if (reportedAlready(episode)) return;
  ++reported_count_;
  reported_above_.insert(episode);
  // Episodes are reported (nearly) in order: keep the set small over millions of them.
  while (!reported_above_.empty() && *reported_above_.begin() == reported_below_) {
    reported_above_.erase(reported_above_.begin());
    ++reported_below_;
  }
}

std::string RunView::place(std::uint32_t episode) const {
  return "[" + std::to_string(episode + 1) + "/" +
         (planned_ ? std::to_string(*planned_) : std::string("?")) + "]";
}

std::string RunView::progressLine(std::int64_t now_ns) const {
  const EpisodeProgress at = progressAt(now_ns);
  switch (at.phase) {
    case EpisodePhase::Ended:
      return "the run has ended";
    case EpisodePhase::NotStarted:
      return "waiting for the first episode";
    case EpisodePhase::StartsSoon:
      return format("%s episode %u starts in %.1f s", place(*at.episode).c_str(), *at.episode,
                    at.starts_in_s);
    case EpisodePhase::Running:
    case EpisodePhase::Closing:
      break;
  }
  constexpr int kWidth = 30;
  const int filled =
      at.horizon_s > 0.0
          ? std::clamp(static_cast<int>(std::lround(kWidth * at.t_s / at.horizon_s)), 0, kWidth)
          : 0;
  std::string line = format("%s episode %u  [%s%s]  t = %.3g / %g s", place(*at.episode).c_str(),
                            *at.episode, std::string(static_cast<std::size_t>(filled), '=').c_str(),
                            std::string(static_cast<std::size_t>(kWidth - filled), ' ').c_str(),
                            at.t_s, at.horizon_s);
  if (at.phase == EpisodePhase::Closing) {
    line += at.starts_in_s > 0.0
                ? format(" (over; episode %u starts in %.1f s)", *at.episode + 1, at.starts_in_s)
                : std::string(" (over; its report is awaited)");
  }
  return line;
}

std::string RunView::screen(std::int64_t now_ns) const {
  std::string out =
      format("sensornet watch: run %s (Ctrl-C leaves; the run goes on)\n", config_.run_id.c_str());
  out += progressLine(now_ns) + "\n";
  if (newest_schedule_) {
    const ScheduleSeen& s = *newest_schedule_;
    const EpisodeProgress at = progressAt(now_ns);
    if (at.episode)
      out += format("schedule v%u in force at the episode's start; ", at.schedule_version);
    out += format("newest v%u (%s) from episode %u at t = %g s, bracket [%.4g, %.4g]\n", s.version,
                  s.surrogate.c_str(), s.effective_episode, s.effective_time_s, s.bracket_lower,
                  s.bracket_upper);
  }
  if (last_report_) {
    const RunningSummary& s = last_report_->summary;
    if (s.episodes_complete == 0) {
      out += "no complete episode yet\n";
    } else {
      out += format("running mean %.4g", s.realized_mean);
      if (s.episodes_complete >= 2) out += format(" (95%%: [%.4g, %.4g])", s.ci95_low, s.ci95_high);
      out += format(" over %u complete episode(s); bracket [%.4g, %.4g]: %s\n", s.episodes_complete,
                    s.bracket_lower_mean, s.bracket_upper_mean,
                    s.episodes_complete < 2 ? "not judged yet"
                    : s.meets_bracket       ? "meets it"
                                            : "OUTSIDE");
    }
    const EpisodeReportSeen& r = *last_report_;
    out += format("last reported: episode %u, realized %.4g", r.episode, r.realized_cost);
    if (!r.complete) {
      out += " (INCOMPLETE" + (r.incomplete_reason.empty() ? "" : ": " + r.incomplete_reason) + ")";
    }
    out += "; " + latencyText(r) + "\n";
  } else {
    out += "no episode reported yet\n";
  }
  out += format("\n%6s  %-9s %8s %10s %10s   %10s %10s %8s\n", "sensor", "state", "schedule",
                "rate (Hz)", "sent now", "sent", "received", "lost");
  for (const auto& [id, v] : sensors_) {
    if (!v.state && !v.failed) continue;  // counts of a report only
    out +=
        format("%6u  %-9s %8s %10.4g %10llu   %10llu %10llu %8llu%s\n", id,
               (v.failed && v.state != emulator::SensorState::Failed ? std::string("failed")
                                                                     : stateWord(v.state))
                   .c_str(),
               ("v" + std::to_string(v.schedule_version)).c_str(), v.rate_hz,
               static_cast<unsigned long long>(v.sent_total),
               static_cast<unsigned long long>(v.sent), static_cast<unsigned long long>(v.received),
               static_cast<unsigned long long>(v.lost), v.alive ? "" : "  (gone)");
  }
  out += format(
      "%6s  (sent now: as the sensor says, all episodes; sent/received/lost: over "
      "the reported episodes)\n",
      "");
  return out;
}

}  // namespace sensornet::launcher
