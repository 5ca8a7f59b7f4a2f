#include "sensor_agent.hpp"

#include <spdlog/spdlog.h>
#include <unistd.h>

#include <csignal>
#include <cstdio>
#include <chrono>
#include <span>
#include <string>
#include <vector>

#include "sensornet/dds/participant.hpp"
#include "sensornet/dds/reader.hpp"
#include "sensornet/dds/topics.hpp"
#include "sensornet/dds/waitset.hpp"
#include "sensornet/dds/wire.hpp"
#include "sensornet/dds/writer.hpp"
#include "sensornet/wire/messages.hpp"
#include "sensornet/wire/run_inputs.hpp"
#include "sensornet/emulator/run_partitions.hpp"
#include "sensornet/emulator/sensor_agent_core.hpp"
#include "sensornet/emulator/stop_signal.hpp"

namespace sensornet::sensor_agent {
namespace {

using namespace std::chrono_literals;
using emulator::wallNowNs;

// Between events the loop still wakes this often: to publish its status and to notice its own
// stalls (StallWatch's slack is 0.5 s). Hundreds of idle agents share two cores: 20 ms cost 0.6%
// of a core each.
constexpr auto kIdleWait = 100ms;

// The wiring of emulator::SensorAgentCore: the run's inputs and the three writers over DDS, and
// a loop that feeds the core and carries out what it decides.
class Agent {
 public:
  explicit Agent(const AgentOptions& options)
      : options_(options),
        domain_(batching(options.run.domainConfig(dds::DiscoveryRole::Leaf))),
        participant_(domain_),
        inputs_(participant_),
        measurement_topic_(participant_),
        tally_topic_(participant_),
        status_topic_(participant_),
        // In its own block's partition: the identity it speaks for its sensors with
        // (emulator/run_partitions.hpp).
        own_partition_(emulator::sensorPartition(participant_.partition(), options.sensors)),
        measurement_writer_(participant_, measurement_topic_,
                            dds::endpointQosIn<sensornet_Measurement>(own_partition_)),
        tally_writer_(participant_, tally_topic_,
                      dds::endpointQosIn<sensornet_EpisodeTally>(own_partition_)),
        status_writer_(participant_, status_topic_,
                       dds::endpointQosIn<sensornet_SensorStatus>(own_partition_)),
        probe_topic_(participant_),
        echo_topic_(participant_),
        probe_reader_(participant_, probe_topic_),
        echo_writer_(participant_, echo_topic_,
                     dds::endpointQosIn<sensornet_ClockEcho>(own_partition_)),
        waitset_(participant_),
        probe_ready_(probe_reader_),
        core_({options.sensors, options.status_period_s}, inputs_.state()),
        process_name_(processName()) {
    inputs_.attachTo(waitset_);
    waitset_.attach(probe_ready_, kProbeToken);
    for (const int j : options.sensors) echo_sensors_.push_back(static_cast<std::uint32_t>(j));
  }

  int run() {
    carryOut(core_.start(wallNowNs()));
    while (!core_.exitCode()) {
      if (emulator::stopRequested()) {
        carryOut(core_.onStopSignal(wallNowNs()));
        break;
      }
      (void)waitset_.wait(core_.untilNextEvent(wallNowNs(), kIdleWait));
      answerProbes();
      core_.onDiscovery({inputs_.controlMatched(), measurement_writer_.matchedReaders() > 0,
                         tally_writer_.matchedReaders() > 0});
      carryOut(core_.onInputs(inputs_.poll(), wallNowNs()));
      carryOut(core_.tick(wallNowNs()));
    }
    return *core_.exitCode();
  }

 private:
  static constexpr dds_attach_t kProbeToken = 2001;

  // "sensor_agent 4711@edge-1": unique in the run while the process lives.
  static std::string processName() {
    char host[256] = {};
    if (::gethostname(host, sizeof host - 1) != 0) host[0] = '\0';
    return "sensor_agent " + std::to_string(::getpid()) + "@" + host;
  }

  // The fusion center's clock probes, answered at once (docs/wire-protocol.md, "Clocks"): t2
  // when taken, t3 just before the write. Best-effort: a lost answer costs nothing.
  void answerProbes() {
    for (auto& received : probe_reader_.take(4).samples) {
      const sensornet_ClockProbe& probe = *received.sample;
      const std::int64_t taken_ns = wallNowNs();
      if (dds::viewString(probe.run_id) != options_.run.run_id) continue;
      sensornet_ClockEcho echo{};
      echo.run_id = dds::borrowString(options_.run.run_id);
      echo.process = dds::borrowString(process_name_);
      dds::borrowSequence(echo.sensor_ids, echo_sensors_);
      echo.probe_seq = probe.seq;
      echo.probe_sent_wall_time_ns = probe.sent_wall_time_ns;
      echo.received_wall_time_ns = taken_ns;
      echo.sent_wall_time_ns = wallNowNs();
      (void)echo_writer_.write(echo);
    }
  }

