#include "serve_command.hpp"

#include <spdlog/spdlog.h>

#include <chrono>
#include <iterator>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "sensornet/core/emulated_plant.hpp"
#include "sensornet/core/input_error.hpp"
#include "sensornet/dds/listener.hpp"
#include "sensornet/dds/participant.hpp"
#include "sensornet/dds/reader.hpp"
#include "sensornet/dds/topics.hpp"
#include "sensornet/dds/waitset.hpp"
#include "sensornet/dds/wire.hpp"
#include "sensornet/dds/writer.hpp"
#include "sensornet/emulator/episode_fusion.hpp"
#include "sensornet/emulator/messages.hpp"
#include "sensornet/emulator/run_inputs.hpp"
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

// A measurement as it came off the wire, stamped on arrival.
struct Arrival {
  emulator::FusedMeasurement measurement;
  std::uint32_t episode = 0;
  std::optional<std::string> other_run;  // the run id it carries, if not this run's
};

// Arrivals handed from Cyclone's receive thread (the listener) to the main loop.
class Inbox {
 public:
  // Returns true if the inbox was empty before: the main loop may be asleep and needs a wake.
  bool push(std::vector<Arrival> arrivals) {
    std::lock_guard lock(mutex_);
    const bool was_empty = arrivals_.empty();
    arrivals_.insert(arrivals_.end(), std::make_move_iterator(arrivals.begin()),
                     std::make_move_iterator(arrivals.end()));
    return was_empty;
  }
  [[nodiscard]] std::vector<Arrival> drain() {
    std::lock_guard lock(mutex_);
    return std::exchange(arrivals_, {});
  }

 private:
  std::mutex mutex_;
  std::vector<Arrival> arrivals_;
};

// An episode in progress: its clock and its fusion.
struct OpenEpisode {
  emulator::EpisodeClock clock;
  std::unique_ptr<emulator::EpisodeFusion> fusion;
};

class FusionCenter {
 public:
  explicit FusionCenter(const ServeOptions& options)
      : options_(options),
        domain_(options.run.domainConfig()),
        participant_(domain_),
        inputs_(participant_),
        measurement_topic_(participant_),
        report_topic_(participant_),
        state_topic_(participant_),
        measurement_reader_(participant_, measurement_topic_),
        report_writer_(participant_, report_topic_),
        state_writer_(participant_, state_topic_),
        waitset_(participant_),
        arrivals_listener_(measurement_reader_, [this] { onMeasurements(); }) {
    inputs_.attachTo(waitset_);
  }

