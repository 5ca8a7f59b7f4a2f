#pragma once
// The words of a run, one type each, with their one spelling (core/words.hpp): what the report's
// `status`, a fault's `kind` and a rejection's reason say. Every program, the report writer and
// its readers, `--require`, `watch` and the page use these, never a free string:
//
//   faultEntry(FaultKind::Stall, ...);                  // {"kind": "stall", ...}
//   lookUpWord<RunStatus>(report["status"]) == RunStatus::Degraded
//   ++rejected[RejectionReason::ForeignWriter];         // counted as "foreign_writer"
//
// docs/ARCHITECTURE.md explains each word: when a fault of that kind is recorded, which status
// follows.

#include <array>

#include "sensornet/core/words.hpp"

namespace sensornet::emulator {

// The report's `status` (DESIGN's run-outcome table; exitCodeOf maps it to the exit code).
enum class RunStatus {
  Completed,    // every episode complete, every sent measurement fused, no fault: exit 0
  Degraded,     // every episode ran, but something was lost, rejected, late or survived: exit 3
  Failed,       // the run could not finish: exit 1
  Interrupted,  // a signal stopped it: exit 1
};

// A fault's `kind`: what happened, named once at its cause.
enum class FaultKind {
  // Seen by the fusion center.
  Stall,              // a sensor owed measurements and stayed silent past the stall limit
  Lost,               // measurements a tally counts never arrived
  Overload,           // the fusion center could not keep up (drain past the keep-up limit)
  SensorLag,          // a sensor published far behind the emulated clock
  LateTally,          // a tally came after its episode was closed without it
  // The network held sensors back past the stall limit: a count written before its episode was
  // closed arrived after (a cut link, a partition). Their stall and late_tally follow from it.
  NetworkPartition,
  // A sensor stamped measurements later than the fusion center received them, by more than the
  // clocks may disagree (kClockBoundS): its host's clock is ahead of the fusion center's.
  ClockOffset,
  Restarted,          // the fusion center was restarted and resumed from its episode log
  MissingEpisodes,    // the coordinator ran episodes the report does not hold
  Rejected,           // samples refused on the wire (the counts by reason are in `rejected`)
  ForeignWriter,      // a second writer claimed a sensor whose first writer lives
  WrongIdentity,      // a writer spoke for a sensor its identity (its partition) does not name
  CommandRefused,     // a Command its sender had no right to send (the coordinator refused it)
  CutShort,           // an episode was open when a signal stopped the run
  RunAborted,         // the coordinator gave up on the run
  // Seen by the launcher (the supervisor of the processes).
  ProcessFailed,      // a child exited with a non-zero status on its own
  ProcessKilled,      // a child was killed by a signal it was not sent by the launcher
  ProcessHung,        // a child stopped answering and was stopped
  Crash,              // a scripted crash of the scenario's `faults:`
  Interrupted,        // the launcher was told to stop (a signal)
  Timeout,            // the run did not end within --timeout
  ReportMissing,      // no readable report: it was rebuilt from the episode log
  ReportInvalid,      // the report says something the launcher cannot believe
  SensorDied,         // a sensor's process died (the failure policy then acts)
  RecordingIncomplete,  // --record could not write everything (a full disk): the file is short
  // A file of the run could not be written (a full disk): the detail names the file and the
  // cause, and where what it should have held went instead.
  WriteFailed,
};

// Why a sample on the wire was refused: counted by reason in the report's `rejected`, never
// part of `received`.
enum class RejectionReason {
  Malformed,                // z of the wrong size, a time outside [0, T], a bad delay
  UnknownSensor,            // a sensor id the scenario does not have
  Duplicate,                // a sequence number already fused
  NetworkDuplicate,         // a copy the emulated network made on purpose (not a fault)
  OtherRun,                 // a sample carrying another run's id
  FinishedEpisode,          // a sample of an episode already closed
  UnknownEpisode,           // a sample of an episode that never started
  ForeignWriter,            // a second writer for a sensor whose first writer lives
  MalformedTally,           // an EpisodeTally for a sensor the scenario does not have
  MalformedScenario,        // a Scenario sample that does not parse
  StaleSchedule,            // a Schedule version older than one in force
  MalformedSchedule,        // a Schedule sample that does not parse
  MalformedEpisodeControl,  // an EpisodeControl sample that does not parse
  BeyondTally,              // a sequence number at or past its sensor's tally: never sent by it
  WrongIdentity,            // from a writer whose identity (partition) does not name its sensor
  FailedSensor,             // a measurement of a sensor declared failed before its episode began
};

// What the coordinator does when the launcher reports that sensors died
// (`coordinator serve --on-sensor-failure`, `sensornet launch --on-sensor-failure`).
enum class FailurePolicy {
  Replan,    // re-plan the rest of the horizon among the survivors
  Continue,  // keep the schedule in force
  Stop,      // end the run as failed
};

// Who tells the coordinator that sensors died (`coordinator serve --sensor-deaths`).
enum class DeathWitness {
  Launcher,    // the launcher's failure notices: it sees its children exit
  Liveliness,  // no launcher (containers): a sensor's status writer that lost its liveliness
};

// A sensor's state as its SensorStatus says it ("starting", ..., what status and watch show).
enum class SensorState {
  Starting,  // waiting for scenario and schedule
  Ready,     // has both, waiting for an episode
  Running,   // publishing measurements of the current episode
  Excluded,  // rate zero by the schedule in force
  Stopped,   // left the run on request
  Failed,    // gave up; the reason is in the status's detail
};

}  // namespace sensornet::emulator

