#pragma once
// The options `sensornet launch` passes on to its children, declared once: each option's name,
// the type and check of its value and what it means live here, and the launcher, `coordinator
// serve` and `fusion_center serve` add them through these functions; the launcher writes its
// children's argv with the same names (sensornet/launcher/launch_plan.hpp). A program may add
// a sentence of its own (its default, who tells it the value) after the shared description.
//
//   addEpisodesOption(*cmd, options->episodes);
//   addSwitchMarginOption(*cmd, options->switch_margin_s);           // coordinator: a default
//   addSwitchMarginOption(*cmd, launch.switch_margin_s, " Default: the coordinator's, 0.3");
//   argv.insert(argv.end(), {std::string(kSwitchMarginFlag), formatNumber(0.5)});
//
// --network-aware is a flag of the coordinator and a word (auto, yes, no) of the launcher: only
// its name is shared.

#include <CLI/CLI.hpp>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

#include "sensornet/core/surrogate_kind.hpp"
#include "sensornet/emulator/vocabulary.hpp"

namespace sensornet {

// Limits of the numeric options of the emulator processes (coordinator serve, fusion_center
// serve, sensor_agent) and of the launcher, which checks its own options against the same
// constants, so that a value a child would refuse is refused before any process starts.
inline constexpr double kMinTimeScale = 1e-3;  // --time-scale: emulated seconds per wall second
inline constexpr double kMaxTimeScale = 1e4;
inline constexpr int kMinEpisodes = 1;  // --episodes
inline constexpr int kMaxEpisodes = 10'000'000;
// Wall-clock durations in seconds (--ready-timeout, --switch-margin, --lag, --grace,
// --status-period): at most about 11.6 days, so that they stay exact in int64 nanoseconds
// added to the wall clock.
inline constexpr double kMaxWallSeconds = 1e6;

// The names, as the children's argv spells them.
inline constexpr std::string_view kEpisodesFlag = "--episodes";
inline constexpr std::string_view kTimeScaleFlag = "--time-scale";
inline constexpr std::string_view kSeedFlag = "--seed";
inline constexpr std::string_view kSurrogateFlag = "--surrogate";
inline constexpr std::string_view kScheduleFlag = "--schedule";
inline constexpr std::string_view kReadyTimeoutFlag = "--ready-timeout";
inline constexpr std::string_view kReplanEveryFlag = "--replan-every";
inline constexpr std::string_view kSwitchMarginFlag = "--switch-margin";
inline constexpr std::string_view kOnSensorFailureFlag = "--on-sensor-failure";
inline constexpr std::string_view kNetworkAwareFlag = "--network-aware";
inline constexpr std::string_view kArrivalsFlag = "--arrivals";
inline constexpr std::string_view kMetricsFlag = "--metrics";
inline constexpr std::string_view kDropFirstCommandCopyFlag = "--drop-first-command-copy";

// A run seed: a decimal integer that fits 64 bits unsigned (CLI11 alone would read "-1" as
// 2^64 - 1 and "010" as octal).
[[nodiscard]] CLI::Validator seedNumber();

// Each adds the option with its shared description followed by `more` (a sentence of the
// program's own, starting with a space), its check, and its default where the value has one.
CLI::Option* addEpisodesOption(CLI::App& app, int& episodes);
CLI::Option* addTimeScaleOption(CLI::App& app, double& time_scale);
CLI::Option* addSeedOption(CLI::App& app, std::string& seed, const std::string& more = {});
CLI::Option* addSeedOption(CLI::App& app, std::uint64_t& seed, const std::string& more = {});
CLI::Option* addSurrogateOption(CLI::App& app, PlanSurrogate& surrogate,
                                const std::string& more = {});
CLI::Option* addScheduleOption(CLI::App& app, std::string& schedule_path);
CLI::Option* addReadyTimeoutOption(CLI::App& app, double& seconds, const std::string& more = {});
CLI::Option* addReplanEveryOption(CLI::App& app, double& seconds, const std::string& more = {});
CLI::Option* addSwitchMarginOption(CLI::App& app, double& seconds, const std::string& more = {});
CLI::Option* addSwitchMarginOption(CLI::App& app, std::optional<double>& seconds,
                                   const std::string& more = {});
CLI::Option* addOnSensorFailureOption(CLI::App& app, emulator::FailurePolicy& policy,
                                      const std::string& more = {});
// Empty: the scenario's `arrivals:`.
CLI::Option* addArrivalsOption(CLI::App& app, std::string& arrivals, const std::string& more = {});
CLI::Option* addMetricsOption(CLI::App& app, std::string& address, const std::string& more = {});
CLI::Option* addDropFirstCommandCopyOption(CLI::App& app, bool& drop);

}  // namespace sensornet
