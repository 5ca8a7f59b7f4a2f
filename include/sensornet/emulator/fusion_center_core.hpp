#pragma once
// What the fusion center decides, free of DDS, files and clocks: when an episode closes, what
// counts as a stall, an overload or a foreign writer, how a resumed run starts, which status the
// run gets. Typed events go in, each with the wall time `now` it happened at; typed actions come
// out, for the executable (fusion_center serve) to carry out: publish a Report or the FusionState,
// append a line to the episode log, log a line, write the final report.
//
//   FusionCenterCore core(config, writers);        // writers: what DDS knows of live writers
//   core.onScenario({scenario, digest, seed}, now);
//   core.onScheduleVersions(new_versions, now);
//   core.onEpisodeStart(start, now);
//   core.onMeasurement(arrival, now);              // a tally, a status, a failure notice alike
//   core.tick(now);                                // fuse, close, time out, publish the state
//   for (FusionAction& a : core.takeActions()) std::visit(carryOut, a);
//   const RunStatus status = core.finish(end, rejected_by_inputs, written_at, now);
//
// Time: every `now` is wall nanoseconds on the clock the measurements' publish and receive times
// use. A test drives the core with a scripted order of events and a fake clock.

#include <Eigen/Core>
#include <cstddef>
#include <cstdint>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <string>
#include <utility>
#include <variant>
#include <vector>

#include <nlohmann/json.hpp>
#include <spdlog/common.h>

#include "sensornet/core/emulated_plant.hpp"
#include "sensornet/core/scenario.hpp"
#include "sensornet/core/surrogate.hpp"
#include "sensornet/emulator/clock_offsets.hpp"
#include "sensornet/emulator/episode_fusion.hpp"
#include "sensornet/emulator/episode_controls.hpp"
#include "sensornet/emulator/log_line.hpp"
#include "sensornet/emulator/run_report.hpp"
#include "sensornet/emulator/schedule_book.hpp"
#include "sensornet/emulator/stall_watch.hpp"
#include "sensornet/emulator/vocabulary.hpp"
#include "sensornet/report/run_status.hpp"
#include "sensornet/emulator/writer_claims.hpp"

