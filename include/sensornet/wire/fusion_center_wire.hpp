#pragma once
// What `fusion_center serve` holds of DDS, without the loop that carries it: its endpoints,
// each topic with its QoS and partition; the WriterFacts the core asks about (who speaks for
// which sensor, whose writers still live), answered from the readers; the Report instances kept
// registered; the FusionState sample.
//
//   FusionCenterEndpoints dds(run.domainConfig(), /*reference=*/false);
//   FusionCenterCore core(config, dds.facts, now);
//   if (!dds.present() && core.holdsEverySensorProcess()) dds.makePresent();
//   dds.report_writer->write(sample);
//   report_instances.written(*dds.report_writer, episode);  // unregisters the oldest
//   dds.state_writer->write(fusionStateSample(run_id, action, values, now));

#include <cstdint>
#include <deque>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "sensornet/dds/domain.hpp"
#include "sensornet/dds/matched_endpoints.hpp"
#include "sensornet/dds/participant.hpp"
#include "sensornet/dds/reader.hpp"
#include "sensornet/dds/topics.hpp"
#include "sensornet/dds/waitset.hpp"
#include "sensornet/dds/writer.hpp"
#include "sensornet/emulator/fusion_center_core.hpp"
#include "sensornet/wire/run_inputs.hpp"
#include "sensornet/wire/sensor_speakers.hpp"

namespace sensornet::wire {

// What the core asks of DDS, answered from the Measurement, EpisodeTally and SensorStatus
// readers. Who speaks for a sensor is looked up in the main loop, the first time a writer's
// sample comes to the core, never in Cyclone's receive thread (sensor_speakers.hpp). A writer
// gone before its first sample reaches the core (a process killed within milliseconds of
// writing) speaks for no sensor: its samples are refused, never taken on trust.
class ReaderFacts final : public emulator::WriterFacts {
 public:
  ReaderFacts(const dds::detail::ReaderCore& measurements, const dds::detail::ReaderCore& tallies,
              const dds::detail::ReaderCore& statuses, std::string run_partition)
      : measurements_(measurements),
        tallies_(tallies),
        statuses_(statuses),
        speakers_(std::move(run_partition)) {}

  [[nodiscard]] const std::vector<int>& sensorsOf(emulator::SensorTopic topic,
                                                  emulator::WriterId w) const override;
  [[nodiscard]] bool live(emulator::SensorTopic topic, emulator::WriterId w) const override;
  [[nodiscard]] std::uint32_t matchedMeasurementWriters() const override;
  // Whether the Measurement and EpisodeTally readers have each matched a writer of the process
  // (participant) of `status_writer`.
  [[nodiscard]] bool writersMatchedWith(emulator::WriterId status_writer) const override;

 private:
  [[nodiscard]] const dds::detail::ReaderCore& readerOf(emulator::SensorTopic topic) const;

  const dds::detail::ReaderCore& measurements_;
  const dds::detail::ReaderCore& tallies_;
  const dds::detail::ReaderCore& statuses_;
  mutable SensorSpeakers speakers_;                 // main thread only
  mutable dds::MatchedWriterParticipants measurement_processes_;  // likewise
  mutable dds::MatchedWriterParticipants tally_processes_;
};

// The Report topic keeps the last report of each episode for late joiners: an instance per
// episode, held by the writer and by every reader until it is unregistered. Only the latest
// `kept` stay registered (a restarted coordinator needs the last one), so that memory does not
// grow with the number of episodes (with Cyclone 0.10 only if the unregistration also gives
// back the key Cyclone keeps of every instance written: unregisterWrittenInstance).
class ReportInstances {
 public:
  static constexpr std::size_t kKept = 64;
  explicit ReportInstances(std::string run_id) : run_id_(std::move(run_id)) {}
  // After `writer` wrote the Report of `episode`.
  void written(dds::Writer<sensornet_Report>& writer, std::uint32_t episode);

