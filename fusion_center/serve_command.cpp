#include "serve_command.hpp"

#include <spdlog/spdlog.h>
#include <unistd.h>

#include <chrono>
#include <iostream>
#include <memory>
#include <optional>
#include <string>
#include <thread>
#include <variant>
#include <vector>

#include "sensornet/io/forwarded_options.hpp"
#include "sensornet/io/utc_time.hpp"
#include "sensornet/dds/listener.hpp"
#include "sensornet/emulator/arrival_inbox.hpp"
#include "sensornet/wire/fusion_center_events.hpp"
#include "sensornet/wire/fusion_center_wire.hpp"
#include "sensornet/wire/messages.hpp"
#include "sensornet/emulator/fusion_center_start.hpp"
#include "sensornet/emulator/fusion_metrics.hpp"
#include "sensornet/io/metrics_server.hpp"
#include "sensornet/wire/run_options.hpp"
#include "sensornet/report/report_page.hpp"
#include "sensornet/emulator/stop_signal.hpp"
#include "sensornet/io/output_path.hpp"
#include "sensornet/io/run_nonce.hpp"
#include "sensornet/io/scenario_file.hpp"
#include "sensornet/core/input_error.hpp"
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
  std::string report_fallback;  // --report-fallback: where a report its path refuses goes
  emulator::FusionCenterConfig core;  // its lag, stall and keep-up limits
  bool json = false;
  bool resume = false;           // restarted by the launcher: go on from the episode log
  bool resume_unfinished = false;  // --resume when an episode log has no final report beside it
  std::string run_nonce;           // --run-nonce: a log of another nonce is an earlier deployment's
  bool page = false;               // --page: the report page beside the final report
  bool reference = false;        // beside an external fusion center: write in P/reference
  std::string metrics_address;   // --metrics: serve /metrics (Prometheus) here while the run lives
};

// After the final report, /metrics stays up this long, so that a scraper polling every second
// gets the final counters.
constexpr auto kMetricsLinger = 2s;
// A run aborted before the scenario came: how long to wait for the scenario, to report why.
constexpr auto kScenarioAfterAbort = 5s;
// How often the fusion center probes the sensor processes' clocks (docs/wire-protocol.md,
// "Clocks").
constexpr std::int64_t kProbePeriodNs = 500'000'000;
// How often a fusion center not yet present asks whether it holds every sensor's writers, and
// how often it says whose it waits for (wall).
constexpr std::int64_t kPresenceCheckPeriodNs = 50'000'000;
constexpr std::int64_t kAbsenceLogPeriodNs = 5'000'000'000;
// How often the metrics are rebuilt while the run lives (wall).
constexpr auto kMetricsPeriod = 250ms;

using Arrival = emulator::MeasurementArrival;

emulator::FusionCenterConfig coreConfig(const ServeOptions& options) {
  emulator::FusionCenterConfig config = options.core;
  config.run_id = options.run.run_id;
  emulator::useLogsBeside(config, options.report_path, options.resume);
  return config;
}

class FusionCenter {
 public:
  explicit FusionCenter(const ServeOptions& options)
      : options_(options),
        metrics_(options.metrics_address.empty()
                     ? nullptr
                     : std::make_unique<MetricsServer>(options.metrics_address)),
        dds_(options.run.domainConfig(), options.reference),
        core_(coreConfig(options), dds_.facts, wallNowNs()),
        arrivals_listener_(dds_.measurement_reader, [this] { onMeasurements(); }) {
    if (!options_.report_path.empty()) {
      const auto log_path = sensornet::report::episodeLogPath(options_.report_path);
      const auto mode =
          options_.resume ? sensornet::report::EpisodeLog::Mode::Append : sensornet::report::EpisodeLog::Mode::Truncate;
      episode_log_.emplace(log_path, mode);
      spdlog::info("episode log: {}", log_path.string());
      fault_log_.emplace(sensornet::report::faultLogPath(options_.report_path), mode);
      // After the logs are truncated: a crash between the two starts afresh again.
      if (!options_.resume) {
        try {
          recordNonce(options_.report_path, options_.run_nonce);
        } catch (const std::exception& e) {  // a full disk costs a restart's resume, not the run
          spdlog::warn("{}: a restart of this process will start afresh", e.what());
        }
      }
    }
  }

