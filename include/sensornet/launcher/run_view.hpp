#pragma once
// One follower of a run's topics, free of DDS and clocks: what `sensornet watch`, `sensornet
// status` and the launcher's progress lines show of a run. The wiring (launcher/run_follower.*)
// decodes the samples of the Scenario, Schedule, EpisodeControl, SensorStatus and Report topics
// into the plain events below and feeds them, each with the wall time `now_ns` it saw them at;
// the view answers where the run is (which episode runs, the emulated time in it), what each
// sensor last said, which episodes were reported, and whether the run has ended, and makes the
// plain lines of what changed.
//
//   RunViewConfig config;  config.run_id = "run-42";
//   RunView view(config);
//   view.onScenario(scenario, now);  view.onEpisodeStart(start, now);  view.onReport(r, now);
//   for (const std::string& line : view.takeLines(now)) print(line);
//   view.progressAt(now);     // episode 3 running at t = 1.25 s of 3 s
//   view.finished(now);       // the run ended, its last reports and sensors' last words are in
//
// Episode numbers are the run's own (0, 1, ...: as on the wire, in report.json and in the
// faults); "[k/N]" in front of a line is the episode's place among the N planned, k = episode
// + 1, the same in the launcher's progress lines and in watch.

#include <cstdint>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "sensornet/emulator/episode_controls.hpp"
#include "sensornet/emulator/vocabulary.hpp"
#include "sensornet/launcher/fault.hpp"  // RunPosition

