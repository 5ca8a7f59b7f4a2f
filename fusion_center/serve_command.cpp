#include "serve_command.hpp"

#include <spdlog/spdlog.h>

#include <chrono>
#include <map>
#include <memory>
#include <optional>

#include "sensornet/core/emulated_plant.hpp"
#include "sensornet/core/input_error.hpp"
#include "sensornet/dds/participant.hpp"
#include "sensornet/dds/reader.hpp"
#include "sensornet/dds/topics.hpp"
#include "sensornet/dds/waitset.hpp"
#include "sensornet/dds/wire.hpp"
#include "sensornet/dds/writer.hpp"
#include "sensornet/emulator/episode_fusion.hpp"
#include "sensornet/emulator/messages.hpp"
#include "sensornet/emulator/run_options.hpp"
#include "sensornet/emulator/run_report.hpp"
#include "sensornet/emulator/stop_signal.hpp"
#include "sensornet/io/scenario_file.hpp"

namespace sensornet::fusion_center {
namespace {

using namespace std::chrono_literals;
using emulator::wallNowNs;

struct ServeOptions {
  emulator::RunOptions run;
  std::string report_path;
  double lag_s = 0.05;          // wall seconds a measurement may take to arrive before fusion
  double grace_s = 5.0;         // wall seconds past T to wait for missing end markers
  double state_period_s = 0.05; // FusionState publication period (wall seconds)
  bool json = false;
};

// An episode in progress: its clock and its fusion.
struct OpenEpisode {
  std::int64_t start_wall_ns = 0;
  double time_scale = 1.0;
  std::unique_ptr<emulator::EpisodeFusion> fusion;
  [[nodiscard]] double emulatedAt(std::int64_t wall_ns) const {
    return 1e-9 * static_cast<double>(wall_ns - start_wall_ns) * time_scale;
  }
};

class FusionCenter {
 public:
  explicit FusionCenter(const ServeOptions& options)
      : options_(options),
        domain_(options.run.domainConfig()),
        participant_(domain_),
        scenario_topic_(participant_),
        schedule_topic_(participant_),
        control_topic_(participant_),
        measurement_topic_(participant_),
        report_topic_(participant_),
        state_topic_(participant_),
        scenario_reader_(participant_, scenario_topic_),
        schedule_reader_(participant_, schedule_topic_),
        control_reader_(participant_, control_topic_),
        measurement_reader_(participant_, measurement_topic_),
        report_writer_(participant_, report_topic_),
        state_writer_(participant_, state_topic_),
        waitset_(participant_),
        scenario_ready_(scenario_reader_),
        schedule_ready_(schedule_reader_),
        control_ready_(control_reader_),
        measurement_ready_(measurement_reader_) {
    waitset_.attach(scenario_ready_, 1);
    waitset_.attach(schedule_ready_, 2);
    waitset_.attach(control_ready_, 3);
    waitset_.attach(measurement_ready_, 4);
  }

  int run() {
    spdlog::info("fusion center of run {} waiting for the scenario", options_.run.run_id);
    bool shutdown = false;
    while (!shutdown && !emulator::stopRequested()) {
      (void)waitset_.wait(10ms);
      readMeasurements();  // first: the receive time is taken as soon as the wait returns
      readScenario();
      readSchedules();
      shutdown = readControls();
      advance();
    }
    // Finish what is open (incomplete episodes are marked so in the report).
    for (auto& [number, open] : open_) finishEpisode(open);
    open_.clear();
    const std::string status = shutdown ? "completed" : "interrupted";
    writeReport(status);
    (void)report_writer_.waitForAcks(2s);
    return shutdown ? kExitOk : kExitFailure;
  }

 private:
  void readScenario() {
    for (auto& received : scenario_reader_.take(4).samples) {
      if (run_) continue;
      try {
        run_ = emulator::scenarioFromWire(*received.sample);
        plant_.emplace(run_->scenario, run_->seed);
        report_.emplace(options_.run.run_id, run_->digest, run_->scenario.sensorCount(),
                        run_->scenario.stateDim());
        spdlog::info("scenario {}: n = {}, M = {}, T = {} s", run_->digest,
                     run_->scenario.stateDim(), run_->scenario.sensorCount(),
                     run_->scenario.horizon_s);
      } catch (const InputError& error) {
        ++rejected_wire_;
        spdlog::warn("rejected a scenario sample: {}", error.what());
      }
    }
  }