 private:
  std::string run_id_;
  std::deque<std::uint32_t> registered_;
};

// The DDS entities of `fusion_center serve`: the run's inputs (Scenario, Schedule,
// EpisodeControl); the Measurement, EpisodeTally and SensorStatus readers over every sensor
// process's partition (run_partitions.hpp: the partition a sample came in names the sensors its
// writer speaks for), created in this order and so announced to the sensors in it (the
// Measurement reader before the status reader: FusionCenterCore::sensorsLackingWriters relies on
// it); the CommandReply reader; the Report and FusionState writers, in the run's partition or,
// as the reference (`reference`), in P/reference, where neither the coordinator nor the
// launcher reads them. The waitset wakes on the inputs, tallies and statuses.
//
// The Report and FusionState writers are made by makePresent(), not with the rest: once they
// match, the coordinator counts this fusion center present and may start the first episode
// (docs/wire-protocol.md, "Fusion center"), so they wait until this process's readers
// hold every sensor process's writers (FusionCenterCore::holdsEverySensorProcess). A sensor's
// READY covers only its side: under DDS Security, and on a lossy link, this side can match
// seconds later, and a volatile reader never gets what was written before it matched.
struct FusionCenterEndpoints {
  FusionCenterEndpoints(const dds::DomainConfig& config, bool reference);
  FusionCenterEndpoints(const FusionCenterEndpoints&) = delete;
  FusionCenterEndpoints& operator=(const FusionCenterEndpoints&) = delete;

  void makePresent();
  [[nodiscard]] bool present() const { return report_writer.has_value(); }

  dds::Domain domain;
  dds::Participant participant;
  RunInputs inputs{participant};
  dds::Topic<sensornet_Measurement> measurement_topic{participant};
  dds::Topic<sensornet_EpisodeTally> tally_topic{participant};
  dds::Topic<sensornet_SensorStatus> status_topic{participant};
  dds::Topic<sensornet_Report> report_topic{participant};
  dds::Topic<sensornet_FusionState> state_topic{participant};
  dds::Reader<sensornet_Measurement> measurement_reader;
  dds::Reader<sensornet_EpisodeTally> tally_reader;
  dds::Reader<sensornet_SensorStatus> status_reader;
  dds::Topic<sensornet_CommandReply> reply_topic{participant};
  dds::Reader<sensornet_CommandReply> reply_reader{participant, reply_topic};
  std::optional<dds::Writer<sensornet_Report>> report_writer;       // makePresent()
  std::optional<dds::Writer<sensornet_FusionState>> state_writer;  // likewise
  // Clocks (docs/wire-protocol.md, "Clocks"): probes in P (P/reference for a reference, where
  // no sensor answers), the sensor processes' echoes from P/sensors/*.
  dds::Topic<sensornet_ClockProbe> probe_topic{participant};
  dds::Topic<sensornet_ClockEcho> echo_topic{participant};
  dds::Writer<sensornet_ClockProbe> probe_writer;
  dds::Reader<sensornet_ClockEcho> echo_reader;
  dds::WaitSet waitset{participant};
  dds::ReadCondition tally_ready{tally_reader};
  dds::ReadCondition status_ready{status_reader};
  dds::ReadCondition echo_ready{echo_reader};
  ReaderFacts facts{measurement_reader, tally_reader, status_reader, participant.partition()};

 private:
  bool reference_;
};

// Takes every Measurement the reader holds (in batches: a small one keeps the loan and its info
// array small) into `arrivals`, each batch stamped with the wall clock once taken (one thread
// hop after the wire, as in ddsperf; never before a sample came); logs a sensor whose writers are all gone. Returns how many were taken. Called
// in Cyclone's receive thread, from the reader's listener.
std::size_t takeArrivals(dds::Reader<sensornet_Measurement>& reader, std::string_view own_run,
                         std::vector<emulator::MeasurementArrival>& arrivals);

// The probes this fusion center sent lately, to know its own among the echoes (a reference
// fusion center reads the echoes of the run's probes too) and to take t1 from its own record.
class ClockProbes {
 public:
  static constexpr std::size_t kKept = 16;
  // Writes the next probe, stamped `now`.
  void send(dds::Writer<sensornet_ClockProbe>& writer, const std::string& run_id, std::int64_t now);
  // The echo decoded, when it answers a probe of ours; none for another's or a garbled one.
  [[nodiscard]] std::optional<emulator::ClockEcho> answerOf(const sensornet_ClockEcho& echo) const;

 private:
  std::uint32_t seq_ = 0;
  std::deque<std::pair<std::uint32_t, std::int64_t>> sent_;  // (seq, t1), the latest kKept
};

// The FusionState sample of `state` (its covariance's entries in `values`, which it borrows, as
// it borrows `run_id`), stamped `wall_time_ns`.
[[nodiscard]] sensornet_FusionState fusionStateSample(const std::string& run_id,
                                                      const emulator::PublishState& state,
                                                      std::vector<double>& values,
                                                      std::int64_t wall_time_ns);

}  // namespace sensornet::wire
