#pragma once
// The coordinator's live re-planning, without DDS: a change of the run's settings (surrogate,
// excluded sensors, budget b), a schedule file, or sensors that died becomes the schedule
// versions to publish and a one-line summary for the reply, or an InputError that refuses it.
// The coordinator reads DDS, calls this, publishes the versions and adopts the settings.
//
//   Replanner replanner(scenario, plant, settings, options);   // plant: only its tick grid
//   RunMoment now{.running = true, .episode = 2, .fused = fused, .emulated_now = clockNow};
//   const Replan r = replanner.exclude({0}, book, now, command_id);  // throws InputError
//   for (const ScheduleVersion& v : r.versions) { book.add(v); publish(v); }
//   replanner.adopt(r);                      // the new settings hold once the plans are out
//   reply(r.replyVersion(), r.summary);
//
// When the change comes while an episode runs, and the fused covariance of that episode is
// known, it takes effect at a tick switch_margin_s wall seconds ahead of now, planned over the
// rest of the horizon from the fused covariance carried forward to that tick (by the surrogate
// of the plan's form under the version in force: what arrives in between is not fused yet).
// Planning takes time: if less than half a margin is left when it is done, the switch moves to
// the first tick half a margin from then (the plan's rates from there on; they stay feasible).
// A second version, planned over the whole horizon from P0 with the same settings, takes over
// from the next episode. Between episodes there is only that one version, from the next one.
//
// Both plans are made, and both must be ones the planner reports as optimal ("acceptable" is
// taken and named in the summary; "not_optimized" is the uniform schedule), before either is
// returned: otherwise this throws InputError and the settings are unchanged. A projected
// quasi-Newton solve that "stalled" (no step decreases the cost in floating point) at a point
// whose scale-free KKT residual is at most kStationaryResidual (every planned rate within 0.1%
// of its projected-gradient step) is taken too, and named so: the fused covariance a
// mid-episode plan starts from often leaves the cost too flat for the 1e-6 tolerance.
//
// Failed sensors (their process died) are a fact, not a setting: noteFailed() records them
// whatever happens next, and every later plan gives them rate zero, like excluded ones.

#include <Eigen/Core>
#include <cstdint>
#include <functional>
#include <optional>
#include <set>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "sensornet/core/emulated_plant.hpp"
#include "sensornet/planning/planner.hpp"
#include "sensornet/core/scenario.hpp"
#include "sensornet/emulator/schedule_book.hpp"

namespace sensornet::emulator {

// What the run plans with; a change holds once its versions are published.
struct ReplanSettings {
  PlanSurrogate surrogate = PlanSurrogate::Information;
  std::set<int> excluded;  // taken out of service by command
  std::set<int> failed;    // died (their process ended)
  Eigen::VectorXd budget;  // b of C λ <= b (C is the scenario's)

  // excluded ∪ failed: the sensors every plan gives rate zero.
  [[nodiscard]] std::set<int> outOfService() const;
  bool operator==(const ReplanSettings& other) const;
};

// The settings a scenario starts with: its budget, nothing excluded or failed.
[[nodiscard]] ReplanSettings initialSettings(const Scenario& scenario, PlanSurrogate surrogate);

// The latest covariance the fusion center published: P at `time_s` of `episode`.
struct FusedCovariance {
  std::uint32_t episode = 0;
  double time_s = 0.0;
  Eigen::MatrixXd covariance;
};

// Where the run is when a change comes.
struct RunMoment {
  bool running = false;       // an episode runs
  std::uint32_t episode = 0;  // the running episode, else the next one to start
  std::optional<FusedCovariance> fused;
  // Emulated seconds into the running episode now (read before and after planning).
  std::function<double()> emulated_now = [] { return 0.0; };

  [[nodiscard]] std::uint32_t nextEpisode() const { return running ? episode + 1 : episode; }
};

struct ReplannerOptions {
  double switch_margin_s = 0.3;  // wall seconds between a change and its effective time
  double time_scale = 1.0;       // emulated seconds per wall second
  double max_plan_seconds = 30.0;
  // Network-aware planning: PlanRequest::delivery of every plan (deliveryFactors()).
  std::optional<Eigen::MatrixXd> delivery;
};

// The outcome of an accepted change.
struct Replan {
  std::vector<ScheduleVersion> versions;  // to publish in this order (numbers follow the book)
  std::string summary;                    // one line for the reply
  ReplanSettings settings;                // in force once the versions are published
  // What the reply and a failure's fault must say beside the versions, when a plan was
  // published that the planner could not certify as optimal (see Replanner::plan).
  std::string caveat;

