#include "sensornet/io/forwarded_options.hpp"

#include <charconv>

#include "sensornet/core/arrival_mode.hpp"
#include "sensornet/io/command_line.hpp"
#include "sensornet/io/word_option.hpp"

namespace sensornet {
namespace {

std::string name(std::string_view flag) { return std::string(flag); }

constexpr const char* kSeedHelp =
    "run seed: keys the plant truth, the arrivals and the sensor noise";
constexpr const char* kReadyTimeoutHelp =
    "seconds the coordinator waits for every sensor and the fusion center before it gives up "
    "and the run fails";
constexpr const char* kReplanEveryHelp =
    "closed loop: at each multiple of DT emulated seconds of every episode, the coordinator "
    "re-plans the rest of it from the fused covariance with the run's --surrogate (info or cov), "
    "taking effect --switch-margin later; every episode starts with the open-loop plan again (a "
    "receding horizon). Default: open loop";
constexpr const char* kSwitchMarginHelp =
    "wall seconds between a re-plan (--replan-every's, a failure's, `sensornet replan`'s) and "
    "the moment it takes effect: the time every sensor has to hear of it. Raise it on a slow or "
    "loaded machine, where a re-plan published late moves to the next episode";

}  // namespace

CLI::Validator seedNumber() {
  const std::string range = "an integer from 0 to 18446744073709551615";
  return CLI::Validator(
      [range](std::string& input) -> std::string {
        std::uint64_t value = 0;
        const char* end = input.data() + input.size();
        const auto [stop, error] = std::from_chars(input.data(), end, value);
        const bool digits_only =
            !input.empty() && input.find_first_not_of("0123456789") == std::string::npos;
        if (!digits_only || error != std::errc() || stop != end) {
          return "expected " + range + ", got '" + input.substr(0, 40) +
                 (input.size() > 40 ? "...'" : "'");
        }
        return {};
      },
      range);
}

CLI::Option* addEpisodesOption(CLI::App& app, int& episodes) {
  return app.add_option(name(kEpisodesFlag), episodes, "episodes to run")
      ->check(integerRange(kMinEpisodes, kMaxEpisodes))
      ->capture_default_str();
}

CLI::Option* addTimeScaleOption(CLI::App& app, double& time_scale) {
  return app
      .add_option(name(kTimeScaleFlag), time_scale,
                  "emulated seconds per wall second (1 = real time, 10 = ten times faster)")
      ->check(numberRange(kMinTimeScale, kMaxTimeScale))
      ->capture_default_str();
}

CLI::Option* addSeedOption(CLI::App& app, std::string& seed, const std::string& more) {
  return app.add_option(name(kSeedFlag), seed, kSeedHelp + more)
      ->check(seedNumber())
      ->capture_default_str();
}

CLI::Option* addSeedOption(CLI::App& app, std::uint64_t& seed, const std::string& more) {
  return app.add_option(name(kSeedFlag), seed, kSeedHelp + more)
      ->check(seedNumber())
      ->capture_default_str();
}

CLI::Option* addSurrogateOption(CLI::App& app, PlanSurrogate& surrogate, const std::string& more) {
  return wordOption<PlanSurrogate>(app.add_option(
      name(kSurrogateFlag), surrogate,
      "how the coordinator plans the schedule: uniform, info (eq. 11), cov (eq. 15) or mc "
      "(E[J] itself by Monte Carlo, up to a minute)" +
          more));
}

CLI::Option* addScheduleOption(CLI::App& app, std::string& schedule_path) {
  return app.add_option(name(kScheduleFlag), schedule_path,
                        "use this schedule file (JSON) instead of planning one");
}

CLI::Option* addReadyTimeoutOption(CLI::App& app, double& seconds, const std::string& more) {
  return app.add_option(name(kReadyTimeoutFlag), seconds, kReadyTimeoutHelp + more)
      ->capture_default_str()
      ->check(positiveNumber(kMaxWallSeconds));
}

CLI::Option* addReplanEveryOption(CLI::App& app, double& seconds, const std::string& more) {
  return app.add_option(name(kReplanEveryFlag), seconds, kReplanEveryHelp + more)
      ->check(positiveNumber(kMaxWallSeconds));
}

CLI::Option* addSwitchMarginOption(CLI::App& app, double& seconds, const std::string& more) {
  return app.add_option(name(kSwitchMarginFlag), seconds, kSwitchMarginHelp + more)
      ->capture_default_str()
      ->check(positiveNumber(kMaxWallSeconds));
}

CLI::Option* addSwitchMarginOption(CLI::App& app, std::optional<double>& seconds,
                                   const std::string& more) {
  return app.add_option(name(kSwitchMarginFlag), seconds, kSwitchMarginHelp + more)
      ->check(positiveNumber(kMaxWallSeconds));
}

CLI::Option* addOnSensorFailureOption(CLI::App& app, emulator::FailurePolicy& policy,
                                      const std::string& more) {
  return wordOption<emulator::FailurePolicy>(app.add_option(
      name(kOnSensorFailureFlag), policy,
      "what the run does when a sensor agent dies: replan = the coordinator re-plans the rest "
      "of the horizon among the survivors (the dead sensors get rate zero from a switch tick "
      "on, a full-horizon version from the next episode) and the run ends degraded; continue = "
      "keep the schedule, so the bracket shows the damage (degraded); stop = end the run as "
      "failed. Either way the dead sensors are announced and nobody waits for them" +
          more));
}

CLI::Option* addArrivalsOption(CLI::App& app, std::string& arrivals, const std::string& more) {
  return wordOption(
      app.add_option(name(kArrivalsFlag), arrivals,
                     "how every sensor's instants follow from its rates: poisson (drawn afresh "
                     "each episode) or timetable (deterministic, where the sensor's integrated "
                     "rate reaches k - 1/2, the same every episode; across a re-plan the count "
                     "continues on the rates in force); default: the scenario's arrivals:, else "
                     "poisson" +
                         more),
      wordTexts<ArrivalMode>());
}

CLI::Option* addMetricsOption(CLI::App& app, std::string& address, const std::string& more) {
  return app.add_option(name(kMetricsFlag), address,
                        "serve the run's live metrics for Prometheus at http://HOST:PORT/metrics "
                        "(text format 0.0.4; HOST a numeric IPv4 address, e.g. 127.0.0.1:9464 "
                        "to stay on this host); kept up 2 s after the final report so that a "
                        "scraper gets the last values" +
                            more);
}

CLI::Option* addDropFirstCommandCopyOption(CLI::App& app, bool& drop) {
  return app.add_flag(name(kDropFirstCommandCopyFlag), drop,
                      "testing a scheduler of your own (sensornet conform scheduler): the "
                      "coordinator leaves the first copy of each Command unanswered, as "
                      "if it were lost, so that the sender must write it again");
}

}  // namespace sensornet
