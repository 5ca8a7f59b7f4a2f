#include "serve_command.hpp"

#include <spdlog/spdlog.h>

#include <chrono>
#include <filesystem>
#include <memory>
#include <optional>
#include <variant>

#include "sensornet/core/input_error.hpp"
#include "sensornet/dds/wire.hpp"
#include "sensornet/emulator/coordinator_start.hpp"
#include "sensornet/wire/coordinator_wire.hpp"
#include "sensornet/wire/messages.hpp"
#include "sensornet/wire/run_options.hpp"
#include "sensornet/emulator/stop_signal.hpp"
#include "sensornet/io/forwarded_options.hpp"
#include "sensornet/io/output_path.hpp"
#include "sensornet/io/run_nonce.hpp"
#include "sensornet/io/scenario_file.hpp"
#include "sensornet/io/word_option.hpp"

namespace sensornet::coordinator {
namespace {

using namespace std::chrono_literals;
namespace fs = std::filesystem;
using emulator::CoordinatorAction;
using emulator::CoordinatorCore;
using emulator::wallNowNs;

struct ServeOptions {
  wire::RunOptions run;
  emulator::CoordinatorConfig core;
  std::string scenario_path;
  PlanSurrogate surrogate = PlanSurrogate::Covariance;
  std::string schedule_path;
  std::uint64_t seed = 1;
  std::string arrivals;    // empty: the scenario's `arrivals:`; else poisson or timetable
  std::string state_path;  // the journal (empty: none)
  bool resume = false;     // start from the journal
  std::string run_nonce;   // --run-nonce: a journal of another nonce is an earlier deployment's
  bool json = false;
  double replan_every = 0.0;  // --replan-every (0: open loop)
};

// ---- the wiring: DDS endpoints, a loop that feeds the core and carries out its actions -----

class CoordinatorNode {
 public:
  void journalFailed(const std::string& why) { core_.onJournalFailed(why); }
  CoordinatorNode(const ServeOptions& options, emulator::RunScenario run,
                  const emulator::CoordinatorJournal& journal)
      : options_(options),
        run_(std::move(run)),
        core_(options.core, {run_.scenario, run_.digest, run_.seed}, journal, &wallNowNs),
        dds_(options.run.domainConfig()) {}

  int run() {
    carryOut(core_.start(wallNowNs()));
    while (!core_.exitCode()) {
      (void)dds_.waitset.wait(core_.waitHint());
      readSamples();
      if (emulator::stopRequested()) core_.onStopSignal();
      carryOut(core_.tick(wallNowNs()));
    }
    return *core_.exitCode();
  }

 private:
  static void mustWrite(dds::WriteResult result, const char* what) {
    if (result == dds::WriteResult::TimedOut) {
      throw std::runtime_error(std::string("publishing the ") + what + " timed out");
    }
  }

  // Commands first: answering one can plan for many seconds (at -O0 under the sanitizers, half a
  // minute), and what the sensors and the fusion center sent meanwhile must be read before the
  // tick judges anyone silent (a report that came during the plan is not a missing report).
  void readSamples() {
    for (auto& received : dds_.launcher_commands.take(8).samples) {
      carryOut(core_.onCommand(
          wire::commandOf(*received.sample, emulator::CommandSender::Launcher), wallNowNs()));
    }
    for (auto& received : dds_.operator_commands.take(8).samples) {
      carryOut(core_.onCommand(
          wire::commandOf(*received.sample, emulator::CommandSender::Operator), wallNowNs()));
    }
    auto statuses = dds_.status_reader.take(64);
    for (const auto& change : statuses.changes) {
      core_.onSensorLiveliness(static_cast<int>(change.key->sensor_id),
                               change.info.instance_state == dds::InstanceState::Alive,
                               wallNowNs());
    }
    for (auto& received : statuses.samples) {
      const auto speaks = [&](int sensor) {
        return dds_.speakers.speaksFor(dds_.status_reader, received.info.publication, sensor);
      };
      if (const auto status = wire::sensorStatusOf(*received.sample, speaks)) {
        core_.onSensorLiveliness(status->sensor_id,
                                 received.info.instance_state == dds::InstanceState::Alive,
                                 wallNowNs());
        carryOut(core_.onSensorStatus(*status, wallNowNs()));
      }
    }
    for (auto& received : dds_.report_reader.take(16).samples) {
      heard_report_ = true;
      carryOut(core_.onReport(wire::reportOf(*received.sample), wallNowNs()));
    }
    for (auto& received : dds_.state_reader.take(8).samples) {
      carryOut(core_.onFusionState(wire::fusionStateOf(*received.sample), wallNowNs()));
    }
    core_.onFusionCenterMatched(dds_.presence.present(wallNowNs()));
  }

  void carryOut(const emulator::CoordinatorActions& actions) {
    for (const CoordinatorAction& action : actions) std::visit(*this, action);
  }

