#include "watch_command.hpp"

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "progress_watcher.hpp"
#include "run_files.hpp"
#include "sensornet/dds/reader.hpp"
#include "sensornet/dds/topics.hpp"
#include "sensornet/dds/waitset.hpp"
#include "sensornet/dds/wire.hpp"
#include "sensornet/emulator/run_inputs.hpp"
#include "sensornet/emulator/messages.hpp"
#include "sensornet/emulator/run_options.hpp"

namespace sensornet::launcher {
namespace {

using Clock = std::chrono::steady_clock;
constexpr std::chrono::milliseconds kRefresh{250};
// After RUN_SHUTDOWN, how long to wait for the reports of the last episodes (another writer's
// samples may arrive after the coordinator's shutdown).
constexpr std::chrono::milliseconds kLastReportsWait{2000};

struct WatchOptions {
  emulator::RunOptions run;
  double wait_s = 30.0;
  bool plain = false;
};

std::string format(const char* pattern, auto... values) {
  char text[512];
  std::snprintf(text, sizeof text, pattern, values...);
  return text;
}

std::string listed(const std::vector<std::uint32_t>& ids) {
  std::string text;
  for (const std::uint32_t id : ids) text += (text.empty() ? "" : ", ") + std::to_string(id);
  return text;
}

struct SensorView {
  std::string state = "unknown";
  std::uint32_t version = 0;
  double rate_hz = 0.0;
  std::uint64_t sent_live = 0;  // SensorStatus.sent_total: every episode so far
  std::int64_t status_wall_ns = 0;
  bool alive = true;
  std::string detail;
  // Over the reported episodes.
  std::uint64_t sent = 0, received = 0, lost = 0;
};

struct ScheduleView {
  std::uint32_t version = 0;
  std::string surrogate;
  std::uint32_t effective_episode = 0;
  double effective_time_s = 0.0;
  double bracket_lower = 0.0, bracket_upper = 0.0;
};

struct LastReport {
  std::uint32_t episode = 0;
  double realized = 0.0;
  bool complete = false;
  double latency_median_s = 0.0, latency_p99_s = 0.0;
  sensornet_RunSummary summary{};
};

// What the run has published so far, and the lines that say what changed.
class RunView {
 public:
  explicit RunView(std::string run_id) : run_id_(std::move(run_id)) {}

  void apply(const sensornet_Scenario& s) {
    if (dds::viewString(s.run_id) != run_id_ || scenario_seen_) return;
    scenario_seen_ = true;
    horizon_s_ = s.horizon_s;
    const std::string digest(dds::viewString(s.digest));
    say(format("run %s: scenario %s, %u sensors, %u states, T = %g s, seed %llu",
               run_id_.c_str(), digest.substr(0, 12).c_str(), s.sensor_count, s.state_dim,
               s.horizon_s, static_cast<unsigned long long>(s.seed)));
  }

  void apply(const sensornet_Schedule& s) {
    if (dds::viewString(s.run_id) != run_id_ || !versions_.insert(s.version).second) return;
    ScheduleView v{s.version,          std::string(dds::viewString(s.surrogate)),
                   s.effective_episode, s.effective_time_s,
                   s.bracket_lower,     s.bracket_upper};
    say(format("schedule v%u (%s) from episode %u at t = %g s, bracket [%.4g, %.4g]", v.version,
               v.surrogate.c_str(), v.effective_episode, v.effective_time_s, v.bracket_lower,
               v.bracket_upper));
    if (!newest_ || v.version > newest_->version) newest_ = v;
  }

  void apply(const sensornet_EpisodeControl& c) {
    if (dds::viewString(c.run_id) != run_id_) return;
    switch (c.command) {
      case sensornet_EPISODE_START:
        if (episode_ && c.episode <= *episode_) return;
        episode_ = c.episode;
        clock_ = {c.start_wall_time_ns, c.time_scale};
        episodes_planned_ = c.episodes_planned;
        version_in_force_ = c.schedule_version;
        say(format("episode %u of %u started (schedule v%u, time scale %g)", c.episode,
                   c.episodes_planned, c.schedule_version, c.time_scale));
        break;
      case sensornet_EPISODE_STOP:
        say(format("episode %u stopped", c.episode));
        break;
      case sensornet_EPISODE_SENSORS_FAILED: {
        const auto span = dds::viewSequence(c.failed_sensors);
        const std::vector<std::uint32_t> failed(span.begin(), span.end());
        if (failed == failed_) return;
        failed_ = failed;
        say(format("sensor(s) %s failed (episode %u, t = %g s)%s%s", listed(failed).c_str(),
                   c.episode, c.failed_at_s, c.detail[0] != '\0' ? ": " : "",
                   std::string(dds::viewString(c.detail)).c_str()));
        break;
      }
      case sensornet_RUN_SHUTDOWN:
        if (ended_) return;
        ended_ = true;
        aborted_ = c.aborted;
        episodes_run_ = c.episodes_planned;
        end_detail_ = std::string(dds::viewString(c.detail));
        break;
    }
  }

