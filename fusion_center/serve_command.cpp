#include "serve_command.hpp"

#include <spdlog/spdlog.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <ctime>
#include <deque>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <thread>
#include <utility>
#include <variant>
#include <vector>

#include "sensornet/core/input_error.hpp"
#include "sensornet/io/forwarded_options.hpp"
#include "sensornet/io/utc_time.hpp"
#include "sensornet/dds/listener.hpp"
#include "sensornet/dds/participant.hpp"
#include "sensornet/dds/reader.hpp"
#include "sensornet/dds/topics.hpp"
#include "sensornet/dds/waitset.hpp"
#include "sensornet/dds/wire.hpp"
#include "sensornet/dds/writer.hpp"
#include "sensornet/emulator/arrival_inbox.hpp"
#include "sensornet/emulator/fusion_center_core.hpp"
#include "sensornet/wire/fusion_center_events.hpp"
#include "sensornet/emulator/fusion_metrics.hpp"
#include "sensornet/io/metrics_server.hpp"
#include "sensornet/wire/messages.hpp"
#include "sensornet/wire/run_inputs.hpp"
#include "sensornet/wire/run_options.hpp"
#include "sensornet/emulator/run_partitions.hpp"
#include "sensornet/wire/sensor_speakers.hpp"
#include "sensornet/report/report_page.hpp"
#include "sensornet/emulator/run_report.hpp"
#include "sensornet/emulator/stop_signal.hpp"
#include "sensornet/io/output_path.hpp"
#include "sensornet/io/scenario_file.hpp"
#include "sensornet/report/report_files.hpp"

// The fusion center's wiring: DDS endpoints, codecs from wire types to the events of
// FusionCenterCore (which decides everything), and a loop that feeds it and carries out its
// actions.
namespace sensornet::fusion_center {
namespace {


using namespace std::chrono_literals;
using emulator::wallNowNs;
using nlohmann::json;

struct ServeOptions {
  wire::RunOptions run;
  std::string report_path;
  double lag_s = 0.05;           // wall seconds a measurement may take to arrive before fusion
  double stall_limit_s = 12.0;   // wall seconds a sensor that owes measurements may stay silent
  double keep_up_limit_s = 1.0;  // wall seconds of drain or sensor lag that count as overload
  double state_period_s = 0.05;  // FusionState publication period (wall seconds)
  bool json = false;
  bool resume = false;           // restarted by the launcher: go on from the episode log
  bool resume_unfinished = false;  // --resume when an episode log has no final report beside it
  bool page = false;               // --page: the report page beside the final report
  bool reference = false;        // beside an external fusion center: write in P/reference
  std::string metrics_address;   // --metrics: serve /metrics (Prometheus) here while the run lives
};

// After the final report, /metrics stays up this long, so that a scraper polling every second
// gets the final counters.
constexpr auto kMetricsLinger = 2s;
// How often the metrics are rebuilt while the run lives (wall).
constexpr auto kMetricsPeriod = 250ms;

// The Report instances (one per episode) kept registered for late joiners: the latest ones.
constexpr std::size_t kReportsKept = 64;

using Arrival = emulator::MeasurementArrival;

// The participant (process) of a writer the reader has matched; nullopt when it has not.
std::optional<dds_guid_t> participantOf(const dds::detail::ReaderCore& reader,
                                        dds_instance_handle_t writer) {
  dds_builtintopic_endpoint_t* endpoint = dds_get_matched_publication_data(reader.handle(), writer);
  if (endpoint == nullptr) return std::nullopt;
  const dds_guid_t participant = endpoint->participant_key;
  dds_builtintopic_free_endpoint(endpoint);
  return participant;
}

bool sameGuid(const dds_guid_t& a, const dds_guid_t& b) {
  return std::equal(std::begin(a.v), std::end(a.v), std::begin(b.v));
}

// What the core asks of DDS, answered from the readers.
class ReaderFacts final : public emulator::WriterFacts {
 public:
  ReaderFacts(const dds::detail::ReaderCore& measurements, const dds::detail::ReaderCore& tallies,
              const dds::detail::ReaderCore& statuses, std::string run_partition)
      : measurements_(measurements),
        tallies_(tallies),
        statuses_(statuses),
        speakers_(std::move(run_partition)) {}

