#include "sensornet/emulator/episode_fusion.hpp"

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>

namespace sensornet::emulator {

std::uint64_t faultyRejections(const RejectionCounts& rejected) {
  std::uint64_t total = 0;
  for (const auto& [reason, count] : rejected) {
    if (reason != kNetworkDuplicate) total += count;
  }
  return total;
}

EpisodeFusion::EpisodeFusion(const Scenario& scenario, const EmulatedPlant& plant,
                             const ScheduleBook& book, std::uint32_t episode,
                             BracketOf bracket_of)
    : scenario_(scenario),
      plant_(plant),
      book_(book),
      episode_(episode),
      bracket_of_(std::move(bracket_of)),
      filter_(scenario),
      tallies_(static_cast<std::size_t>(scenario.sensorCount())),
      sent_at_least_(tallies_.size(), 0) {
  scheduleChanged();
}

void EpisodeFusion::scheduleChanged() {
  segments_ = book_.segments(episode_, scenario_.horizon_s);
  const double previous = switch_time_s_;
  switch_time_s_ = segments_.size() > 1 ? segments_.back().from_s : 0.0;
  if (switch_time_s_ != previous) {
    at_switch_.reset();
    // The filter must stop at the new switch point to record P(s); if it has passed it,
    // finish() fuses the episode again from the start.
    if (switch_time_s_ > 0.0 && filter_.time() > switch_time_s_) replay_ = true;
  }
}

std::optional<Rejection> EpisodeFusion::add(FusedMeasurement m) {
  const auto reject = [this](const char* reason, std::string detail) -> std::optional<Rejection> {
    ++rejected_[reason];
    return Rejection{reason, std::move(detail)};
  };
  const std::string who = "sensor " + std::to_string(m.sensor);
  if (m.sensor < 0 || m.sensor >= scenario_.sensorCount()) {
    return reject("unknown_sensor", who + " is not a sensor of the scenario");
  }
  const auto j = static_cast<std::size_t>(m.sensor);
  if (m.z.size() != scenario_.sensors[j].H.rows() || !m.z.allFinite()) {
    return reject("malformed", who + ": z must hold " +
                                   std::to_string(scenario_.sensors[j].H.rows()) +
                                   " finite values");
  }
  if (!(m.time_s >= 0.0 && m.time_s <= scenario_.horizon_s)) {
    return reject("malformed", who + ": time outside [0, T]");
  }
  SensorTally& tally = tallies_[j];
  if (!seen_.insert({m.sensor, m.seq}).second) {
    // Counted by finish(): the network's copies and the rest apart, once the tally says how many
    // copies the network made.
    ++tally.duplicates;
    return Rejection{"duplicate", who + ": duplicate seq " + std::to_string(m.seq)};
  }
  ++tally.received;
  sent_at_least_[j] = std::max(sent_at_least_[j], m.seq + 1);
  const std::size_t index = all_.size();
  const Key key{m.time_s, m.sensor, m.seq};
  if (m.time_s < filter_.time()) {
    ++tally.late;
    replay_ = true;  // fused again, in order, by finish()
  } else {
    pending_.insert({key, index});
  }
  all_.push_back(std::move(m));
  return std::nullopt;
}

void EpisodeFusion::setTally(int sensor, const EpisodeCount& count) {
  if (sensor < 0 || sensor >= scenario_.sensorCount()) return;
  SensorTally& tally = tallies_[static_cast<std::size_t>(sensor)];
  tally.tallied = true;
  tally.sent = count.sent;
  tally.dropped_by_network = count.dropped_by_network;
  tally.duplicated_by_network = count.duplicated_by_network;
}

void EpisodeFusion::noteSentAtLeast(int sensor, std::uint64_t sent) {
  if (sensor < 0 || sensor >= scenario_.sensorCount()) return;
  auto& at_least = sent_at_least_[static_cast<std::size_t>(sensor)];
  at_least = std::max(at_least, sent);
}

bool EpisodeFusion::settled(int sensor) const {
  const SensorTally& t = tallies_[static_cast<std::size_t>(sensor)];
  return t.tallied && t.received + t.dropped_by_network >= t.sent;
}

bool EpisodeFusion::allSettled() const { return unsettled().empty(); }

std::vector<int> EpisodeFusion::unsettled() const {
  std::vector<int> sensors;
  for (int j = 0; j < scenario_.sensorCount(); ++j) {
    if (!settled(j)) sensors.push_back(j);
  }
  return sensors;
}

void EpisodeFusion::propagateTo(double t) {
  if (switch_time_s_ > 0.0 && !at_switch_ && filter_.time() <= switch_time_s_ &&
      switch_time_s_ <= t) {
    filter_.propagateTo(switch_time_s_);
    at_switch_.emplace(filter_.runningCost(), filter_.covariance());
  }
  filter_.propagateTo(t);
}

void EpisodeFusion::fuse(const FusedMeasurement& m) {
  propagateTo(m.time_s);
  filter_.update(m.sensor, m.z);
}

void EpisodeFusion::fuseUpTo(double t) {
  t = std::min(t, scenario_.horizon_s);
  while (!pending_.empty() && std::get<0>(pending_.begin()->first) <= t) {
    fuse(all_[pending_.begin()->second]);
    pending_.erase(pending_.begin());
  }
}

EpisodeResult EpisodeFusion::finish() {
  scheduleChanged();
  if (replay_) {
    filter_.reset();
    at_switch_.reset();
    std::vector<std::size_t> order(all_.size());
    for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
    std::sort(order.begin(), order.end(), [this](std::size_t a, std::size_t b) {
      return Key{all_[a].time_s, all_[a].sensor, all_[a].seq} <
             Key{all_[b].time_s, all_[b].sensor, all_[b].seq};
    });
    for (const std::size_t i : order) fuse(all_[i]);
    pending_.clear();
  }
  fuseUpTo(scenario_.horizon_s);
  propagateTo(scenario_.horizon_s);

  EpisodeResult result;
  result.episode = episode_;
  result.realized_cost = filter_.cost();
  for (const ScheduleSegment& segment : segments_) result.versions.push_back(segment.version->version);
  result.switch_time_s = switch_time_s_;
  if (at_switch_) {
    RolloutOptions options;
    options.start_time = switch_time_s_;
    options.start_covariance = at_switch_->second;
    const CostBracket rest = computeBracket(scenario_, segments_.back().version->schedule, options);
    result.bracket = {at_switch_->first + rest.info, at_switch_->first + rest.cov};
  } else if (!segments_.empty()) {
    result.bracket = bracket_of_(*segments_.front().version);
  }
  const Eigen::VectorXd error = plant_.stateAt(episode_, plant_.tickCount()) - filter_.mean();
  result.nees = error.dot(filter_.covariance().llt().solve(error));
  result.complete = allSettled();
  std::vector<SensorTally> tallies = tallies_;
  for (const ScheduleSegment& segment : segments_) {
    const Eigen::VectorXd expected =
        segment.version->schedule.expectedCounts(segment.from_s, segment.to_s);
    for (std::size_t j = 0; j < tallies.size(); ++j) {
      tallies[j].expected += expected(static_cast<Eigen::Index>(j));
    }
  }
  for (const FusedMeasurement& m : all_) {
    for (const ScheduleSegment& segment : segments_) {
      if (m.time_s >= segment.from_s &&
          (m.time_s < segment.to_s || segment.to_s >= scenario_.horizon_s)) {
        if (segment.version->version != m.version) {
          ++tallies[static_cast<std::size_t>(m.sensor)].wrong_version;
        }
        break;
      }
    }
  }
  result.rejected = rejected_;
  for (std::size_t j = 0; j < tallies.size(); ++j) {
    SensorTally tally = tallies[j];
    if (!tally.tallied) tally.sent = sent_at_least_[j];
    const std::uint64_t accounted = tally.received + tally.dropped_by_network;
    tally.lost = tally.sent > accounted ? tally.sent - accounted : 0;
    const std::uint64_t by_network = std::min(tally.duplicates, tally.duplicated_by_network);
    if (by_network > 0) result.rejected[kNetworkDuplicate] += by_network;
    if (tally.duplicates > by_network) result.rejected["duplicate"] += tally.duplicates - by_network;
    result.sensors.push_back(tally);
  }
  for (const FusedMeasurement& m : all_) {
    result.latencies_s.push_back(1e-9 * static_cast<double>(m.receive_wall_ns - m.publish_wall_ns));
  }
  return result;
}

}  // namespace sensornet::emulator