namespace sensornet::emulator {

struct FusionCenterConfig {
  std::string run_id;
  double lag_s = 0.05;           // wall seconds a measurement may take to arrive before fusion
  double stall_limit_s = 12.0;   // wall seconds a sensor that owes measurements may stay silent
  double keep_up_limit_s = 1.0;  // wall seconds of drain or sensor lag that count as overload
  double state_period_s = 0.05;  // FusionState publication period (wall seconds)
  // Restarted (--resume): the entries of the episode log it goes on from (empty: none yet).
  std::optional<std::vector<nlohmann::json>> resumed_log;
  // ... and the faults its earlier lives recorded (faultLogPath), which the report keeps.
  std::vector<nlohmann::json> resumed_faults;
  bool episode_log = false;      // the report's entries are read back from an episode log
  std::string episode_log_path;  // ... this one
};

// A restarted fusion center waits at most this long (wall seconds after it joined, not counting
// its own stalls) for the writers of every live sensor process before it answers for the episode
// it could not fuse (the coordinator then starts the next one, which must lose nothing).
inline constexpr double kResumeMatchWaitS = 5.0;

// A failure notice that comes this long (wall seconds this process ran) after the sensor was
// last heard came late: a live sensor is heard at least every second (its SensorStatus), and a
// death reaches the notice within a fraction of one unless the launcher was stalled. The death
// is then dated by the silence, not by the notice.
inline constexpr double kLateFailureNoticeS = 2.0;

// The wire topics whose writers claim sensors.
enum class SensorTopic { Measurement, Tally, Status };

// What DDS knows of the writers the fusion center reads: the wiring implements it on its readers.
class WriterFacts {
 public:
  virtual ~WriterFacts() = default;
  // The writer `w` of `topic` is matched by this process's reader (alive).
  [[nodiscard]] virtual bool live(SensorTopic topic, WriterId w) const = 0;
  // How many Measurement writers the reader has matched.
  [[nodiscard]] virtual std::uint32_t matchedMeasurementWriters() const = 0;
  // The Measurement and the EpisodeTally reader have each matched a writer of the participant
  // (process) whose SensorStatus writer is `status_writer`: what it writes from now reaches
  // this process. (Under DDS Security each side matches when the other's crypto tokens come,
  // so that a writer has matched this reader says nothing of this reader's side.)
  [[nodiscard]] virtual bool writersMatchedWith(WriterId status_writer) const = 0;
  // The sensors the writer `w` of `topic` speaks for, as the partition it writes in says
  // (run_partitions.hpp; in a secured run its authenticated identity), sorted; empty when it
  // names none or is not known. Asked for every sample: answered from a cache.
  [[nodiscard]] virtual const std::vector<int>& sensorsOf(SensorTopic topic, WriterId w) const = 0;
};

// The announced scenario, decoded.
struct ScenarioAnnounced {
  Scenario scenario;
  std::string digest;
  std::uint64_t seed = 0;
};

// A measurement as it came off the wire, stamped on arrival (receive_wall_ns).
struct MeasurementArrival {
  FusedMeasurement measurement;
  std::uint32_t episode = 0;
  // The run the sample named, when that is not the fusion center's own run; nullopt for the
  // fusion center's own (arrivalOfSample compares, so nearly every arrival copies no string).
  std::optional<std::string> other_run;
  WriterId writer = 0;  // the DDS writer that sent it (publication handle)
};

// A sensor's end-of-episode count (the EpisodeTally topic), decoded.
struct EpisodeTally {
  std::uint32_t sensor = 0;
  std::string run_id;
  std::uint32_t episode = 0;
  EpisodeCount count;
  double max_lag_s = 0.0;  // wall seconds it published behind the emulated clock
  double stalled_s = 0.0;  // wall seconds the sensor's process was stopped in the episode
  std::int64_t wall_time_ns = 0;  // its publication
  WriterId writer = 0;
};

struct SensorStatus {
  std::uint32_t sensor = 0;
  std::string run_id;
  std::uint32_t episode = 0;
  SensorState state = SensorState::Starting;  // vocabulary.hpp
  std::uint64_t sent_in_episode = 0;
  std::int32_t process_id = 0;
  std::int64_t wall_time_ns = 0;
  WriterId writer = 0;
};

// A process's answer to a clock probe (the ClockEcho topic), decoded: t1 to t3 of the exchange
// (clock_offsets.hpp); t4 is the `now` it is handed in with.
struct ClockEcho {
  std::string run_id;
  std::string process;
  std::vector<int> sensors;
  std::int64_t probe_sent_ns = 0;
  std::int64_t probe_taken_ns = 0;
  std::int64_t answered_ns = 0;
};

// Actions: what the wiring carries out.
struct PublishReport {
  EpisodeResult result;
  RunSummary summary;
  // Not every live sensor process's writers are held (a restarted fusion center that answered
  // after kResumeMatchWaitS): these sensors' measurements of the next episode may be lost.
  std::vector<int> lacking_writers;
};
struct PublishState {
  std::uint32_t episode = 0;
  double emulated_time_s = 0.0;
  Eigen::MatrixXd covariance;
  std::uint32_t schedule_version = 0;
};
struct AppendEpisodeLog {
  nlohmann::json entry;
};
// How far the clocks of a run's hosts may disagree before latency figures across them are not
// believed: a process whose clock is measured (clock_offsets.hpp) farther than this from the
// fusion center's for certain, or a sensor that stamps measurements later than the fusion
// center receives them by more than this, is a clock_offset fault. (NTP keeps hosts within a
// millisecond or so on a LAN; PTP within microseconds: docs/guide/many-hosts.md.)
inline constexpr double kClockBoundS = 1e-3;

struct RecordFault {
  report::FaultRecord fault;  // faultEntry(...), also kept for the final report
};
struct WriteFinalReport {
  RunStatus status = RunStatus::Completed;
  nlohmann::json doc;  // without per_episode: RunReport::write streams it in (report())
  std::string written_at;
};
using FusionAction =
    std::variant<PublishReport, PublishState, AppendEpisodeLog, RecordFault, LogLine, WriteFinalReport>;

class FusionCenterCore {
 public:
  FusionCenterCore(FusionCenterConfig config, const WriterFacts& writers, std::int64_t joined_ns);
  ~FusionCenterCore();
  FusionCenterCore(const FusionCenterCore&) = delete;
  FusionCenterCore& operator=(const FusionCenterCore&) = delete;