  // Looked up in the main loop, the first time a writer's sample comes to the core, never in
  // Cyclone's receive thread (sensor_speakers.hpp). A writer gone before its first sample
  // reaches the core (a process killed within milliseconds of writing) speaks for no sensor:
  // its samples are refused, never taken on trust.
  [[nodiscard]] const std::vector<int>& sensorsOf(emulator::SensorTopic topic,
                                                  emulator::WriterId w) const override {
    return speakers_.of(readerOf(topic), w);
  }

  [[nodiscard]] bool live(emulator::SensorTopic topic, emulator::WriterId w) const override {
    switch (topic) {
      case emulator::SensorTopic::Measurement: return measurements_.matchesWriter(w);
      case emulator::SensorTopic::Tally: return tallies_.matchesWriter(w);
      case emulator::SensorTopic::Status: return statuses_.matchesWriter(w);
    }
    return false;
  }
  [[nodiscard]] const dds::detail::ReaderCore& readerOf(emulator::SensorTopic topic) const {
    switch (topic) {
      case emulator::SensorTopic::Measurement: return measurements_;
      case emulator::SensorTopic::Tally: return tallies_;
      case emulator::SensorTopic::Status: return statuses_;
    }
    return measurements_;
  }
  [[nodiscard]] std::uint32_t matchedMeasurementWriters() const override {
    return measurements_.matchedWriters();
  }
  [[nodiscard]] bool measurementWriterMatchedWith(emulator::WriterId status_writer) const override {
    const std::optional<dds_guid_t> process = participantOf(statuses_, status_writer);
    if (!process) return false;
    std::vector<dds_instance_handle_t> writers(measurements_.matchedWriters() + 8);
    const dds_return_t n = dds_get_matched_publications(
        measurements_.handle(), writers.data(), writers.size());
    for (dds_return_t i = 0; i < std::min<dds_return_t>(n, static_cast<dds_return_t>(writers.size()));
         ++i) {
      const auto writer = participantOf(measurements_, writers[static_cast<std::size_t>(i)]);
      if (writer && sameGuid(*writer, *process)) return true;
    }
    return false;
  }

 private:
  const dds::detail::ReaderCore& measurements_;
  const dds::detail::ReaderCore& tallies_;
  const dds::detail::ReaderCore& statuses_;
  mutable wire::SensorSpeakers speakers_;  // main thread only
};

emulator::FusionCenterConfig coreConfig(const ServeOptions& options) {
  emulator::FusionCenterConfig config;
  config.run_id = options.run.run_id;
  config.lag_s = options.lag_s;
  config.stall_limit_s = options.stall_limit_s;
  config.keep_up_limit_s = options.keep_up_limit_s;
  config.state_period_s = options.state_period_s;
  if (!options.report_path.empty()) {
    const auto log_path = sensornet::report::episodeLogPath(options.report_path);
    config.episode_log = true;
    config.episode_log_path = log_path.string();
    if (options.resume) {
      config.resumed_log = sensornet::report::readEpisodeLog(log_path);
      spdlog::info("resuming from {} episodes in the episode log {}", config.resumed_log->size(),
                   log_path.string());
      config.resumed_faults = sensornet::report::readFaultLog(sensornet::report::faultLogPath(options.report_path));
    }
  }
  if (options.resume && !config.resumed_log) config.resumed_log.emplace();
  return config;
}

// The launcher's pid when `sensornet launch` started this process, else 0. The launcher arms the
// parent-death signal emulator::kLauncherDeathSignal in it, so that signal (or this parent gone)
// is the launcher's death (kill -9), and this process is the last one of the run to say so.
pid_t launcherParent() {
  const pid_t parent = ::getppid();
  std::ifstream comm("/proc/" + std::to_string(parent) + "/comm");
  std::string name;
  std::getline(comm, name);
  return name == "sensornet" ? parent : 0;
}

// The report and the episode log are written and closed (each entry in one write(2)): what is
// left is deleting the DDS entities, and Cyclone lets a reliable writer linger for the readers'
// acknowledgements, which readers killed with the launcher never send. Nothing of this process
// is owed to anyone any more.
[[noreturn]] void leaveNow(int code) {
  spdlog::shutdown();
  std::fflush(nullptr);
  ::_exit(code);
}

class FusionCenter {
 public:
  explicit FusionCenter(const ServeOptions& options)
      : options_(options),
        metrics_(options.metrics_address.empty()
                     ? nullptr
                     : std::make_unique<MetricsServer>(options.metrics_address)),
        domain_(options.run.domainConfig()),
        participant_(domain_),
        inputs_(participant_),
        measurement_topic_(participant_),
        tally_topic_(participant_),
        status_topic_(participant_),
        report_topic_(participant_),
        state_topic_(participant_),
        // Every sensor process's partition (run_partitions.hpp): the partition a sample came
        // in names the sensors its writer speaks for.
        measurement_reader_(participant_, measurement_topic_,
                            dds::readerQosMatching<sensornet_Measurement>(sensorPartitions())),
        tally_reader_(participant_, tally_topic_,
                      dds::readerQosMatching<sensornet_EpisodeTally>(sensorPartitions())),
        status_reader_(participant_, status_topic_,
                       dds::readerQosMatching<sensornet_SensorStatus>(sensorPartitions())),
        reply_topic_(participant_),
        reply_reader_(participant_, reply_topic_),
        report_writer_(participant_, report_topic_, outputQos(dds::reportWriterQos())),
        state_writer_(participant_, state_topic_,
                      outputQos(dds::defaultEndpointQos<sensornet_FusionState>())),
        waitset_(participant_),
        tally_ready_(tally_reader_),
        status_ready_(status_reader_),
        facts_(measurement_reader_, tally_reader_, status_reader_, participant_.partition()),
        core_(coreConfig(options), facts_, wallNowNs()),
        arrivals_listener_(measurement_reader_, [this] { onMeasurements(); }) {
    inputs_.attachTo(waitset_);
    waitset_.attach(tally_ready_, 1);
    waitset_.attach(status_ready_, 2);
    if (!options_.report_path.empty()) {
      const auto log_path = sensornet::report::episodeLogPath(options_.report_path);
      const auto mode =
          options_.resume ? sensornet::report::EpisodeLog::Mode::Append : sensornet::report::EpisodeLog::Mode::Truncate;
      episode_log_.emplace(log_path, mode);
      spdlog::info("episode log: {}", log_path.string());
      fault_log_.emplace(sensornet::report::faultLogPath(options_.report_path), mode);
    }
  }