  void apply(const sensornet_SensorStatus& s, bool alive) {
    if (dds::viewString(s.run_id) != run_id_) return;
    SensorView& view = sensors_[s.sensor_id];
    if (s.wall_time_ns < view.status_wall_ns) return;  // an older sample of another writer
    const std::string state = emulator::sensorStateName(s.state);
    const bool changed = state != view.state || s.schedule_version != view.version;
    view.state = state;
    view.version = s.schedule_version;
    view.rate_hz = s.current_rate_hz;
    view.sent_live = s.sent_total;
    view.status_wall_ns = s.wall_time_ns;
    view.detail = std::string(dds::viewString(s.detail));
    if (changed || alive != view.alive) {
      view.alive = alive;
      saySensor(s.sensor_id, format("%s under schedule v%u%s%s", state.c_str(),
                                    s.schedule_version, alive ? "" : " (its process is gone)",
                                    view.detail.empty() ? "" : (": " + view.detail).c_str()));
    }
  }

  void sensorGone(std::uint32_t sensor) {
    auto found = sensors_.find(sensor);
    if (found == sensors_.end() || !found->second.alive) return;
    found->second.alive = false;
    saySensor(sensor, "its process is gone (" + found->second.state + " before)");
  }

  void apply(const sensornet_Report& r) {
    if (dds::viewString(r.run_id) != run_id_ || !reported_.insert(r.episode).second) return;
    for (const sensornet_SensorCounts& c : dds::viewSequence(r.counts)) {
      SensorView& view = sensors_[c.sensor_id];
      view.sent += c.sent;
      view.received += c.received;
      view.lost += c.lost;
    }
    if (!last_ || r.episode >= last_->episode) {
      last_ = LastReport{r.episode, r.realized_cost, r.complete, r.latency_median_s,
                         r.latency_p99_s, r.summary};
    }
    say(formatProgress(r, static_cast<int>(episodes_planned_)) +
        format("; latency median %.3g ms, p99 %.3g ms", 1e3 * r.latency_median_s,
               1e3 * r.latency_p99_s));
  }

  // The coordinator's EpisodeControl instance lost every writer.
  void coordinatorGone() {
    if (ended_ || coordinator_gone_) return;
    coordinator_gone_ = true;
    say("the run's coordinator left without shutting the run down");
  }

  [[nodiscard]] bool started() const { return scenario_seen_; }
  [[nodiscard]] bool ended() const { return ended_ || coordinator_gone_; }
  [[nodiscard]] bool endedCleanly() const { return ended_; }
  // Every episode the shutdown says ran has its report.
  [[nodiscard]] bool allReported() const { return reported_.size() >= episodes_run_; }

  void sayEnd() {
    if (coordinator_gone_) return;
    say(aborted_ ? format("run aborted after %u episode(s): %s", episodes_run_, end_detail_.c_str())
                 : format("run ended: %u episode(s), %zu reported", episodes_run_,
                          reported_.size()));
  }

  [[nodiscard]] std::vector<std::string> takeChanges() {
    flushSensorChanges();
    return std::exchange(changes_, {});
  }

  [[nodiscard]] std::string screen(std::int64_t wall_now_ns) const {
    std::string out = format("sensornet watch: run %s (Ctrl-C leaves; the run goes on)\n",
                             run_id_.c_str());
    out += progressLine(wall_now_ns) + "\n";
    if (newest_) {
      out += format("schedule v%u in force at the episode's start; newest v%u (%s) from "
                    "episode %u at t = %g s, bracket [%.4g, %.4g]\n",
                    version_in_force_, newest_->version, newest_->surrogate.c_str(),
                    newest_->effective_episode, newest_->effective_time_s,
                    newest_->bracket_lower, newest_->bracket_upper);
    }
    if (last_) {
      const sensornet_RunSummary& s = last_->summary;
      out += format("running mean %.4g", s.realized_mean);
      if (s.episodes_complete >= 2) {
        out += format(" (95%%: [%.4g, %.4g])", s.realized_ci95_low, s.realized_ci95_high);
      }
      out += format(" over %u complete episode(s); bracket [%.4g, %.4g]: %s\n",
                    s.episodes_complete, s.bracket_lower_mean, s.bracket_upper_mean,
                    s.episodes_complete < 2 ? "not judged yet"
                    : s.meets_bracket       ? "meets it"
                                            : "OUTSIDE");
      out += format("last reported: episode %u, realized %.4g%s; latency median %.3g ms, "
                    "p99 %.3g ms\n",
                    last_->episode, last_->realized, last_->complete ? "" : " (INCOMPLETE)",
                    1e3 * last_->latency_median_s, 1e3 * last_->latency_p99_s);
    } else {
      out += "no episode reported yet\n";
    }
    out += format("\n%6s  %-9s %8s %10s %10s   %10s %10s %8s\n", "sensor", "state", "schedule",
                  "rate (Hz)", "sent now", "sent", "received", "lost");
    for (const auto& [id, v] : sensors_) {
      out += format("%6u  %-9s %8s %10.4g %10llu   %10llu %10llu %8llu%s\n", id,
                    v.state.c_str(), ("v" + std::to_string(v.version)).c_str(), v.rate_hz,
                    static_cast<unsigned long long>(v.sent_live),
                    static_cast<unsigned long long>(v.sent),
                    static_cast<unsigned long long>(v.received),
                    static_cast<unsigned long long>(v.lost), v.alive ? "" : "  (gone)");
    }
    out += format("%6s  (sent now: as the sensor says, all episodes; sent/received/lost: over "
                  "the reported episodes)\n",
                  "");
    return out;
  }