  void readSchedules() {
    if (!run_) return;
    for (auto& received : schedule_reader_.take(32).samples) {
      try {
        emulator::ScheduleVersion v =
            emulator::scheduleFromWire(*received.sample, run_->scenario, run_->digest);
        const auto number = v.version;
        if (book_.add(std::move(v)) == emulator::ScheduleBook::Outcome::Stale) {
          ++rejected_wire_;
          spdlog::warn("refused stale schedule version {}", number);
          continue;
        }
        spdlog::info("schedule version {} ({}) from episode {} at {} s", number,
                     book_.latest().surrogate, book_.latest().effective_episode,
                     book_.latest().effective_time_s);
        for (auto& [episode, open] : open_) open.fusion->scheduleChanged();
      } catch (const InputError& error) {
        ++rejected_wire_;
        spdlog::warn("rejected a schedule sample: {}", error.what());
      }
    }
  }

  bool readControls() {
    bool shutdown = false;
    for (auto& received : control_reader_.take(16).samples) {
      const sensornet_EpisodeControl& c = *received.sample;
      if (c.command == sensornet_RUN_SHUTDOWN) shutdown = true;
      if (c.command == sensornet_EPISODE_START) {
        pending_starts_.push_back({c.episode, c.start_wall_time_ns, c.time_scale});
      }
    }
    // A start can overtake the scenario or schedule (other topics): it waits for them.
    std::erase_if(pending_starts_, [this](const PendingStart& c) { return startEpisode(c); });
    return shutdown;
  }

  struct PendingStart {
    std::uint32_t episode;
    std::int64_t start_wall_time_ns;
    double time_scale;
  };

  // False while the scenario or the schedule in force at the episode's start is missing.
  bool startEpisode(const PendingStart& c) {
    if (!run_ || book_.inForce(c.episode, 0.0) == nullptr) return false;
    if (open_.count(c.episode) != 0 || (last_started_ && c.episode <= *last_started_)) return true;
    last_started_ = c.episode;
    OpenEpisode open;
    open.start_wall_ns = c.start_wall_time_ns;
    open.time_scale = c.time_scale > 0.0 ? c.time_scale : 1.0;
    open.fusion = std::make_unique<emulator::EpisodeFusion>(
        run_->scenario, *plant_, book_, c.episode,
        [this](const emulator::ScheduleVersion& v) { return bracketOf(v); });
    auto& slot = open_.emplace(c.episode, std::move(open)).first->second;
    // Measurements that came before the episode's control sample.
    if (auto early = early_.find(c.episode); early != early_.end()) {
      for (auto& m : early->second) route(slot, std::move(m));
      early_.erase(early);
    }
    return true;
  }

  CostBracket bracketOf(const emulator::ScheduleVersion& v) {
    auto it = brackets_.find(v.version);
    if (it == brackets_.end()) {
      it = brackets_.emplace(v.version, computeBracket(run_->scenario, v.schedule)).first;
    }
    return it->second;
  }

  void readMeasurements() {
    for (;;) {
      const std::int64_t received_ns = wallNowNs();
      const std::size_t count = measurement_reader_.takeEach(
          256,
          [this, received_ns](const sensornet_Measurement& m, const dds::SampleInfo&) {
            accept(m, received_ns);
          },
          [](const sensornet_Measurement& key, const dds::SampleInfo& info) {
            if (info.instance_state == dds::InstanceState::NoWriters) {
              spdlog::warn("sensor {} has no live writer any more", key.sensor_id);
            }
          });
      if (count < 256) return;
    }
  }

  void accept(const sensornet_Measurement& m, std::int64_t received_ns) {
    emulator::FusedMeasurement fused;
    fused.sensor = static_cast<int>(m.sensor_id);
    fused.seq = m.seq;
    fused.time_s = m.emulated_time_s;
    fused.version = m.schedule_version;
    const auto z = dds::viewSequence(m.z);
    fused.z = Eigen::Map<const Eigen::VectorXd>(z.data(), static_cast<Eigen::Index>(z.size()));
    fused.publish_wall_ns = m.publish_wall_time_ns;
    fused.receive_wall_ns = received_ns;
    if (dds::viewString(m.run_id) != options_.run.run_id) {
      ++rejected_wire_;
      spdlog::warn("rejected a measurement of another run '{}'", dds::viewString(m.run_id));
      return;
    }
    auto open = open_.find(m.episode);
    if (open == open_.end()) {
      if (last_started_ && m.episode <= *last_started_) {
        ++rejected_wire_;
        spdlog::warn("rejected a measurement of finished episode {} (sensor {})", m.episode,
                     m.sensor_id);
      } else {
        early_[m.episode].push_back(std::move(fused));
      }
      return;
    }
    route(open->second, std::move(fused));
  }

