#include "serve_command.hpp"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <filesystem>
#include <memory>
#include <optional>
#include <thread>
#include <variant>

#include "sensornet/core/input_error.hpp"
#include "sensornet/core/network.hpp"
#include "sensornet/planning/planner.hpp"
#include "sensornet/core/surrogate.hpp"
#include "sensornet/dds/matched_endpoints.hpp"
#include "sensornet/dds/participant.hpp"
#include "sensornet/dds/reader.hpp"
#include "sensornet/dds/topics.hpp"
#include "sensornet/dds/waitset.hpp"
#include "sensornet/dds/wire.hpp"
#include "sensornet/dds/writer.hpp"
#include "sensornet/emulator/coordinator_core.hpp"
#include "sensornet/emulator/coordinator_journal.hpp"
#include "sensornet/emulator/coordinator_start.hpp"
#include "sensornet/wire/coordinator_wire.hpp"
#include "sensornet/wire/messages.hpp"
#include "sensornet/wire/run_inputs.hpp"
#include "sensornet/wire/run_options.hpp"
#include "sensornet/emulator/run_partitions.hpp"
#include "sensornet/wire/sensor_speakers.hpp"
#include "sensornet/emulator/stop_signal.hpp"
#include "sensornet/io/forwarded_options.hpp"
#include "sensornet/io/output_path.hpp"
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
        domain_(options.run.domainConfig()),
        participant_(domain_),
        scenario_topic_(participant_),
        schedule_topic_(participant_),
        control_topic_(participant_),
        command_topic_(participant_),
        reply_topic_(participant_),
        status_topic_(participant_),
        report_topic_(participant_),
        state_topic_(participant_),
        scenario_writer_(participant_, scenario_topic_),
        schedule_writer_(participant_, schedule_topic_),
        control_writer_(participant_, control_topic_),
        reply_writer_(participant_, reply_topic_),
        // Commands by right (run_partitions.hpp): the partition a Command came in names who
        // sent it, and in a secured run only the launcher may write in the launcher's.
        launcher_commands_(participant_, command_topic_,
                           dds::endpointQosIn<sensornet_Command>(emulator::commandPartition(
                               participant_.partition(), emulator::CommandSender::Launcher))),
        operator_commands_(participant_, command_topic_,
                           dds::endpointQosIn<sensornet_Command>(emulator::commandPartition(
                               participant_.partition(), emulator::CommandSender::Operator))),
        status_reader_(participant_, status_topic_,
                       dds::readerQosMatching<sensornet_SensorStatus>(
                           emulator::sensorPartitionPattern(participant_.partition()))),
        speakers_(participant_.partition()),
        report_reader_(participant_, report_topic_),
        state_reader_(participant_, state_topic_),
        waitset_(participant_),
        launcher_command_ready_(launcher_commands_),
        operator_command_ready_(operator_commands_),
        status_ready_(status_reader_),
        report_ready_(report_reader_) {
    waitset_.attach(launcher_command_ready_, 1);
    waitset_.attach(status_ready_, 2);
    waitset_.attach(report_ready_, 3);
    waitset_.attach(operator_command_ready_, 4);
  }

  int run() {
    carryOut(core_.start(wallNowNs()));
    while (!core_.exitCode()) {
      (void)waitset_.wait(core_.waitHint());
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
    for (auto& received : launcher_commands_.take(8).samples) {
      carryOut(core_.onCommand(
          wire::commandOf(*received.sample, emulator::CommandSender::Launcher), wallNowNs()));
    }
    for (auto& received : operator_commands_.take(8).samples) {
      carryOut(core_.onCommand(
          wire::commandOf(*received.sample, emulator::CommandSender::Operator), wallNowNs()));
    }
    auto statuses = status_reader_.take(64);
    for (const auto& change : statuses.changes) {
      core_.onSensorLiveliness(static_cast<int>(change.key->sensor_id),
                               change.info.instance_state == dds::InstanceState::Alive,
                               wallNowNs());
    }
    for (auto& received : statuses.samples) {
      const sensornet_SensorStatus& s = *received.sample;
      if (const auto state = wire::sensorStateOf(s.state)) {
        const int sensor = static_cast<int>(s.sensor_id);
        core_.onSensorLiveliness(sensor, received.info.instance_state == dds::InstanceState::Alive,
                                 wallNowNs());
        carryOut(core_.onSensorStatus(
            {sensor, *state, s.schedule_version, std::string(dds::viewString(s.detail)),
             speakers_.speaksFor(status_reader_, received.info.publication, sensor)},
            wallNowNs()));
      } else {
        spdlog::warn("ignored a status of sensor {} with state {}", s.sensor_id,
                     static_cast<int>(s.state));
      }
    }
    for (auto& received : report_reader_.take(16).samples) {
      heard_report_ = true;
      carryOut(core_.onReport(wire::reportOf(*received.sample), wallNowNs()));
    }
    for (auto& received : state_reader_.take(8).samples) {
      carryOut(core_.onFusionState(wire::fusionStateOf(*received.sample), wallNowNs()));
    }
    core_.onFusionCenterMatched(fusionCenterPresent());
  }

  // The fusion center counts as present once one participant matched all three: a reader of
  // this EpisodeControl writer, and writers of the Report and FusionState readers. Discovery
  // announces endpoints one by one (on a lossy link seconds apart), and a control reader that
  // matches after the first two episodes were announced gets only the latest of them. The
  // participants are looked up again when a match count changes, and twice a second in case
  // one endpoint left and another came between two looks.
  bool fusionCenterPresent() {
    const std::array<std::uint32_t, 3> counts{control_writer_.matchedReaders(),
                                              report_reader_.matchedWriters(),
                                              state_reader_.matchedWriters()};
    const std::int64_t now = wallNowNs();
    if (counts != presence_counts_ || now >= presence_recheck_ns_) {
      presence_counts_ = counts;
      presence_recheck_ns_ = now + 500'000'000;
      fusion_present_ = counts[1] > 0 && counts[2] > 0 &&
                        dds::sharesParticipant({dds::participantsOfMatchedReaders(control_writer_),
                                                dds::participantsOfMatchedWriters(report_reader_),
                                                dds::participantsOfMatchedWriters(state_reader_)});
    }
    return fusion_present_;
  }

  // Until every participant that reads EpisodeControl reads the Scenario too, or `limit`.
  void awaitScenarioReaders(std::chrono::milliseconds limit) const {
    const auto deadline = std::chrono::steady_clock::now() + limit;
    const auto missing = [this] {
      const auto scenario = dds::participantsOfMatchedReaders(scenario_writer_);
      for (const dds::ParticipantKey& p : dds::participantsOfMatchedReaders(control_writer_)) {
        if (std::find(scenario.begin(), scenario.end(), p) == scenario.end()) return true;
      }
      return false;
    };
    while (missing() && std::chrono::steady_clock::now() < deadline) {
      std::this_thread::sleep_for(20ms);
    }
  }

  void carryOut(const emulator::CoordinatorActions& actions) {
    for (const CoordinatorAction& action : actions) std::visit(*this, action);
  }

 public:  // std::visit's overloads, one per action
  void operator()(const emulator::PublishScenario&) {
    mustWrite(wire::publishScenario(scenario_writer_, options_.run.run_id, run_), "scenario");
  }
  void operator()(const emulator::PublishVersion& a) {
    mustWrite(wire::publishSchedule(schedule_writer_, options_.run.run_id, run_.digest,
                                        a.version),
              "schedule");
  }
  void operator()(const emulator::PublishControl& a) {
    mustWrite(control_writer_.write(wire::wireControl(a.control, options_.run.run_id)),
              "episode control");
  }
  void operator()(const emulator::SendReply& a) {
    sensornet_CommandReply reply{};
    reply.run_id = dds::borrowString(options_.run.run_id);
    reply.command_id = a.command_id;
    reply.accepted = a.answer.accepted;
    reply.schedule_version = a.answer.schedule_version;
    reply.reason = dds::borrowString(a.answer.reason);
    if (reply_writer_.write(reply) == dds::WriteResult::TimedOut) {
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
    if (control_writer_.write(wire::wireControl(a.control, options_.run.run_id)) ==
        dds::WriteResult::TimedOut) {
      spdlog::warn("the shutdown announcement timed out");
    }
    // A run aborted before any Report came (a journal that failed at once): the readers of the
    // shutdown may not have matched the Scenario writer yet (discovery announces endpoints one
    // by one), and without the scenario the fusion center writes no report that says why. So
    // wait (2 s at most: an external fusion center need not read the scenario) until they
    // have, and for their acknowledgements.
    if (a.control.aborted && !heard_report_) awaitScenarioReaders(2s);
    (void)scenario_writer_.waitForAcks(3s);
    (void)schedule_writer_.waitForAcks(3s);
    (void)control_writer_.waitForAcks(3s);
    (void)reply_writer_.waitForAcks(1s);
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

  dds::Domain domain_;
  dds::Participant participant_;
  dds::Topic<sensornet_Scenario> scenario_topic_;
  dds::Topic<sensornet_Schedule> schedule_topic_;
  dds::Topic<sensornet_EpisodeControl> control_topic_;
  dds::Topic<sensornet_Command> command_topic_;
  dds::Topic<sensornet_CommandReply> reply_topic_;
  dds::Topic<sensornet_SensorStatus> status_topic_;
  dds::Topic<sensornet_Report> report_topic_;
  dds::Topic<sensornet_FusionState> state_topic_;
  dds::Writer<sensornet_Scenario> scenario_writer_;
  dds::Writer<sensornet_Schedule> schedule_writer_;
  dds::Writer<sensornet_EpisodeControl> control_writer_;
  dds::Writer<sensornet_CommandReply> reply_writer_;
  dds::Reader<sensornet_Command> launcher_commands_;
  dds::Reader<sensornet_Command> operator_commands_;
  dds::Reader<sensornet_SensorStatus> status_reader_;
  wire::SensorSpeakers speakers_;
  dds::Reader<sensornet_Report> report_reader_;
  dds::Reader<sensornet_FusionState> state_reader_;
  dds::WaitSet waitset_;
  dds::ReadCondition launcher_command_ready_;
  dds::ReadCondition operator_command_ready_;
  dds::ReadCondition status_ready_;
  dds::ReadCondition report_ready_;
  std::array<std::uint32_t, 3> presence_counts_{};
  bool heard_report_ = false;  // a Report came: the fusion center had the scenario
  std::int64_t presence_recheck_ns_ = 0;
  bool fusion_present_ = false;
};

// Plans version 1 (or adopts --schedule), as a fresh journal.
emulator::CoordinatorJournal freshJournal(const ServeOptions& options,
                                          const emulator::RunScenario& run) {
  std::optional<RateSchedule> schedule_file;
  if (!options.schedule_path.empty()) {
    schedule_file = loadScheduleFile(options.schedule_path, run.scenario);
  }
  emulator::ScheduleVersion first = emulator::firstVersion(
      run.scenario, options.surrogate, options.core.network_aware, schedule_file);
  emulator::CoordinatorJournal journal =
      emulator::journalHeader(options.core, run.digest, run.seed);
  journal.settings = emulator::initialSettings(run.scenario, options.surrogate);
  journal.versions.push_back(std::move(first));
  return journal;
}

// The journal of --state, checked against this run (exit 2 when it belongs to another).
emulator::CoordinatorJournal resumedJournal(ServeOptions& options,
                                            const emulator::RunScenario& run) {
  emulator::CoordinatorJournal journal = emulator::loadJournal(options.state_path, run.scenario);
  emulator::checkJournalOfRun(journal, options.state_path, run.digest, options.scenario_path,
                              run.seed);
  if (journal.run_id != options.run.run_id) {
    spdlog::warn("resuming run {} from the journal of run {}", options.run.run_id,
                 journal.run_id);
  }
  // The run's own episode count and time scale, whatever the command line says.
  options.core.episodes = static_cast<int>(journal.episodes_planned);
  options.core.time_scale = journal.time_scale;
  spdlog::info("resuming from {}: schedule v{}, {} episodes reported, {} failed sensor(s)",
               options.state_path, journal.versions.back().version,
               journal.episodes_reported.size(), journal.settings.failed.size());
  return journal;
}

int runServe(ServeOptions options) {
  emulator::RunScenario run;
  run.yaml = readTextFile(options.scenario_path, "scenario");  // read once: parsed and sent
  run.scenario = parseScenarioYaml(run.yaml, options.scenario_path);
  run.digest = emulator::digestOf(run.yaml);
  run.seed = options.seed;
  if (!options.arrivals.empty()) {
    run.scenario.arrivals = parseWord<ArrivalMode>(options.arrivals, "--arrivals", "arrivals");
  }
  (void)options.run.domainConfig();  // bad run or domain id: exit 2 before any planning
  if (!options.state_path.empty()) makeParentFolders(options.state_path, "--state");
  if (options.core.network_aware && !run.scenario.network) {
    throw InputError(options.scenario_path, "network",
                     "a network: section (--network-aware plans for the rates it delivers)");
  }
  if (options.replan_every > 0.0) {
    if (options.surrogate != PlanSurrogate::Information &&
        options.surrogate != PlanSurrogate::Covariance) {
      throw InputError("--replan-every", "--surrogate",
                       "info or cov (the closed loop re-plans with the run's surrogate, within "
                       "the switch margin), got " + std::string(describe(options.surrogate)));
    }
    options.core.replan_every_s = options.replan_every;
  }
  options.core.run_id = options.run.run_id;
  // The journal is written before anything is published: with --resume, none means the last
  // coordinator died before it announced anything, and the run starts afresh (chaos seed 69).
  std::error_code error;
  const bool journaled = !options.state_path.empty() && fs::exists(options.state_path, error);
  if (options.resume && !journaled) {
    spdlog::info("no journal at {}: the coordinator before this one announced nothing; starting "
                 "the run afresh",
                 options.state_path);
  }
  const emulator::CoordinatorJournal journal =
      options.resume && journaled ? resumedJournal(options, run) : freshJournal(options, run);
  // A path where no file can be made is bad input (exit 2); a disk that refuses the bytes ends
  // the run, which the others can only hear of once the node is up.
  std::optional<std::string> journal_failure;
  if (!options.state_path.empty() && !(options.resume && journaled)) {
    try {
      emulator::saveJournal(options.state_path, journal);
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
  cmd->add_flag("--json", options->json, "print a one-line JSON summary at the end");
  return {cmd, [options] { return runServe(*options); }};
}

}  // namespace sensornet::coordinator