  // What the reply names: the first new version (0 when none).
  [[nodiscard]] std::uint32_t replyVersion() const {
    return versions.empty() ? 0 : versions.front().version;
  }
  // "version 3 from 1.25 s of episode 2; version 4 from episode 3", and the caveat if any.
  [[nodiscard]] std::string versionsInBrief() const;
};

class Replanner {
 public:
  static constexpr double kStationaryResidual = 1e-3;

  // `plant` is used only for its tick grid (effective times fall on ticks) and must outlive
  // this object.
  Replanner(Scenario scenario, const EmulatedPlant& plant, ReplanSettings settings,
            ReplannerOptions options);

  [[nodiscard]] const ReplanSettings& settings() const { return settings_; }
  [[nodiscard]] const ReplannerOptions& options() const { return options_; }
  // The settings of `r` hold from now on.
  void adopt(const Replan& r) { settings_ = r.settings; }
  // Records sensors that died (ids checked: below M); no plan.
  void noteFailed(std::span<const std::uint32_t> sensors, std::uint64_t command_id);

  // The changes a Command asks for; each throws InputError (source "command <id>") to refuse.
  // `surrogate`: "info", "cov" or "uniform".
  [[nodiscard]] Replan changeSurrogate(std::string_view surrogate, const ScheduleBook& book,
                                       const RunMoment& now, std::uint64_t command_id) const;
  [[nodiscard]] Replan exclude(std::span<const std::uint32_t> sensors, const ScheduleBook& book,
                               const RunMoment& now, std::uint64_t command_id) const;
  // Brings excluded sensors back into the plan; refused for a sensor that failed (its process
  // is dead) or that is in service.
  [[nodiscard]] Replan include(std::span<const std::uint32_t> sensors, const ScheduleBook& book,
                               const RunMoment& now, std::uint64_t command_id) const;
  // b must have one finite value > 0 per row of C, and the scenario with it must pass
  // validateScenario.
  [[nodiscard]] Replan setBudget(std::span<const double> budget, const ScheduleBook& book,
                                 const RunMoment& now, std::uint64_t command_id) const;
  // A schedule file's text (JSON), feasible under the budget in force, from the next episode.
  [[nodiscard]] Replan adoptScheduleFile(const std::string& schedule_json, const ScheduleBook& book,
                                         const RunMoment& now, std::uint64_t command_id) const;
  // Plans again with the settings in force (after noteFailed: without the failed sensors).
  [[nodiscard]] Replan replanAsIs(const ScheduleBook& book, const RunMoment& now,
                                  std::uint64_t command_id) const;
  // Closed loop (--replan-every): the rest of the running episode planned from its fused
  // covariance as above, and from the next episode the version in force there before (the
  // open-loop plan every episode starts with), copied under a new number so that it follows the
  // tail. No versions when the tail cannot be planned now (no fused covariance of the episode
  // yet, the episode ends within the margin, planning outlasted it); InputError as for any
  // plan the planner does not certify and that is no better than the schedule in force.
  [[nodiscard]] Replan replanTail(const ScheduleBook& book, const RunMoment& now,
                                  std::uint64_t command_id) const;

 private:
  // next_episodes: the schedule of the version from the next episode (null: plan it, over the
  // whole horizon from P0).
  [[nodiscard]] Replan plan(ReplanSettings settings, const ScheduleBook& book, const RunMoment& now,
                            std::uint64_t command_id,
                            const RateSchedule* next_episodes = nullptr) const;
  [[nodiscard]] PlanRequest planRequest(const ReplanSettings& settings,
                                        const ScheduleBook& book) const;
  struct Chosen {
    RateSchedule schedule;
    std::string description;  // for the summary: "optimal", "not certified optimal (...)" ...
    std::string caveat;       // empty when the planner certified the plan
  };
  [[nodiscard]] Chosen choosePlan(const Scenario& planned_for, const PlanRequest& request,
                                  const RateSchedule& in_force, const ReplanSettings& settings,
                                  const std::string& which, std::uint64_t command_id) const;
  [[nodiscard]] Eigen::MatrixXd covarianceExpectedAt(const ReplanSettings& settings,
                                                     const ScheduleBook& book, const RunMoment& now,
                                                     double at) const;
  [[nodiscard]] Scenario plannedFor(const ReplanSettings& settings) const;
  [[nodiscard]] ScheduleVersion makeVersion(const Scenario& planned_for, RateSchedule schedule,
                                            SurrogateKind surrogate, std::uint64_t command_id,
                                            std::uint32_t episode, double at) const;
  [[nodiscard]] double emulatedNow(const RunMoment& now) const;
  [[nodiscard]] double marginEmulated() const {
    return options_.switch_margin_s * options_.time_scale;
  }

  Scenario scenario_;
  const EmulatedPlant& plant_;
  ReplanSettings settings_;
  ReplannerOptions options_;
};

}  // namespace sensornet::emulator
