#include "sensor_agent.hpp"

#include <spdlog/spdlog.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <map>
#include <optional>
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
#include "sensornet/emulator/sensor_timeline.hpp"
#include "sensornet/emulator/stop_signal.hpp"
#include "sensornet/io/command_line.hpp"

namespace sensornet::sensor_agent {
namespace {

using namespace std::chrono_literals;
using emulator::wallNowNs;

constexpr auto kIdleWait = 20ms;

// The episode being emulated.
struct Episode {
  std::uint32_t number = 0;
  std::int64_t start_wall_ns = 0;
  double time_scale = 1.0;
  std::vector<emulator::TimedArrival> timeline;
  std::size_t next = 0;  // first arrival not yet published
  double last_published_s = -1.0;
  std::map<int, std::uint64_t> sent;  // per hosted sensor

  [[nodiscard]] double emulatedNow() const {
    return 1e-9 * static_cast<double>(wallNowNs() - start_wall_ns) * time_scale;
  }
};

class Agent {
 public:
  explicit Agent(const AgentOptions& options)
      : options_(options),
        domain_(options.run.domainConfig()),
        participant_(domain_),
        scenario_topic_(participant_),
        schedule_topic_(participant_),
        control_topic_(participant_),
        measurement_topic_(participant_),
        status_topic_(participant_),
        scenario_reader_(participant_, scenario_topic_),
        schedule_reader_(participant_, schedule_topic_),
        control_reader_(participant_, control_topic_),
        measurement_writer_(participant_, measurement_topic_),
        status_writer_(participant_, status_topic_),
        waitset_(participant_),
        scenario_ready_(scenario_reader_),
        schedule_ready_(schedule_reader_),
        control_ready_(control_reader_) {
    waitset_.attach(scenario_ready_, 1);
    waitset_.attach(schedule_ready_, 2);
    waitset_.attach(control_ready_, 3);
  }

  int run() {
    publishStatus(sensornet_SENSOR_STARTING, "waiting for scenario and schedule");
    while (!emulator::stopRequested()) {
      const auto wait = untilNextArrival();
      (void)waitset_.wait(wait);
      readScenario();
      readSchedules();
      if (readControls()) {
        publishStatus(sensornet_SENSOR_STOPPED, "run shut down");
        (void)measurement_writer_.waitForAcks(2s);
        (void)status_writer_.waitForAcks(1s);
        return kExitOk;
      }
      if (episode_) publishDue();
      if (wallNowNs() >= next_status_ns_) publishStatus(currentState(), "");
    }
    publishStatus(sensornet_SENSOR_STOPPED, "stopped by a signal");
    return kExitFailure;
  }

 private:
  std::chrono::nanoseconds untilNextArrival() const {
    if (!episode_ || episode_->next >= episode_->timeline.size()) return kIdleWait;
    const double t = episode_->timeline[episode_->next].time_s;
    const auto due_ns = episode_->start_wall_ns +
                        static_cast<std::int64_t>(1e9 * t / episode_->time_scale);
    return std::clamp(std::chrono::nanoseconds(due_ns - wallNowNs()), std::chrono::nanoseconds(0),
                      std::chrono::nanoseconds(kIdleWait));
  }

  void readScenario() {
    for (auto& received : scenario_reader_.take(4).samples) {
      if (run_) continue;  // one scenario per run
      try {
        run_ = emulator::scenarioFromWire(*received.sample);
        const Scenario& s = run_->scenario;
        for (const int id : options_.sensors) {
          if (id >= s.sensorCount()) {
            throw InputError("--sensors", "sensors",
                             "ids below the scenario's M = " + std::to_string(s.sensorCount()) +
                                 ", got " + std::to_string(id));
          }
        }
        plant_.emplace(s, run_->seed);
        spdlog::info("scenario {} received: n = {}, M = {}, T = {} s", run_->digest, s.stateDim(),
                     s.sensorCount(), s.horizon_s);
      } catch (const InputError& error) {
        if (std::string(error.what()).find("--sensors") != std::string::npos) throw;
        ++rejected_;
        run_.reset();
        spdlog::warn("rejected a scenario sample: {}", error.what());
      }
    }
  }

