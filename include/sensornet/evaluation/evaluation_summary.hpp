#pragma once
// What `fusion_center evaluate` says of its Monte Carlo runs: whether the mean's 95% interval
// meets the bracket, the JSON document of --json and the text summary, for the open loop (a
// schedule over many episodes, with the timetable beside it) and for the closed loop of
// --replan-every (against the open loop on the same arrivals). Also which surrogate the closed
// loop plans with when --surrogate is not given. The program runs and prints; these decide.
//
//   const MonteCarloResult mc = evaluateSchedule(scenario, schedule, options);
//   const OpenLoopEvaluation e{scenario, "default.yaml", "uniform", bracket, mc, nullptr,
//                              ArrivalMode::Poisson, true, seed, seconds};
//   std::fputs(evaluationText(e).c_str(), stdout);    // or printJson(evaluationJson(e))

#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>

#include "sensornet/core/arrival_mode.hpp"
#include "sensornet/core/monte_carlo.hpp"
#include "sensornet/planning/planner.hpp"
#include "sensornet/core/student_t.hpp"
#include "sensornet/core/surrogate.hpp"
#include "sensornet/evaluation/closed_loop.hpp"

namespace sensornet::evaluation {

// The closed loop's surrogate: `flag` (--surrogate) when given, else the schedule file's
// "surrogate" when it is one the closed loop plans with (info, cov), else cov (the run's
// default). `schedule_text` is the schedule file's text (empty: no file; unparsable: ignored).
// Throws InputError naming --surrogate when `flag` is neither info nor cov.
[[nodiscard]] PlanSurrogate closedLoopSurrogate(const std::string& flag,
                                                const std::string& schedule_text);

// The Monte Carlo mean's 95% interval overlaps [info, cov].
[[nodiscard]] bool meetsBracket(const MonteCarloResult& mc, const CostBracket& bracket);

struct OpenLoopEvaluation {
  const Scenario& scenario;
  std::string scenario_path;
  std::string schedule;  // the schedule file's path, or "uniform"
  CostBracket bracket;
  const MonteCarloResult& mc;         // Poisson arrivals
  const MonteCarloResult* timetable;  // with timetable arrivals: the same schedule; else null
  ArrivalMode mode = ArrivalMode::Poisson;
  bool simulate_plant = true;
  std::uint64_t seed = 1;
  double seconds = 0.0;
};

[[nodiscard]] nlohmann::json evaluationJson(const OpenLoopEvaluation& e);
[[nodiscard]] std::string evaluationText(const OpenLoopEvaluation& e);

struct ClosedLoopEvaluation {
  const Scenario& scenario;
  std::string scenario_path;
  std::string schedule;  // the open-loop plan's file, or "uniform"
  CostBracket bracket;   // of the open-loop plan alone
  const ClosedLoopResult& closed;
  double open_mean = 0.0;  // the open loop on the same arrivals
  SampleMean gain;         // closed minus open, paired
  PlanSurrogate surrogate = PlanSurrogate::Covariance;
  double replan_every = 0.0;
  double margin_emulated = 0.0;  // --switch-margin times --time-scale
  std::uint64_t seed = 1;
  double seconds = 0.0;
};

// "feedback pays", "feedback costs" or "no difference at this sample size": where the paired
// difference's 95% interval lies against 0.
[[nodiscard]] const char* feedbackVerdict(const SampleMean& gain);

[[nodiscard]] nlohmann::json closedLoopJson(const ClosedLoopEvaluation& e);
[[nodiscard]] std::string closedLoopText(const ClosedLoopEvaluation& e);

}  // namespace sensornet::evaluation