  // The measurements of one call fell due together (all at or before now): they share packets,
  // sent when the last is written. Under load a wake finds several due, and one sendmsg instead
  // of one each is most of the agent's CPU and of the fusion center's receive thread
  // (bench/README.md, "Issue 28, third step").
  void carryOut(const emulator::SensorAgentActions& actions) {
    const auto burst = measurement_writer_.burst();
    for (const emulator::SensorAgentAction& action : actions) std::visit(*this, action);
  }

  static dds::DomainConfig batching(dds::DomainConfig config) {
    config.write_batching = true;
    return config;
  }

 public:  // the actions, for std::visit
  // A reliable write that timed out is retried: a measurement is never dropped (by DDS).
  void operator()(const emulator::PublishMeasurement& a) {
    const emulator::HeldMeasurement& held = a.measurement;
    sensornet_Measurement m{};
    m.sensor_id = static_cast<std::uint32_t>(held.sensor);
    m.run_id = dds::borrowString(options_.run.run_id);
    m.episode = a.episode;
    m.seq = held.seq;
    m.emulated_time_s = held.time_s;
    m.schedule_version = held.version;
    m.network_delay_s = held.delay_s;
    dds::borrowSequence(
        m.z, std::span<const double>(held.z.data(), static_cast<std::size_t>(held.z.size())));
    for (;;) {
      m.publish_wall_time_ns = wallNowNs();
      if (measurement_writer_.write(m) == dds::WriteResult::Written) return;
      core_.onWriteTimeout(wallNowNs());
      if (emulator::stopRequested()) return;
    }
  }

  // Reliable and kept (transient-local): retried like a measurement, never dropped.
  void operator()(const emulator::PublishTally& a) {
    sensornet_EpisodeTally t{};
    t.sensor_id = static_cast<std::uint32_t>(a.sensor);
    t.run_id = dds::borrowString(options_.run.run_id);
    t.episode = a.episode;
    t.sent = a.sent;
    t.dropped_by_network = a.dropped_by_network;
    t.duplicated_by_network = a.duplicated_by_network;
    t.finished = a.finished;
    t.write_timeouts = a.write_timeouts;
    t.max_lag_s = a.max_lag_s;
    t.stalled_s = a.stalled_s;
    t.process_id = static_cast<std::int32_t>(::getpid());
    t.wall_time_ns = a.wall_time_ns;
    while (tally_writer_.write(t) == dds::WriteResult::TimedOut) {
      core_.onWriteTimeout(wallNowNs());
      if (emulator::stopRequested()) break;
    }
  }

  void operator()(const emulator::PublishSensorStatus& a) {
    sensornet_SensorStatus s{};
    s.sensor_id = static_cast<std::uint32_t>(a.sensor);
    s.run_id = dds::borrowString(options_.run.run_id);
    s.state = wire::wireSensorState(a.state);
    s.episode = a.episode;
    s.schedule_version = a.schedule_version;
    s.current_rate_hz = a.current_rate_hz;
    s.sent_in_episode = a.sent_in_episode;
    s.sent_total = a.sent_total;
    s.write_timeouts = a.write_timeouts;
    s.process_id = static_cast<std::int32_t>(::getpid());
    s.wall_time_ns = a.wall_time_ns;
    s.detail = dds::borrowString(a.detail);
    if (status_writer_.write(s) == dds::WriteResult::TimedOut) core_.onWriteTimeout(wallNowNs());
  }

  void operator()(const emulator::LogLine& a) const { spdlog::log(a.level, "{}", a.text); }

  // Dies like kill -9: no clean DDS exit, no tally. What was written before goes out first.
  void operator()(const emulator::CrashProcess& /*crash*/) {
    measurement_writer_.flush();
    spdlog::default_logger()->flush();
    std::fflush(stderr);
    ::kill(::getpid(), SIGKILL);
  }

  void operator()(const emulator::LeaveRun& a) {
    if (!a.flush) return;
    (void)measurement_writer_.waitForAcks(2s);
    (void)tally_writer_.waitForAcks(2s);
    (void)status_writer_.waitForAcks(1s);
  }

 private:
  AgentOptions options_;
  dds::Domain domain_;
  dds::Participant participant_;
  wire::RunInputs inputs_;
  dds::Topic<sensornet_Measurement> measurement_topic_;
  dds::Topic<sensornet_EpisodeTally> tally_topic_;
  dds::Topic<sensornet_SensorStatus> status_topic_;
  std::string own_partition_;
  dds::Writer<sensornet_Measurement> measurement_writer_;
  dds::Writer<sensornet_EpisodeTally> tally_writer_;
  dds::Writer<sensornet_SensorStatus> status_writer_;
  dds::Topic<sensornet_ClockProbe> probe_topic_;
  dds::Topic<sensornet_ClockEcho> echo_topic_;
  dds::Reader<sensornet_ClockProbe> probe_reader_;
  dds::Writer<sensornet_ClockEcho> echo_writer_;
  dds::WaitSet waitset_;
  dds::ReadCondition probe_ready_;
  emulator::SensorAgentCore core_;
  std::string process_name_;
  std::vector<std::uint32_t> echo_sensors_;
};

}  // namespace

int runSensorAgent(const AgentOptions& options) {
  emulator::installStopSignals();
  Agent agent(options);
  return agent.run();
}

}  // namespace sensornet::sensor_agent
