#include "sensornet/emulator/covariance_trace.hpp"

#include <algorithm>
#include <stdexcept>
#include <tuple>

#include "sensornet/core/cdkf.hpp"
#include "sensornet/core/surrogate.hpp"

namespace sensornet::emulator {
namespace {

double weighted(const Eigen::MatrixXd& weight, const Eigen::MatrixXd& covariance) {
  return (weight.array() * covariance.array()).sum();  // <W, P>_F
}

}  // namespace

TraceWeight traceWeight(const Scenario& scenario) {
  if (scenario.cost.W.size() > 0 && !scenario.cost.W.isZero(0.0)) return {scenario.cost.W, "W"};
  return {scenario.cost.WT, "W_T"};
}

std::vector<double> traceGrid(double horizon_s, int points) {
  if (points < 2) throw std::invalid_argument("a trace grid needs at least 2 points");
  std::vector<double> grid(static_cast<std::size_t>(points));
  for (int i = 0; i < points; ++i) {
    grid[static_cast<std::size_t>(i)] =
        i == points - 1 ? horizon_s : horizon_s * static_cast<double>(i) / (points - 1);
  }
  return grid;
}

TraceCurve fusedCovarianceTrace(const Scenario& scenario,
                                std::vector<FusedMeasurement> measurements,
                                const TraceWeight& weight, int points) {
  std::sort(measurements.begin(), measurements.end(),
            [](const FusedMeasurement& a, const FusedMeasurement& b) {
              return std::tie(a.time_s, a.sensor, a.seq) < std::tie(b.time_s, b.sensor, b.seq);
            });
  CdKalmanFilter filter(scenario);
  filter.reset();
  TraceCurve curve;
  curve.times_s = traceGrid(scenario.horizon_s, points);
  std::size_t next = 0;
  for (const double t : curve.times_s) {
    for (; next < measurements.size() && measurements[next].time_s <= t; ++next) {
      filter.propagateTo(measurements[next].time_s);
      filter.updateCovariance(measurements[next].sensor);
    }
    filter.propagateTo(t);
    curve.values.push_back(weighted(weight.matrix, filter.covariance()));
  }
  return curve;
}

SurrogateTraces surrogateTraces(const Scenario& scenario, const RateSchedule& schedule,
                                const TraceWeight& weight, int points) {
  const std::vector<double> grid = traceGrid(scenario.horizon_s, points);
  const auto sample = [&](SurrogateForm form) {
    TraceCurve curve;
    curve.times_s = grid;
    Eigen::MatrixXd covariance = scenario.plant.P0;
    curve.values.push_back(weighted(weight.matrix, covariance));
    for (std::size_t i = 1; i < grid.size(); ++i) {
      RolloutOptions options;
      options.start_time = grid[i - 1];
      if (i > 1) options.start_covariance = covariance;
      options.end_time = grid[i];
      covariance = rollout(form, scenario, schedule, options).covariances.back();
      curve.values.push_back(weighted(weight.matrix, covariance));
    }
    return curve;
  };
  return {sample(SurrogateForm::Information), sample(SurrogateForm::Covariance)};
}

nlohmann::json traceJson(const TraceCurve& curve) {
  return {{"times_s", curve.times_s}, {"values", curve.values}};
}

}  // namespace sensornet::emulator
