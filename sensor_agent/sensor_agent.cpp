#include "sensor_agent.hpp"

#include <spdlog/spdlog.h>
#include <unistd.h>

#include <algorithm>
#include <csignal>
#include <cstdio>
#include <chrono>
#include <deque>
#include <map>
#include <optional>
#include <set>
#include <thread>

#include "sensornet/core/emulated_plant.hpp"
#include "sensornet/core/input_error.hpp"
#include "sensornet/dds/participant.hpp"
#include "sensornet/dds/reader.hpp"
#include "sensornet/dds/topics.hpp"
#include "sensornet/dds/waitset.hpp"
#include "sensornet/dds/wire.hpp"
#include "sensornet/dds/writer.hpp"
#include "sensornet/emulator/messages.hpp"
#include "sensornet/emulator/network_emulation.hpp"
#include "sensornet/emulator/run_inputs.hpp"
#include "sensornet/emulator/run_partitions.hpp"
#include "sensornet/emulator/sensor_timeline.hpp"
#include "sensornet/emulator/stall_watch.hpp"
#include "sensornet/emulator/stop_signal.hpp"
#include "sensornet/io/command_line.hpp"

namespace sensornet::sensor_agent {
namespace {

using namespace std::chrono_literals;
using emulator::wallNowNs;

// Between events the loop still wakes this often: to publish its status and to notice its own
// stalls (StallWatch's slack is 0.5 s). Hundreds of idle agents share two cores: 20 ms cost 0.6%
// of a core each.
constexpr auto kIdleWait = 100ms;

// A scripted crash (the scenario's `faults:`) of a hosted sensor in this episode.
struct ScriptedCrash {
  int sensor = 0;
  double at_s = 0.0;
};

// The episode being emulated.
struct Episode {
  std::uint32_t number = 0;
  emulator::EpisodeClock clock;
  std::vector<emulator::TimedArrival> timeline;
  std::size_t next = 0;  // first arrival not yet published
  double last_published_s = -1.0;
  std::map<int, std::uint64_t> sent;  // per live hosted sensor: every drawn arrival (its seq)
  std::map<int, std::uint64_t> dropped_by_network;     // of sent: never written
  std::map<int, std::uint64_t> duplicated_by_network;  // of sent: written twice
  emulator::DelayLine held;  // delayed by the emulated network, not yet written
  std::optional<ScriptedCrash> crash;
  double max_lag_s = 0.0;  // behind the emulated clock, own stalls left out
  // When its start reached this process: nothing is due before (a start the network delivered
  // late is the network's delay, not this sensor falling behind).
  std::int64_t known_from_ns = 0;
  std::uint64_t write_timeouts_at_start = 0;
};

class Agent {
 public:
  explicit Agent(const AgentOptions& options)
      : options_(options),
        domain_(options.run.domainConfig(dds::DiscoveryRole::Leaf)),
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
        waitset_(participant_) {
    inputs_.attachTo(waitset_);
  }

  int run() {
    publishStatus(sensornet_SENSOR_STARTING, "waiting for scenario and schedule");
    while (!emulator::stopRequested()) {
      const auto wait = untilNextEvent();
      (void)waitset_.wait(wait);
      noteOwnStall();
      if (follow()) {
        publishStatus(sensornet_SENSOR_STOPPED, "run shut down");
        (void)measurement_writer_.waitForAcks(2s);
        (void)tally_writer_.waitForAcks(2s);
        (void)status_writer_.waitForAcks(1s);
        return kExitOk;
      }
      if (episode_) publishDue();
      if (!episode_ && !pending_.empty()) startNextEpisode();
      const sensornet_SensorState state = currentState();
      if (wallNowNs() >= next_status_ns_ || state != last_state_) publishStatus(state, "");
    }
    publishStatus(sensornet_SENSOR_STOPPED, "stopped by a signal");
    return kExitFailure;
  }

 private:
  void noteOwnStall() {
    if (const auto stall = stall_watch_.tick(wallNowNs())) {
      spdlog::warn("this sensor agent was stalled for {:.3g} s", stall->seconds());
    }
  }