 private:
  void say(std::string line) {
    flushSensorChanges();
    changes_.push_back(std::move(line));
  }
  // Sensors that change alike in one poll share a line: "sensors 0, 1, 3: running under ...".
  void saySensor(std::uint32_t sensor, const std::string& change) {
    sensor_changes_[change].push_back(sensor);
  }
  void flushSensorChanges() {
    for (auto& [change, ids] : sensor_changes_) {
      std::sort(ids.begin(), ids.end());
      changes_.push_back((ids.size() == 1 ? "sensor " : "sensors ") + listed(ids) + ": " +
                         change);
    }
    sensor_changes_.clear();
  }

  [[nodiscard]] std::string progressLine(std::int64_t wall_now_ns) const {
    if (ended_) return "the run has ended";
    if (!episode_) return "waiting for the first episode";
    const double t = clock_.emulatedAt(wall_now_ns);
    const double shown = std::clamp(t, 0.0, horizon_s_);
    constexpr int kWidth = 30;
    const int filled =
        horizon_s_ > 0.0 ? static_cast<int>(std::lround(kWidth * shown / horizon_s_)) : 0;
    return format("episode %u of %u  [%s%s]  t = %.3g / %g s%s", *episode_, episodes_planned_,
                  std::string(static_cast<std::size_t>(filled), '=').c_str(),
                  std::string(static_cast<std::size_t>(kWidth - filled), ' ').c_str(), shown,
                  horizon_s_, t < 0.0 ? " (starts soon)" : "");
  }

  std::string run_id_;
  bool scenario_seen_ = false;
  double horizon_s_ = 0.0;
  std::set<std::uint32_t> versions_;
  std::optional<ScheduleView> newest_;
  std::optional<std::uint32_t> episode_;
  emulator::EpisodeClock clock_;
  std::uint32_t episodes_planned_ = 0;
  std::uint32_t version_in_force_ = 0;
  std::vector<std::uint32_t> failed_;
  bool ended_ = false;
  bool aborted_ = false;
  bool coordinator_gone_ = false;
  std::uint32_t episodes_run_ = 0;
  std::string end_detail_;
  std::map<std::uint32_t, SensorView> sensors_;
  std::set<std::uint32_t> reported_;
  std::optional<LastReport> last_;
  std::vector<std::string> changes_;
  std::map<std::string, std::vector<std::uint32_t>> sensor_changes_;  // not yet in changes_
};

// The run's topics, read (never written) by one participant of its own.
class RunTopics {
 public:
  explicit RunTopics(const dds::DomainConfig& config)
      : domain_(config),
        participant_(domain_),
        scenario_topic_(participant_),
        schedule_topic_(participant_),
        control_topic_(participant_),
        status_topic_(participant_),
        report_topic_(participant_),
        scenarios_(participant_, scenario_topic_),
        schedules_(participant_, schedule_topic_),
        controls_(participant_, control_topic_),
        statuses_(participant_, status_topic_),
        reports_(participant_, report_topic_),
        has_scenario_(scenarios_),
        has_schedule_(schedules_),
        has_control_(controls_),
        has_status_(statuses_),
        has_report_(reports_),
        waitset_(participant_) {
    dds_attach_t token = 0;
    for (const dds::ReadCondition* c :
         {&has_scenario_, &has_schedule_, &has_control_, &has_status_, &has_report_}) {
      waitset_.attach(*c, ++token);
    }
  }