  void readSchedules() {
    if (!run_) return;  // kept by the reader (transient local) until the scenario is known
    for (auto& received : schedule_reader_.take(32).samples) {
      try {
        emulator::ScheduleVersion v =
            emulator::scheduleFromWire(*received.sample, run_->scenario, run_->digest);
        const auto number = v.version;
        const auto episode = v.effective_episode;
        const double at = v.effective_time_s;
        if (book_.add(std::move(v)) == emulator::ScheduleBook::Outcome::Stale) {
          ++rejected_;
          spdlog::warn("refused stale schedule version {} (have {})", number,
                       book_.latest().version);
          continue;
        }
        spdlog::info("schedule version {} from episode {} at {} s", number, episode, at);
        onNewVersion(episode, at);
        publishStatus(currentState(), "");
      } catch (const InputError& error) {
        ++rejected_;
        spdlog::warn("rejected a schedule sample: {}", error.what());
      }
    }
  }

  // Re-plans the rest of the current episode; what was already published is unchanged.
  void onNewVersion(std::uint32_t episode, double at) {
    if (!episode_ || episode != episode_->number) return;
    if (at < episode_->last_published_s) {
      ++late_switches_;
      spdlog::warn("schedule switch at {} s arrived after {} s was already published", at,
                   episode_->last_published_s);
    }
    episode_->timeline = emulator::sensorTimeline(book_, *plant_, run_->seed, episode_->number,
                                                  options_.sensors, run_->scenario.horizon_s);
    episode_->next = static_cast<std::size_t>(
        std::upper_bound(episode_->timeline.begin(), episode_->timeline.end(),
                         episode_->last_published_s,
                         [](double t, const emulator::TimedArrival& a) { return t < a.time_s; }) -
        episode_->timeline.begin());
  }

  // Returns true on RUN_SHUTDOWN.
  bool readControls() {
    bool shutdown = false;
    for (auto& received : control_reader_.take(16).samples) {
      const sensornet_EpisodeControl& c = *received.sample;
      switch (c.command) {
        case sensornet_RUN_SHUTDOWN:
          shutdown = true;
          break;
        case sensornet_EPISODE_STOP:
          if (episode_ && episode_->number == c.episode) finishEpisode("stopped");
          break;
        case sensornet_EPISODE_START:
          pending_starts_.push_back(c);
          pending_starts_.back().run_id = nullptr;  // freed with the sample; not needed
          break;
      }
    }
    // A start can overtake the scenario or schedule (other topics): it waits for them.
    std::erase_if(pending_starts_,
                  [this](const sensornet_EpisodeControl& c) { return startEpisode(c); });
    return shutdown;
  }

  // False while the scenario or the schedule in force at the episode's start is missing.
  bool startEpisode(const sensornet_EpisodeControl& c) {
    if (!run_ || book_.inForce(c.episode, 0.0) == nullptr) return false;
    if (last_episode_ && c.episode <= *last_episode_) return true;  // a repeat (durability)
    if (!(c.time_scale > 0.0) || c.seed != run_->seed) {
      ++rejected_;
      spdlog::warn("rejected episode control {}: bad time scale or seed", c.episode);
      return true;
    }
    if (episode_) finishEpisode("overtaken by the next episode");
    Episode e;
    e.number = c.episode;
    e.start_wall_ns = c.start_wall_time_ns;
    e.time_scale = c.time_scale;
    e.timeline = emulator::sensorTimeline(book_, *plant_, run_->seed, c.episode, options_.sensors,
                                          run_->scenario.horizon_s);
    for (const int id : options_.sensors) e.sent[id] = 0;
    episode_ = std::move(e);
    last_episode_ = c.episode;
    publishStatus(sensornet_SENSOR_RUNNING, "");
    return true;
  }

  void publishDue() {
    Episode& e = *episode_;
    const double now = e.emulatedNow();
    while (e.next < e.timeline.size() && e.timeline[e.next].time_s <= now) {
      const emulator::TimedArrival& a = e.timeline[e.next];
      const std::uint64_t seq = e.sent[a.sensor]++;
      const Eigen::VectorXd z =
          plant_->measure(plant_->stateAt(e.number, a.tick), a.sensor, e.number, seq);
      publishMeasurement(a.sensor, e.number, seq, a.time_s, a.version, z);
      e.last_published_s = a.time_s;
      ++e.next;
      ++sent_total_;
    }
    if (now >= run_->scenario.horizon_s && e.next >= e.timeline.size()) finishEpisode("");
  }

  void finishEpisode(const char* why) {
    Episode& e = *episode_;
    for (const auto& [sensor, count] : e.sent) {
      publishMeasurement(sensor, e.number, count, run_->scenario.horizon_s,
                         book_.inForce(e.number, run_->scenario.horizon_s)->version,
                         Eigen::VectorXd());
    }
    if (*why != '\0') spdlog::info("episode {} ended early: {}", e.number, why);
    last_sent_in_episode_ = 0;
    for (const auto& [sensor, count] : e.sent) last_sent_in_episode_ += count;
    episode_.reset();
    publishStatus(sensornet_SENSOR_READY, "");
  }