  // Until the next arrival, held-back measurement, scripted crash or the episode's end falls due
  // (at most the idle wait): the tally goes out as soon as the episode ends.
  std::chrono::nanoseconds untilNextEvent() const {
    if (!episode_) return kIdleWait;
    const Episode& e = *episode_;
    std::int64_t due_ns = wallNowNs() + std::chrono::nanoseconds(kIdleWait).count();
    if (e.next < e.timeline.size()) {
      due_ns = std::min(due_ns, e.clock.wallAt(e.timeline[e.next].time_s));
    } else {
      due_ns = std::min(due_ns, e.clock.wallAt(inputs_.scenario().horizon_s));
    }
    if (const auto held = e.held.nextDueWallNs()) due_ns = std::min(due_ns, *held);
    if (e.crash) due_ns = std::min(due_ns, e.clock.wallAt(e.crash->at_s));
    return std::clamp(std::chrono::nanoseconds(due_ns - wallNowNs()), std::chrono::nanoseconds(0),
                      std::chrono::nanoseconds(kIdleWait));
  }

  // Takes what the run announced; returns true on RUN_SHUTDOWN.
  bool follow() {
    const emulator::RunInputs::Update update = inputs_.poll();
    if (update.scenario_arrived) {
      for (const int id : options_.sensors) {
        if (id >= inputs_.scenario().sensorCount()) {
          throw InputError("--sensors", "sensors",
                           "ids below the scenario's M = " +
                               std::to_string(inputs_.scenario().sensorCount()) + ", got " +
                               std::to_string(id));
        }
      }
      const auto& network = inputs_.scenario().network;
      network_ = network && emulator::impairs(*network) ? &*network : nullptr;
    }
    const auto& versions = inputs_.book().versions();
    for (auto v = versions.end() - static_cast<std::ptrdiff_t>(update.new_versions);
         v != versions.end(); ++v) {
      onNewVersion(v->effective_episode, v->effective_time_s);
    }
    if (update.new_versions > 0) publishStatus(currentState(), "");
    for (const std::uint32_t episode : update.stops) {
      if (episode_ && episode_->number == episode) finishEpisode("stopped");
      std::erase_if(pending_, [&](const Announced& a) { return a.start.episode == episode; });
    }
    // The next episode is announced while this one runs: it starts once this one is finished.
    for (const emulator::EpisodeStart& start : update.starts) {
      pending_.push_back({start, wallNowNs()});
    }
    return update.shutdown;
  }

  // Re-plans the rest of the current episode; what was already published is unchanged.
  void onNewVersion(std::uint32_t episode, double at) {
    if (!episode_ || episode != episode_->number) return;
    if (at < episode_->last_published_s) {
      spdlog::warn("schedule switch at {} s arrived after {} s was already published", at,
                   episode_->last_published_s);
    }
    episode_->timeline = timelineOf(episode_->number);
    episode_->next = static_cast<std::size_t>(
        std::upper_bound(episode_->timeline.begin(), episode_->timeline.end(),
                         episode_->last_published_s,
                         [](double t, const emulator::TimedArrival& a) { return t < a.time_s; }) -
        episode_->timeline.begin());
  }

  [[nodiscard]] std::vector<emulator::TimedArrival> timelineOf(std::uint32_t episode) const {
    return emulator::sensorTimeline(inputs_.book(), inputs_.plant(), inputs_.run().seed, episode,
                                    live_sensors_, inputs_.scenario().horizon_s,
                                    inputs_.scenario().arrivals);
  }

  // The hosted sensors the coordinator has not declared dead (they publish nothing, no tally).
  void noteFailedSensors(const std::set<int>& failed) {
    live_sensors_.clear();
    for (const int id : options_.sensors) {
      if (failed.count(id) == 0) {
        live_sensors_.push_back(id);
      } else {
        spdlog::warn("sensor {} was declared failed: it publishes nothing more", id);
      }
    }
  }

  // The earliest scripted crash of a live hosted sensor in `episode`.
  [[nodiscard]] std::optional<ScriptedCrash> crashIn(std::uint32_t episode) const {
    std::optional<ScriptedCrash> first;
    for (const CrashFault& fault : inputs_.scenario().faults) {
      const bool hosted = std::find(live_sensors_.begin(), live_sensors_.end(), fault.sensor) !=
                          live_sensors_.end();
      if (hosted && fault.episode == episode && (!first || fault.at_s < first->at_s)) {
        first = ScriptedCrash{fault.sensor, fault.at_s};
      }
    }
    return first;
  }