 public:  // std::visit's overloads, one per action
  void operator()(const emulator::PublishScenario&) {
    mustWrite(wire::publishScenario(dds_.scenario_writer, options_.run.run_id, run_), "scenario");
  }
  void operator()(const emulator::PublishVersion& a) {
    mustWrite(wire::publishSchedule(dds_.schedule_writer, options_.run.run_id, run_.digest,
                                        a.version),
              "schedule");
  }
  void operator()(const emulator::PublishControl& a) {
    mustWrite(dds_.control_writer.write(wire::wireControl(a.control, options_.run.run_id)),
              "episode control");
  }
  void operator()(const emulator::SendReply& a) {
    if (dds_.reply_writer.write(wire::wireReply(options_.run.run_id, a.command_id, a.answer)) ==
        dds::WriteResult::TimedOut) {
      spdlog::warn("the reply to command {} timed out", a.command_id);
    }
  }
  void operator()(const emulator::WriteJournal& a) {
    if (options_.state_path.empty()) return;
    try {
      emulator::saveJournal(options_.state_path, a.journal);
    } catch (const std::exception& e) {  // a full disk: the run ends with the reason
      core_.onJournalFailed(e.what());
    }
  }
  void operator()(const emulator::ShutDownRun& a) {
    if (dds_.control_writer.write(wire::wireControl(a.control, options_.run.run_id)) ==
        dds::WriteResult::TimedOut) {
      spdlog::warn("the shutdown announcement timed out");
    }
    // A run aborted before any Report came (a journal that failed at once): the readers of the
    // shutdown may not have matched the Scenario writer yet (discovery announces endpoints one
    // by one), and without the scenario the fusion center writes no report that says why. So
    // wait (2 s at most: an external fusion center need not read the scenario) until they
    // have, and for their acknowledgements.
    if (a.control.aborted && !heard_report_) {
      wire::awaitScenarioReaders(dds_.scenario_writer, dds_.control_writer, 2s);
    }
    (void)dds_.scenario_writer.waitForAcks(3s);
    (void)dds_.schedule_writer.waitForAcks(3s);
    (void)dds_.control_writer.waitForAcks(3s);
    (void)dds_.reply_writer.waitForAcks(1s);
  }
  void operator()(const emulator::LogLine& a) const { spdlog::log(a.level, "{}", a.text); }
  void operator()(const emulator::ExitProgram& a) const {
    if (options_.json && a.summary) {
      printJson({{"run_id", a.summary->run_id},
                 {"episodes", a.summary->episodes},
                 {"schedule_versions", a.summary->schedule_versions}});
    }
  }

 private:
  ServeOptions options_;
  emulator::RunScenario run_;
  CoordinatorCore core_;

