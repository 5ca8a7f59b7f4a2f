#include "sensornet/io/plan_request.hpp"

#include <spdlog/spdlog.h>

#include <iostream>
#include <stdexcept>

#include "sensornet/core/input_error.hpp"
#include "sensornet/core/network.hpp"
#include "sensornet/io/scenario_file.hpp"

namespace sensornet {

PlanRequest planRequest(const Scenario& scenario, const std::string& scenario_path,
                        const PlanChoices& choices) {
  PlanRequest request;
  request.surrogate = choices.surrogate;
  request.method = choices.method;
  request.tolerance = choices.tolerance;
  request.max_iterations = choices.max_iterations;
  request.max_seconds = choices.max_seconds;
  if (choices.surrogate == PlanSurrogate::MonteCarlo && !choices.max_seconds_given) {
    request.max_seconds = kMonteCarloPlanSeconds;
  }
  for (const int sensor : choices.excluded) {
    if (sensor < 0 || sensor >= scenario.sensorCount()) {
      throw InputError("command line", "--exclude",
                       "sensor indices in [0, " + std::to_string(scenario.sensorCount()) +
                           "), got " + std::to_string(sensor));
    }
  }
  request.excluded_sensors = choices.excluded;
  if (choices.network_aware) {
    if (!scenario.network) {
      throw InputError(scenario_path, "network",
                       "a network: section for --network-aware (the scenario has none; see "
                       "scenarios/lossy.yaml)");
    }
    request.delivery = deliveryFactors(scenario);
  }
  if (!choices.warm_start_path.empty()) {
    request.warm_start = loadScheduleFile(choices.warm_start_path, scenario);
  }
  return request;
}

std::function<bool(const PlanProgress&)> planProgressLog(PlanSurrogate surrogate) {
  const char* what = surrogate == PlanSurrogate::MonteCarlo
                         ? "Monte Carlo cost (screening sample)"
                         : "surrogate cost";
  return [next_report = 2.0, what](const PlanProgress& p) mutable {
    if (p.elapsed_seconds >= next_report) {
      next_report = p.elapsed_seconds + 2.0;
      spdlog::info("plan: iteration {}, {} {:.8g}, {:.1f} s", p.iteration, what, p.objective,
                   p.elapsed_seconds);
    }
    return true;
  };
}

void writePlannedSchedule(const std::string& out_path, const RateSchedule& schedule,
                          const nlohmann::json& record) {
  if (out_path != "-") {
    writeScheduleFile(out_path, schedule, record);
    return;
  }
  nlohmann::json doc = scheduleToJson(schedule);
  for (const auto& [key, value] : record.items()) doc[key] = value;
  std::cout << doc.dump(2) << std::endl;
  if (!std::cout) throw std::runtime_error("cannot write the schedule to standard output");
}

}  // namespace sensornet
