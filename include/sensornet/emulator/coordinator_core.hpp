#pragma once
// What the coordinator decides, without DDS, files or a clock of its own: when each episode is
// announced and starts, when the run is ready, how a command is answered (once per command id),
// what the failure policy does, where a live change switches, what goes into the journal and
// when the run ends, with which exit code. Typed events go in (a sensor status, a report, a
// fused covariance, the fusion center's discovery, a command, a stop signal, tick(now)); the
// actions to carry out, in order, come out:
//
//   CoordinatorCore core(config, run, journal, [] { return wallNowNs(); });
//   carryOut(core.start(now));                        // journal, scenario, versions
//   while (!core.exitCode()) {
//     waitset.wait(core.waitHint());
//     for (const CommandEvent& c : commands()) carryOut(core.onCommand(c, now()));
//     ...
//     carryOut(core.tick(now()));                     // readiness, pacing, deadlines
//   }
//   return *core.exitCode();
//
// Order matters: a WriteJournal comes before the announcement or version it records, so what the
// others have heard of is always in the journal (a coordinator killed in between resumes from it
// and announces again what the others may have missed).
//
// Planning (emulator::Replanner) is called in place and can take seconds, as it always did; the
// `wall_clock` given to the constructor is read only by the planner's view of the emulated time
// (before and after a plan) and to tell planning from a stall. Every other time is the `now`
// passed with an event.

#include <chrono>
#include <cstdint>
#include <deque>
#include <functional>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <variant>
#include <vector>

#include <spdlog/common.h>

#include "sensornet/core/emulated_plant.hpp"
#include "sensornet/emulator/run_partitions.hpp"
#include "sensornet/emulator/coordinator_journal.hpp"
#include "sensornet/core/scenario.hpp"
#include "sensornet/emulator/episode_controls.hpp"
#include "sensornet/emulator/log_line.hpp"
#include "sensornet/emulator/replanner.hpp"
#include "sensornet/emulator/schedule_book.hpp"
#include "sensornet/emulator/stall_watch.hpp"
#include "sensornet/emulator/vocabulary.hpp"

namespace sensornet::emulator {

// The coordinator's exit codes (`coordinator serve --help` says them): it did what it was told
// (ran the run to its end, ended it by the failure policy, on a shutdown request or a signal);
// it could not carry the run (peers not ready, no report, a write that failed); bad input.
inline constexpr int kCoordinatorExitDone = 0;
inline constexpr int kCoordinatorExitFailed = 1;
inline constexpr int kCoordinatorExitBadInput = 2;

// The run being coordinated: its scenario, the digest of the scenario's text and the seed.
struct CoordinatedRun {
  Scenario scenario;
  std::string digest;
  std::uint64_t seed = 0;
};

struct CoordinatorConfig {
  std::string run_id;
  int episodes = 20;
  double time_scale = 1.0;
  double ready_timeout_s = 30.0;
  double start_lead_s = 0.2;       // wall seconds between announcing the first episode and its start
  double episode_gap_s = 0.002;    // wall seconds between one episode's end and the next's start
  // Wall seconds between a re-plan and its effective time: the replanner's default.
  double switch_margin_s = ReplannerOptions{}.switch_margin_s;
  double report_timeout_s = 30.0;  // wall seconds of fusion-center silence before giving up
  FailurePolicy on_sensor_failure = FailurePolicy::Replan;
  // Who says that sensors died. Liveliness (no launcher: containers, a process manager of the
  // user's): a sensor whose SensorStatus writer stays without liveliness for death_grace_s wall
  // seconds while episodes run is dead, and the failure policy answers as for a launcher's
  // notice; one back within the grace was a stall. Before the first episode readiness decides.
  DeathWitness sensor_deaths = DeathWitness::Launcher;
  double death_grace_s = 2.0;
  bool network_aware = false;  // plans for the rates the scenario's network: delivers
  // Closed loop (closed_loop.hpp): re-plan the tail of every episode from the fused covariance
  // at each multiple of this many emulated seconds; absent: open loop.
  std::optional<double> replan_every_s;
  // Wall time between every peer being ready and the first announcement: the last discovery
  // settles (the others' readers match the coordinator's writers).
  std::chrono::nanoseconds settle = std::chrono::milliseconds(100);
  // `sensornet conform scheduler`: the first copy of each command goes unanswered, as a lost
  // one would, so that a scheduler under test must write it again.
  bool drop_first_command_copy = false;
};

// Events: the wire samples as plain values (the executable's codecs make them).
struct SensorStatusEvent {
  int sensor_id = 0;
  SensorState state = SensorState::Starting;
  std::uint32_t schedule_version = 0;
  std::string detail;
  // The writer's identity (its partition, run_partitions.hpp) names this sensor: a status of
  // any other writer is ignored (in a secured run, a forged readiness or failure).
  bool from_its_sensor = true;
};

struct ReportEvent {
  std::uint32_t episode = 0;
  double realized_cost = 0.0;
  double bracket_lower = 0.0;
  double bracket_upper = 0.0;
  std::uint32_t episodes_summarized = 0;  // the run summary's count
  double realized_mean = 0.0;
  double realized_ci95_low = 0.0;
  double realized_ci95_high = 0.0;
};

// The fusion center's latest P (FusionState): `values` column-major, state_dim x state_dim.
struct FusionStateEvent {
  std::uint32_t episode = 0;
  double emulated_time_s = 0.0;
  std::uint32_t state_dim = 0;
  std::vector<double> values;
};

enum class CommandKind { Replan, ExcludeSensors, SetBudget, ScheduleFile, Status, Shutdown,
                         SensorsFailed, IncludeSensors, Unknown };

struct CommandEvent {
  std::string run_id;
  std::uint64_t command_id = 0;
  CommandKind kind = CommandKind::Unknown;
  // Who sent it, as the partition it came in says (authenticated in a secured run): the
  // launcher may report sensors failed, an operator everything else.
  CommandSender sender = CommandSender::Operator;
  std::string issuer;  // the sample's free-text field: logged, never trusted
  std::string surrogate;                 // Replan
  std::vector<std::uint32_t> sensor_ids;  // ExcludeSensors, IncludeSensors, SensorsFailed
  std::vector<double> budget;            // SetBudget
  std::string schedule_json;             // ScheduleFile
  std::string detail;                    // SensorsFailed: what happened
};

// Actions, to carry out in the order given.
struct PublishScenario {};
struct PublishVersion {
  ScheduleVersion version;
};
struct PublishControl {
  EpisodeControl control;
};
struct SendReply {
  std::uint64_t command_id = 0;
  AnsweredCommand answer;
};
struct WriteJournal {
  CoordinatorJournal journal;
};
// RUN_SHUTDOWN, then wait (a few seconds at most) until the others have it.
struct ShutDownRun {
  EpisodeControl control;
};
// The program ends with this code; `summary` when the run ran to its end (for --json).
struct CoordinatorSummary {
  std::string run_id;
  int episodes = 0;
  std::uint32_t schedule_versions = 0;
};
struct ExitProgram {
  int exit_code = kCoordinatorExitDone;
  std::optional<CoordinatorSummary> summary;
};

using CoordinatorAction = std::variant<PublishScenario, PublishVersion, PublishControl, SendReply,
                                       WriteJournal, ShutDownRun, LogLine, ExitProgram>;
using CoordinatorActions = std::vector<CoordinatorAction>;

// The journal's fixed part: which run it belongs to (what --resume checks) and its length.
[[nodiscard]] CoordinatorJournal journalHeader(const CoordinatorConfig& config,
                                               const std::string& scenario_digest,
                                               std::uint64_t seed);

class CoordinatorCore {
 public:
  using WallClock = std::function<std::int64_t()>;