  // The episode announced next: its timeline is drawn now (its clock may not have started yet;
  // nothing is published before its arrivals fall due). A version that arrives before its
  // start and takes effect in it redraws the timeline (onNewVersion).
  void startNextEpisode() {
    const emulator::EpisodeStart start = pending_.front().start;
    const std::int64_t learned_ns = pending_.front().learned_ns;
    pending_.pop_front();
    std::set<int> failed = start.failed_sensors;  // and those a notice named since
    failed.insert(inputs_.failedSensors().begin(), inputs_.failedSensors().end());
    noteFailedSensors(failed);
    Episode e;
    e.number = start.episode;
    e.clock = start.clock;
    e.timeline = timelineOf(start.episode);
    for (const int id : live_sensors_) e.sent[id] = 0;
    e.crash = crashIn(start.episode);
    e.write_timeouts_at_start = write_timeouts_;
    e.known_from_ns = learned_ns;
    if (const double late_s = 1e-9 * static_cast<double>(learned_ns - e.clock.wallAt(0.0));
        late_s > 0.1) {
      spdlog::warn("episode {}: its start reached this process {:.3f} s after it began (the "
                   "network's delay; what fell due meanwhile goes out now)",
                   e.number, late_s);
    }
    episode_ = std::move(e);
    publishStatus(sensornet_SENSOR_RUNNING, "");
  }

  void publishDue() {
    Episode& e = *episode_;
    const double now = e.clock.emulatedNow();
    while (e.next < e.timeline.size() && e.timeline[e.next].time_s <= now) {
      const emulator::TimedArrival& a = e.timeline[e.next];
      crashIfDue(e, a.time_s);  // a crash at or before this arrival comes first
      transmit(e, a);
      noteLag(e, a.time_s);
      e.last_published_s = a.time_s;
      ++e.next;
      ++sent_total_;
    }
    crashIfDue(e, now);
    writeHeld(e.held.takeDue(wallNowNs()));
    if (now >= inputs_.scenario().horizon_s && e.next >= e.timeline.size() && e.held.empty()) {
      finishEpisode("");
    }
  }

  // One drawn arrival through the emulated network: it takes its seq whatever happens to it;
  // dropped, it is only counted; delayed, it waits in the delay line; otherwise it is written
  // now (twice when duplicated). Without a network it is written now, as always.
  void transmit(Episode& e, const emulator::TimedArrival& a) {
    const std::uint64_t seq = e.sent[a.sensor]++;
    const emulator::NetworkDecision fate =
        network_ != nullptr ? emulator::decideDelivery(*network_, inputs_.run().seed, a.sensor,
                                                       e.number, seq, a.time_s)
                            : emulator::NetworkDecision{};
    if (fate.dropped()) {
      ++e.dropped_by_network[a.sensor];
      return;
    }
    const EmulatedPlant& plant = inputs_.plant();
    emulator::HeldMeasurement m{a.sensor, seq, a.time_s, a.version,
                                plant.measure(plant.stateAt(e.number, a.tick), a.sensor,
                                              e.number, seq),
                                fate.delay_s};
    const int copies = fate.duplicated ? 2 : 1;
    if (fate.duplicated) ++e.duplicated_by_network[a.sensor];
    if (fate.delay_s > 0.0) {
      e.held.hold(e.clock.wallAt(a.time_s + fate.delay_s), std::move(m), copies);
      return;
    }
    for (int copy = 0; copy < copies; ++copy) publishMeasurement(e.number, m);
  }

  void writeHeld(const std::vector<emulator::HeldMeasurement>& due) {
    for (const emulator::HeldMeasurement& m : due) publishMeasurement(episode_->number, m);
  }

  // The scenario's scripted crash, once its instant has come by `time_s`: what the network
  // held until then goes out, one line is logged, and the process dies like kill -9 (no clean
  // DDS exit, no tally).
  void crashIfDue(Episode& e, double time_s) {
    if (!e.crash || e.crash->at_s > time_s) return;
    writeHeld(e.held.takeDue(e.clock.wallAt(e.crash->at_s)));
    spdlog::error("scripted crash of sensor {} at {} s of episode {}", e.crash->sensor,
                  e.crash->at_s, e.number);
    spdlog::default_logger()->flush();
    std::fflush(stderr);
    ::kill(::getpid(), SIGKILL);
  }