  void onScenario(ScenarioAnnounced announced, std::int64_t now);
  // Versions RunInputs accepted, in order (each once).
  void onScheduleVersions(const std::vector<ScheduleVersion>& versions, std::int64_t now);
  void onEpisodeStart(const EpisodeStart& start, std::int64_t now);
  void onSensorFailure(const SensorFailure& failure, std::int64_t now);
  void onMeasurement(MeasurementArrival arrival, std::int64_t now);
  void onTally(const EpisodeTally& tally, std::int64_t now);
  void onStatus(const SensorStatus& status, std::int64_t now);
  // A process answered a clock probe, the answer taken at `now` (t4). One naming sensors out
  // of the scenario, or with times that cannot be, is counted and logged, and changes nothing.
  void onClockEcho(const ClockEcho& echo, std::int64_t now);
  // The coordinator refused command `command_id` because its sender had no right to send it
  // (a CommandReply whose reason begins with kNotPermitted): a fault, once per command.
  void onCommandRefused(std::uint64_t command_id, const std::string& reason, std::int64_t now);
  // `seen` coordinator processes have driven the run so far (their EpisodeControl writers): each
  // beyond the first is a coordinator restarted (by a restart policy: no launcher supervises
  // this run, or the launcher's own fault would name it), a `restarted` fault of the
  // coordinator that survived. Call it only when no launcher supervises the run.
  void onCoordinatorProcesses(std::size_t seen, std::int64_t now);
  // The launcher that started this process died (kill -9), and its parent-death signal is what
  // stops this one: the run ends interrupted with that death as its cause, recorded here since
  // no launcher is left to add it to the report (issue 31).
  void onLauncherGone(const std::string& detail, std::int64_t now);
  // The episode log refused `entry` (a full disk, `why` says so): a write_failed fault; this
  // entry and every later one are held for the report instead, and no more are logged.
  void onEpisodeLogRefused(const nlohmann::json& entry, const std::string& why);
  // After finish(): the report's path refused `refused` (a full disk, `why`); it goes to
  // `elsewhere` instead, with a write_failed fault that says so (the run at least degraded).
  // Called again for the next place to try, the one fault says the newer place.
  [[nodiscard]] WriteFinalReport reportRefused(const WriteFinalReport& refused,
                                               const std::string& why,
                                               const std::filesystem::path& elsewhere);
  // The main loop's turn: its own stalls, fusion up to the watermark, episodes closed or timed out.
  void tick(std::int64_t now);
  // The run ended (`end`) or was stopped by a signal (nullopt): what is open is closed, the
  // status decided and the final report handed out. `rejected_by_inputs`: RunInputs' counts.
  RunStatus finish(const std::optional<RunEnd>& end,
                   const std::map<std::string, std::uint64_t>& rejected_by_inputs,
                   const std::string& written_at, std::int64_t now);

  [[nodiscard]] std::vector<FusionAction> takeActions();

  [[nodiscard]] bool hasScenario() const { return announced_.has_value(); }
  [[nodiscard]] bool hasReport() const { return report_.has_value(); }
  [[nodiscard]] const RunReport& report() const { return *report_; }
  [[nodiscard]] const std::vector<report::FaultRecord>& faults() const { return faults_; }
  [[nodiscard]] const nlohmann::json& stalls() const { return stalls_; }
  // Live sensor processes whose Measurement and EpisodeTally writers this process does not hold
  // (by identity).
  [[nodiscard]] std::vector<int> sensorsLackingWriters() const;
  // It has the scenario and holds the writers of every live sensor process: what a fusion
  // center waits for before it makes itself present to the coordinator, which then starts the
  // first episode (docs/wire-protocol.md, "Fusion center"); a restarted one waits for it before
  // it fuses.
  [[nodiscard]] bool holdsEverySensorProcess() const;

 private:
  struct OpenEpisode;
  struct SensorProcess {
    std::int32_t id = 0;
    SensorState state = SensorState::Starting;  // vocabulary.hpp
    WriterId status_writer = 0;
  };