  // A reliable write that timed out is retried: a measurement is never dropped.
  void publishMeasurement(int sensor, std::uint32_t episode, std::uint64_t seq, double t,
                          std::uint32_t version, const Eigen::VectorXd& z) {
    sensornet_Measurement m{};
    m.sensor_id = static_cast<std::uint32_t>(sensor);
    m.run_id = dds::borrowString(options_.run.run_id);
    m.episode = episode;
    m.seq = seq;
    m.emulated_time_s = t;
    m.schedule_version = version;
    dds::borrowSequence(m.z, std::span<const double>(z.data(), static_cast<std::size_t>(z.size())));
    for (;;) {
      m.publish_wall_time_ns = wallNowNs();
      if (measurement_writer_.write(m) == dds::WriteResult::Written) return;
      ++write_timeouts_;
      if (emulator::stopRequested()) return;
    }
  }

  [[nodiscard]] sensornet_SensorState currentState() const {
    if (episode_) return sensornet_SENSOR_RUNNING;
    if (run_ && !book_.empty()) return sensornet_SENSOR_READY;
    return sensornet_SENSOR_STARTING;
  }

  void publishStatus(sensornet_SensorState state, const std::string& detail) {
    next_status_ns_ = wallNowNs() + static_cast<std::int64_t>(1e9 * options_.status_period_s);
    for (const int id : options_.sensors) {
      const emulator::ScheduleVersion* v =
          book_.empty() ? nullptr
                        : book_.inForce(episode_ ? episode_->number : last_episode_.value_or(0),
                                        episode_ ? std::max(0.0, episode_->emulatedNow()) : 0.0);
      double rate = 0.0;
      if (v != nullptr && run_) {
        const double t = episode_ ? std::clamp(episode_->emulatedNow(), 0.0,
                                               run_->scenario.horizon_s)
                                  : 0.0;
        rate = v->schedule.rateAt(t, id);
      }
      const sensornet_SensorState shown =
          state == sensornet_SENSOR_READY && v != nullptr && v->schedule.rates().col(id).isZero()
              ? sensornet_SENSOR_EXCLUDED
              : state;
      sensornet_SensorStatus s{};
      s.sensor_id = static_cast<std::uint32_t>(id);
      s.run_id = dds::borrowString(options_.run.run_id);
      s.state = shown;
      s.episode = episode_ ? episode_->number : last_episode_.value_or(0);
      s.schedule_version = v != nullptr ? v->version : 0;
      s.current_rate_hz = rate;
      s.sent_in_episode = episode_ ? episode_->sent.at(id) : 0;
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
  dds::Topic<sensornet_Scenario> scenario_topic_;
  dds::Topic<sensornet_Schedule> schedule_topic_;
  dds::Topic<sensornet_EpisodeControl> control_topic_;
  dds::Topic<sensornet_Measurement> measurement_topic_;
  dds::Topic<sensornet_SensorStatus> status_topic_;
  dds::Reader<sensornet_Scenario> scenario_reader_;
  dds::Reader<sensornet_Schedule> schedule_reader_;
  dds::Reader<sensornet_EpisodeControl> control_reader_;
  dds::Writer<sensornet_Measurement> measurement_writer_;
  dds::Writer<sensornet_SensorStatus> status_writer_;
  dds::WaitSet waitset_;
  dds::ReadCondition scenario_ready_;
  dds::ReadCondition schedule_ready_;
  dds::ReadCondition control_ready_;

  std::optional<emulator::RunScenario> run_;
  std::optional<EmulatedPlant> plant_;
  emulator::ScheduleBook book_;
  std::optional<Episode> episode_;
  std::optional<std::uint32_t> last_episode_;
  std::vector<sensornet_EpisodeControl> pending_starts_;  // run_id cleared
  std::uint64_t sent_total_ = 0;
  std::uint64_t last_sent_in_episode_ = 0;
  std::uint64_t write_timeouts_ = 0;
  std::uint64_t rejected_ = 0;
  std::uint64_t late_switches_ = 0;
  std::int64_t next_status_ns_ = 0;
};

}  // namespace

int runSensorAgent(const AgentOptions& options) {
  emulator::installStopSignals();
  Agent agent(options);
  return agent.run();
}

}  // namespace sensornet::sensor_agent