  // `journal` is where the run stands: a fresh one (version 1, nothing announced) or one read
  // back with --resume.
  CoordinatorCore(CoordinatorConfig config, CoordinatedRun run, const CoordinatorJournal& journal,
                  WallClock wall_clock);
  CoordinatorCore(const CoordinatorCore&) = delete;
  CoordinatorCore& operator=(const CoordinatorCore&) = delete;

  // The journal, the scenario and every version go out; then the run waits for its peers.
  [[nodiscard]] CoordinatorActions start(std::int64_t now_ns);
  [[nodiscard]] CoordinatorActions onSensorStatus(const SensorStatusEvent& status,
                                                  std::int64_t now_ns);
  [[nodiscard]] CoordinatorActions onReport(const ReportEvent& report, std::int64_t now_ns);
  [[nodiscard]] CoordinatorActions onFusionState(const FusionStateEvent& state,
                                                 std::int64_t now_ns);
  // A sensor's SensorStatus instance lost every live writer (alive = false) or has one again:
  // a death after death_grace_s, under DeathWitness::Liveliness; ignored otherwise.
  void onSensorLiveliness(int sensor_id, bool alive, std::int64_t now_ns);
  // Whether the fusion center's report and state writers are matched (discovery).
  void onFusionCenterMatched(bool matched) { fusion_matched_ = matched; }
  [[nodiscard]] CoordinatorActions onCommand(const CommandEvent& command, std::int64_t now_ns);
  // SIGINT or SIGTERM: the run ends at the next tick, as one the coordinator was told to end.
  void onStopSignal() { stop_signal_ = true; }
  // A WriteJournal could not be carried out (`why`: a full disk). Without its journal a restart
  // could not resume the run, so the run ends at the next tick as failed, the reason in the
  // RUN_SHUTDOWN that every process and the report get; no journal is written any more.
  void onJournalFailed(const std::string& why);
  // Readiness, the next announcements, deadlines, the end of the run.
  [[nodiscard]] CoordinatorActions tick(std::int64_t now_ns);

  // Set once the run is over (after ExitProgram).
  [[nodiscard]] std::optional<int> exitCode() const { return exit_code_; }
  // How long the loop may wait for the next sample before the next tick.
  [[nodiscard]] std::chrono::nanoseconds waitHint() const;
  // Samples refused by the coordinator's own readers (counted and logged).
  [[nodiscard]] std::uint64_t rejectedSamples() const { return rejected_; }

