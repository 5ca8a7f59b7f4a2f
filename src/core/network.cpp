#include "sensornet/core/network.hpp"

#include <algorithm>
#include <cmath>
#include <string>
#include <utility>

#include "sensornet/core/input_error.hpp"

namespace sensornet {
namespace {

// A time is on the grid of step `step` when it is a whole number of steps, to 1e-6 of a step.
bool onGrid(double time_s, double step_s) {
  const double steps = time_s / step_s;
  return std::abs(steps - std::round(steps)) <= 1e-6;
}

std::vector<Outage> outagesOf(const NetworkSpec& network, std::uint32_t episode) {
  std::vector<Outage> applying;
  for (const Outage& outage : network.outages) {
    if (outage.appliesTo(episode)) applying.push_back(outage);
  }
  return applying;
}

// Delivered fraction of a link: what independent loss leaves of a Poisson process.
double deliveredFraction(const NetworkSpec& network, int sensor) {
  if (sensor >= static_cast<int>(network.links.size())) return 1.0;
  return 1.0 - network.links[static_cast<std::size_t>(sensor)].loss;
}

void requireSensorInRange(const Outage& outage, int sensors) {
  if (outage.sensor < 0 || outage.sensor >= sensors) {
    throw InputError("network", "outages.sensor",
                     "a sensor index below " + std::to_string(sensors) + ", got " +
                         std::to_string(outage.sensor));
  }
}

// Zeroes the rate of the outage's sensor on every refined interval inside [from, to); edges are
// on the refined grid, so each refined interval is either wholly inside or wholly outside.
void cutOutage(Eigen::MatrixXd& rates, const Outage& outage, double step_s) {
  const auto first = static_cast<Eigen::Index>(std::llround(outage.from_s / step_s));
  const auto last = std::min<Eigen::Index>(
      static_cast<Eigen::Index>(std::llround(outage.to_s / step_s)), rates.rows());
  for (Eigen::Index k = std::max<Eigen::Index>(first, 0); k < last; ++k) {
    rates(k, outage.sensor) = 0.0;
  }
}

// Length of the union of `windows` (pairs from, to) inside [t0, t1).
double coveredLength(std::vector<std::pair<double, double>> windows, double t0, double t1) {
  std::sort(windows.begin(), windows.end());
  double covered = 0.0;
  double reached = t0;
  for (const auto& [from, to] : windows) {
    const double start = std::max(from, reached);
    const double end = std::min(to, t1);
    if (end > start) {
      covered += end - start;
      reached = end;
    }
  }
  return covered;
}

}  // namespace

bool Outage::appliesTo(std::uint32_t episode) const {
  return episodes.empty() || std::find(episodes.begin(), episodes.end(), episode) != episodes.end();
}

int outageRefinement(double horizon_s, int intervals, const std::vector<Outage>& outages) {
  const double interval_s = horizon_s / intervals;
  for (int factor = 1; factor <= kMaxOutageRefinement; ++factor) {
    const double step_s = interval_s / factor;
    const bool all_on_grid = std::all_of(outages.begin(), outages.end(), [&](const Outage& o) {
      return onGrid(o.from_s, step_s) && onGrid(o.to_s, step_s);
    });
    if (all_on_grid) return factor;
  }
  return 0;
}

RateSchedule deliveredSchedule(const RateSchedule& schedule, const NetworkSpec& network,
                               std::uint32_t episode) {
  const std::vector<Outage> outages = outagesOf(network, episode);
  const int factor = outageRefinement(schedule.horizon(), schedule.intervals(), outages);
  if (factor == 0) {
    throw InputError(
        "network", "outages",
        "edges on the schedule's grid refined by at most " + std::to_string(kMaxOutageRefinement));
  }
  Eigen::MatrixXd rates(static_cast<Eigen::Index>(schedule.intervals()) * factor,
                        schedule.sensorCount());
  for (Eigen::Index k = 0; k < rates.rows(); ++k) rates.row(k) = schedule.rates().row(k / factor);
  for (int j = 0; j < schedule.sensorCount(); ++j) rates.col(j) *= deliveredFraction(network, j);
  const double step_s = schedule.intervalLength() / factor;
  for (const Outage& outage : outages) {
    requireSensorInRange(outage, schedule.sensorCount());
    cutOutage(rates, outage, step_s);
  }
  return RateSchedule(schedule.horizon(), std::move(rates));
}

RateSchedule silencedSchedule(const RateSchedule& schedule,
                              const std::vector<std::optional<double>>& silent_from_s) {
  Eigen::MatrixXd rates = schedule.rates();
  const double h = schedule.intervalLength();
  const std::size_t silenced = std::min(silent_from_s.size(),
                                        static_cast<std::size_t>(schedule.sensorCount()));
  for (std::size_t j = 0; j < silenced; ++j) {
    if (!silent_from_s[j]) continue;
    const auto col = static_cast<Eigen::Index>(j);
    for (int k = 0; k < schedule.intervals(); ++k) {
      const double live = std::clamp(*silent_from_s[j] - k * h, 0.0, h) / h;  // part before it
      rates(k, col) *= live;
    }
  }
  return RateSchedule(schedule.horizon(), std::move(rates));
}

Eigen::MatrixXd deliveryFactors(const Scenario& scenario) {
  const int sensors = scenario.sensorCount();
  Eigen::MatrixXd factors = Eigen::MatrixXd::Ones(scenario.intervals, sensors);
  if (!scenario.network) return factors;
  const NetworkSpec& network = *scenario.network;
  std::vector<std::vector<std::pair<double, double>>> windows(static_cast<std::size_t>(sensors));
  for (const Outage& outage : network.outages) {
    requireSensorInRange(outage, sensors);
    if (outage.episodes.empty()) {
      windows[static_cast<std::size_t>(outage.sensor)].emplace_back(outage.from_s, outage.to_s);
    }
  }
  const double h = scenario.intervalLength();
  for (int j = 0; j < sensors; ++j) {
    for (int k = 0; k < scenario.intervals; ++k) {
      const double down = coveredLength(windows[static_cast<std::size_t>(j)], k * h, (k + 1) * h);
      factors(k, j) = deliveredFraction(network, j) * std::max(0.0, 1.0 - down / h);
    }
  }
  return factors;
}

}  // namespace sensornet