  int run() {
    spdlog::info("fusion center of run {} waiting for the scenario", options_.run.run_id);
    bool shutdown = false;
    while (!shutdown && !emulator::stopRequested()) {
      (void)waitset_.wait(10ms);
      for (Arrival& arrival : inbox_.drain()) accept(std::move(arrival));
      shutdown = follow();
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
  // Takes what the run announced; returns true on RUN_SHUTDOWN.
  bool follow() {
    const emulator::RunInputs::Update update = inputs_.poll();
    if (update.scenario_arrived) {
      const Scenario& s = inputs_.scenario();
      report_.emplace(options_.run.run_id, inputs_.run().digest, s.sensorCount(), s.stateDim());
    }
    if (update.new_versions > 0) {
      for (auto& [episode, open] : open_) open.fusion->scheduleChanged();
    }
    for (const emulator::EpisodeStart& start : update.starts) startEpisode(start);
    return update.shutdown;
  }

  void startEpisode(const emulator::EpisodeStart& start) {
    OpenEpisode open;
    open.clock = start.clock;
    open.fusion = std::make_unique<emulator::EpisodeFusion>(
        inputs_.scenario(), inputs_.plant(), inputs_.book(), start.episode,
        [this](const emulator::ScheduleVersion& v) { return bracketOf(v); });
    auto& slot = open_.emplace(start.episode, std::move(open)).first->second;
    // Measurements that came before the episode's control sample.
    if (auto early = early_.find(start.episode); early != early_.end()) {
      for (auto& m : early->second) route(slot, std::move(m));
      early_.erase(early);
    }
  }

  CostBracket bracketOf(const emulator::ScheduleVersion& v) {
    auto it = brackets_.find(v.version);
    if (it == brackets_.end()) {
      it = brackets_.emplace(v.version, computeBracket(inputs_.scenario(), v.schedule)).first;
    }
    return it->second;
  }

  // In Cyclone's receive thread, as measurements are delivered: takes them, stamps their arrival
  // there (one thread hop after the wire, as in ddsperf) and hands them to the main loop.
  void onMeasurements() {
    constexpr std::size_t kBatch = 64;
    std::vector<Arrival> arrivals;
    for (;;) {
      const std::int64_t received_ns = wallNowNs();
      const std::size_t count = measurement_reader_.takeEach(
          kBatch,
          [&](const sensornet_Measurement& m, const dds::SampleInfo&) {
            arrivals.push_back(arrivalOf(m, received_ns));
          },
          [](const sensornet_Measurement& key, const dds::SampleInfo& info) {
            if (info.instance_state == dds::InstanceState::NoWriters) {
              spdlog::warn("sensor {} has no live writer any more", key.sensor_id);
            }
          });
      if (count < kBatch) break;
    }
    if (!arrivals.empty() && inbox_.push(std::move(arrivals))) waitset_.wake();
  }

  // Reads only what never changes after construction (the run id): safe in the receive thread.
  [[nodiscard]] Arrival arrivalOf(const sensornet_Measurement& m, std::int64_t received_ns) const {
    Arrival a;
    emulator::FusedMeasurement& fused = a.measurement;
    fused.sensor = static_cast<int>(m.sensor_id);
    fused.seq = m.seq;
    fused.time_s = m.emulated_time_s;
    fused.version = m.schedule_version;
    const auto z = dds::viewSequence(m.z);
    fused.z = Eigen::Map<const Eigen::VectorXd>(z.data(), static_cast<Eigen::Index>(z.size()));
    fused.publish_wall_ns = m.publish_wall_time_ns;
    fused.receive_wall_ns = received_ns;
    a.episode = m.episode;
    if (const std::string_view run = dds::viewString(m.run_id); run != options_.run.run_id) {
      a.other_run = std::string(run);
    }
    return a;
  }

  void accept(Arrival arrival) {
    if (arrival.other_run) {
      ++rejected_wire_;
      spdlog::warn("rejected a measurement of another run '{}'", *arrival.other_run);
      return;
    }
    const std::uint32_t episode = arrival.episode;
    auto open = open_.find(episode);
    if (open == open_.end()) {
      if (inputs_.lastStarted() && episode <= *inputs_.lastStarted()) {
        ++rejected_wire_;
        spdlog::warn("rejected a measurement of finished episode {} (sensor {})", episode,
                     arrival.measurement.sensor);
      } else {
        early_[episode].push_back(std::move(arrival.measurement));
      }
      return;
    }
    route(open->second, std::move(arrival.measurement));
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
      const double horizon = inputs_.scenario().horizon_s;
      const double watermark =
          open.clock.emulatedAt(now - static_cast<std::int64_t>(1e9 * options_.lag_s));
      if (watermark > 0.0) open.fusion->fuseUpTo(std::min(watermark, horizon));
      const bool overdue =
          open.clock.emulatedAt(now) > horizon + options_.grace_s * open.clock.time_scale;
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
    const emulator::ScheduleVersion* v = inputs_.book().inForce(episode, open.fusion->fusedTime());
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
    const nlohmann::json doc =
        report_->toJson(inputs_.book(), status, inputs_.rejected() + rejected_wire_);
    if (!options_.report_path.empty()) {
      writeJsonFile(options_.report_path, doc, "run report");
      spdlog::info("report written to {}", options_.report_path);
    }
    if (options_.json) printJson(doc);
  }

  ServeOptions options_;
  dds::Domain domain_;
  dds::Participant participant_;
  emulator::RunInputs inputs_;
  dds::Topic<sensornet_Measurement> measurement_topic_;
  dds::Topic<sensornet_Report> report_topic_;
  dds::Topic<sensornet_FusionState> state_topic_;
  dds::Reader<sensornet_Measurement> measurement_reader_;
  dds::Writer<sensornet_Report> report_writer_;
  dds::Writer<sensornet_FusionState> state_writer_;
  dds::WaitSet waitset_;
  Inbox inbox_;
  // After what its callback touches (reader, waitset, inbox): it is destroyed before them, and
  // its destructor waits for a callback in progress.
  dds::DataAvailableListener arrivals_listener_;

  std::optional<emulator::RunReport> report_;
  std::map<std::uint32_t, CostBracket> brackets_;
  std::map<std::uint32_t, OpenEpisode> open_;
  std::map<std::uint32_t, std::vector<emulator::FusedMeasurement>> early_;
  std::uint64_t rejected_wire_ = 0;  // measurements of other runs or finished episodes
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
      ->check(nonNegativeNumber(emulator::kMaxWallSeconds));
  cmd->add_option("--grace", options->grace_s,
                  "wall seconds past the end of an episode to wait for missing sensors")
      ->capture_default_str()
      ->check(positiveNumber(emulator::kMaxWallSeconds));
  cmd->add_flag("--json", options->json, "also print the final report as one JSON line");
  return {cmd, [options] {
            (void)options->run.domainConfig();
            emulator::installStopSignals();
            FusionCenter center(*options);
            return center.run();
          }};
}

}  // namespace sensornet::fusion_center