 private:
  enum class Phase { Starting, AwaitingPeers, Settling, Running, Ended };

  // An episode announced and not reported yet.
  struct Outstanding {
    std::uint32_t episode = 0;
    EpisodeClock clock;
  };

  // What one command changes: versions to publish (and settings to adopt) or none, and why.
  struct Answer {
    std::optional<Replan> replan;
    std::string reason;
  };

  CoordinatorActions take();
  template <class A>
  void act(A action);
  void log(spdlog::level::level_enum level, std::string text);
  void saveState();

  void tickAwaitingPeers(std::int64_t now_ns);
  void tickRunning(std::int64_t now_ns);
  [[nodiscard]] bool peersReady() const;
  void announceAhead(std::int64_t now_ns);
  void announceEpisode(std::uint32_t episode, std::int64_t now_ns);
  void announceAgain(const Outstanding& outstanding, std::int64_t now_ns);
  [[nodiscard]] std::int64_t nextStartNs(std::int64_t now_ns) const;
  [[nodiscard]] bool reportOverdue(const Outstanding& awaited, std::int64_t now_ns);
  void endRun(const std::string& failure, int exit_code, std::int64_t now_ns);

  [[nodiscard]] EpisodeControl control(ControlKind kind, std::uint32_t episode,
                                       std::int64_t now_ns) const;
  [[nodiscard]] std::vector<std::uint32_t> failedIds() const;
  [[nodiscard]] int episodesDone() const { return static_cast<int>(reported_.size()); }
  [[nodiscard]] int sensorsInService() const;
  [[nodiscard]] int readySensorsInService() const;

  [[nodiscard]] static std::string withoutRight(const CommandEvent& c);
  AnsweredCommand answer(const CommandEvent& c, std::int64_t now_ns);
  Answer execute(const CommandEvent& c, std::int64_t now_ns);
  Answer onSensorsFailed(const CommandEvent& c, std::int64_t now_ns);
  Answer replanAmongSurvivors(const CommandEvent& c, std::int64_t now_ns);
  void adoptAndPublish(const Replan& replan);
  void declareDeaths(std::int64_t now_ns);
  void announceFailure(const std::string& detail, std::int64_t now_ns);
  void replanOnCadence(std::int64_t now_ns);

  [[nodiscard]] const Outstanding* runningEpisode(std::int64_t now_ns) const;
  [[nodiscard]] const Outstanding* pendingEpisode(std::int64_t now_ns) const;
  [[nodiscard]] std::uint32_t firstNotStarted(std::int64_t now_ns) const;
  [[nodiscard]] RunMoment moment(std::int64_t now_ns) const;

  CoordinatorConfig config_;
  CoordinatedRun run_;
  WallClock wall_clock_;
  EmulatedPlant plant_;  // only for its tick grid: effective times fall on ticks
  Replanner replanner_;
  ScheduleBook book_;

  Phase phase_ = Phase::Starting;
  std::int64_t ready_deadline_ns_ = 0;
  std::int64_t settled_ns_ = 0;
  bool resumed_with_outstanding_ = false;
  std::set<int> ready_sensors_;
  std::map<int, std::int64_t> lively_lost_ns_;  // DeathWitness::Liveliness: since when, per sensor
  bool fusion_matched_ = false;
  bool stop_signal_ = false;
  EpisodeSet reported_;  // as ranges: small over millions of episodes
  std::optional<AnnouncedEpisode> announced_;
  std::map<std::uint64_t, AnsweredCommand> answered_;
  std::set<std::uint64_t> dropped_copies_;  // config_.drop_first_command_copy: ids met once
  std::int64_t fusion_heard_ns_ = 0;  // the fusion center's latest state or report
  std::optional<std::uint32_t> awaited_;  // whose report fusion_heard_ns_ is counted for
  StallWatch stall_watch_;
  std::optional<FusedCovariance> fused_;
  // --replan-every: the episode whose instants are being served and the next instant's index
  // (k of k DT).
  struct Cadence {
    std::uint32_t episode = 0;
    int next = 1;
    bool waiting_logged = false;  // "no fused covariance yet", once per episode
  };
  std::optional<Cadence> cadence_;
  std::uint32_t current_episode_ = 0;  // whose report is awaited
  std::uint32_t next_episode_ = 0;     // to announce next
  std::deque<Outstanding> outstanding_;  // announced, not reported, in order (at most two)
  std::int64_t last_end_ns_ = 0;         // wall time of the end of the episode announced last
  bool stopping_ = false;                // COMMAND_SHUTDOWN: no more announcements
  std::string abort_detail_;             // the run ends as failed (--on-sensor-failure stop)
  bool journal_failed_ = false;          // onJournalFailed: saveState writes nothing
  std::uint64_t rejected_ = 0;
  std::set<int> impostors_;  // sensors a foreign identity's status spoke for (logged once)
  std::optional<int> exit_code_;
  CoordinatorActions actions_;  // what the event being handled asks for, in order
};

}  // namespace sensornet::emulator
