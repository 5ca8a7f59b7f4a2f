// sensornet's math from Python (python/math_bindings.hpp): numpy arrays in and out, over the same
// functions the programs call with the same defaults, so that a plan, a bracket or a Monte Carlo
// estimate here is the number `coordinator plan` or `fusion_center evaluate` prints for the same
// inputs. The package (python/sensornet/__init__.py) gives them keyword arguments and result
// types; errors in the input raise ValueError with the programs' one-line text.
#include "math_bindings.hpp"

#include <pybind11/eigen.h>
#include <pybind11/stl.h>

#include <Eigen/Core>
#include <algorithm>
#include <cstdint>
#include <limits>
#include <numeric>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "sensornet/core/cdkf.hpp"
#include "sensornet/core/input_error.hpp"
#include "sensornet/core/monte_carlo.hpp"
#include "sensornet/core/plan_status.hpp"
#include "sensornet/core/rate_schedule.hpp"
#include "sensornet/core/scenario.hpp"
#include "sensornet/core/student_t.hpp"
#include "sensornet/core/surrogate.hpp"
#include "sensornet/core/words.hpp"
#include "sensornet/evaluation/closed_loop.hpp"
#include "sensornet/evaluation/evaluation_summary.hpp"
#include "sensornet/evaluation/schedule_evaluation.hpp"
#include "sensornet/io/plan_request.hpp"
#include "sensornet/io/scenario_file.hpp"
#include "sensornet/planning/planner.hpp"

namespace py = pybind11;