  // The Report and FusionState writers' QoS: in the run's partition, or as the reference
  // (--reference) in P/reference, where neither the coordinator nor the launcher reads them.
  [[nodiscard]] dds::Qos outputQos(dds::Qos qos) const {
    if (options_.reference) qos.partition(emulator::referencePartition(participant_.partition()));
    return qos;
  }

  int run() {
    spdlog::info("fusion center of run {} waiting for the scenario", options_.run.run_id);
    std::optional<emulator::RunEnd> end;
    auto metrics_due = std::chrono::steady_clock::now();
    while (!end && !emulator::stopRequested()) {
      if (metrics_ && std::chrono::steady_clock::now() >= metrics_due) {
        metrics_->publish(emulator::fusionCenterMetrics(core_, inputs_.book()));
        metrics_due = std::chrono::steady_clock::now() + kMetricsPeriod;
      }
      if (inbox_.mayWait()) (void)waitset_.wait(10ms);
      const std::int64_t now = wallNowNs();
      inbox_.drainInto(drained_);
      for (Arrival& arrival : drained_) core_.onMeasurement(std::move(arrival), now);
      end = follow(now);
      readTallies(now);
      readStatuses(now);
      readReplies(now);
      core_.tick(now);
      carryOut();
    }
    // The death signal says so at once; the parent's id changes only once every thread of the
    // dying launcher is gone.
    const bool launcher_gone =
        !end && launcher_ != 0 && (emulator::launcherDied() || ::getppid() != launcher_);
    if (launcher_gone) {
      core_.onLauncherGone("the launcher (sensornet launch, pid " + std::to_string(launcher_) +
                               ") died while the run went on (its children got the "
                               "parent-death signal); the run ends here",
                           wallNowNs());
    }
    const emulator::RunStatus status =
        core_.finish(end, inputs_.rejected(), utcNow(), wallNowNs());
    carryOut();
    // With the launcher dead, the other processes of the run were killed with it: no reader is
    // left to take the last Report or a scrape, and waiting for them would only keep this
    // process alive after its launcher.
    if (metrics_ && !launcher_gone) {
      metrics_->publish(emulator::fusionCenterMetrics(core_, inputs_.book()));
      std::this_thread::sleep_for(kMetricsLinger);
    }
    if (!launcher_gone) (void)report_writer_.waitForAcks(2s);
    spdlog::info("run {}: {}", options_.run.run_id, wordOf(status));
    if (launcher_gone) leaveNow(kExitFailure);
    // The report carries the run's status; the exit code says whether this process did its job
    // (followed the run to its end and wrote the report).
    return end && core_.hasReport() ? kExitOk : kExitFailure;
  }