  // How far behind the emulated clock a measurement went out, leaving out the time this
  // process was stalled since it fell due (a stall is not overload) and the time before its
  // episode's start reached it (the network's delay, not this process falling behind).
  void noteLag(Episode& e, double time_s) {
    const std::int64_t now = wallNowNs();
    noteOwnStall();
    const std::int64_t due = std::max(e.clock.wallAt(time_s), e.known_from_ns);
    if (now <= due) return;
    const double lag = 1e-9 * static_cast<double>(now - due) - stall_watch_.stalledBetween(due, now);
    e.max_lag_s = std::max(e.max_lag_s, lag);
  }

  // Publishes each hosted sensor's tally of the episode (`why` empty: it ran to T).
  void finishEpisode(const char* why) {
    Episode& e = *episode_;
    if (!e.held.empty()) {  // ended early: what the network still held goes out now
      spdlog::info("episode {}: writing {} measurements the network still held", e.number,
                   e.held.size());
      writeHeld(e.held.takeAll());
    }
    const std::int64_t now = wallNowNs();
    const double stalled_s = stall_watch_.stalledBetween(e.clock.start_wall_ns, now);
    for (const auto& [sensor, count] : e.sent) {
      sensornet_EpisodeTally t{};
      t.sensor_id = static_cast<std::uint32_t>(sensor);
      t.run_id = dds::borrowString(options_.run.run_id);
      t.episode = e.number;
      t.sent = count;
      t.dropped_by_network = e.dropped_by_network[sensor];
      t.duplicated_by_network = e.duplicated_by_network[sensor];
      t.finished = *why == '\0';
      t.write_timeouts = write_timeouts_ - e.write_timeouts_at_start;
      t.max_lag_s = e.max_lag_s;
      t.stalled_s = stalled_s;
      t.process_id = static_cast<std::int32_t>(::getpid());
      t.wall_time_ns = now;
      // Reliable and kept (transient-local): retried like a measurement, never dropped.
      while (tally_writer_.write(t) == dds::WriteResult::TimedOut) {
        ++write_timeouts_;
        if (emulator::stopRequested()) break;
      }
    }
    if (*why != '\0') spdlog::info("episode {} ended early: {}", e.number, why);
    stall_watch_.forgetBefore(e.clock.start_wall_ns);
    episode_.reset();
    if (pending_.empty()) publishStatus(sensornet_SENSOR_READY, "");  // else running on
  }

  // A reliable write that timed out is retried: a measurement is never dropped (by DDS).
  void publishMeasurement(std::uint32_t episode, const emulator::HeldMeasurement& held) {
    sensornet_Measurement m{};
    m.sensor_id = static_cast<std::uint32_t>(held.sensor);
    m.run_id = dds::borrowString(options_.run.run_id);
    m.episode = episode;
    m.seq = held.seq;
    m.emulated_time_s = held.time_s;
    m.schedule_version = held.version;
    m.network_delay_s = held.delay_s;
    dds::borrowSequence(
        m.z, std::span<const double>(held.z.data(), static_cast<std::size_t>(held.z.size())));
    for (;;) {
      m.publish_wall_time_ns = wallNowNs();
      if (measurement_writer_.write(m) == dds::WriteResult::Written) return;
      ++write_timeouts_;
      noteOwnStall();
      if (emulator::stopRequested()) return;
    }
  }

  // Ready once it has the scenario and a schedule, its measurement and tally writers have
  // matched a reader (the fusion center's): a measurement written before the match would not
  // reach a volatile reader, and its episode-control reader has matched the coordinator's
  // writer: a reader that matches late gets only the latest announcement. (On a lossy link
  // discovery can lag the scenario by seconds, and endpoints are announced one by one.)
  [[nodiscard]] sensornet_SensorState currentState() const {
    if (episode_) return sensornet_SENSOR_RUNNING;
    if (inputs_.hasScenario() && !inputs_.book().empty() && inputs_.controlMatched() &&
        measurement_writer_.matchedReaders() > 0 && tally_writer_.matchedReaders() > 0) {
      return sensornet_SENSOR_READY;
    }
    return sensornet_SENSOR_STARTING;
  }

