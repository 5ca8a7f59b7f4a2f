#include "sensornet/emulator/network_emulation.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

#include "sensornet/core/random.hpp"

namespace sensornet::emulator {
namespace {

bool inOutage(const NetworkSpec& network, int sensor, std::uint32_t episode, double time_s) {
  return std::any_of(network.outages.begin(), network.outages.end(), [&](const Outage& o) {
    return o.sensor == sensor && o.appliesTo(episode) && time_s >= o.from_s && time_s < o.to_s;
  });
}

// The random part of the delay. Lognormal: log(delay) ~ N(mu, sigma^2) with
// mu = log(mean) - sigma^2 / 2, so that its mean is `jitter_mean_s`.
double jitterDraw(const LinkSpec& link, Rng& rng) {
  switch (link.jitter) {
    case Jitter::Exponential:
      return rng.exponential(1.0 / link.jitter_mean_s);
    case Jitter::Lognormal: {
      const double sigma = link.jitter_sigma;
      const double mu = std::log(link.jitter_mean_s) - 0.5 * sigma * sigma;
      return std::exp(mu + sigma * rng.normal());
    }
    case Jitter::None:
      break;
  }
  return 0.0;
}

}  // namespace

NetworkDecision decideDelivery(const NetworkSpec& network, std::uint64_t seed, int sensor,
                               std::uint32_t episode, std::uint64_t seq, double emulated_time_s) {
  NetworkDecision decision;
  if (inOutage(network, sensor, episode, emulated_time_s)) {
    decision.drop = DropCause::Outage;
    return decision;
  }
  if (sensor < 0 || sensor >= static_cast<int>(network.links.size())) return decision;
  const LinkSpec& link = network.links[static_cast<std::size_t>(sensor)];
  if (link.perfect()) return decision;
  // Always the same draws in the same order, so each part of the decision has its own
  // uniform whatever the link's parameters.
  Rng rng = Rng::keyed(seed, kNetworkStream, static_cast<std::uint64_t>(sensor), episode, seq);
  const double loss_draw = rng.uniform();
  const double duplicate_draw = rng.uniform();
  if (loss_draw < link.loss) {
    decision.drop = DropCause::Loss;
    return decision;
  }
  decision.duplicated = duplicate_draw < link.duplicate;
  decision.delay_s = link.delay_fixed_s + jitterDraw(link, rng);
  return decision;
}

bool impairs(const NetworkSpec& network) {
  return !network.outages.empty() ||
         std::any_of(network.links.begin(), network.links.end(),
                     [](const LinkSpec& link) { return !link.perfect(); });
}

void DelayLine::hold(std::int64_t due_wall_ns, HeldMeasurement measurement, int copies) {
  for (int copy = 1; copy < copies; ++copy) queue_.push({due_wall_ns, next_order_++, measurement});
  if (copies > 0) queue_.push({due_wall_ns, next_order_++, std::move(measurement)});
}

std::vector<HeldMeasurement> DelayLine::takeDue(std::int64_t wall_ns) {
  std::vector<HeldMeasurement> due;
  while (!queue_.empty() && queue_.top().due_wall_ns <= wall_ns) {
    due.push_back(queue_.top().measurement);
    queue_.pop();
  }
  return due;
}

std::vector<HeldMeasurement> DelayLine::takeAll() {
  return takeDue(std::numeric_limits<std::int64_t>::max());
}

std::optional<std::int64_t> DelayLine::nextDueWallNs() const {
  if (queue_.empty()) return std::nullopt;
  return queue_.top().due_wall_ns;
}

}  // namespace sensornet::emulator