  void route(OpenEpisode& open, emulator::FusedMeasurement m) {
    if (m.z.size() == 0) {  // end-of-episode marker: seq = how many the sensor sent
      open.fusion->finishSensor(m.sensor, m.seq);
      return;
    }
    if (auto reason = open.fusion->add(std::move(m))) {
      spdlog::warn("rejected a measurement: {}", *reason);
    }
  }

  void advance() {
    const std::int64_t now = wallNowNs();
    for (auto it = open_.begin(); it != open_.end();) {
      OpenEpisode& open = it->second;
      const double horizon = run_->scenario.horizon_s;
      const double watermark =
          open.emulatedAt(now - static_cast<std::int64_t>(1e9 * options_.lag_s));
      if (watermark > 0.0) open.fusion->fuseUpTo(std::min(watermark, horizon));
      const bool overdue =
          open.emulatedAt(now) > horizon + options_.grace_s * open.time_scale;
      if (open.fusion->allSensorsFinished() || overdue) {
        if (!open.fusion->allSensorsFinished()) {
          spdlog::warn("episode {}: end markers missing {} s after T; closing it incomplete",
                       it->first, options_.grace_s);
        }
        finishEpisode(open);
        it = open_.erase(it);
        continue;
      }
      if (now >= next_state_ns_ && open.fusion->fusedTime() > 0.0) publishState(it->first, open);
      ++it;
    }
  }

  void publishState(std::uint32_t episode, const OpenEpisode& open) {
    next_state_ns_ = wallNowNs() + static_cast<std::int64_t>(1e9 * options_.state_period_s);
    const Eigen::MatrixXd& P = open.fusion->covariance();
    std::vector<double> values(P.data(), P.data() + P.size());  // symmetric: order is moot
    const emulator::ScheduleVersion* v = book_.inForce(episode, open.fusion->fusedTime());
    sensornet_FusionState s{};
    s.run_id = dds::borrowString(options_.run.run_id);
    s.episode = episode;
    s.emulated_time_s = open.fusion->fusedTime();
    s.state_dim = static_cast<std::uint32_t>(P.rows());
    dds::borrowSequence(s.covariance, values);
    s.schedule_version = v != nullptr ? v->version : 0;
    s.wall_time_ns = wallNowNs();
    (void)state_writer_.write(s);  // keep-last 1: a timeout only loses a superseded estimate
  }

  void finishEpisode(OpenEpisode& open) {
    emulator::EpisodeResult result = open.fusion->finish();
    report_->add(result);
    const emulator::RunSummary s = report_->summary();
    spdlog::info(
        "episode {}: realized {:.6g}, bracket [{:.6g}, {:.6g}]; running mean {:.6g} ± {:.3g} "
        "over {} episodes",
        result.episode, result.realized_cost, result.bracket.info, result.bracket.cov, s.mean,
        s.ci95, s.episodes);
    publishReport(result, s);
  }

  void publishReport(const emulator::EpisodeResult& e, const emulator::RunSummary& s) {
    std::vector<sensornet_SensorCounts> counts;
    for (std::size_t j = 0; j < e.sensors.size(); ++j) {
      const emulator::SensorTally& t = e.sensors[j];
      counts.push_back({static_cast<std::uint32_t>(j), t.received, t.expected, t.lost, t.late});
    }
    sensornet_Report r{};
    r.run_id = dds::borrowString(options_.run.run_id);
    r.episode = e.episode;
    r.realized_cost = e.realized_cost;
    r.bracket_lower = e.bracket.info;
    r.bracket_upper = e.bracket.cov;
    dds::borrowSequence(r.schedule_versions, e.versions);
    r.nees = e.nees;
    dds::borrowSequence(r.counts, counts);
    r.latency_median_s = s.latency_median_s;
    r.latency_p99_s = s.latency_p99_s;
    r.summary.episodes = s.episodes;
    r.summary.realized_mean = s.mean;
    r.summary.realized_ci95_low = s.mean - s.ci95;
    r.summary.realized_ci95_high = s.mean + s.ci95;
    r.summary.bracket_lower_mean = s.bracket_mean.info;
    r.summary.bracket_upper_mean = s.bracket_mean.cov;
    r.summary.meets_bracket = s.meets_bracket;
    r.summary.nees_mean = s.nees_mean;
    r.summary.received = s.received;
    r.summary.lost = s.lost;
    r.summary.latency_median_s = s.latency_median_s;
    r.summary.latency_p99_s = s.latency_p99_s;
    if (report_writer_.write(r) == dds::WriteResult::TimedOut) {
      spdlog::warn("the report of episode {} timed out on the wire (kept in the file)", e.episode);
    }
  }