  void publishStatus(sensornet_SensorState state, const std::string& detail) {
    last_state_ = state;
    next_status_ns_ = wallNowNs() + static_cast<std::int64_t>(1e9 * options_.status_period_s);
    // The version in force now, or between episodes the one the next episode starts with (the
    // same for every hosted sensor).
    const std::optional<std::uint32_t> last = inputs_.lastStarted();
    const std::uint32_t episode = episode_ ? episode_->number : last.value_or(0);
    const std::uint32_t in_force_episode = episode_ ? episode : (last ? *last + 1 : 0);
    const emulator::ScheduleVersion* v = nullptr;
    double t = 0.0;
    if (inputs_.hasScenario() && !inputs_.book().empty()) {
      if (episode_) {
        t = std::clamp(episode_->clock.emulatedNow(), 0.0, inputs_.scenario().horizon_s);
      }
      v = inputs_.book().inForce(in_force_episode, t);
    }
    for (const int id : options_.sensors) {
      const double rate = v != nullptr ? v->schedule.rateAt(t, id) : 0.0;
      // Excluded: the version in force gives it no rate at all, from where the version took
      // effect (a sensor a plan merely leaves idle late in an episode is still running).
      bool excluded_by_version = false;
      if (v != nullptr) {
        const RateSchedule& schedule = v->schedule;
        const int first =
            v->effective_episode == in_force_episode ? schedule.intervalAt(v->effective_time_s)
                                                     : 0;
        excluded_by_version = schedule.rates().col(id).tail(schedule.intervals() - first).isZero();
      }
      const bool live = state == sensornet_SENSOR_READY || state == sensornet_SENSOR_RUNNING;
      const sensornet_SensorState shown =
          live && excluded_by_version ? sensornet_SENSOR_EXCLUDED : state;
      sensornet_SensorStatus s{};
      s.sensor_id = static_cast<std::uint32_t>(id);
      s.run_id = dds::borrowString(options_.run.run_id);
      s.state = shown;
      s.episode = episode;
      s.schedule_version = v != nullptr ? v->version : 0;
      s.current_rate_hz = rate;
      const bool counted = episode_ && episode_->sent.count(id) > 0;
      s.sent_in_episode = counted ? episode_->sent.at(id) : 0;
      s.sent_total = sent_total_;
      s.write_timeouts = write_timeouts_;
      s.process_id = static_cast<std::int32_t>(::getpid());
      s.wall_time_ns = wallNowNs();
      s.detail = dds::borrowString(detail);
      if (status_writer_.write(s) == dds::WriteResult::TimedOut) ++write_timeouts_;
    }
  }

  AgentOptions options_;
  dds::Domain domain_;
  dds::Participant participant_;
  emulator::RunInputs inputs_;
  dds::Topic<sensornet_Measurement> measurement_topic_;
  dds::Topic<sensornet_EpisodeTally> tally_topic_;
  dds::Topic<sensornet_SensorStatus> status_topic_;
  std::string own_partition_;
  dds::Writer<sensornet_Measurement> measurement_writer_;
  dds::Writer<sensornet_EpisodeTally> tally_writer_;
  dds::Writer<sensornet_SensorStatus> status_writer_;
  dds::WaitSet waitset_;
  emulator::StallWatch stall_watch_;

  std::optional<Episode> episode_;
  struct Announced {
    emulator::EpisodeStart start;
    std::int64_t learned_ns = 0;  // when the start reached this process
  };
  std::deque<Announced> pending_;  // announced, to run after the current one
  std::vector<int> live_sensors_ = options_.sensors;
  const NetworkSpec* network_ = nullptr;  // the scenario's, when it impairs anything
  std::uint64_t sent_total_ = 0;
  std::uint64_t write_timeouts_ = 0;
  std::int64_t next_status_ns_ = 0;
  sensornet_SensorState last_state_ = sensornet_SENSOR_STARTING;
};

}  // namespace

int runSensorAgent(const AgentOptions& options) {
  emulator::installStopSignals();
  Agent agent(options);
  return agent.run();
}

}  // namespace sensornet::sensor_agent