  [[nodiscard]] const Scenario& scenario() const { return announced_->scenario; }
  // Built in place: moving a fresh action into the variant trips GCC 12's -Wmaybe-uninitialized.
  template <class Action, class... Args>
  void emit(Args&&... args) {
    actions_.emplace_back(std::in_place_type<Action>, std::forward<Args>(args)...);
  }
  void log(spdlog::level::level_enum level, std::string text);
  void recordFault(report::FaultRecord fault);
  void countOutside(RejectionReason reason, std::uint64_t count = 1);

  void startEpisode(const EpisodeStart& start, std::int64_t now);
  void recordDeaths(const SensorFailure& failure);
  void applyFailure(std::uint32_t number, OpenEpisode& open, const SensorFailure& failure);
  void applySilentFailure(OpenEpisode& open, int sensor, std::int64_t last_heard_ns);
  void heard(std::uint32_t sensor, std::int64_t now);
  CostBracket bracketOf(const ScheduleVersion& v);
  CostBracket deliveredBracketOf(const ScheduleVersion& v, std::uint32_t episode);
  [[nodiscard]] bool duplicatesLink(int sensor) const;
  bool networkCopyAfterClose(std::uint32_t episode, int sensor);
  void rejectOutside(RejectionReason reason, const std::string& detail);
  bool refuseWriter(WriterClaims& claims, SensorTopic topic, std::uint32_t sensor, WriterId writer,
                    std::uint32_t episode);
  void releaseClaims(const std::set<int>& sensors);
  void route(OpenEpisode& open, FusedMeasurement m, WriterId writer, std::int64_t now);
  void applyTally(OpenEpisode& open, const EpisodeTally& t, std::int64_t now);
  void lateTally(const EpisodeTally& t);
  [[nodiscard]] double awakeSince(std::int64_t from_ns, std::int64_t now_ns) const;
  void giveUpUnheldStarts(std::int64_t now);
  void answerRestarted(std::int64_t now);
  [[nodiscard]] std::set<std::int32_t> liveSensorProcesses() const;
  void finishRestarted(std::uint32_t episode, std::int64_t now);
  [[nodiscard]] bool silentTooLong(const OpenEpisode& open, std::int64_t now) const;
  void closeUnsettled(std::uint32_t number, OpenEpisode& open, const std::string& why,
                      std::int64_t now);
  void blameNetwork(const EpisodeTally& t);
  void noteClocks();
  [[nodiscard]] nlohmann::json clocksJson() const;
  [[nodiscard]] bool clocksDisagree(const EpisodeResult& r) const;
  void cutShort(const std::string& why, std::optional<FaultKind> cause);
  void publishState(std::uint32_t episode, const OpenEpisode& open, std::int64_t now);
  // cut_short: why the run ended while it was open (its incomplete_reason says so).
  void finishEpisode(std::uint32_t number, OpenEpisode& open,
                     const std::string* cut_short = nullptr);
  void traceCovariance(const EpisodeFusion& fusion, const EpisodeResult& r);
  [[nodiscard]] nlohmann::json covarianceTraces();
  void checkKeepingUp(std::uint32_t number, const OpenEpisode& open, EpisodeResult& result);
  void noteHeldBack(std::uint32_t number, const OpenEpisode& open);
  void publishReport(const EpisodeResult& e, std::vector<int> lacking_writers = {});
  // What the fusion center saw of how the run went, for the one status rule (run_status.hpp);
  // records the faults it implies (the coordinator's abort, missing episodes, rejections).
  report::StatusEvidence gatherStatusEvidence(
      const std::optional<RunEnd>& end,
      const std::map<std::string, std::uint64_t>& rejected_by_inputs);
  void noteRestart();
  [[nodiscard]] report::FaultRecord restartFault() const;
  [[nodiscard]] nlohmann::json finalReport(RunStatus status, const std::string& written_at);

  FusionCenterConfig config_;
  const WriterFacts& writers_;
  std::optional<ScenarioAnnounced> announced_;
  std::optional<EmulatedPlant> plant_;
  ScheduleBook book_;
  std::optional<std::uint32_t> last_started_;
  std::set<int> failed_sensors_;  // every sensor the coordinator said is dead
  std::vector<FusionAction> actions_;

