#include "run_supervisor.hpp"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <map>
#include <optional>

#include "interrupts.hpp"
#include "sensornet/wire/messages.hpp"

namespace sensornet::launcher {
namespace {

using Clock = std::chrono::steady_clock;
constexpr std::chrono::milliseconds kWatchStep{50};
constexpr std::chrono::seconds kStopGrace{3};
// An external sensor whose SensorStatus writer (liveliness 1 s) stays gone this long is dead.
constexpr std::chrono::seconds kExternalGoneLimit{2};
// Stopped last and given longer: on SIGTERM the fusion center closes its open episodes and
// writes the report.
constexpr std::chrono::seconds kFusionCenterStopGrace{10};

class Wiring {
 public:
  Wiring(Supervisor& core, RunHandles run) : core_(core), run_(std::move(run)) {}

  void step() {
    run_.progress.poll(kWatchStep);
    for (const auto& [process, reply] : run_.notices.poll()) core_.onReply(process, reply);
    const std::int64_t now_ns = emulator::wallNowNs();
    const RunPosition at = run_.progress.positionAt(now_ns);
    for (const ChildExit& exit : run_.group.reap()) {
      carryOut(core_.onChildExit(exit, at, Clock::now(), lastSeenAlive(exit, now_ns)), at);
    }
    last_look_ns_ = now_ns;
    if (const std::vector<int> gone = externalsGone(); !gone.empty()) {
      carryOut(core_.onExternalSensorsGone(gone, at), at);
    }
    if (const int signal = pendingInterrupt()) carryOut(core_.onSignal(signal, at), at);
    carryOut(core_.onTick(Clock::now(), at), at);
  }

 private:
  // The previous reap found the child running, and so did its latest SensorStatus: the later of
  // the two is the last the launcher knows it alive. Far from now only when the launcher itself
  // did not run in between (the core then dates the death by it).
  [[nodiscard]] std::optional<LastSeenAlive> lastSeenAlive(const ChildExit& exit,
                                                           std::int64_t now_ns) const {
    if (last_look_ns_ == 0) return std::nullopt;
    const std::int64_t seen_ns = std::clamp(run_.progress.lastStatusWallNs(exit.pid),
                                            last_look_ns_, now_ns);
    return LastSeenAlive{run_.progress.positionAt(seen_ns),
                         1e-9 * static_cast<double>(now_ns - seen_ns)};
  }

  // The external sensors gone for kExternalGoneLimit without a break: their participant left
  // (a pause shorter than that, of the process or of its link, is a stall, as for our agents).
  std::vector<int> externalsGone() {
    std::vector<int> gone;
    const auto now = Clock::now();
    for (const int j : run_.external_sensors) {
      if (!run_.progress.gone(j)) {
        gone_since_.erase(j);
        continue;
      }
      const auto since = gone_since_.try_emplace(j, now).first->second;
      if (now - since >= kExternalGoneLimit) gone.push_back(j);
    }
    return gone;
  }

  void carryOut(const std::vector<Action>& actions, const RunPosition& at) {
    for (const Action& action : actions) {
      if (const auto* restart = std::get_if<RestartChild>(&action)) {
        carryOut(this->restart(*restart), at);
      } else if (const auto* notice = std::get_if<NotifySensorsFailed>(&action)) {
        run_.notices.send(notice->process, notice->sensors, notice->detail);
      } else if (std::holds_alternative<StopRun>(action)) {
        stop(at);
      } else if (const auto* line = std::get_if<LogLine>(&action)) {
        if (line->error) {
          spdlog::error("{}", line->text);
        } else {
          std::fprintf(stderr, "sensornet: %s\n", line->text.c_str());
        }
      }
    }
  }

  std::vector<Action> restart(const RestartChild& restart) {
    const auto spec = std::find_if(run_.children.begin(), run_.children.end(),
                                   [&](const ChildSpec& c) { return c.name == restart.name; });
    if (spec == run_.children.end()) return core_.onRestartFailed(restart.name, "not in the plan");
    ChildSpec again = *spec;
    again.argv.emplace_back("--resume");
    again.log_path =
        run_.log_dir / (restart.name + ".restart-" + std::to_string(restart.attempt) + ".log");
    try {
      const pid_t pid = run_.group.start(again);
      return core_.onRestarted(restart.name, pid, again.log_path.filename().string());
    } catch (const std::exception& e) {
      return core_.onRestartFailed(restart.name, e.what());
    }
  }

  // The fusion center (ours, or the reference beside an external one) last, so that it can
  // write its report; how each child ended goes back to the core, which counts none of it as a
  // fault.
  void stop(const RunPosition& at) {
    std::vector<std::string> others = run_.group.runningNames();
    std::erase(others, std::string(kFusionCenter));
    std::erase(others, std::string(kReferenceFusionCenter));
    std::vector<ChildExit> ended = run_.group.stop(others, kStopGrace);
    for (ChildExit& e : run_.group.stop({kFusionCenter, kReferenceFusionCenter},
                                        kFusionCenterStopGrace)) {
      ended.push_back(std::move(e));
    }
    for (ChildExit& e : run_.group.reap()) ended.push_back(std::move(e));
    for (const ChildExit& e : ended) carryOut(core_.onChildExit(e, at, Clock::now()), at);
    core_.onStopped();
  }

  Supervisor& core_;
  RunHandles run_;
  std::map<int, Clock::time_point> gone_since_;
  std::int64_t last_look_ns_ = 0;  // wall time of the previous reap
};

}  // namespace

void superviseRun(Supervisor& core, RunHandles run) {
  Wiring wiring(core, std::move(run));
  while (!core.done()) wiring.step();
}

}  // namespace sensornet::launcher
