#include "record_command.hpp"

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>

#include "interrupts.hpp"
#include "sensornet/io/utc_time.hpp"
#include "sensornet/launcher/live_runs.hpp"
#include "sensornet/io/output_file.hpp"
#include "sensornet/launcher/run_follower.hpp"
#include "runs_command.hpp"
#include "sensornet/wire/messages.hpp"
#include "sensornet/wire/run_options.hpp"
#include "sensornet/recording/run_recorder.hpp"
#include "sensornet/launcher/run_view.hpp"

namespace sensornet::launcher {
namespace {

using Clock = std::chrono::steady_clock;
constexpr std::chrono::milliseconds kPoll{100};

struct RecordOptions {
  wire::RunOptions run;
  std::string path;
  double wait_s = 30.0;
};

int runRecord(RecordOptions options) {
  checkOutputFile(options.path, "RUN.mcap");
  options.run.run_id = chooseLiveRun(options.run.run_id, options.run.domain_id).run_id;
  installInterruptHandlers();
  RunFollower follower(options.run.domainConfig());
  RunViewConfig config;
  config.run_id = options.run.run_id;
  RunView view(config);
  recording::RunRecorder recorder(follower.participant(), options.run.run_id, options.path,
                                 {{"joined_at", utcNow()}, {"joined", "sensornet record"}});
  std::fprintf(stderr, "sensornet record: recording run %s into %s until it ends (Ctrl-C stops)\n",
               options.run.run_id.c_str(), options.path.c_str());
  const auto give_up = Clock::now() + std::chrono::duration_cast<Clock::duration>(
                                          std::chrono::duration<double>(options.wait_s));
  std::string ended = "ended";
  int code = kExitOk;
  for (;;) {
    follower.pollInto(view, kPoll);
    if (view.finished(emulator::wallNowNs())) break;
    if (pendingInterrupt() != 0) {
      ended = "interrupted";  // this recording was; the run goes on
      break;
    }
    if (!view.answered() && Clock::now() >= give_up) {
      std::fprintf(stderr,
                   "sensornet record: nothing of run %s answered within %g s (is it running? a "
                   "secured run answers only with --security)\n",
                   options.run.run_id.c_str(), options.wait_s);
      ended = "never answered";
      code = kExitFailure;
      break;
    }
  }
  if (const recording::RecordingSummary& drained = recorder.drain(); !drained.error.empty()) {
    std::fprintf(stderr, "sensornet record: the recording fell short: %s\n",
                 drained.error.c_str());
    code = kExitFailure;
  }
  const recording::RecordingSummary s = recorder.stop({{"status", ended}, {"ended_at", utcNow()}});
  std::printf("recorded %llu samples (%llu bytes) of run %s in %s (%s)\n",
              static_cast<unsigned long long>(s.messages),
              static_cast<unsigned long long>(s.bytes), options.run.run_id.c_str(),
              s.path.c_str(), ended.c_str());
  return code;
}

}  // namespace

Subcommand addRecordCommand(CLI::App& app) {
  auto options = std::make_shared<RecordOptions>();
  CLI::App* cmd = app.add_subcommand(
      "record",
      "Join a running emulation and record it into an MCAP file, as `sensornet launch --record` "
      "does from the start: every sample of every topic of the run as it arrives (CDR, with the "
      "project's IDL as schema, readable by any MCAP tool; `sensornet replay --info` shows what "
      "is in it). What was sent before it joined is there only where the topic keeps it for "
      "late joiners (scenario, schedule versions, episode controls, latest reports). It writes "
      "nothing to the run, stops when the run ends or on Ctrl-C, and closes the file with its "
      "summary either way. Exit 0 when the file holds all it took, 1 when the run never "
      "answered within --wait or the disk refused part of it, 2 on bad input. Example:\n"
      "  sensornet record run.mcap            (the one run live on this host)");
  wire::addRunOptions(*cmd, options->run, /*run_id_required=*/false);
  cmd->get_option("--run-id")
      ->description(
          "the run to record (default: the one run live on this host; with several, it lists "
          "them and asks)");
  cmd->add_option("RUN.mcap", options->path, "the recording to write (replaced if it exists)")
      ->required();
  cmd->add_option("--wait", options->wait_s,
                  "seconds to wait for the run to show itself before giving up (exit 1)")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  return {cmd, [options] { return runRecord(*options); }};
}

}  // namespace sensornet::launcher