namespace sensornet {

template <>
struct Words<emulator::RunStatus> {
  using S = emulator::RunStatus;
  static constexpr std::array<WordOf<S>, 4> kTable{{{S::Completed, "completed"},
                                                    {S::Degraded, "degraded"},
                                                    {S::Failed, "failed"},
                                                    {S::Interrupted, "interrupted"}}};
};

template <>
struct Words<emulator::FaultKind> {
  using F = emulator::FaultKind;
  static constexpr std::array<WordOf<F>, 26> kTable{{{F::Stall, "stall"},
                                                     {F::Lost, "lost"},
                                                     {F::Overload, "overload"},
                                                     {F::SensorLag, "sensor_lag"},
                                                     {F::LateTally, "late_tally"},
                                                     {F::NetworkPartition, "network_partition"},
                                                     {F::ClockOffset, "clock_offset"},
                                                     {F::Restarted, "restarted"},
                                                     {F::MissingEpisodes, "missing_episodes"},
                                                     {F::Rejected, "rejected"},
                                                     {F::ForeignWriter, "foreign_writer"},
                                                     {F::WrongIdentity, "wrong_identity"},
                                                     {F::CommandRefused, "command_refused"},
                                                     {F::CutShort, "cut_short"},
                                                     {F::RunAborted, "run_aborted"},
                                                     {F::ProcessFailed, "process_failed"},
                                                     {F::ProcessKilled, "process_killed"},
                                                     {F::ProcessHung, "process_hung"},
                                                     {F::Crash, "crash"},
                                                     {F::Interrupted, "interrupted"},
                                                     {F::Timeout, "timeout"},
                                                     {F::ReportMissing, "report_missing"},
                                                     {F::ReportInvalid, "report_invalid"},
                                                     {F::SensorDied, "sensor_died"},
                                                     {F::RecordingIncomplete,
                                                      "recording_incomplete"},
                                                     {F::WriteFailed, "write_failed"}}};
};

template <>
struct Words<emulator::RejectionReason> {
  using R = emulator::RejectionReason;
  static constexpr std::array<WordOf<R>, 16> kTable{
      {{R::Malformed, "malformed"},
       {R::UnknownSensor, "unknown_sensor"},
       {R::Duplicate, "duplicate"},
       {R::NetworkDuplicate, "network_duplicate"},
       {R::OtherRun, "other_run"},
       {R::FinishedEpisode, "finished_episode"},
       {R::UnknownEpisode, "unknown_episode"},
       {R::ForeignWriter, "foreign_writer"},
       {R::MalformedTally, "malformed_tally"},
       {R::MalformedScenario, "malformed_scenario"},
       {R::StaleSchedule, "stale_schedule"},
       {R::MalformedSchedule, "malformed_schedule"},
       {R::MalformedEpisodeControl, "malformed_episode_control"},
       {R::BeyondTally, "beyond_tally"},
       {R::WrongIdentity, "wrong_identity"},
       {R::FailedSensor, "failed_sensor"}}};
};

}  // namespace sensornet

namespace sensornet {

template <>
struct Words<emulator::FailurePolicy> {
  using P = emulator::FailurePolicy;
  static constexpr std::array<WordOf<P>, 3> kTable{
      {{P::Replan, "replan"}, {P::Continue, "continue"}, {P::Stop, "stop"}}};
};

template <>
struct Words<emulator::DeathWitness> {
  using W = emulator::DeathWitness;
  static constexpr std::array<WordOf<W>, 2> kTable{
      {{W::Launcher, "launcher"}, {W::Liveliness, "liveliness"}}};
};

template <>
struct Words<emulator::SensorState> {
  using S = emulator::SensorState;
  static constexpr std::array<WordOf<S>, 6> kTable{{{S::Starting, "starting"},
                                                    {S::Ready, "ready"},
                                                    {S::Running, "running"},
                                                    {S::Excluded, "excluded"},
                                                    {S::Stopped, "stopped"},
                                                    {S::Failed, "failed"}}};
};

}  // namespace sensornet