 private:
  // Hands what the run announced to the core; the run's end on RUN_SHUTDOWN.
  std::optional<emulator::RunEnd> follow(std::int64_t now) {
    return wire::feedInputs(core_, inputs_.state(), inputs_.poll(), now);
  }

  // In Cyclone's receive thread, as measurements are delivered: takes them, stamps their arrival
  // there (one thread hop after the wire, as in ddsperf) and hands them to the main loop.
  void onMeasurements() {
    // Usually one sample a call: a small batch keeps the loan and its info array small.
    constexpr std::size_t kBatch = 16;
    std::vector<Arrival>& arrivals = taken_;  // Cyclone runs one call of a listener at a time
    for (;;) {
      const std::int64_t received_ns = wallNowNs();
      const std::size_t count = measurement_reader_.takeEach(
          kBatch,
          [&](const sensornet_Measurement& m, const dds::SampleInfo& info) {
            arrivals.push_back(wire::arrivalOfSample(m, received_ns, info.publication,
                                                         options_.run.run_id));
          },
          [](const sensornet_Measurement& key, const dds::SampleInfo& info) {
            if (info.instance_state == dds::InstanceState::NoWriters) {
              spdlog::info("sensor {} has no live writer at the moment", key.sensor_id);
            }
          });
      if (count < kBatch) break;
    }
    if (!arrivals.empty() && inbox_.push(arrivals)) waitset_.wake();
  }

  void readTallies(std::int64_t now) {
    if (!core_.hasScenario()) return;  // kept by the reader (transient local) until then
    for (auto& received : tally_reader_.take(64).samples) {
      core_.onTally(wire::tallyOfSample(*received.sample, received.info.publication), now);
    }
  }

  void readStatuses(std::int64_t now) {
    for (auto& received : status_reader_.take(64).samples) {
      core_.onStatus(wire::statusOfSample(*received.sample, received.info.publication), now);
    }
  }

  // The coordinator's replies: a command it refused because its sender had no right to send
  // it is a fault of the run (run_partitions.hpp, kNotPermitted).
  void readReplies(std::int64_t now) {
    for (auto& received : reply_reader_.take(64).samples) {
      const sensornet_CommandReply& r = *received.sample;
      if (const auto why = wire::refusalByRight(r, options_.run.run_id)) {
        core_.onCommandRefused(r.command_id, *why, now);
      }
    }
  }

  [[nodiscard]] std::string sensorPartitions() const {
    return emulator::sensorPartitionPattern(participant_.partition());
  }

