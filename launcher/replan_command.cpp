#include "replan_command.hpp"

#include <unistd.h>

#include <chrono>
#include <cstdint>
#include <cstdio>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "sensornet/launcher/command_client.hpp"
#include "sensornet/launcher/host_placement.hpp"
#include "sensornet/launcher/run_files.hpp"
#include "sensornet/planning/planner.hpp"
#include "sensornet/wire/messages.hpp"
#include "sensornet/wire/run_options.hpp"
#include "sensornet/io/scenario_file.hpp"
#include "sensornet/io/word_option.hpp"

namespace sensornet::launcher {
namespace {

using Clock = std::chrono::steady_clock;

struct ReplanOptions {
  wire::RunOptions run;
  std::string surrogate;
  std::vector<std::uint32_t> exclude;
  std::vector<std::uint32_t> include;
  std::vector<double> budget;
  std::string schedule_path;
  double timeout_s = 10.0;
  bool json = false;
};

CommandRequest buildRequest(const ReplanOptions& options) {
  CommandRequest request;
  if (!options.surrogate.empty()) {
    request.kind = sensornet_COMMAND_REPLAN;
    request.surrogate = options.surrogate;
  } else if (!options.exclude.empty()) {
    request.kind = sensornet_COMMAND_EXCLUDE_SENSORS;
    request.sensor_ids = options.exclude;
  } else if (!options.include.empty()) {
    request.kind = sensornet_COMMAND_INCLUDE_SENSORS;
    request.sensor_ids = options.include;
  } else if (!options.budget.empty()) {
    request.kind = sensornet_COMMAND_SET_BUDGET;
    request.budget = options.budget;
  } else {
    request.kind = sensornet_COMMAND_SCHEDULE_FILE;
    request.schedule_json = readTextFile(options.schedule_path, "schedule");
    // Bad input fails here, not at the coordinator.
    (void)parseScheduleJson(request.schedule_json, options.schedule_path);
  }
  return request;
}

// Sends the command once the coordinator's reader is there (again until it answers: a
// coordinator restarted meanwhile answers the repeat), then waits for its answer; nullopt when
// no answer came before `deadline` (`why` says what was missing).
std::optional<CommandReply> exchange(const dds::DomainConfig& config, const std::string& run_id,
                                     CommandRequest request, Clock::time_point deadline,
                                     std::uint64_t& command_id, std::string& why) {
  dds::Domain domain(config);
  dds::Participant participant(domain);
  CommandClient client(participant, run_id, emulator::CommandSender::Operator,
                       "sensornet replan " + std::to_string(::getpid()));
  if (!client.waitForCoordinator(deadline - Clock::now())) {
    why = "no coordinator of run " + run_id + " is listening";
    return std::nullopt;
  }
  command_id = client.send(std::move(request));
  std::optional<CommandReply> reply = client.await(command_id, deadline);
  if (!reply) why = "the coordinator of run " + run_id + " did not answer";
  return reply;
}

int runReplan(ReplanOptions options) {
  options.run.run_id = chooseRunId(options.run.run_id, options.run.domain_id);
  const dds::DomainConfig config = options.run.domainConfig();
  const std::string& run_id = options.run.run_id;
  CommandRequest request = buildRequest(options);
  const auto deadline = Clock::now() + std::chrono::duration_cast<Clock::duration>(
                                           std::chrono::duration<double>(options.timeout_s));
  std::string why;
  std::uint64_t command_id = 0;
  const std::optional<CommandReply> reply =
      exchange(config, run_id, std::move(request), deadline, command_id, why);
  if (!reply) {
    std::fprintf(stderr,
                 "sensornet replan: no answer within %g s: %s (is the run still going? see "
                 "`sensornet status %s`)\n",
                 options.timeout_s, why.c_str(), shellLine(options.run.reachFlags()).c_str());
    if (options.json) {
      printJson({{"run_id", run_id},
                 {"command_id", command_id},
                 {"answered", false},
                 {"reason", why}});
    }
    return kExitFailure;
  }
  if (options.json) {
    printJson({{"run_id", run_id},
               {"command_id", command_id},
               {"answered", true},
               {"accepted", reply->accepted},
               {"schedule_version", reply->schedule_version},
               {"reason", reply->reason}});
  } else if (reply->accepted) {
    std::printf("accepted: version %u%s\n", reply->schedule_version,
                reply->reason.empty() ? "" : (" (" + reply->reason + ")").c_str());
  } else {
    std::printf("refused: %s\n", reply->reason.c_str());
  }
  return reply->accepted ? kExitOk : kExitFailure;
}

}  // namespace

Subcommand addReplanCommand(CLI::App& app) {
  auto options = std::make_shared<ReplanOptions>();
  CLI::App* cmd = app.add_subcommand(
      "replan",
      "Change the schedule of a running emulation: the coordinator re-plans the rest of the "
      "horizon from the fused covariance and publishes a new version, which every sensor "
      "adopts at its effective time. Give exactly one change. Prints \"accepted: version V\" "
      "(exit 0) or \"refused: reason\" (exit 1). Examples:\n"
      "  sensornet replan --surrogate cov\n  sensornet replan --exclude 2,5\n"
      "  sensornet replan --include 5\n"
      "  sensornet replan --budget 8,4\n  sensornet replan --run-id run-42 --schedule plan.json");
  CLI::Option_group* change = cmd->add_option_group("change", "what to change (exactly one)");
  wordOption(change->add_option("--surrogate", options->surrogate,
                                "re-plan with this surrogate: info (eq. 11), cov (eq. 15), "
                                "uniform (no optimization: the budget spread evenly) or mc (E[J] "
                                "itself by Monte Carlo; takes up to the coordinator's plan time "
                                "limit)"),
             wordTexts<PlanSurrogate>());
  change
      ->add_option("--exclude", options->exclude,
                   "re-plan with these sensor ids at rate zero (added to those excluded before)")
      ->delimiter(',');
  change
      ->add_option("--include", options->include,
                   "re-plan with these excluded sensor ids back in service (refused for a "
                   "sensor whose process died, or one in service)")
      ->delimiter(',');
  change
      ->add_option("--budget", options->budget,
                   "re-plan with this constraint right-hand side b (one value per row of C)")
      ->delimiter(',')
      ->check(CLI::NonNegativeNumber);
  change
      ->add_option("--schedule", options->schedule_path,
                   "adopt this schedule file (JSON) for the rest of the run")
      ->check(CLI::ExistingFile);
  change->require_option(1);
  wire::addRunOptions(*cmd, options->run, /*run_id_required=*/false);
  cmd->get_option("--run-id")
      ->description("the run to change (default: the run last launched on this host)");
  cmd->add_option("--timeout", options->timeout_s, "seconds to wait for the coordinator's answer")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  cmd->add_flag("--json", options->json,
                "print {\"accepted\", \"schedule_version\", \"reason\", ...} as one JSON line");
  return {cmd, [options] { return runReplan(*options); }};
}

}  // namespace sensornet::launcher