namespace sensornet::python {
namespace {

using Matrix = Eigen::MatrixXd;

// A schedule of `scenario` from an N x M array of rates (Hz), checked like a schedule file.
RateSchedule scheduleOf(const Scenario& scenario, const Matrix& rates) {
  if (rates.rows() != scenario.intervals || rates.cols() != scenario.sensorCount()) {
    throw InputError("rates", "shape",
                     "an array of " + std::to_string(scenario.intervals) + " intervals x " +
                         std::to_string(scenario.sensorCount()) + " sensors, got " +
                         std::to_string(rates.rows()) + " x " + std::to_string(rates.cols()));
  }
  RateSchedule schedule(scenario.horizon_s, rates);
  const Feasibility f = checkFeasibility(schedule, scenario);
  if (!f.feasible)
    throw InputError("rates", "values", "rates meeting C λ <= b, λ >= 0: " + f.reason);
  return schedule;
}

Eigen::VectorXd vectorOf(const std::vector<double>& values) {
  return Eigen::VectorXd::Map(values.data(), static_cast<Eigen::Index>(values.size()));
}

py::dict bracketDict(const CostBracket& b) {
  py::dict d;
  d["info"] = b.info;
  d["cov"] = b.cov;
  return d;
}

py::dict sampleDict(const SampleMean& s) {
  py::dict d;
  d["mean"] = s.mean;
  d["std_dev"] = s.std_dev;
  d["ci95"] = s.ci95;
  return d;
}

py::dict monteCarloDict(const MonteCarloResult& mc) {
  py::dict d;
  d["runs"] = mc.runs;
  d["mean"] = mc.mean;
  d["std_dev"] = mc.std_dev;
  d["ci95"] = mc.ci95;
  d["nees_mean"] = mc.nees_mean;
  d["squared_error_mean"] = mc.squared_error_mean;
  d["arrivals_mean"] = mc.arrivals_mean;
  d["episode_costs"] = vectorOf(mc.episode_costs);
  return d;
}

py::dict plan(const Scenario& scenario, const std::string& surrogate, const std::string& method,
              double tolerance, int max_iterations, std::optional<double> max_seconds,
              const std::vector<int>& excluded, bool network_aware,
              const std::optional<Matrix>& warm_start, std::uint64_t seed) {
  PlanChoices choices;
  choices.surrogate = parseWord<PlanSurrogate>(surrogate, "plan", "surrogate");
  choices.method = parseWord<PlanMethod>(method, "plan", "method");
  choices.tolerance = tolerance;
  choices.max_iterations = max_iterations;
  if (max_seconds) {
    choices.max_seconds = *max_seconds;
    choices.max_seconds_given = true;
  }
  choices.excluded = excluded;
  choices.network_aware = network_aware;
  PlanRequest request = planRequest(scenario, "plan", choices);
  if (warm_start) request.warm_start = RateSchedule(scenario.horizon_s, *warm_start);
  request.realized.seed = seed;
  PlanResult result;
  {
    py::gil_scoped_release unlocked;  // a plan takes seconds: let other threads go on
    result = planSchedule(scenario, request);
  }
  py::dict d;
  d["rates"] = result.schedule.rates();
  d["surrogate"] = surrogate;
  d["status"] = statusText(result.status, result.failure);
  d["solved"] = solved(result.status);
  d["objective"] = result.objective;
  d["objective_half_width"] = result.objective_half_width;
  d["bracket"] = bracketDict(result.bracket);
  d["iterations"] = result.iterations;
  d["substeps"] = result.substeps;
  d["kkt_residual"] = result.kkt_residual;
  d["solve_seconds"] = result.solve_seconds;
  d["episodes"] = result.episodes;
  return d;
}

py::dict evaluate(const Scenario& scenario, const Matrix& rates, int runs, std::uint64_t seed,
                  int threads, bool plant, const std::string& arrivals) {
  const RateSchedule schedule = scheduleOf(scenario, rates);
  MonteCarloOptions options;
  options.runs = runs;
  options.seed = seed;
  options.threads = threads;
  options.simulate_plant = plant;
  const ArrivalMode mode = arrivals.empty()
                               ? scenario.arrivals
                               : parseWord<ArrivalMode>(arrivals, "evaluate", "arrivals");
  evaluation::OpenLoopRun run;
  {
    py::gil_scoped_release unlocked;
    run = evaluation::runOpenLoop(scenario, schedule, options, mode);
  }
  py::dict d = monteCarloDict(run.mc);
  d["timetable"] =
      run.timetable ? py::object(monteCarloDict(*run.timetable)) : py::object(py::none());
  d["seconds"] = run.seconds;
  return d;
}

py::dict closedLoop(const Scenario& scenario, const Matrix& rates, double replan_every,
                    const std::string& surrogate, int runs, std::uint64_t seed, int threads,
                    double switch_margin, double time_scale) {
  const RateSchedule schedule = scheduleOf(scenario, rates);
  evaluation::ClosedLoopOptions loop;
  loop.replan_every_s = replan_every;
  loop.surrogate = evaluation::closedLoopSurrogate(surrogate, "");
  loop.replanner.switch_margin_s = switch_margin;
  loop.replanner.time_scale = time_scale;
  loop.runs = runs;
  loop.seed = seed;
  loop.threads = threads;
  evaluation::ClosedLoopRun run;
  {
    py::gil_scoped_release unlocked;
    run = evaluation::runClosedLoop(scenario, schedule, loop);
  }
  py::dict d;
  d["runs"] = run.closed.runs;
  d["mean"] = run.closed.mean;
  d["std_dev"] = run.closed.std_dev;
  d["ci95"] = run.closed.ci95;
  d["open_mean"] = run.open_mean;
  d["gain"] = sampleDict(run.gain);
  d["tails_mean"] = run.closed.tails_mean;
  d["refused"] = run.closed.refused;
  d["arrivals_mean"] = run.closed.arrivals_mean;
  d["episode_costs"] = vectorOf(run.closed.episode_costs);
  d["seconds"] = run.seconds;
  return d;
}

// P_info(t) or P_cov(t) at the given times (nondecreasing, in [0, T]), by chained rollouts: each
// from the covariance at the time before, so every stretch is integrated once.
std::pair<Eigen::VectorXd, py::list> trajectory(const Scenario& scenario, const Matrix& rates,
                                                const std::string& form,
                                                const std::optional<Eigen::VectorXd>& times) {
  const RateSchedule schedule = scheduleOf(scenario, rates);
  const SurrogateForm f =
      form == "info"  ? SurrogateForm::Information
      : form == "cov" ? SurrogateForm::Covariance
                      : throw InputError("trajectory", "form", "info or cov, got '" + form + "'");
  py::list covariances;
  if (!times) {
    const SurrogateRollout r = rollout(f, scenario, schedule);
    for (const Matrix& p : r.covariances) covariances.append(p);
    return {vectorOf(r.times), covariances};
  }
  RolloutOptions options;
  options.start_covariance = scenario.plant.P0;
  for (Eigen::Index i = 0; i < times->size(); ++i) {
    const double t = (*times)(i);
    if (!(t >= options.start_time && t <= scenario.horizon_s)) {
      throw InputError("trajectory", "times[" + std::to_string(i) + "]",
                       "nondecreasing times in [0, " + std::to_string(scenario.horizon_s) + "]");
    }
    if (t > options.start_time) {
      options.end_time = t;
      const SurrogateRollout r = rollout(f, scenario, schedule, options);
      options.start_time = t;
      options.start_covariance = r.covariances.back();
    }
    covariances.append(*options.start_covariance);
  }
  return {*times, covariances};
}

// The exact CD-KF's covariance over the given arrivals (times in [0, T], sensors 0..M-1): the
// realized cost J(P) of eq. (6) and P(T).
py::dict exactFilter(const Scenario& scenario, const Eigen::VectorXd& times,
                     const std::vector<int>& sensors) {
  if (static_cast<std::size_t>(times.size()) != sensors.size()) {
    throw InputError("cdkf", "sensors",
                     "one sensor per time (" + std::to_string(times.size()) + " times, " +
                         std::to_string(sensors.size()) + " sensors)");
  }
  std::vector<std::size_t> order(sensors.size());
  std::iota(order.begin(), order.end(), std::size_t{0});
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    return times(static_cast<Eigen::Index>(a)) < times(static_cast<Eigen::Index>(b));
  });
  CdKalmanFilter filter(scenario);
  for (const std::size_t i : order) {
    const double t = times(static_cast<Eigen::Index>(i));
    const int j = sensors[i];
    if (!(t >= 0.0 && t <= scenario.horizon_s)) {
      throw InputError("cdkf", "times[" + std::to_string(i) + "]",
                       "a time in [0, " + std::to_string(scenario.horizon_s) + "]");
    }
    if (j < 0 || j >= scenario.sensorCount()) {
      throw InputError("cdkf", "sensors[" + std::to_string(i) + "]",
                       "a sensor in 0.." + std::to_string(scenario.sensorCount() - 1) + ", got " +
                           std::to_string(j));
    }
    filter.propagateTo(t);
    filter.updateCovariance(j);
  }
  filter.propagateTo(scenario.horizon_s);
  py::dict d;
  d["cost"] = filter.cost();
  d["running_cost"] = filter.runningCost();
  d["terminal_cost"] = filter.terminalCost();
  d["covariance"] = filter.covariance();
  return d;
}

}  // namespace

