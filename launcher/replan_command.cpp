#include "replan_command.hpp"

#include <unistd.h>

#include <chrono>
#include <cstdint>
#include <cstdio>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "run_files.hpp"
#include "sensornet/core/planner.hpp"
#include "sensornet/dds/topics.hpp"
#include "sensornet/dds/waitset.hpp"
#include "sensornet/dds/wire.hpp"
#include "sensornet/dds/writer.hpp"
#include "sensornet/emulator/messages.hpp"
#include "sensornet/emulator/run_options.hpp"
#include "sensornet/io/scenario_file.hpp"

namespace sensornet::launcher {
namespace {

using Clock = std::chrono::steady_clock;
constexpr dds_attach_t kReplies = 1;
constexpr std::chrono::milliseconds kWaitStep{100};

struct ReplanOptions {
  emulator::RunOptions run;
  std::string surrogate;
  std::vector<std::uint32_t> exclude;
  std::vector<double> budget;
  std::string schedule_path;
  double timeout_s = 10.0;
  bool json = false;
};

// The request as it goes on the wire, with the memory its sample borrows.
struct Request {
  std::string run_id;
  std::uint64_t command_id = 0;
  sensornet_CommandKind kind = sensornet_COMMAND_REPLAN;
  std::string surrogate;
  std::vector<std::uint32_t> sensor_ids;
  std::vector<double> budget;
  std::string schedule_json;
  std::string issuer;
  std::int64_t issued_wall_time_ns = 0;

  [[nodiscard]] sensornet_Command sample() const {
    sensornet_Command command{};
    command.run_id = dds::borrowString(run_id);
    command.command_id = command_id;
    command.kind = kind;
    command.surrogate = dds::borrowString(surrogate);
    dds::borrowSequence(command.sensor_ids, sensor_ids);
    dds::borrowSequence(command.budget, budget);
    command.schedule_json = dds::borrowString(schedule_json);
    command.issuer = dds::borrowString(issuer);
    command.issued_wall_time_ns = issued_wall_time_ns;
    return command;
  }
};

struct Reply {
  bool accepted = false;
  std::uint32_t schedule_version = 0;
  std::string reason;
};

Request buildRequest(const ReplanOptions& options, const std::string& run_id) {
  Request request;
  request.run_id = run_id;
  request.issued_wall_time_ns = emulator::wallNowNs();
  request.command_id = static_cast<std::uint64_t>(request.issued_wall_time_ns);
  request.issuer = "sensornet replan " + std::to_string(::getpid());
  if (!options.surrogate.empty()) {
    request.kind = sensornet_COMMAND_REPLAN;
    request.surrogate = options.surrogate;
  } else if (!options.exclude.empty()) {
    request.kind = sensornet_COMMAND_EXCLUDE_SENSORS;
    request.sensor_ids = options.exclude;
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

// Sends the command once the coordinator's reader is there, then waits for its answer; nullopt
// when no answer came before `deadline` (`why` says what was missing).
std::optional<Reply> exchange(const dds::DomainConfig& config, const Request& request,
                              Clock::time_point deadline, std::string& why) {
  dds::Domain domain(config);
  dds::Participant participant(domain);
  dds::Topic<sensornet_Command> command_topic(participant);
  dds::Topic<sensornet_CommandReply> reply_topic(participant);
  dds::Reader<sensornet_CommandReply> replies(participant, reply_topic);
  dds::Writer<sensornet_Command> commands(participant, command_topic);

  if (!commands.waitForReaders(1, deadline - Clock::now())) {
    why = "no coordinator of run " + request.run_id + " is listening";
    return std::nullopt;
  }
  const sensornet_Command sample = request.sample();
  while (commands.write(sample) == dds::WriteResult::TimedOut) {
    if (Clock::now() >= deadline) {
      why = "the command could not be sent (the coordinator does not acknowledge)";
      return std::nullopt;
    }
  }
  dds::ReadCondition has_reply(replies);
  dds::WaitSet waitset(participant);
  waitset.attach(has_reply, kReplies);
  while (Clock::now() < deadline) {
    (void)waitset.wait(kWaitStep);
    for (const auto& received : replies.take().samples) {
      const sensornet_CommandReply& reply = *received.sample;
      if (reply.command_id != request.command_id ||
          dds::viewString(reply.run_id) != request.run_id) {
        continue;
      }
      return Reply{reply.accepted, reply.schedule_version,
                   std::string(dds::viewString(reply.reason))};
    }
  }
  why = "the coordinator of run " + request.run_id + " did not answer";
  return std::nullopt;
}

int runReplan(ReplanOptions options) {
  options.run.run_id = chooseRunId(options.run.run_id, options.run.domain_id);
  const dds::DomainConfig config = options.run.domainConfig();
  const Request request = buildRequest(options, options.run.run_id);
  const auto deadline = Clock::now() + std::chrono::duration_cast<Clock::duration>(
                                           std::chrono::duration<double>(options.timeout_s));
  std::string why;
  const std::optional<Reply> reply = exchange(config, request, deadline, why);
  if (!reply) {
    std::fprintf(stderr,
                 "sensornet replan: no answer within %g s: %s (is the run still going? see "
                 "`sensornet status --run-id %s`)\n",
                 options.timeout_s, why.c_str(), request.run_id.c_str());
    if (options.json) {
      printJson({{"run_id", request.run_id},
                 {"command_id", request.command_id},
                 {"answered", false},
                 {"reason", why}});
    }
    return kExitFailure;
  }
  if (options.json) {
    printJson({{"run_id", request.run_id},
               {"command_id", request.command_id},
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
      "  sensornet replan --budget 8,4\n  sensornet replan --run-id run-42 --schedule plan.json");
  CLI::Option_group* change = cmd->add_option_group("change", "what to change (exactly one)");
  change
      ->add_option("--surrogate", options->surrogate,
                   "re-plan with this surrogate: info (eq. 11), cov (eq. 15), uniform (no "
                   "optimization: the budget spread evenly) or mc (E[J] itself by Monte Carlo; "
                   "takes up to the coordinator's plan time limit)")
      ->check(CLI::IsMember(wordTexts<PlanSurrogate>()));
  change->add_option("--exclude", options->exclude, "re-plan with these sensor ids at rate zero")
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
  emulator::addRunOptions(*cmd, options->run, /*run_id_required=*/false);
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