  void carryOut() {
    for (emulator::FusionAction& action : core_.takeActions()) {
      std::visit([this](auto& a) { carryOut(a); }, action);
    }
  }
  void carryOut(const emulator::PublishReport& a) {
    if (!a.lacking_writers.empty()) {
      spdlog::warn("episode {} reported without the measurement writers of sensors {}",
                   a.result.episode, json(a.lacking_writers).dump());
    }
    std::vector<sensornet_SensorCounts> counts;
    const sensornet_Report r = wire::reportSample(options_.run.run_id, a.result, a.summary, counts);
    if (report_writer_.write(r) == dds::WriteResult::TimedOut) {
      spdlog::warn("the report of episode {} timed out on the wire (kept in the file)",
                   a.result.episode);
    }
    forgetOldReports(a.result.episode);
  }
  void carryOut(const emulator::PublishState& a) {
    const Eigen::MatrixXd& P = a.covariance;
    std::vector<double> values(P.data(), P.data() + P.size());  // symmetric: order is moot
    sensornet_FusionState s{};
    s.run_id = dds::borrowString(options_.run.run_id);
    s.episode = a.episode;
    s.emulated_time_s = a.emulated_time_s;
    s.state_dim = static_cast<std::uint32_t>(P.rows());
    dds::borrowSequence(s.covariance, values);
    s.schedule_version = a.schedule_version;
    s.wall_time_ns = wallNowNs();
    (void)state_writer_.write(s);  // keep-last 1: a timeout only loses a superseded estimate
  }
  void carryOut(const emulator::AppendEpisodeLog& a) {
    if (episode_log_) episode_log_->append(a.entry);
  }
  // Kept by the core for the report, and in the fault log for a restarted fusion center. A
  // fault log that cannot take it costs only what a restart would have carried over: a warning.
  void carryOut(const emulator::RecordFault& a) {
    if (!fault_log_) return;
    try {
      fault_log_->append(a.fault);
    } catch (const std::exception& e) {
      spdlog::warn("{}; a restarted fusion center would not know of this fault", e.what());
    }
  }
  static void carryOut(const emulator::LogLine& a) { spdlog::log(a.level, "{}", a.text); }
  void carryOut(const emulator::WriteFinalReport& a) {
    if (!options_.report_path.empty()) {
      writeJsonFile(options_.report_path, "run report", [&](std::ostream& out) {
        core_.report().write(out, a.doc, 2);
        out << '\n';
      });
      spdlog::info("report written to {}", options_.report_path);
      if (options_.page) {
        if (const auto problem = sensornet::report::writePageBeside(options_.report_path)) {
          spdlog::warn("{}", *problem);
        } else {
          spdlog::info("report page written to {}",
                       sensornet::report::pagePathBeside(options_.report_path).string());
        }
      }
    }
    if (options_.json) {
      core_.report().write(std::cout, a.doc, -1);
      std::cout << std::endl;
    }
  }

  // The Report topic keeps the last report of each episode for late joiners: an instance per
  // episode, held by this writer and by every reader until it is unregistered. Only the latest
  // kReportsKept stay registered (a restarted coordinator needs the last one), so that memory
  // does not grow with the number of episodes (with Cyclone 0.10 only if the unregistration also
  // gives back the key Cyclone keeps of every instance written: unregisterWrittenInstance).
  void forgetOldReports(std::uint32_t episode) {
    reports_registered_.push_back(episode);
    if (reports_registered_.size() <= kReportsKept) return;
    sensornet_Report key{};
    key.run_id = dds::borrowString(options_.run.run_id);
    key.episode = reports_registered_.front();
    reports_registered_.pop_front();
    (void)report_writer_.unregisterWrittenInstance(key);  // a timeout keeps the report longer
  }