  int run() {
    spdlog::info("fusion center of run {} waiting for the scenario", options_.run.run_id);
    std::optional<emulator::RunEnd> end;
    auto metrics_due = std::chrono::steady_clock::now();
    while (!end && !emulator::stopRequested()) {
      if (metrics_ && std::chrono::steady_clock::now() >= metrics_due) {
        metrics_->publish(emulator::fusionCenterMetrics(core_, dds_.inputs.book()));
        metrics_due = std::chrono::steady_clock::now() + kMetricsPeriod;
      }
      if (inbox_.mayWait()) (void)dds_.waitset.wait(10ms);
      readEchoes();  // first: an echo's wait here widens its clock's bound
      const std::int64_t now = wallNowNs();
      if (now >= next_probe_ns_) {
        probes_.send(dds_.probe_writer, options_.run.run_id, now);
        next_probe_ns_ = now + kProbePeriodNs;
      }
      inbox_.drainInto(drained_);
      for (Arrival& arrival : drained_) core_.onMeasurement(std::move(arrival), now);
      end = follow(now);
      readTallies(now);
      readStatuses(now);
      readReplies(now);
      // Under a launcher the launcher names a coordinator it restarted; without one (containers,
      // a process manager) only this process can tell, by the new coordinator's writer.
      if (launcher_ == 0) core_.onCoordinatorProcesses(dds_.inputs.coordinatorProcessesSeen(), now);
      core_.tick(now);
      carryOut();
      presentOnceHeld(now);
    }
    // A run the coordinator aborted at once (a journal it could not write) may end here before
    // its scenario did (discovery matches the topics one by one, slowly on a loaded machine):
    // the scenario is kept for late readers (transient local), so wait a little for it, to
    // write the report that says why rather than none.
    if (end && end->aborted && !core_.hasScenario()) {
      const auto deadline = std::chrono::steady_clock::now() + kScenarioAfterAbort;
      while (!core_.hasScenario() && std::chrono::steady_clock::now() < deadline &&
             !emulator::stopRequested()) {
        (void)dds_.waitset.wait(10ms);
        (void)follow(wallNowNs());
      }
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
        core_.finish(end, dds_.inputs.rejected(), utcNow(), wallNowNs());
    carryOut();
    // With the launcher dead, the other processes of the run were killed with it: no reader is
    // left to take the last Report or a scrape, and waiting for them would only keep this
    // process alive after its launcher.
    if (metrics_ && !launcher_gone) {
      metrics_->publish(emulator::fusionCenterMetrics(core_, dds_.inputs.book()));
      std::this_thread::sleep_for(kMetricsLinger);
    }
    if (!launcher_gone && dds_.present()) (void)dds_.report_writer->waitForAcks(2s);
    spdlog::info("run {}: {}", options_.run.run_id, wordOf(status));
    if (launcher_gone) emulator::leaveNow(kExitFailure);
    // The report carries the run's status; the exit code says whether this process did its job
    // (followed the run to its end and wrote the report).
    return end && core_.hasReport() ? kExitOk : kExitFailure;
  }

 private:
  // Hands what the run announced to the core; the run's end on RUN_SHUTDOWN.
  std::optional<emulator::RunEnd> follow(std::int64_t now) {
    return wire::feedInputs(core_, dds_.inputs.state(), dds_.inputs.poll(), now);
  }

  // In Cyclone's receive thread, as measurements are delivered: takes them, stamps their arrival
  // there (one thread hop after the wire, as in ddsperf) and hands them to the main loop.
  void onMeasurements() {
    std::vector<Arrival>& arrivals = taken_;  // Cyclone runs one call of a listener at a time
    wire::takeArrivals(dds_.measurement_reader, options_.run.run_id, arrivals);
    if (!arrivals.empty() && inbox_.push(arrivals)) dds_.waitset.wake();
  }

  void readTallies(std::int64_t now) {
    if (!core_.hasScenario()) return;  // kept by the reader (transient local) until then
    for (auto& received : dds_.tally_reader.take(64).samples) {
      core_.onTally(wire::tallyOfSample(*received.sample, received.info.publication), now);
    }
  }

  // The sensor processes' answers to our clock probes, each stamped when taken (t4).
  void readEchoes() {
    for (auto& received : dds_.echo_reader.take(64).samples) {
      const std::int64_t now = wallNowNs();
      if (const auto echo = probes_.answerOf(*received.sample)) core_.onClockEcho(*echo, now);
    }
  }

  void readStatuses(std::int64_t now) {
    for (auto& received : dds_.status_reader.take(64).samples) {
      core_.onStatus(wire::statusOfSample(*received.sample, received.info.publication), now);
    }
  }

  // The coordinator's replies: a command it refused because its sender had no right to send
  // it is a fault of the run (run_partitions.hpp, kNotPermitted).
  void readReplies(std::int64_t now) {
    for (auto& received : dds_.reply_reader.take(64).samples) {
      const sensornet_CommandReply& r = *received.sample;
      if (const auto why = wire::refusalByRight(r, options_.run.run_id)) {
        core_.onCommandRefused(r.command_id, *why, now);
      }
    }
  }

  // The Report and FusionState writers, whose match makes this process present to the
  // coordinator, once its readers hold every sensor process's writers (FusionCenterEndpoints).
  // A restarted process is present at once: the run it rejoins is under way.
  void presentOnceHeld(std::int64_t now) {
    if (dds_.present() || now < next_presence_check_ns_) return;
    // Asking DDS about every sensor's writers costs a look-up per sensor: every 50 ms, not
    // every turn (at 200 sensor processes a turn's worth would be thousands a second).
    next_presence_check_ns_ = now + kPresenceCheckPeriodNs;
    if (options_.resume || core_.holdsEverySensorProcess()) {
      becomePresent(options_.resume ? "it rejoins a run" : "it holds every sensor's writers");
    } else if (core_.hasScenario() && now >= next_absence_log_ns_) {
      if (next_absence_log_ns_ != 0) {
        spdlog::info("not yet present to the coordinator: this process's readers have not "
                     "matched the Measurement and EpisodeTally writers of sensors {}",
                     json(core_.sensorsLackingWriters()).dump());
      }
      next_absence_log_ns_ = now + kAbsenceLogPeriodNs;
    }
  }
  void becomePresent(const char* why) {
    if (dds_.present()) return;
    dds_.makePresent();
    spdlog::info("present to the coordinator (its Report and FusionState writers made): {}", why);
  }

  // Until none is left: carrying one out may make more (a refused write's fault).
  void carryOut() {
    for (auto actions = core_.takeActions(); !actions.empty(); actions = core_.takeActions()) {
      for (emulator::FusionAction& action : actions) {
        std::visit([this](auto& a) { carryOut(a); }, action);
      }
    }
  }
  void carryOut(const emulator::PublishReport& a) {
    if (!a.lacking_writers.empty()) {
      spdlog::warn("episode {} reported without the measurement writers of sensors {}",
                   a.result.episode, json(a.lacking_writers).dump());
    }
    std::vector<sensornet_SensorCounts> counts;
    const sensornet_Report r = wire::reportSample(options_.run.run_id, a.result, a.summary, counts);
    becomePresent("it reports an episode");
    if (dds_.report_writer->write(r) == dds::WriteResult::TimedOut) {
      spdlog::warn("the report of episode {} timed out on the wire (kept in the file)",
                   a.result.episode);
    }
    report_instances_.written(*dds_.report_writer, a.result.episode);
  }
  void carryOut(const emulator::PublishState& a) {
    std::vector<double> values;
    // Keep-last 1: a timeout only loses a superseded estimate.
    becomePresent("an episode runs");
    (void)dds_.state_writer->write(
        wire::fusionStateSample(options_.run.run_id, a, values, wallNowNs()));
  }
  // A log the disk refuses (full) costs its later lines, not the run: the core holds them.
  void carryOut(const emulator::AppendEpisodeLog& a) {
    if (!episode_log_) return;
    try {
      episode_log_->append(a.entry);
    } catch (const std::exception& e) {
      episode_log_.reset();
      core_.onEpisodeLogRefused(a.entry, e.what());
    }
  }
  // Kept by the core for the report, and in the fault log for a restarted fusion center. A
  // fault log that cannot take it costs only what a restart would have carried over: a warning.
  void carryOut(const emulator::RecordFault& a) {
    if (!fault_log_) return;
    try {
      fault_log_->append(sensornet::report::encode(a.fault));
    } catch (const std::exception& e) {
      spdlog::warn("{}; a restarted fusion center would not know of this fault", e.what());
    }
  }
  static void carryOut(const emulator::LogLine& a) { spdlog::log(a.level, "{}", a.text); }
  void writeReport(const std::string& path, const json& doc) {
    writeJsonFile(path, "run report", [&](std::ostream& out) {
      core_.report().write(out, doc, 2);
      out << '\n';
    });
  }
  // The report its path refused (`why`) where the fallbacks take it (report_files.hpp), with
  // the fault that says so in `doc`; throws when none does.
  std::string writeElsewhere(const emulator::WriteFinalReport& a, const std::string& why,
                             json& doc) {
    std::string problems = why;
    for (const auto& path : sensornet::report::fallbackReportPaths(
             options_.report_path, options_.run.run_id, options_.report_fallback)) {
      try {
        const emulator::WriteFinalReport again = core_.reportRefused(a, problems, path);
        writeReport(path.string(), again.doc);
        doc = again.doc;
        return path.string();
      } catch (const std::exception& e) {
        problems += std::string("; nor ") + e.what();
      }
    }
    throw std::runtime_error(problems);
  }
  void carryOut(const emulator::WriteFinalReport& a) {
    json doc = a.doc;
    if (!options_.report_path.empty()) {
      std::string written = options_.report_path;
      try {
        writeReport(options_.report_path, a.doc);
      } catch (const InputError&) {
        throw;
      } catch (const std::exception& e) {  // a full disk: nothing the run measured is lost
        written = writeElsewhere(a, e.what(), doc);
      }
      spdlog::info("report written to {}", written);
      if (options_.page) {
        if (const auto problem = sensornet::report::writePageBeside(written)) {
          spdlog::warn("{}", *problem);
        } else {
          spdlog::info("report page written to {}",
                       sensornet::report::pagePathBeside(written).string());
        }
      }
    }
    if (options_.json) {
      core_.report().write(std::cout, doc, -1);
      std::cout << std::endl;
    }
  }

  ServeOptions options_;
  const pid_t launcher_ = emulator::launcherParent();  // read at start, while the parent lives
  std::unique_ptr<MetricsServer> metrics_;  // --metrics; made first: a bad address is bad input
  wire::FusionCenterEndpoints dds_;
  emulator::FusionCenterCore core_;
  std::optional<sensornet::report::EpisodeLog> episode_log_;
  std::optional<sensornet::report::EpisodeLog> fault_log_;  // faultLogPath: what a restart carries over
  emulator::ArrivalInbox<Arrival> inbox_;
  std::vector<Arrival> taken_;    // the listener's batch (receive thread only)
  std::vector<Arrival> drained_;  // the main loop's (main thread only)
  wire::ClockProbes probes_;
  std::int64_t next_probe_ns_ = 0;
  wire::ReportInstances report_instances_{options_.run.run_id};
  std::int64_t next_absence_log_ns_ = 0;
  std::int64_t next_presence_check_ns_ = 0;
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
  cmd->add_option("--report-fallback", options->report_fallback,
                  "where the report goes when the disk of --report refuses it (full): "
                  "DIR/<run id>-<report's name>, with a write_failed fault that says so (the "
                  "launcher gives its log folder; default: the system's temporary folder)");
  cmd->add_option("--lag", options->core.lag_s,
                  "wall seconds a measurement may take to arrive before it is fused (a later "
                  "one is still fused in order: the episode is re-fused at its end)")
      ->capture_default_str()
      ->check(nonNegativeNumber(kMaxWallSeconds));
  cmd->add_option("--stall-limit", options->core.stall_limit_s,
                  "wall seconds a sensor that still owes measurements may stay silent after an "
                  "episode's end before the episode is closed incomplete (longer than the 10 s "
                  "stalls a run absorbs)")
      ->capture_default_str()
      ->check(positiveNumber(kMaxWallSeconds));
  cmd->add_option("--keep-up-limit", options->core.keep_up_limit_s,
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
  addRunNonceOption(*cmd, options->run_nonce,
                    "with --resume-unfinished: an episode log beside --report");
  return {cmd, [options] {
            if (options->resume_unfinished) {
              const bool unfinished = sensornet::report::unfinishedRunAt(options->report_path);
              options->resume =
                  unfinished && writtenUnderNonce(options->report_path, options->run_nonce);
              if (options->resume) {
                spdlog::info("no final report yet: --resume-unfinished resumes");
              } else if (unfinished) {
                spdlog::info("the episode log beside {} is an earlier deployment's (run nonce "
                             "'{}', this one '{}'): starting afresh over it",
                             options->report_path,
                             recordedNonce(options->report_path).value_or(""),
                             options->run_nonce);
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