namespace sensornet::launcher {

// Events: what the run's topics said, decoded.
struct ScenarioSeen {
  std::string digest;
  std::uint32_t sensor_count = 0;
  std::uint32_t state_dim = 0;
  double horizon_s = 0.0;
  std::uint64_t seed = 0;
};

struct ScheduleSeen {
  std::uint32_t version = 0;
  std::string surrogate;
  std::uint32_t effective_episode = 0;
  double effective_time_s = 0.0;
  double bracket_lower = 0.0;
  double bracket_upper = 0.0;
};

struct EpisodeAnnounced {
  std::uint32_t episode = 0;
  emulator::EpisodeClock clock;
  std::uint32_t episodes_planned = 0;
  std::uint32_t schedule_version = 0;  // in force at the episode's start
};

struct SensorStatusSeen {
  std::uint32_t sensor_id = 0;
  emulator::SensorState state = emulator::SensorState::Starting;
  std::uint32_t episode = 0;
  std::uint32_t schedule_version = 0;
  double rate_hz = 0.0;
  std::uint64_t sent_in_episode = 0;
  std::uint64_t sent_total = 0;
  std::uint64_t write_timeouts = 0;
  std::int32_t process_id = 0;
  std::int64_t wall_time_ns = 0;  // when the sensor said it
  std::string detail;
  bool alive = true;  // its process still writes the instance
};

struct SensorCountsSeen {
  std::uint32_t sensor_id = 0;
  std::uint64_t sent = 0;
  std::uint64_t received = 0;
  std::uint64_t lost = 0;
};

// The running summary a Report carries (over the complete episodes so far).
struct RunningSummary {
  std::uint32_t episodes = 0;
  std::uint32_t episodes_complete = 0;
  double realized_mean = 0.0;
  double ci95_low = 0.0;
  double ci95_high = 0.0;
  double bracket_lower_mean = 0.0;
  double bracket_upper_mean = 0.0;
  bool meets_bracket = false;
  // Of what the schedules delivered (network losses and outages, dead sensors): the same as the
  // bracket above when nothing was lost on the way.
  double delivered_lower_mean = 0.0;
  double delivered_upper_mean = 0.0;
};

struct EpisodeReportSeen {
  std::uint32_t episode = 0;
  double realized_cost = 0.0;  // not finite: the fusion center did not fuse it (restarted)
  bool complete = false;
  std::string incomplete_reason;  // why not complete ("sensor 1 failed at 0.202 s")
  std::vector<std::uint32_t> schedule_versions;
  std::vector<SensorCountsSeen> counts;
  double latency_median_s = 0.0;
  double latency_p99_s = 0.0;
  RunningSummary summary;
};

// The progress line of one episode's report: "[3/20] episode 2: realized 12.3, mean 11.8 over 3
// complete (95%: [...]), bracket [10.2, 30.1]"; an incomplete episode says why. Without a
// planned count "[3/?]".
[[nodiscard]] std::string formatProgress(const EpisodeReportSeen& report,
                                         std::optional<std::uint32_t> episodes_planned);

// Where the run's episodes are at some wall time.
enum class EpisodePhase {
  NotStarted,  // no episode announced yet
  StartsSoon,  // the first episode announced is still ahead
  Running,     // `episode` runs, at emulated time `t_s`
  Closing,     // `episode` is past its horizon; its report or the next start is awaited
  Ended,       // the run has shut down (RUN_SHUTDOWN)
};
struct EpisodeProgress {
  EpisodePhase phase = EpisodePhase::NotStarted;
  std::optional<std::uint32_t> episode;
  double t_s = 0.0;  // in [0, horizon_s]
  double horizon_s = 0.0;
  double starts_in_s = 0.0;            // StartsSoon: wall seconds until it starts
  std::uint32_t schedule_version = 0;  // in force at the episode's start
};

// What the view knows of one sensor.
struct SensorView {
  std::optional<emulator::SensorState> state;  // none until its first status
  std::uint32_t episode = 0;
  std::uint32_t schedule_version = 0;
  double rate_hz = 0.0;
  std::uint64_t sent_in_episode = 0;
  std::uint64_t sent_total = 0;  // as the sensor says, every episode so far
  std::uint64_t write_timeouts = 0;
  std::int32_t process_id = 0;
  std::int64_t status_wall_ns = 0;
  std::string detail;
  bool alive = true;    // false once its process is gone
  bool failed = false;  // the coordinator said it died
  // Over the reported episodes.
  std::uint64_t sent = 0, received = 0, lost = 0;
  // It will say nothing more: stopped, failed, or gone.
  [[nodiscard]] bool final() const {
    return !alive || failed || state == emulator::SensorState::Stopped ||
           state == emulator::SensorState::Failed;
  }
};

struct RunViewConfig {
  std::string run_id;
  // The launcher knows how many episodes it asked for; watch learns it from the first start.
  std::optional<std::uint32_t> episodes_planned;
  // After the run's end, how long the last reports and the sensors' last words may take.
  std::int64_t end_grace_ns = 3'000'000'000;
  // Sensors that change alike within this share one line ("sensors 0, 1, 3: stopped").
  std::int64_t sensor_batch_ns = 300'000'000;
  bool keep_lines = true;     // for takeLines (watch)
  bool keep_reports = false;  // for takeReports (the launcher's progress lines)
};

class RunView {
 public:
  explicit RunView(RunViewConfig config);

  void onScenario(const ScenarioSeen& scenario, std::int64_t now_ns);
  void onSchedule(const ScheduleSeen& schedule, std::int64_t now_ns);
  void onEpisodeStart(const EpisodeAnnounced& start, std::int64_t now_ns);
  void onEpisodeStop(std::uint32_t episode, std::int64_t now_ns);
  void onSensorsFailed(const emulator::SensorFailure& failure, std::int64_t now_ns);
  void onRunEnd(const emulator::RunEnd& end, std::int64_t now_ns);
  void onSensorStatus(const SensorStatusSeen& status, std::int64_t now_ns);
  void onSensorGone(std::uint32_t sensor, std::int64_t now_ns);
  void onReport(const EpisodeReportSeen& report, std::int64_t now_ns);
  // The coordinator's episode controls lost their writer without a RUN_SHUTDOWN.
  void onCoordinatorGone(std::int64_t now_ns);