void bindMath(py::module_& m) {
  py::register_exception<InputError>(m, "InputError", PyExc_ValueError);

  py::class_<Scenario>(m, "Scenario", R"(A validated scenario: plant, sensors, cost weights, the
constraints C λ <= b, on N intervals of [0, T]. From load_scenario, parse_scenario or
random_scenario; its matrices are numpy arrays (copies).)")
      .def_property_readonly("horizon", [](const Scenario& s) { return s.horizon_s; })
      .def_property_readonly("intervals", [](const Scenario& s) { return s.intervals; })
      .def_property_readonly("state_dim", &Scenario::stateDim)
      .def_property_readonly("sensor_count", &Scenario::sensorCount)
      .def_property_readonly("A", [](const Scenario& s) { return s.plant.A; })
      .def_property_readonly("Q", [](const Scenario& s) { return s.plant.Q; })
      .def_property_readonly("P0", [](const Scenario& s) { return s.plant.P0; })
      .def_property_readonly("W", [](const Scenario& s) { return s.cost.W; })
      .def_property_readonly("WT", [](const Scenario& s) { return s.cost.WT; })
      .def_property_readonly("C", [](const Scenario& s) { return s.constraints.C; })
      .def_property_readonly("b", [](const Scenario& s) { return s.constraints.b; })
      .def_property_readonly(
          "energy",
          [](const Scenario& s) {
            return s.constraints.energy.size() > 0
                       ? Eigen::VectorXd(s.constraints.energy)
                       : Eigen::VectorXd::Constant(s.sensorCount(),
                                                   std::numeric_limits<double>::infinity());
          },
          "Each sensor's energy budget, expected measurements over the horizon (inf: none).")
      .def_property_readonly("H",
                             [](const Scenario& s) {
                               std::vector<Matrix> h;
                               for (const SensorModel& j : s.sensors) h.push_back(j.H);
                               return h;
                             })
      .def_property_readonly("R",
                             [](const Scenario& s) {
                               std::vector<Matrix> r;
                               for (const SensorModel& j : s.sensors) r.push_back(j.R);
                               return r;
                             })
      .def_property_readonly("max_rates", &Scenario::maxRates)
      .def(
          "with_budget",
          [](const Scenario& s, double budget) { return withBudget(s, budget, "budget"); },
          py::arg("budget"), "The same scenario with its one budget row 1'λ <= b set to `budget`.")
      .def(
          "with_energy",
          [](const Scenario& s, const Eigen::VectorXd& energy) {
            return withEnergy(s, energy, "energy");
          },
          py::arg("energy"),
          "The same scenario with energy budgets ∫λ_j dt <= energy_j: one per sensor, or one "
          "value for every sensor (inf: none).")
      .def(
          "with_energy",
          [](const Scenario& s, double energy) {
            return withEnergy(s, Eigen::VectorXd::Constant(1, energy), "energy");
          },
          py::arg("energy"))
      .def("__repr__", [](const Scenario& s) {
        return "Scenario(states=" + std::to_string(s.stateDim()) +
               ", sensors=" + std::to_string(s.sensorCount()) +
               ", horizon=" + std::to_string(s.horizon_s) +
               ", intervals=" + std::to_string(s.intervals) + ")";
      });

  m.def("load_scenario", &loadScenarioFile, py::arg("path"));
  m.def("parse_scenario", &parseScenarioYaml, py::arg("text"), py::arg("source") = "scenario");
  m.def(
      "random_scenario",
      [](int states, int sensors, std::uint64_t seed, double noise_scale, double budget,
         double horizon, int intervals, int rows_per_sensor, double energy) {
        RandomPlantSpec spec;
        spec.state_dim = states;
        spec.sensor_count = sensors;
        spec.seed = seed;
        spec.noise_scale = noise_scale;
        spec.budget = budget;
        spec.horizon_s = horizon;
        spec.intervals = intervals;
        spec.rows_per_sensor = rows_per_sensor;
        spec.energy = energy;
        Scenario s = generateRandomScenario(spec);
        validateScenario(s, "random_scenario");
        return s;
      },
      py::arg("states"), py::arg("sensors"), py::arg("seed"), py::arg("noise_scale"),
      py::arg("budget"), py::arg("horizon"), py::arg("intervals"), py::arg("rows_per_sensor"),
      py::arg("energy"));
  m.def(
      "uniform_rates", [](const Scenario& s) { return uniformSchedule(s).rates(); },
      py::arg("scenario"));
  m.def(
      "load_rates",
      [](const std::string& path, const Scenario& s) { return loadScheduleFile(path, s).rates(); },
      py::arg("path"), py::arg("scenario"));
  m.def(
      "write_rates",
      [](const std::string& path, const Scenario& s, const Matrix& rates) {
        writeScheduleFile(path, scheduleOf(s, rates));
      },
      py::arg("path"), py::arg("scenario"), py::arg("rates"));
  m.def("plan", &plan, py::arg("scenario"), py::arg("surrogate"), py::arg("method"),
        py::arg("tolerance"), py::arg("max_iterations"), py::arg("max_seconds"),
        py::arg("excluded"), py::arg("network_aware"), py::arg("warm_start"), py::arg("seed"));
  m.def(
      "bracket",
      [](const Scenario& s, const Matrix& rates) {
        const RateSchedule schedule = scheduleOf(s, rates);
        CostBracket b;
        {
          py::gil_scoped_release unlocked;
          b = computeBracket(s, schedule);
        }
        return bracketDict(b);
      },
      py::arg("scenario"), py::arg("rates"));
  m.def("evaluate", &evaluate, py::arg("scenario"), py::arg("rates"), py::arg("runs"),
        py::arg("seed"), py::arg("threads"), py::arg("plant"), py::arg("arrivals"));
  m.def("closed_loop", &closedLoop, py::arg("scenario"), py::arg("rates"), py::arg("replan_every"),
        py::arg("surrogate"), py::arg("runs"), py::arg("seed"), py::arg("threads"),
        py::arg("switch_margin"), py::arg("time_scale"));
  m.def("trajectory", &trajectory, py::arg("scenario"), py::arg("rates"), py::arg("form"),
        py::arg("times"));
  m.def("cdkf", &exactFilter, py::arg("scenario"), py::arg("times"), py::arg("sensors"));
}

}  // namespace sensornet::python