  // Waits up to `wait` for data, then hands everything new to `view`.
  void pollInto(RunView& view, std::chrono::milliseconds wait) {
    (void)waitset_.wait(wait);
    for (const auto& s : scenarios_.take().samples) view.apply(*s.sample);
    for (const auto& s : schedules_.take().samples) view.apply(*s.sample);
    const auto controls = controls_.take();
    for (const auto& s : controls.samples) view.apply(*s.sample);
    for (const auto& change : controls.changes) {
      if (change.info.instance_state == dds::InstanceState::NoWriters) view.coordinatorGone();
    }
    const auto statuses = statuses_.take();
    for (const auto& s : statuses.samples) {
      view.apply(*s.sample, s.info.instance_state == dds::InstanceState::Alive);
    }
    for (const auto& change : statuses.changes) {
      if (change.info.instance_state != dds::InstanceState::Alive) {
        view.sensorGone(change.key->sensor_id);
      }
    }
    for (const auto& s : reports_.take().samples) view.apply(*s.sample);
  }

 private:
  dds::Domain domain_;
  dds::Participant participant_;
  dds::Topic<sensornet_Scenario> scenario_topic_;
  dds::Topic<sensornet_Schedule> schedule_topic_;
  dds::Topic<sensornet_EpisodeControl> control_topic_;
  dds::Topic<sensornet_SensorStatus> status_topic_;
  dds::Topic<sensornet_Report> report_topic_;
  dds::Reader<sensornet_Scenario> scenarios_;
  dds::Reader<sensornet_Schedule> schedules_;
  dds::Reader<sensornet_EpisodeControl> controls_;
  dds::Reader<sensornet_SensorStatus> statuses_;
  dds::Reader<sensornet_Report> reports_;
  dds::ReadCondition has_scenario_, has_schedule_, has_control_, has_status_, has_report_;
  dds::WaitSet waitset_;
};

void printLines(const std::vector<std::string>& lines) {
  for (const std::string& line : lines) std::printf("%s\n", line.c_str());
  std::fflush(stdout);
}

void redraw(const RunView& view) {
  // Home, clear to the end, then the screen: no terminal mode to restore on Ctrl-C.
  std::printf("\x1b[H\x1b[J%s", view.screen(emulator::wallNowNs()).c_str());
  std::fflush(stdout);
}

int runWatch(WatchOptions options) {
  options.run.run_id = chooseRunId(options.run.run_id, options.run.domain_id);
  const bool screen = !options.plain && ::isatty(STDOUT_FILENO) == 1;
  RunTopics topics(options.run.domainConfig());
  RunView view(options.run.run_id);

  const auto give_up = Clock::now() + std::chrono::duration_cast<Clock::duration>(
                                          std::chrono::duration<double>(options.wait_s));
  std::optional<Clock::time_point> ended_at;
  for (;;) {
    topics.pollInto(view, kRefresh);
    if (view.ended() && !ended_at) ended_at = Clock::now();
    const bool done =
        ended_at && (view.allReported() || !view.endedCleanly() ||
                     Clock::now() - *ended_at >= kLastReportsWait);
    if (done) view.sayEnd();
    const std::vector<std::string> changes = view.takeChanges();
    if (screen) {
      if (view.started()) redraw(view);
    } else {
      printLines(changes);
    }
    if (done) return view.endedCleanly() ? kExitOk : kExitFailure;
    if (!view.started() && Clock::now() >= give_up) {
      std::fprintf(stderr,
                   "sensornet watch: nothing of run %s answered within %g s (is it running? "
                   "start one with `sensornet launch SCENARIO`)\n",
                   options.run.run_id.c_str(), options.wait_s);
      return kExitFailure;
    }
  }
}

}  // namespace

Subcommand addWatchCommand(CLI::App& app) {
  auto options = std::make_shared<WatchOptions>();
  CLI::App* cmd = app.add_subcommand(
      "watch",
      "Watch a running emulation: episode and progress, the schedule version in force, the "
      "running mean against the bracket, latency, and per sensor its state, rate, sent and "
      "received, redrawn four times a second on a terminal; otherwise (or with --plain) one "
      "plain line per change, for logs. It only reads the run's topics. Exits 0 when the run "
      "ends. Example:\n  sensornet watch            (the run last launched on this host)");
  emulator::addRunOptions(*cmd, options->run, /*run_id_required=*/false);
  cmd->get_option("--run-id")
      ->description("the run to watch (default: the run last launched on this host)");
  cmd->add_option("--wait", options->wait_s,
                  "seconds to wait for the run to show itself before giving up (exit 1)")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  cmd->add_flag("--plain", options->plain,
                "plain lines, one per change, even on a terminal");
  return {cmd, [options] { return runWatch(*options); }};
}

}  // namespace sensornet::launcher