  // Anything of the run answered.
  [[nodiscard]] bool answered() const noexcept { return answered_; }
  [[nodiscard]] const std::optional<ScenarioSeen>& scenario() const noexcept { return scenario_; }
  [[nodiscard]] const std::optional<ScheduleSeen>& newestSchedule() const noexcept {
    return newest_schedule_;
  }
  [[nodiscard]] std::optional<std::uint32_t> episodesPlanned() const noexcept { return planned_; }
  [[nodiscard]] EpisodeProgress progressAt(std::int64_t now_ns) const;
  [[nodiscard]] RunPosition positionAt(std::int64_t now_ns) const;
  [[nodiscard]] const std::map<std::uint32_t, SensorView>& sensors() const noexcept {
    return sensors_;
  }
  // Sensors whose status names a schedule version (as the coordinator counts them ready).
  [[nodiscard]] std::size_t sensorsReady() const;
  // A status of `sensor` came (from its agent or a participant speaking for it).
  [[nodiscard]] bool heardFrom(std::uint32_t sensor) const;
  // It spoke, and its SensorStatus has no writer any more without its having said it stopped:
  // its process is gone (or has not asserted liveliness for a lease).
  [[nodiscard]] bool gone(std::uint32_t sensor) const;
  // The scenario is known and every one of its sensors answered or is known dead.
  [[nodiscard]] bool allSensorsAccounted() const;
  [[nodiscard]] std::size_t episodesReported() const noexcept { return reported_count_; }
  [[nodiscard]] const std::optional<EpisodeReportSeen>& lastReport() const noexcept {
    return last_report_;
  }

  // The coordinator shut the run down, or left.
  [[nodiscard]] bool ended() const noexcept { return end_ns_.has_value(); }
  [[nodiscard]] bool endedCleanly() const noexcept { return run_end_.has_value(); }
  // Ended, and every episode run reported and every sensor said its last (stopped, failed or
  // gone), or the end grace passed.
  [[nodiscard]] bool finished(std::int64_t now_ns) const;

  // The plain lines of what changed since the last call, in order; the end line once finished.
  [[nodiscard]] std::vector<std::string> takeLines(std::int64_t now_ns);
  // The reports released since the last call (in order, each once), with keep_reports.
  [[nodiscard]] std::vector<EpisodeReportSeen> takeReports();
  // The terminal screen of `sensornet watch`.
  [[nodiscard]] std::string screen(std::int64_t now_ns) const;

 private:
  void say(std::string line);
  void saySensor(std::uint32_t sensor, const std::string& change, std::int64_t now_ns);
  void flushSensorLines();
  void releaseReports(bool even_unplaced = false);
  void sayReport(const EpisodeReportSeen& report);
  void sayStart(const EpisodeAnnounced& start, std::int64_t now_ns);
  void markEnded(std::int64_t now_ns);
  [[nodiscard]] bool reportedAlready(std::uint32_t episode) const;
  void noteReported(std::uint32_t episode);
  [[nodiscard]] std::string place(std::uint32_t episode) const;  // "[3/20]"
  [[nodiscard]] std::string progressLine(std::int64_t now_ns) const;

  RunViewConfig config_;
  bool answered_ = false;
  std::optional<ScenarioSeen> scenario_;
  std::optional<std::uint32_t> planned_;
  std::set<std::uint32_t> versions_;
  std::optional<ScheduleSeen> newest_schedule_;
  std::map<std::uint32_t, EpisodeAnnounced> announced_;   // the latest few
  std::vector<EpisodeAnnounced> starts_before_scenario_;  // said once its horizon is known
  std::set<std::uint32_t> failed_;
  std::map<std::uint32_t, SensorView> sensors_;
  // Reported episodes: every one below reported_below_, and those in reported_above_.
  std::uint32_t reported_below_ = 0;
  std::set<std::uint32_t> reported_above_;
  std::size_t reported_count_ = 0;
  std::map<std::uint32_t, EpisodeReportSeen> held_reports_;  // until the scenario and N are known
  std::optional<EpisodeReportSeen> last_report_;
  std::vector<EpisodeReportSeen> released_;
  std::optional<emulator::RunEnd> run_end_;
  bool coordinator_gone_ = false;
  std::optional<std::int64_t> end_ns_;
  bool end_said_ = false;
  std::vector<std::string> lines_;
  std::map<std::string, std::set<std::uint32_t>> sensor_lines_;  // not yet in lines_
  std::optional<std::int64_t> sensor_lines_since_ns_;
};

}  // namespace sensornet::launcher
