#include "sensornet/evaluation/evaluation_summary.hpp"

#include "sensornet/core/input_error.hpp"
#include "sensornet/io/append_format.hpp"

namespace sensornet::evaluation {
namespace {

nlohmann::json toJson(const CostBracket& bracket) {
  return {{"info", bracket.info}, {"cov", bracket.cov}};
}

void appendScenario(std::string& out, const Scenario& scenario, const std::string& path) {
  appendf(out, "scenario  %s (n = %d states, M = %d sensors, T = %g s, N = %d)\n", path.c_str(),
          scenario.stateDim(), scenario.sensorCount(), scenario.horizon_s, scenario.intervals);
}

// With timetable arrivals: the deterministic cost of the timetable beside the Poisson mean of
// the same schedule (which the bracket is about).
nlohmann::json timetableJson(const MonteCarloResult& timetable, const MonteCarloResult& poisson,
                             bool simulate_plant) {
  nlohmann::json doc = {{"cost", timetable.mean},
                        {"std", timetable.std_dev},
                        {"arrivals", timetable.arrivals_mean},
                        {"minus_poisson_mean", timetable.mean - poisson.mean},
                        {"poisson_ci95", poisson.ci95}};
  doc["nees"] = simulate_plant ? nlohmann::json(timetable.nees_mean) : nlohmann::json(nullptr);
  return doc;
}

}  // namespace

PlanSurrogate closedLoopSurrogate(const std::string& flag, const std::string& schedule_text) {
  if (!flag.empty()) {
    const auto given = lookUpWord<PlanSurrogate>(flag);
    if (given != PlanSurrogate::Information && given != PlanSurrogate::Covariance) {
      throw InputError("--surrogate", "", "info or cov for --replan-every, got '" + flag + "'");
    }
    return *given;
  }
  if (!schedule_text.empty()) {
    const nlohmann::json file = nlohmann::json::parse(schedule_text, nullptr, false);
    if (file.is_object() && file.contains("surrogate") && file["surrogate"].is_string()) {
      const auto named = lookUpWord<PlanSurrogate>(file["surrogate"].get<std::string>());
      if (named == PlanSurrogate::Information || named == PlanSurrogate::Covariance) return *named;
    }
  }
  return PlanSurrogate::Covariance;
}

bool meetsBracket(const MonteCarloResult& mc, const CostBracket& bracket) {
  return mc.mean - mc.ci95 <= bracket.cov && mc.mean + mc.ci95 >= bracket.info;
}

nlohmann::json evaluationJson(const OpenLoopEvaluation& e) {
  const MonteCarloResult& mc = e.mc;
  nlohmann::json doc = {
      {"bracket", toJson(e.bracket)},
      {"mc", {{"mean", mc.mean}, {"std", mc.std_dev}, {"ci95", mc.ci95}, {"runs", mc.runs}}},
      {"meets_bracket", meetsBracket(mc, e.bracket)},
      {"schedule", e.schedule},
      {"arrivals", wordOf(e.mode)},
      {"seed", e.seed},
      {"seconds", e.seconds}};
  if (e.simulate_plant) {
    doc["nees"] = mc.nees_mean;
    doc["squared_error"] = mc.squared_error_mean;
  } else {
    doc["nees"] = nullptr;
  }
  doc["timetable"] = e.timetable != nullptr ? timetableJson(*e.timetable, mc, e.simulate_plant)
                                            : nlohmann::json(nullptr);
  return doc;
}

std::string evaluationText(const OpenLoopEvaluation& e) {
  const MonteCarloResult& mc = e.mc;
  std::string out;
  appendScenario(out, e.scenario, e.scenario_path);
  appendf(out, "schedule  %s\n", e.schedule.c_str());
  appendf(out, "bracket   J(P_info) = %.6g <= E[J] <= J(P_cov) = %.6g\n", e.bracket.info,
          e.bracket.cov);
  appendf(out, "arrivals  %s\n", std::string(wordOf(e.mode)).c_str());
  appendf(out, "monte carlo  mean %.6g ± %.3g (95%%), std %.4g, %d episodes in %.2f s\n", mc.mean,
          mc.ci95, mc.std_dev, mc.runs, e.seconds);
  appendf(out, "             the 95%% interval %s the bracket\n",
          meetsBracket(mc, e.bracket) ? "meets" : "DOES NOT meet");
  if (e.simulate_plant) {
    appendf(out, "simulated plant  mean NEES at T %.4g (ideal %d), mean e'W_T e at T %.6g\n",
            mc.nees_mean, e.scenario.stateDim(), mc.squared_error_mean);
  }
  if (e.timetable != nullptr) {
    const MonteCarloResult& t = *e.timetable;
    appendf(out, "timetable  J = %.6g (std over episodes %.3g), %.0f arrivals per episode\n",
            t.mean, t.std_dev, t.arrivals_mean);
    appendf(out, "           minus the Poisson mean: %.6g (Poisson 95%% half-width %.3g)\n",
            t.mean - mc.mean, mc.ci95);
    if (e.simulate_plant) appendf(out, "           mean NEES at T %.4g\n", t.nees_mean);
  }
  return out;
}

const char* feedbackVerdict(const SampleMean& gain) {
  return gain.mean + gain.ci95 < 0.0   ? "feedback pays"
         : gain.mean - gain.ci95 > 0.0 ? "feedback costs"
                                       : "no difference at this sample size";
}

nlohmann::json closedLoopJson(const ClosedLoopEvaluation& e) {
  const ClosedLoopResult& closed = e.closed;
  return {{"closed_loop",
           {{"replan_every", e.replan_every},
            {"surrogate", std::string(wordOf(e.surrogate))},
            {"switch_margin_emulated", e.margin_emulated},
            {"mean", closed.mean},
            {"std", closed.std_dev},
            {"ci95", closed.ci95},
            {"runs", closed.runs},
            {"tails_per_episode", closed.tails_mean},
            {"refused", closed.refused},
            {"arrivals", closed.arrivals_mean}}},
          {"open_loop", {{"mean", e.open_mean}}},
          {"closed_minus_open", {{"mean", e.gain.mean}, {"ci95", e.gain.ci95}}},
          {"bracket", toJson(e.bracket)},
          {"schedule", e.schedule},
          {"seed", e.seed},
          {"seconds", e.seconds}};
}

std::string closedLoopText(const ClosedLoopEvaluation& e) {
  const ClosedLoopResult& closed = e.closed;
  std::string out;
  appendScenario(out, e.scenario, e.scenario_path);
  appendf(out, "open-loop plan  %s (bracket [%.6g, %.6g] of the plan alone)\n", e.schedule.c_str(),
          e.bracket.info, e.bracket.cov);
  appendf(out,
          "closed loop  re-plan with %s every %g s, each tail from %g s later; %.2f tails "
          "per episode, %lld refused\n",
          std::string(wordOf(e.surrogate)).c_str(), e.replan_every, e.margin_emulated,
          closed.tails_mean, closed.refused);
  appendf(out, "closed loop  mean %.6g ± %.3g (95%%), std %.4g, %d episodes in %.2f s\n",
          closed.mean, closed.ci95, closed.std_dev, closed.runs, e.seconds);
  appendf(out, "open loop    mean %.6g on the same arrivals (time-changed unit-rate points)\n",
          e.open_mean);
  appendf(out, "closed - open  %+.6g ± %.3g (95%%, paired): %s\n", e.gain.mean, e.gain.ci95,
          feedbackVerdict(e.gain));
  return out;
}

}  // namespace sensornet::evaluation