  wire::CoordinatorEndpoints dds_;
  bool heard_report_ = false;  // a Report came: the fusion center had the scenario
};

int runServe(ServeOptions options) {
  emulator::RunScenario run;
  run.yaml = readTextFile(options.scenario_path, "scenario");  // read once: parsed and sent
  run.scenario = parseScenarioYaml(run.yaml, options.scenario_path);
  run.digest = digestOf(run.yaml);
  run.seed = options.seed;
  if (!options.arrivals.empty()) {
    run.scenario.arrivals = parseWord<ArrivalMode>(options.arrivals, "--arrivals", "arrivals");
  }
  (void)options.run.domainConfig();  // bad run or domain id: exit 2 before any planning
  if (!options.state_path.empty()) makeParentFolders(options.state_path, "--state");
  if (options.replan_every > 0.0) options.core.replan_every_s = options.replan_every;
  options.core.run_id = options.run.run_id;
  emulator::checkServeRequest(options.core, run.scenario, options.scenario_path, options.surrogate);
  // The journal is written before anything is published: with --resume, none means the last
  // coordinator died before it announced anything, and the run starts afresh (chaos seed 69).
  std::error_code error;
  const bool journal_file = !options.state_path.empty() && fs::exists(options.state_path, error);
  const bool journaled = journal_file && writtenUnderNonce(options.state_path, options.run_nonce);
  if (options.resume && journal_file && !journaled) {
    spdlog::info("the journal at {} is an earlier deployment's (run nonce '{}', this one '{}'): "
                 "starting the run afresh over it",
                 options.state_path, recordedNonce(options.state_path).value_or(""),
                 options.run_nonce);
  } else if (options.resume && !journaled) {
    spdlog::info("no journal at {}: the coordinator before this one announced nothing; starting "
                 "the run afresh",
                 options.state_path);
  }
  std::optional<RateSchedule> schedule_file;
  if (!options.schedule_path.empty()) {
    schedule_file = loadScheduleFile(options.schedule_path, run.scenario);
  }
  const emulator::CoordinatorJournal journal =
      options.resume && journaled
          ? emulator::resumedJournal(options.core, run, options.state_path, options.scenario_path)
          : emulator::freshJournal(options.core, run, options.surrogate, schedule_file);
  // A path where no file can be made is bad input (exit 2); a disk that refuses the bytes ends
  // the run, which the others can only hear of once the node is up.
  std::optional<std::string> journal_failure;
  if (!options.state_path.empty() && !(options.resume && journaled)) {
    try {
      emulator::saveJournal(options.state_path, journal);
      recordNonce(options.state_path, options.run_nonce);  // after: a journal is never taken
                                                          // for this deployment's too early
    } catch (const InputError&) {
      throw;
    } catch (const std::exception& e) {
      journal_failure = e.what();
    }
  }
  emulator::installStopSignals();
  CoordinatorNode node(options, std::move(run), journal);
  if (journal_failure) node.journalFailed(*journal_failure);
  return node.run();
}

}  // namespace

Subcommand addServeCommand(CLI::App& app) {
  auto options = std::make_shared<ServeOptions>();
  CLI::App* cmd = app.add_subcommand(
      "serve",
      "Coordinate one emulation run over DDS: publish the scenario and the planned schedule, "
      "wait for every sensor and the fusion center, run the episodes on the emulated clock, "
      "re-plan live on command (sensornet replan) and when sensors die, then shut the run "
      "down. Example:\n"
      "  coordinator serve --scenario scenarios/default.yaml --run-id demo --episodes 20\n"
      "After a crash, the same command with --state FILE --resume carries the run on.\n"
      "Exit status: 0 = the coordinator did what it was told: it ran the run to its end, or "
      "ended it by --on-sensor-failure stop, because every sensor failed, on a shutdown "
      "command or on SIGINT/SIGTERM (whether the run failed is the report's status, which the "
      "fusion center and the launcher set); 1 = the coordinator failed: its peers were not "
      "ready within --ready-timeout, no report came within the report timeout, or a write "
      "failed; 2 = bad input (a file, a flag, a journal of another run).");
  wire::addRunOptions(*cmd, options->run);
  options->run.security_identity = dds::SecurityRole::Coordinator;
  cmd->add_option("--scenario", options->scenario_path, "scenario file (YAML)")->required();
  // The options the launcher forwards: declared once (io/forwarded_options.hpp).
  addSurrogateOption(*cmd, options->surrogate);
  addScheduleOption(*cmd, options->schedule_path);
  addEpisodesOption(*cmd, options->core.episodes);
  addTimeScaleOption(*cmd, options->core.time_scale);
  addSeedOption(*cmd, options->seed);
  addReadyTimeoutOption(*cmd, options->core.ready_timeout_s);
  addSwitchMarginOption(*cmd, options->core.switch_margin_s);
  addDropFirstCommandCopyOption(*cmd, options->core.drop_first_command_copy);
  addReplanEveryOption(*cmd, options->replan_every);
  cmd->add_option("--episode-gap", options->core.episode_gap_s,
                  "wall seconds between one episode's end and the next one's start (the next "
                  "episode is announced while the current one runs)")
      ->capture_default_str()
      ->check(positiveNumber(kMaxWallSeconds));
  addOnSensorFailureOption(*cmd, options->core.on_sensor_failure,
                           ". --sensor-deaths says who tells; with stop the report says the run "
                           "failed and the coordinator itself exits 0");
  wordOption<emulator::DeathWitness>(
      cmd->add_option("--sensor-deaths", options->core.sensor_deaths,
                      "who tells the coordinator that sensors died: launcher = the launcher's "
                      "failure notices (it sees its children exit; the default), liveliness = "
                      "no launcher supervises the run (containers, a process manager of your "
                      "own): a sensor whose SensorStatus writer loses its DDS liveliness (1 s "
                      "lease) while episodes run and does not get it back within --death-grace "
                      "is dead, and --on-sensor-failure answers"));
  cmd->add_option("--death-grace", options->core.death_grace_s,
                  "with --sensor-deaths liveliness: wall seconds a sensor may stay without "
                  "liveliness (a stall, a cut link) before it counts as dead")
      ->capture_default_str()
      ->check(positiveNumber(kMaxWallSeconds));
  cmd->add_flag(std::string(kNetworkAwareFlag), options->core.network_aware,
                "plan the initial schedule and every re-plan for the rates the scenario's "
                "network: section delivers (loss thins them, outages of every episode zero "
                "them), with C lambda <= b on the planned rates; needs a network: section");
  addArrivalsOption(*cmd, options->arrivals, "; announced with the scenario");
  CLI::Option* state =
      cmd->add_option("--state", options->state_path,
                      "keep a journal of the run in FILE (JSON, missing folders made; replaced "
                      "atomically after every "
                      "change, before the change goes out): settings, schedule versions, "
                      "episodes reported and announced, commands answered");
  cmd->add_flag("--resume", options->resume,
                "start from the journal in --state instead of planning (after a crash): the "
                "scenario and --seed must be the run's; republishes the scenario and every "
                "version, waits for the report of the episode announced last, then goes on")
      ->needs(state);
  addRunNonceOption(*cmd, options->run_nonce, "a journal in --state");
  cmd->add_flag("--json", options->json, "print a one-line JSON summary at the end");
  return {cmd, [options] { return runServe(*options); }};
}

}  // namespace sensornet::coordinator
