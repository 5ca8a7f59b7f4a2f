#include "sensornet/wire/fusion_center_wire.hpp"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <iterator>
#include <limits>
#include <optional>

#include "sensornet/dds/matched_endpoints.hpp"
#include "sensornet/dds/wire.hpp"
#include "sensornet/emulator/run_partitions.hpp"
#include "sensornet/emulator/episode_controls.hpp"  // wallNowNs
#include "sensornet/wire/fusion_center_events.hpp"

namespace sensornet::wire {

const std::vector<int>& ReaderFacts::sensorsOf(emulator::SensorTopic topic,
                                               emulator::WriterId w) const {
  return speakers_.of(readerOf(topic), w);
}

bool ReaderFacts::live(emulator::SensorTopic topic, emulator::WriterId w) const {
  return readerOf(topic).matchesWriter(w);
}

const dds::detail::ReaderCore& ReaderFacts::readerOf(emulator::SensorTopic topic) const {
  switch (topic) {
    case emulator::SensorTopic::Measurement: return measurements_;
    case emulator::SensorTopic::Tally: return tallies_;
    case emulator::SensorTopic::Status: return statuses_;
  }
  return measurements_;
}

std::uint32_t ReaderFacts::matchedMeasurementWriters() const {
  return measurements_.matchedWriters();
}

bool ReaderFacts::writersMatchedWith(emulator::WriterId status_writer) const {
  const std::optional<dds::ParticipantKey> process =
      dds::participantOfMatchedWriter(statuses_, status_writer);
  if (!process) return false;
  const auto holds = [&process](const std::vector<dds::ParticipantKey>& participants) {
    return std::binary_search(participants.begin(), participants.end(), *process);
  };
  return holds(measurement_processes_.of(measurements_)) && holds(tally_processes_.of(tallies_));
}

void ReportInstances::written(dds::Writer<sensornet_Report>& writer, std::uint32_t episode) {
  registered_.push_back(episode);
  if (registered_.size() <= kKept) return;
  sensornet_Report key{};
  key.run_id = dds::borrowString(run_id_);
  key.episode = registered_.front();
  registered_.pop_front();
  (void)writer.unregisterWrittenInstance(key);  // a timeout keeps the report longer
}

namespace {

// The Report and FusionState writers' QoS: in the run's partition, or in P/reference.
dds::Qos outputQos(dds::Qos qos, const dds::Participant& participant, bool reference) {
  if (reference) qos.partition(emulator::referencePartition(participant.partition()));
  return qos;
}

}  // namespace

FusionCenterEndpoints::FusionCenterEndpoints(const dds::DomainConfig& config, bool reference)
    : domain(config),
      participant(domain),
      measurement_reader(participant, measurement_topic,
                         dds::readerQosMatching<sensornet_Measurement>(
                             emulator::sensorPartitionPattern(participant.partition()))),
      tally_reader(participant, tally_topic,
                   dds::readerQosMatching<sensornet_EpisodeTally>(
                       emulator::sensorPartitionPattern(participant.partition()))),
      status_reader(participant, status_topic,
                    dds::readerQosMatching<sensornet_SensorStatus>(
                        emulator::sensorPartitionPattern(participant.partition()))),
      probe_writer(participant, probe_topic,
                   outputQos(dds::defaultEndpointQos<sensornet_ClockProbe>(), participant,
                             reference)),
      echo_reader(participant, echo_topic,
                  dds::readerQosMatching<sensornet_ClockEcho>(
                      emulator::sensorPartitionPattern(participant.partition()))),
      reference_(reference) {
  inputs.attachTo(waitset);
  waitset.attach(tally_ready, 1);
  waitset.attach(status_ready, 2);
  waitset.attach(echo_ready, 3);
}

void FusionCenterEndpoints::makePresent() {
  if (present()) return;
  report_writer.emplace(participant, report_topic,
                        outputQos(dds::reportWriterQos(), participant, reference_));
  state_writer.emplace(participant, state_topic,
                       outputQos(dds::defaultEndpointQos<sensornet_FusionState>(), participant,
                                 reference_));
}

void ClockProbes::send(dds::Writer<sensornet_ClockProbe>& writer, const std::string& run_id,
                       std::int64_t now) {
  sensornet_ClockProbe probe{};
  probe.run_id = dds::borrowString(run_id);
  probe.seq = ++seq_;
  probe.sent_wall_time_ns = now;
  sent_.emplace_back(probe.seq, now);
  if (sent_.size() > kKept) sent_.pop_front();
  (void)writer.write(probe);  // best-effort: the next probe replaces a lost one
}

std::optional<emulator::ClockEcho> ClockProbes::answerOf(const sensornet_ClockEcho& echo) const {
  const auto ours = std::find_if(sent_.begin(), sent_.end(), [&echo](const auto& probe) {
    return probe.first == echo.probe_seq && probe.second == echo.probe_sent_wall_time_ns;
  });
  if (ours == sent_.end()) return std::nullopt;
  emulator::ClockEcho out;
  out.run_id = std::string(dds::viewString(echo.run_id));
  out.process = std::string(dds::viewString(echo.process));
  // An id beyond int's range reads as -1: not a sensor of the run, so the core refuses it.
  for (const std::uint32_t id : dds::viewSequence(echo.sensor_ids)) {
    out.sensors.push_back(id <= static_cast<std::uint32_t>(std::numeric_limits<int>::max())
                              ? static_cast<int>(id)
                              : -1);
  }
  out.probe_sent_ns = ours->second;
  out.probe_taken_ns = echo.received_wall_time_ns;
  out.answered_ns = echo.sent_wall_time_ns;
  return out;
}

sensornet_FusionState fusionStateSample(const std::string& run_id,
                                        const emulator::PublishState& state,
                                        std::vector<double>& values, std::int64_t wall_time_ns) {
  const Eigen::MatrixXd& P = state.covariance;
  values.assign(P.data(), P.data() + P.size());  // symmetric: order is moot
  sensornet_FusionState s{};
  s.run_id = dds::borrowString(run_id);
  s.episode = state.episode;
  s.emulated_time_s = state.emulated_time_s;
  s.state_dim = static_cast<std::uint32_t>(P.rows());
  dds::borrowSequence(s.covariance, values);
  s.schedule_version = state.schedule_version;
  s.wall_time_ns = wall_time_ns;
  return s;
}

std::size_t takeArrivals(dds::Reader<sensornet_Measurement>& reader, std::string_view own_run,
                         std::vector<emulator::MeasurementArrival>& arrivals) {
  constexpr std::size_t kBatch = 16;  // usually one sample a call
  std::size_t total = 0;
  for (;;) {
    const std::size_t first = arrivals.size();
    const std::size_t count = reader.takeEach(
        kBatch,
        [&](const sensornet_Measurement& m, const dds::SampleInfo& info) {
          arrivals.push_back(arrivalOfSample(m, 0, info.publication, own_run));
        },
        [](const sensornet_Measurement& key, const dds::SampleInfo& info) {
          if (info.instance_state == dds::InstanceState::NoWriters) {
            spdlog::info("sensor {} has no live writer at the moment", key.sensor_id);
          }
        });
    // Stamped once taken: a clock read before the take could precede a sample that came while
    // this thread waited for a core, and show a negative latency (a clock ahead that is not;
    // chaos seed 377 under load).
    const std::int64_t received_ns = emulator::wallNowNs();
    for (std::size_t i = first; i < arrivals.size(); ++i) {
      arrivals[i].measurement.receive_wall_ns = received_ns;
    }
    total += count;
    if (count < kBatch) return total;
  }
}

}  // namespace sensornet::wire