  std::optional<RunReport> report_;
  std::map<std::uint32_t, CostBracket> brackets_;
  // (version, the outages of an episode) -> the bracket of what the network delivers
  std::map<std::pair<std::uint32_t, std::vector<std::size_t>>, CostBracket> delivered_brackets_;
  std::map<std::uint32_t, std::unique_ptr<OpenEpisode>> open_;
  std::map<std::uint32_t, std::vector<MeasurementArrival>> early_;
  std::map<std::uint32_t, std::vector<EpisodeTally>> early_tallies_;
  std::vector<SensorFailure> failures_;  // the coordinator's notices, in order
  std::map<int, std::int64_t> heard_ns_;  // per sensor: when anything of it last arrived
  // Failed sensors whose notice came late (the launcher, which tells the coordinator, was
  // stalled): long after they fell silent, or after the end of an episode whose count they
  // still owed. When they were last heard dates the death better than the notice.
  std::map<int, std::int64_t> silent_from_ns_;
  bool launcher_gone_ = false;           // onLauncherGone: the run's cause is the launcher's death
  bool episode_log_refused_ = false;     // onEpisodeLogRefused: entries are held, not logged
  std::optional<std::size_t> report_refused_fault_;  // reportRefused: its fault in faults_
  std::size_t restart_fault_ = 0;        // resumed: where this life's restart fault is in faults_
  std::optional<ResumedRun> resumed_;    // with --resume
  std::map<std::uint32_t, std::int64_t> restarted_;  // not fusable here -> end wall time (0: past)
  std::map<std::uint32_t, SensorProcess> sensor_processes_;  // by sensor, from their statuses
  bool holds_writers_ = false;          // restarted: held every sensor process's writers once
  std::size_t coordinators_seen_ = 0;   // onCoordinatorProcesses
  std::set<int> returned_;              // failed sensors that published again (logged once)
  std::set<std::uint32_t> began_unheld_;  // episodes that began before that: not fused
  std::set<int> answered_without_;  // sensors whose writers a restarted episode's answer lacked
  // (episode, sensor) closed with no tally -> when it was closed (the stall limit), or
  // kClosedAtRunEnd (cut short)
  std::map<std::pair<std::uint32_t, int>, std::int64_t> closed_without_;
  // (episode, sensor) whose count the network held back past the stall limit (blameNetwork),
  // and the samples of those episodes refused as finished_episode after the close
  std::set<std::pair<std::uint32_t, int>> held_back_;
  // Per sensor, the smallest publish-to-fusion latency of the run (+inf: none yet): below zero,
  // its clock is ahead of this process's by at least as much (noteClocks).
  std::vector<double> earliest_latency_s_;
  ClockOffsets clocks_;  // the sensor processes' clocks, measured both ways
  std::uint64_t clock_echoes_refused_ = 0;  // naming sensors out of the run
  std::map<std::pair<std::uint32_t, int>, std::uint64_t> after_close_;
  // (episode, sensor) of a closed episode: copies its tally says the network made, not yet seen.
  std::map<std::pair<std::uint32_t, int>, std::uint64_t> copies_left_;
  std::map<RejectionReason, std::uint64_t> rejected_outside_;  // refused before an episode
  // Malformed samples by (sensor, episode): how many, and why the first was refused.
  struct Refusals {
    std::uint64_t samples = 0;
    std::string first_detail;
  };
  std::map<std::pair<int, std::uint32_t>, Refusals> refusals_;
  // Which writer speaks for each sensor, per topic (first live writer wins).
  WriterClaims measurement_claims_, tally_claims_, status_claims_;
  std::set<std::uint64_t> refused_commands_;  // commands refused by right, recorded once each
  std::vector<report::FaultRecord> faults_;
  nlohmann::json traced_episodes_ = nlohmann::json::array();  // the first episodes' curves
  std::set<std::uint32_t> traced_versions_;  // ... and the versions in force at their start
  nlohmann::json stalls_ = nlohmann::json::array();  // stalls absorbed, for the report
  StallWatch stall_watch_;
  std::uint32_t episodes_planned_ = 0;
  std::uint64_t waiting_ = 0;  // measurements that arrived since the last tick
  std::int64_t next_state_ns_ = 0;
};

}  // namespace sensornet::emulator
