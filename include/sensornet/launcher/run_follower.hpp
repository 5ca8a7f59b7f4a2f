#pragma once
// The one reader of a run's topics for `sensornet watch`, `sensornet status` and the launcher's
// progress lines: its own DDS participant in the run's domain and partition reads (never writes)
// Scenario, Schedule, EpisodeControl, SensorStatus and Report, decodes each sample of this run
// into the plain events of RunView (sensornet/launcher/run_view.hpp) and feeds them, stamped
// with the wall clock. Samples of another run are dropped. The run's end is seen on RUN_SHUTDOWN,
// or when the coordinator's episode controls lose their writer without one, whoever else is in
// the partition.
//
//   RunFollower follower(run.domainConfig());
//   RunView view(config);
//   while (!view.finished(wallNowNs())) follower.pollInto(view, 250ms);

#include <chrono>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <set>
#include <string>

#include "sensornet/dds/domain.hpp"
#include "sensornet/dds/participant.hpp"
#include "sensornet/dds/reader.hpp"
#include "sensornet/dds/topics.hpp"
#include "sensornet/dds/waitset.hpp"
#include "sensornet/emulator/run_report.hpp"
#include "sensornet/launcher/run_view.hpp"

namespace sensornet::launcher {

class RunFollower {
 public:
  explicit RunFollower(const dds::DomainConfig& config);

  // Waits up to `wait` for data, then hands everything new to `view`.
  void pollInto(RunView& view, std::chrono::milliseconds wait);
  // True if, within `wait`, a writer of the run's Scenario or (with `fusion_centers`) Report
  // topic matches: a coordinator or fusion center of this run id is alive in this domain and
  // partition. A launch that waits for an external fusion center asks only for coordinators:
  // the user's fusion center may well be there first.
  [[nodiscard]] bool seesLiveRun(std::chrono::milliseconds wait, bool fusion_centers = true) const;
  // From now on, appends every episode's Report (the first of each episode) to the episode log
  // at `path` as its per_episode entry (episodeEntryOfReport): the record of an external fusion
  // center's results, from which the launcher builds the run's report. A Report that does not
  // fit the scenario's `sensor_count` sensors is logged and counted, never recorded.
  void recordReportsTo(const std::filesystem::path& path, int sensor_count);
  [[nodiscard]] std::uint64_t reportsRefused() const noexcept { return reports_refused_; }
  // True once a writer of the run's Report topic was matched (an external fusion center came).
  [[nodiscard]] bool reportWriterSeen() const noexcept { return report_writer_seen_; }
  // Its participant, for other launcher entities of the run.
  [[nodiscard]] const dds::Participant& participant() const noexcept { return participant_; }

 private:
  void takeControls(RunView& view, std::int64_t now_ns);
  void takeStatuses(RunView& view, std::int64_t now_ns);
  void record(const sensornet_Report& report);
  [[nodiscard]] bool ours(const char* run_id) const;

  std::string run_id_;  // from the partition "sensornet/<run id>"; empty: take every sample
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
  bool coordinator_seen_ = false;  // the episode controls had a writer
  bool report_writer_seen_ = false;
  std::unique_ptr<sensornet::report::EpisodeLog> record_;  // recordReportsTo
  int record_sensor_count_ = 0;
  std::set<std::uint32_t> recorded_;
  std::uint64_t reports_refused_ = 0;
};

}  // namespace sensornet::launcher