  ServeOptions options_;
  const pid_t launcher_ = launcherParent();  // read at start, while the parent lives
  std::unique_ptr<MetricsServer> metrics_;  // --metrics; made first: a bad address is bad input
  dds::Domain domain_;
  dds::Participant participant_;
  wire::RunInputs inputs_;
  dds::Topic<sensornet_Measurement> measurement_topic_;
  dds::Topic<sensornet_EpisodeTally> tally_topic_;
  dds::Topic<sensornet_SensorStatus> status_topic_;
  dds::Topic<sensornet_Report> report_topic_;
  dds::Topic<sensornet_FusionState> state_topic_;
  // Created in this order, and so announced to the sensors' processes in it: the Measurement
  // reader before the status reader (FusionCenterCore::sensorsLackingWriters relies on it).
  dds::Reader<sensornet_Measurement> measurement_reader_;
  dds::Reader<sensornet_EpisodeTally> tally_reader_;
  dds::Reader<sensornet_SensorStatus> status_reader_;
  dds::Topic<sensornet_CommandReply> reply_topic_;
  dds::Reader<sensornet_CommandReply> reply_reader_;
  dds::Writer<sensornet_Report> report_writer_;
  dds::Writer<sensornet_FusionState> state_writer_;
  dds::WaitSet waitset_;
  dds::ReadCondition tally_ready_;
  dds::ReadCondition status_ready_;
  ReaderFacts facts_;
  emulator::FusionCenterCore core_;
  std::optional<sensornet::report::EpisodeLog> episode_log_;
  std::optional<sensornet::report::EpisodeLog> fault_log_;  // faultLogPath: what a restart carries over
  emulator::ArrivalInbox<Arrival> inbox_;
  std::vector<Arrival> taken_;    // the listener's batch (receive thread only)
  std::vector<Arrival> drained_;  // the main loop's (main thread only)
  std::deque<std::uint32_t> reports_registered_;  // episodes whose Report instance is registered
  // After what its callback touches (reader, waitset, inbox): it is destroyed before them, and
  // its destructor waits for a callback in progress.
  dds::DataAvailableListener arrivals_listener_;
};

}  // namespace

Subcommand addServeCommand(CLI::App& app) {
  auto options = std::make_shared<ServeOptions>();
  CLI::App* cmd = app.add_subcommand(
      "serve",
      "Fuse a running emulation: the exact CD-KF over every sensor's measurements in timestamp "
      "order, a Report per episode (realized cost against the bracket of the schedule in "
      "force), and the final report on shutdown. An episode closes when every sensor's "
      "end-of-episode tally is in and every measurement it counts has arrived; a sensor that "
      "owes measurements and stays silent past --stall-limit is named in the report's faults. "
      "Each finished episode is appended at once to the JSON Lines log beside the report "
      "(report.jsonl beside report.json). Example:\n  fusion_center serve --run-id demo "
      "--report report.json");
  wire::addRunOptions(*cmd, options->run);
  options->run.security_identity = dds::SecurityRole::FusionCenter;
  CLI::Option* report = cmd->add_option("--report", options->report_path,
                  "final report (JSON) written when the run shuts down (missing folders are made "
                  "at start); the episode log goes beside it");
  cmd->add_option("--lag", options->lag_s,
                  "wall seconds a measurement may take to arrive before it is fused (a later "
                  "one is still fused in order: the episode is re-fused at its end)")
      ->capture_default_str()
      ->check(nonNegativeNumber(kMaxWallSeconds));
  cmd->add_option("--stall-limit", options->stall_limit_s,
                  "wall seconds a sensor that still owes measurements may stay silent after an "
                  "episode's end before the episode is closed incomplete (longer than the 10 s "
                  "stalls a run absorbs)")
      ->capture_default_str()
      ->check(positiveNumber(kMaxWallSeconds));
  cmd->add_option("--keep-up-limit", options->keep_up_limit_s,
                  "wall seconds of drain after the last of an episode arrived (not counting "
                  "samples the network held back: those are stalls), or of a sensor's lag behind "
                  "the emulated clock, past which the run is reported as overloaded (degraded)")
      ->capture_default_str()
      ->check(positiveNumber(kMaxWallSeconds));
  cmd->add_flag("--reference", options->reference,
                "run as the reference beside an external fusion center (sensornet launch "
                "--reference-fusion): fuse the same measurements, write the report file, and "
                "publish Report and FusionState in partition <partition>/reference, where the "
                "coordinator does not pace on them");
  addMetricsOption(*cmd, options->metrics_address);
  cmd->add_flag("--json", options->json, "also print the final report as one JSON line");
  cmd->add_flag("--resume", options->resume,
                "restarted after a death (the launcher adds it): start the report from the "
                "episode log beside --report and append to it; an episode that began before this "
                "process and is not in the log is recorded incomplete (fusion_center_restarted)");
  cmd->add_flag("--page", options->page,
                "also write the report page beside the final report (report.json -> "
                "report.html, as `sensornet report` makes it): for runs without a launcher, "
                "which writes it otherwise")
      ->needs(report);
  cmd->add_flag("--resume-unfinished", options->resume_unfinished,
                "for a command that is the same at every start (a container's restart policy, "
                "systemd): --resume when the episode log beside --report exists and the final "
                "report does not (an earlier process of the run died), else start afresh")
      ->needs(report)
      ->excludes("--resume");
  return {cmd, [options] {
            if (options->resume_unfinished) {
              const std::filesystem::path log = sensornet::report::episodeLogPath(options->report_path);
              options->resume =
                  std::filesystem::exists(log) && !std::filesystem::exists(options->report_path);
              if (options->resume) {
                spdlog::info("{} has no final report beside it: resuming (--resume-unfinished)",
                             log.string());
              }
            }
            (void)options->run.domainConfig();
            // A folder the report cannot go in is bad input now, not after the run.
            if (!options->report_path.empty()) {
              makeParentFolders(options->report_path, "--report");
            }
            emulator::installStopSignals();
            FusionCenter center(*options);
            return center.run();
          }};
}

}  // namespace sensornet::fusion_center
