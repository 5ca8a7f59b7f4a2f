#include "sensornet/emulator/replanner.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <set>
#include <cstdio>
#include <utility>

#include "sensornet/core/input_error.hpp"
#include "sensornet/core/surrogate.hpp"
#include "sensornet/io/command_line.hpp"
#include "sensornet/io/scenario_file.hpp"

namespace sensornet::emulator {
namespace {

std::string sourceOf(std::uint64_t command_id) { return "command " + std::to_string(command_id); }

bool stalledAtAStationaryPoint(const PlanResult& plan) {
  return plan.status == PlanStatus::Stalled &&
         plan.kkt_residual <= Replanner::kStationaryResidual;
}

// The planner reports the plan as one to publish as it is (see the header).
bool certified(const PlanResult& plan) {
  return solved(plan.status) || stalledAtAStationaryPoint(plan);
}

std::string endedText(const PlanResult& plan) {
  return "ended '" + statusText(plan.status, plan.failure) + "' (kkt residual " +
         formatNumber(plan.kkt_residual) + " after " + std::to_string(plan.iterations) +
         " iterations)";
}

// `schedule` with the sensors in `out` at rate zero in every interval.
RateSchedule withoutSensors(const RateSchedule& schedule, const std::set<int>& out) {
  Eigen::MatrixXd rates = schedule.rates();
  for (const int j : out) {
    if (j >= 0 && j < rates.cols()) rates.col(j).setZero();
  }
  return RateSchedule(schedule.horizon(), std::move(rates));
}

// The surrogate's cost of `schedule` over [start time, T] from the request's start covariance.
double surrogateCost(const Scenario& scenario, const RateSchedule& schedule,
                     const PlanRequest& request) {
  RolloutOptions options;
  options.start_time = request.start_time;
  options.start_covariance = request.start_covariance;
  const SurrogateRollout r = rollout(formOf(request.surrogate), scenario, schedule, options);
  return r.running_cost + r.terminal_cost;
}

std::string describePlan(const PlanResult& plan) {
  if (plan.status == PlanStatus::Acceptable) return "acceptable: IPOPT's looser tolerance";
  if (stalledAtAStationaryPoint(plan)) {
    return "stalled, accepted: kkt residual " + formatNumber(plan.kkt_residual) +
           " <= " + formatNumber(Replanner::kStationaryResidual);
  }
  return statusText(plan.status, plan.failure);
}

std::set<int> checkedSensorIds(std::span<const std::uint32_t> ids, int sensor_count,
                               std::uint64_t command_id) {
  std::set<int> sensors;
  for (const std::uint32_t id : ids) {
    if (id >= static_cast<std::uint32_t>(sensor_count)) {
      throw InputError(sourceOf(command_id), "sensor_ids",
                       "ids below M = " + std::to_string(sensor_count));
    }
    sensors.insert(static_cast<int>(id));
  }
  return sensors;
}

// Four significant digits: effective times fall on ticks of T / 2^20 and would read 1.2499990463.
std::string shortSeconds(double seconds) {
  std::array<char, 32> text{};
  const int length = std::snprintf(text.data(), text.size(), "%.4g", seconds);
  return std::string(text.data(), static_cast<std::size_t>(std::max(length, 0)));
}

}  // namespace

std::set<int> ReplanSettings::outOfService() const {
  std::set<int> out = excluded;
  out.insert(failed.begin(), failed.end());
  return out;
}

bool ReplanSettings::operator==(const ReplanSettings& other) const {
  return surrogate == other.surrogate && excluded == other.excluded && failed == other.failed &&
         budget.size() == other.budget.size() && budget == other.budget;
}

ReplanSettings initialSettings(const Scenario& scenario, PlanSurrogate surrogate) {
  ReplanSettings settings;
  settings.surrogate = surrogate;
  settings.budget = scenario.constraints.b;
  return settings;
}

std::string Replan::versionsInBrief() const {
  std::string text;
  for (const ScheduleVersion& v : versions) {
    if (!text.empty()) text += "; ";
    text += "version " + std::to_string(v.version) + " from ";
    if (v.effective_time_s > 0.0) text += shortSeconds(v.effective_time_s) + " s of ";
    text += "episode " + std::to_string(v.effective_episode);
  }
  if (!caveat.empty()) text += " (" + caveat + ")";
  return text;
}

Replanner::Replanner(Scenario scenario, const EmulatedPlant& plant, ReplanSettings settings,
                     ReplannerOptions options)
    : scenario_(std::move(scenario)),
      plant_(plant),
      settings_(std::move(settings)),
      options_(std::move(options)) {}

void Replanner::noteFailed(std::span<const std::uint32_t> sensors, std::uint64_t command_id) {
  const std::set<int> failed = checkedSensorIds(sensors, scenario_.sensorCount(), command_id);
  settings_.failed.insert(failed.begin(), failed.end());
}

Replan Replanner::changeSurrogate(std::string_view surrogate, const ScheduleBook& book,
                                  const RunMoment& now, std::uint64_t command_id) const {
  ReplanSettings settings = settings_;
  settings.surrogate = parseWord<PlanSurrogate>(surrogate, sourceOf(command_id), "surrogate");
  return plan(std::move(settings), book, now, command_id);
}

Replan Replanner::exclude(std::span<const std::uint32_t> sensors, const ScheduleBook& book,
                          const RunMoment& now, std::uint64_t command_id) const {
  ReplanSettings settings = settings_;
  const std::set<int> excluded = checkedSensorIds(sensors, scenario_.sensorCount(), command_id);
  settings.excluded.insert(excluded.begin(), excluded.end());
  if (static_cast<int>(settings.outOfService().size()) == scenario_.sensorCount()) {
    throw InputError(sourceOf(command_id), "sensor_ids", "at least one sensor left in service");
  }
  return plan(std::move(settings), book, now, command_id);
}

Replan Replanner::include(std::span<const std::uint32_t> sensors, const ScheduleBook& book,
                          const RunMoment& now, std::uint64_t command_id) const {
  ReplanSettings settings = settings_;
  for (const int j : checkedSensorIds(sensors, scenario_.sensorCount(), command_id)) {
    const std::string sensor = "sensor " + std::to_string(j);
    if (settings.failed.count(j) != 0) {
      throw InputError(sourceOf(command_id), "sensor_ids",
                       "sensors excluded by command, but " + sensor +
                           " failed (its process died): a dead sensor cannot be brought back");
    }
    if (settings.excluded.erase(j) == 0) {
      throw InputError(sourceOf(command_id), "sensor_ids",
                       "sensors excluded by command, but " + sensor + " is in service");
    }
  }
  return plan(std::move(settings), book, now, command_id);
}

Replan Replanner::setBudget(std::span<const double> budget, const ScheduleBook& book,
                            const RunMoment& now, std::uint64_t command_id) const {
  const std::string source = sourceOf(command_id);
  if (budget.size() != static_cast<std::size_t>(settings_.budget.size())) {
    throw InputError(source, "budget",
                     std::to_string(settings_.budget.size()) + " values (one per row of C)");
  }
  for (const double value : budget) {
    if (!(value > 0.0) || !std::isfinite(value)) {
      throw InputError(source, "budget", "finite values > 0, got " + formatNumber(value));
    }
  }
  ReplanSettings settings = settings_;
  settings.budget = Eigen::Map<const Eigen::VectorXd>(budget.data(), settings_.budget.size());
  // The rules of a scenario file hold for a live budget too (at most
  // kMaxMeasurementsPerHorizon expected measurements per sensor and horizon, ...).
  try {
    validateScenario(plannedFor(settings), source);
  } catch (const InputError& e) {
    throw InputError(source, "budget", e.expected());
  }
  return plan(std::move(settings), book, now, command_id);
}

Replan Replanner::adoptScheduleFile(const std::string& schedule_json, const ScheduleBook& book,
                                    const RunMoment& now, std::uint64_t command_id) const {
  const std::string source = sourceOf(command_id);
  RateSchedule schedule = parseScheduleJson(schedule_json, source);
  const Scenario planned_for = plannedFor(settings_);
  const Feasibility feasibility = checkFeasibility(schedule, planned_for, 1e-9);
  if (!feasibility.feasible) throw InputError(source, "rates", feasibility.reason);
  Replan r;
  r.versions.push_back(
      makeVersion(planned_for, std::move(schedule), SurrogateKind::File, command_id,
                  now.nextEpisode(), 0.0));
  r.versions.back().version = book.latest().version + 1;
  r.summary = "schedule file";
  r.settings = settings_;
  return r;
}

Replan Replanner::replanAsIs(const ScheduleBook& book, const RunMoment& now,
                             std::uint64_t command_id) const {
  if (static_cast<int>(settings_.outOfService().size()) == scenario_.sensorCount()) {
    throw InputError(sourceOf(command_id), "sensor_ids", "at least one sensor left in service");
  }
  return plan(settings_, book, now, command_id);
}

Replan Replanner::replanTail(const ScheduleBook& book, const RunMoment& now,
                             std::uint64_t command_id) const {
  // Before the tail goes in, the latest version is the one in force from the next episode on:
  // the run's open-loop plan (or an operator's change of it), which every episode starts with.
  const RateSchedule open_loop = book.latest().schedule;
  Replan r = plan(settings_, book, now, command_id, &open_loop);
  if (r.versions.size() < 2) {  // no tail: nothing changes, and the summary says why
    r.versions.clear();
    r.summary = now.running ? r.summary.substr(0, r.summary.find("; "))
                            : "the episode ends within the switch margin (the next one keeps "
                              "the version it was announced with)";
  }
  return r;
}

// The mid-episode version (when one is possible) and the full-horizon one; see the header.
Replan Replanner::plan(ReplanSettings settings, const ScheduleBook& book, const RunMoment& now,
                       std::uint64_t command_id, const RateSchedule* next_episodes) const {
  const Scenario planned_for = plannedFor(settings);
  const SurrogateKind kind = surrogateKindOf(settings.surrogate);
  const std::string surrogate(wordOf(kind));
  const auto notInThisEpisode = [&now](const char* why) {
    return "not in episode " + std::to_string(now.episode) + ": " + why + "; ";
  };
  std::string summary;
  std::optional<Chosen> tail_plan;
  double at = 0.0;
  if (now.running && !(now.fused && now.fused->episode == now.episode)) {
    summary = notInThisEpisode("no fused covariance of it yet");
  } else if (now.running) {
    at = plant_.timeOf(plant_.tickAt(emulatedNow(now) + marginEmulated()));
    if (at >= scenario_.horizon_s) {
      summary = notInThisEpisode("it ends within the switch margin");
    } else {
      PlanRequest request = planRequest(settings, book);
      request.start_time = at;
      request.start_covariance = covarianceExpectedAt(settings, book, now, at);
      const ScheduleVersion* in_force = book.inForce(now.episode, at);
      // The rates before `at` are those in force, and the versions in force so far spent
      // energy that the rest of the episode may not.
      if (in_force != nullptr) request.warm_start = in_force->schedule;
      if (planned_for.constraints.hasEnergyBudgets()) {
        Eigen::VectorXd spent = Eigen::VectorXd::Zero(planned_for.sensorCount());
        for (const ScheduleSegment& piece : book.segments(now.episode, scenario_.horizon_s)) {
          if (piece.from_s < at) {
            spent += piece.version->schedule.expectedCounts(piece.from_s, std::min(piece.to_s, at));
          }
        }
        request.energy_spent = spent;
      }
      tail_plan = choosePlan(planned_for, request, *request.warm_start, settings, "mid-episode",
                             command_id);
    }
  }
  const Chosen full_plan =
      next_episodes != nullptr
          ? Chosen{*next_episodes, "the open-loop plan again", ""}
          : choosePlan(planned_for, planRequest(settings, book), book.latest().schedule, settings,
                       "full-horizon", command_id);

  Replan r;
  std::uint32_t number = book.latest().version;
  if (tail_plan) {
    // Planning took time: every process must still hear of the version before it takes effect.
    const double earliest =
        plant_.timeOf(plant_.tickAt(emulatedNow(now) + 0.5 * marginEmulated()) + 1);
    const double effective = std::max(at, earliest);
    if (effective < scenario_.horizon_s) {
      r.versions.push_back(makeVersion(planned_for, tail_plan->schedule, kind, command_id,
                                       now.episode, effective));
      r.versions.back().version = ++number;
      summary = "version " + std::to_string(number) + " from " + std::to_string(effective) +
                " s of episode " + std::to_string(now.episode) + " (" + tail_plan->description +
                ", planned from the fused covariance at " + std::to_string(now.fused->time_s) +
                " s carried to " + std::to_string(at) + " s); ";
    } else {
      summary = notInThisEpisode("planning outlasted it");
    }
  }
  r.versions.push_back(
      makeVersion(planned_for, full_plan.schedule, kind, command_id, now.nextEpisode(), 0.0));
  r.versions.back().version = ++number;
  r.summary = summary + "version " + std::to_string(number) + " from episode " +
              std::to_string(now.nextEpisode()) + " (" + surrogate + ", " +
              full_plan.description + ")";
  for (const std::string& caveat : {tail_plan ? tail_plan->caveat : std::string(), full_plan.caveat}) {
    if (!caveat.empty()) r.caveat += (r.caveat.empty() ? "" : "; ") + caveat;
  }
  r.settings = std::move(settings);
  return r;
}

// What to publish for one plan (see the header of plan): the planner's plan when it certifies it
// (from the schedule in force, else from its own start); else the best plan found, when the
// surrogate says it beats the schedule in force as that can still be delivered (out-of-service
// sensors at zero); else, when sensors are out of service that the schedule in force still asks
// for, that schedule with them at zero (a dead sensor is never left scheduled). Otherwise the
// change is refused (InputError), and nothing is published.
Replanner::Chosen Replanner::choosePlan(const Scenario& planned_for, const PlanRequest& request,
                                        const RateSchedule& in_force,
                                        const ReplanSettings& settings, const std::string& which,
                                        std::uint64_t command_id) const {
  const std::string surrogate(describe(settings.surrogate));
  const PlanResult warm = planSchedule(planned_for, request);
  if (certified(warm)) return {warm.schedule, describePlan(warm), ""};
  PlanResult best = warm;
  std::string tried = "from the schedule in force it " + endedText(warm);
  if (request.warm_start) {
    // The planner's own start (its uniform rates among the sensors in service); before the
    // switch the version keeps the warm start's rates, as a warm-started plan does.
    PlanRequest cold = request;
    cold.cold_start = true;  // the rows before the start stay the warm start's
    const PlanResult own = planSchedule(planned_for, cold);
    if (certified(own)) {
      return {own.schedule, describePlan(own) + " from the planner's own start (" + tried + ")", ""};
    }
    tried += ", from its own start " + endedText(own);
    if (surrogateCost(planned_for, own.schedule, request) <
        surrogateCost(planned_for, warm.schedule, request)) {
      best = own;
    }
  }
  const std::set<int> out = settings.outOfService();
  const RateSchedule deliverable = withoutSensors(in_force, out);
  const bool kept_feasible = checkFeasibility(deliverable, planned_for, 1e-9).feasible;
  const double best_cost = surrogateCost(planned_for, best.schedule, request);
  const double kept_cost = surrogateCost(planned_for, deliverable, request);
  const std::string costs = surrogate + " cost " + formatNumber(best_cost) +
                            " against the schedule in force's " + formatNumber(kept_cost) +
                            (out.empty() ? "" : " without the out-of-service sensors");
  if (best_cost < kept_cost || !kept_feasible) {
    const std::string caveat = "the " + which + " plan is not certified optimal (" + tried +
                               "); published because it is better by the surrogate: " + costs;
    return {best.schedule, "not certified optimal, better than the schedule in force", caveat};
  }
  if ((deliverable.rates() - in_force.rates()).cwiseAbs().maxCoeff() > 0.0) {
    const std::string caveat = "the " + which + " plan is not certified optimal (" + tried +
                               ") and no better than the schedule in force (" + costs +
                               "): that schedule is kept with the out-of-service sensors at zero";
    return {deliverable, "the schedule in force without the out-of-service sensors", caveat};
  }
  throw InputError(sourceOf(command_id), "plan",
                   "a plan the planner reports as optimal, or one better than the schedule in "
                   "force, but the " + which + " " + surrogate + " plan " + tried + " (" + costs +
                   "); nothing was published, the settings are unchanged");
}

PlanRequest Replanner::planRequest(const ReplanSettings& settings, const ScheduleBook& book) const {
  PlanRequest request;
  request.surrogate = settings.surrogate;
  const std::set<int> out = settings.outOfService();
  request.excluded_sensors.assign(out.begin(), out.end());
  request.warm_start = book.latest().schedule;
  request.max_seconds = options_.max_plan_seconds;
  request.delivery = options_.delivery;
  return request;
}

// The latest fused covariance carried forward to `at` by the surrogate of the plan's form
// under the version in force: the plan of the rest of the episode starts from the covariance
// expected when it takes effect.
Eigen::MatrixXd Replanner::covarianceExpectedAt(const ReplanSettings& settings,
                                                const ScheduleBook& book, const RunMoment& now,
                                                double at) const {
  const FusedCovariance& fused = *now.fused;
  const ScheduleVersion* v = book.inForce(now.episode, fused.time_s);
  if (v == nullptr || !(fused.time_s < at)) return fused.covariance;
  RolloutOptions carry;
  carry.start_time = fused.time_s;
  carry.end_time = at;
  carry.start_covariance = fused.covariance;
  return rollout(formOf(settings.surrogate), scenario_, v->schedule, carry).covariances.back();
}

Scenario Replanner::plannedFor(const ReplanSettings& settings) const {
  Scenario planned_for = scenario_;
  planned_for.constraints.b = settings.budget;
  return planned_for;
}

ScheduleVersion Replanner::makeVersion(const Scenario& planned_for, RateSchedule schedule,
                                       SurrogateKind surrogate, std::uint64_t command_id,
                                       std::uint32_t episode, double at) const {
  ScheduleVersion v;
  v.effective_episode = episode;
  v.effective_time_s = at;
  v.bracket = computeBracket(planned_for, schedule);
  v.schedule = std::move(schedule);
  v.surrogate = surrogate;
  v.command_id = command_id;
  return v;
}

double Replanner::emulatedNow(const RunMoment& now) const {
  return std::max(0.0, now.emulated_now());
}

}  // namespace sensornet::emulator
