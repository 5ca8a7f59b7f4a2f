#include "watch_command.hpp"

#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "sensornet/launcher/live_runs.hpp"
#include "sensornet/launcher/run_follower.hpp"
#include "sensornet/wire/messages.hpp"
#include "sensornet/wire/run_options.hpp"
#include "sensornet/launcher/run_view.hpp"

namespace sensornet::launcher {
namespace {

using Clock = std::chrono::steady_clock;
constexpr std::chrono::milliseconds kRefresh{250};

struct WatchOptions {
  wire::RunOptions run;
  double wait_s = 30.0;
  bool plain = false;
};

void printLines(const std::vector<std::string>& lines) {
  for (const std::string& line : lines) std::printf("%s\n", line.c_str());
  std::fflush(stdout);
}

void redraw(const RunView& view, std::int64_t now_ns) {
  // Home, clear to the end, then the screen: no terminal mode to restore on Ctrl-C.
  std::printf("\x1b[H\x1b[J%s", view.screen(now_ns).c_str());
  std::fflush(stdout);
}

int runWatch(WatchOptions options) {
  options.run.run_id = chooseLiveRun(options.run.run_id, options.run.domain_id).run_id;
  const bool screen = !options.plain && ::isatty(STDOUT_FILENO) == 1;
  RunFollower follower(options.run.domainConfig());
  RunViewConfig config;
  config.run_id = options.run.run_id;
  RunView view(config);

  const auto give_up = Clock::now() + std::chrono::duration_cast<Clock::duration>(
                                          std::chrono::duration<double>(options.wait_s));
  for (;;) {
    follower.pollInto(view, kRefresh);
    const std::int64_t now = emulator::wallNowNs();
    const bool done = view.finished(now);
    const std::vector<std::string> lines = view.takeLines(now);
    if (screen) {
      if (view.scenario()) redraw(view, now);
      if (done) printLines(lines.empty() ? lines : std::vector<std::string>{lines.back()});
    } else {
      printLines(lines);
    }
    if (done) return view.endedCleanly() ? kExitOk : kExitFailure;
    if (!view.answered() && Clock::now() >= give_up) {
      std::fprintf(stderr,
                   "sensornet watch: nothing of run %s answered within %g s (is it running? "
                   "start one with `sensornet launch SCENARIO`; a run across --hosts answers "
                   "with --cyclone-config <its log dir>/cyclone-launcher.xml, a secured run "
                   "only with --security)\n",
                   options.run.run_id.c_str(), options.wait_s);
      return kExitFailure;
    }
  }
}

}  // namespace

Subcommand addWatchCommand(CLI::App& app) {
  auto options = std::make_shared<WatchOptions>();
  CLI::App* cmd = app.add_subcommand(
      "watch",
      "Watch a running emulation: episode and progress, the schedule version in force, the "
      "running mean against the bracket, latency, and per sensor its state, rate, sent and "
      "received, redrawn four times a second on a terminal; otherwise (or with --plain) one "
      "plain line per change, for logs. It only reads the run's topics. Exits 0 when the run "
      "ends (once its last reports are in and its sensors have stopped). Episode numbers are "
      "the run's own (0, 1, ..., as in report.json); [k/N] is the episode's place among the N "
      "planned. Example:\n  sensornet watch            (the one run live on this host)");
  wire::addRunOptions(*cmd, options->run, /*run_id_required=*/false);
  cmd->get_option("--run-id")
      ->description(
          "the run to watch (default: the one run live on this host; with several, "
          "it lists them and asks)");
  cmd->add_option("--wait", options->wait_s,
                  "seconds to wait for the run to show itself before giving up (exit 1)")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  cmd->add_flag("--plain", options->plain, "plain lines, one per change, even on a terminal");
  return {cmd, [options] { return runWatch(*options); }};
}

}  // namespace sensornet::launcher