  void writeReport(const std::string& status) {
    if (!report_) {
      spdlog::error("no scenario ever arrived; no report");
      return;
    }
    const nlohmann::json doc = report_->toJson(book_, status, rejected_wire_);
    if (!options_.report_path.empty()) {
      writeJsonFile(options_.report_path, doc, "run report");
      spdlog::info("report written to {}", options_.report_path);
    }
    if (options_.json) printJson(doc);
  }

  ServeOptions options_;
  dds::Domain domain_;
  dds::Participant participant_;
  dds::Topic<sensornet_Scenario> scenario_topic_;
  dds::Topic<sensornet_Schedule> schedule_topic_;
  dds::Topic<sensornet_EpisodeControl> control_topic_;
  dds::Topic<sensornet_Measurement> measurement_topic_;
  dds::Topic<sensornet_Report> report_topic_;
  dds::Topic<sensornet_FusionState> state_topic_;
  dds::Reader<sensornet_Scenario> scenario_reader_;
  dds::Reader<sensornet_Schedule> schedule_reader_;
  dds::Reader<sensornet_EpisodeControl> control_reader_;
  dds::Reader<sensornet_Measurement> measurement_reader_;
  dds::Writer<sensornet_Report> report_writer_;
  dds::Writer<sensornet_FusionState> state_writer_;
  dds::WaitSet waitset_;
  dds::ReadCondition scenario_ready_;
  dds::ReadCondition schedule_ready_;
  dds::ReadCondition control_ready_;
  dds::ReadCondition measurement_ready_;

  std::optional<emulator::RunScenario> run_;
  std::optional<EmulatedPlant> plant_;
  std::optional<emulator::RunReport> report_;
  emulator::ScheduleBook book_;
  std::map<std::uint32_t, CostBracket> brackets_;
  std::map<std::uint32_t, OpenEpisode> open_;
  std::map<std::uint32_t, std::vector<emulator::FusedMeasurement>> early_;
  std::optional<std::uint32_t> last_started_;
  std::vector<PendingStart> pending_starts_;
  std::uint64_t rejected_wire_ = 0;
  std::int64_t next_state_ns_ = 0;
};

}  // namespace

Subcommand addServeCommand(CLI::App& app) {
  auto options = std::make_shared<ServeOptions>();
  CLI::App* cmd = app.add_subcommand(
      "serve",
      "Fuse a running emulation: the exact CD-KF over every sensor's measurements in timestamp "
      "order, a Report per episode (realized cost against the bracket of the schedule in "
      "force), and the final report on shutdown. Example:\n  fusion_center serve --run-id demo "
      "--report report.json");
  emulator::addRunOptions(*cmd, options->run);
  cmd->add_option("--report", options->report_path,
                   "final report (JSON) written when the run shuts down");
  cmd->add_option("--lag", options->lag_s,
                  "wall seconds a measurement may take to arrive before it is fused (a later "
                  "one is still fused in order: the episode is re-fused at its end)")
      ->capture_default_str()
      ->check(CLI::NonNegativeNumber);
  cmd->add_option("--grace", options->grace_s,
                  "wall seconds past the end of an episode to wait for missing sensors")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  cmd->add_flag("--json", options->json, "also print the final report as one JSON line");
  return {cmd, [options] {
            (void)options->run.domainConfig();
            emulator::installStopSignals();
            FusionCenter center(*options);
            return center.run();
          }};
}

}  // namespace sensornet::fusion_center
