#include "sensornet/emulator/episode_fusion.hpp"

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <deque>
#include <functional>
#include <limits>

#include "sensornet/core/network.hpp"
#include "sensornet/emulator/vocabulary.hpp"

namespace sensornet::emulator {
namespace {

// A rejection reason as RejectionCounts keys it.
std::string reasonText(RejectionReason reason) { return std::string(wordOf(reason)); }

using Key = std::tuple<double, int, std::uint64_t>;  // (time, sensor, seq): timestamp order

Key keyOf(const FusedMeasurement& m) { return {m.time_s, m.sensor, m.seq}; }

// How many steps the fusion's filters keep (TransitionCache): gaps between measurements are
// whole ticks of the emulated plant, so at high rates a few hundred lengths come again and
// again. Each step is three n x n matrices: at most about 4 MB of them.
std::size_t stepSlots(const Scenario& scenario) {
  const auto bytes = static_cast<std::size_t>(24 * scenario.stateDim() * scenario.stateDim());
  return std::clamp<std::size_t>((std::size_t{4} << 20) / bytes, 1, 256);
}

// The real-time cost of an episode (see the header): the covariance of what had arrived by each
// instant, integrated exactly. Every step is one of CdKalmanFilter's exact steps, split at the
// switch point as EpisodeFusion's own filter splits it, so that with zero delays the sequence of
// floating-point operations is the hindsight filter's.
class RealtimeCost {
 public:
  RealtimeCost(const Scenario& scenario, double switch_time_s)
      : work_(scenario),
        horizon_s_(scenario.horizon_s),
        switch_time_s_(switch_time_s),
        zero_mean_(Eigen::VectorXd::Zero(scenario.stateDim())) {
    work_.reset();
    work_.cacheSteps(stepSlots(scenario));
    initial_ = work_.covariance();
  }

  // A measurement as this pass sees it: its key and the instant it arrives.
  struct Arrival {
    Key key;
    double at = 0.0;
  };

  // NaN when it would re-fuse more than max_refused measurements (see realtimeCost).
  [[nodiscard]] double of(std::vector<Arrival> all, std::size_t max_refused) {
    // By arrival (ties in timestamp order); what arrives after T plays no part.
    std::erase_if(all, [this](const Arrival& a) { return a.at > horizon_s_; });
    std::sort(all.begin(), all.end(), [](const Arrival& a, const Arrival& b) {
      return std::tie(a.at, a.key) < std::tie(b.at, b.key);
    });
    const std::vector<Key> earliest = earliestKeyFrom(all);
    double now = 0.0;
    Eigen::MatrixXd current = initial_;  // the covariance of what had arrived by `now`
    Eigen::MatrixXd fused;               // of the set with the measurement just arrived
    double cost = 0.0;
    for (std::size_t i = 0; i < all.size(); ++i) {
      const Key& key = all[i].key;
      const double time_s = std::get<0>(key);
      const double arrival = all[i].at;
      // No measurement still to come is before the second checkpoint: the first is never a
      // starting point again.
      while (checkpoints_.size() >= 2 && checkpoints_[1].key < earliest[i]) {
        spare_.push_back(std::move(checkpoints_.front().covariance));
        checkpoints_.pop_front();
      }
      const auto after = std::upper_bound(
          checkpoints_.begin(), checkpoints_.end(), key,
          [](const Key& k, const Checkpoint& c) { return k < c.key; });
      if (after == checkpoints_.end() && time_s >= now) {
        // The last of the set in timestamp order: its filter is the current one up to time_s.
        propagate(now, current, time_s, &cost, current);
        now = time_s;
        update(now, current, std::get<1>(key), fused);
        checkpoints_.push_back({key, spareCopyOf(fused)});
        if (arrival > now) {
          propagate(now, current, arrival, &cost, current);  // not arrived yet on [time_s, a)
          propagate(now, fused, arrival, nullptr, fused);
          now = arrival;
        }
        std::swap(current, fused);
      } else {
        propagate(now, current, arrival, &cost, current);
        now = arrival;
        refuseFrom(checkpoints_.insert(after, {key, spareMatrix()}), now, current);
        if (refused_ > max_refused) return std::numeric_limits<double>::quiet_NaN();
      }
    }
    propagate(now, current, horizon_s_, &cost, current);
    work_.reset(horizon_s_, zero_mean_, current);
    return cost + work_.terminalCost();
  }

 private:
  struct Checkpoint {
    Key key;
    Eigen::MatrixXd covariance;  // right after the measurement `key` was fused
  };

  // earliest[i]: the smallest key among all[i..] (the measurements still to arrive).
  [[nodiscard]] static std::vector<Key> earliestKeyFrom(const std::vector<Arrival>& all) {
    std::vector<Key> earliest(all.size());
    for (std::size_t i = all.size(); i-- > 0;) {
      earliest[i] = all[i].key;
      if (i + 1 < all.size()) earliest[i] = std::min(earliest[i], earliest[i + 1]);
    }
    return earliest;
  }

  // A matrix of a checkpoint dropped before, or a new one: no allocation once the pass holds as
  // many as it ever keeps. Its contents are whatever they were.
  [[nodiscard]] Eigen::MatrixXd spareMatrix() {
    if (spare_.empty()) return Eigen::MatrixXd(initial_.rows(), initial_.cols());
    Eigen::MatrixXd spare = std::move(spare_.back());
    spare_.pop_back();
    return spare;
  }

  // A copy of `covariance` in a spare matrix.
  [[nodiscard]] Eigen::MatrixXd spareCopyOf(const Eigen::MatrixXd& covariance) {
    Eigen::MatrixXd copy = spareMatrix();
    copy = covariance;
    return copy;
  }

  // The filter of the set again from the checkpoint before `inserted` (P0 at 0 when none), with
  // the new measurement fused at its time; puts the set's covariance at `arrival` in *out.
  void refuseFrom(std::deque<Checkpoint>::iterator inserted, double arrival,
                  Eigen::MatrixXd& out) {
    double t = 0.0;
    refused_covariance_ = initial_;
    if (inserted != checkpoints_.begin()) {
      const Checkpoint& before = *std::prev(inserted);
      t = std::get<0>(before.key);
      refused_covariance_ = before.covariance;
    }
    for (auto it = inserted; it != checkpoints_.end(); ++it) {
      const double at = std::get<0>(it->key);
      propagate(t, refused_covariance_, at, nullptr, refused_covariance_);
      t = at;
      update(t, refused_covariance_, std::get<1>(it->key), refused_covariance_);
      it->covariance = refused_covariance_;
      ++refused_;
    }
    propagate(t, refused_covariance_, arrival, nullptr, out);
  }

  // P at `to` from P at `from` (`out` may be `covariance`), in the hindsight filter's steps
  // (split at the switch point); adds ∫ <W, P> of each step to *cost when given.
  void propagate(double from, const Eigen::MatrixXd& covariance, double to, double* cost,
                 Eigen::MatrixXd& out) {
    if (to == from) {
      if (&out != &covariance) out = covariance;
      return;
    }
    work_.reset(from, zero_mean_, covariance);
    if (from < switch_time_s_ && switch_time_s_ < to) {
      advanceTo(switch_time_s_);
      if (cost != nullptr) *cost += work_.runningCost();
      work_.reset(switch_time_s_, zero_mean_, work_.covariance());
    }
    advanceTo(to);
    if (cost != nullptr) *cost += work_.runningCost();
    out = work_.covariance();
  }

  // work_.propagateTo(t). Its steps are cached by length: a measurement's set and the set
  // without it go from its time to its arrival over the same interval, a re-fusion goes again
  // over intervals it went over just before, and gaps of whole ticks repeat.
  void advanceTo(double t) { work_.propagateTo(t); }

  // `covariance` updated with a measurement of `sensor` at t, into `out` (may be `covariance`).
  void update(double t, const Eigen::MatrixXd& covariance, int sensor, Eigen::MatrixXd& out) {
    work_.reset(t, zero_mean_, covariance);
    work_.updateCovariance(sensor);
    out = work_.covariance();
  }

  CdKalmanFilter work_;
  double horizon_s_;
  double switch_time_s_;
  Eigen::VectorXd zero_mean_;
  Eigen::MatrixXd initial_;  // P0
  std::deque<Checkpoint> checkpoints_;  // the set so far, in timestamp order
  std::vector<Eigen::MatrixXd> spare_;  // the matrices of checkpoints dropped, for new ones
  Eigen::MatrixXd refused_covariance_;  // refuseFrom's running covariance
  std::size_t refused_ = 0;             // measurements fused again by refuseFrom
};

}  // namespace

double realtimeCost(const Scenario& scenario, double switch_time_s,
                    const std::vector<FusedMeasurement>& measurements, std::size_t max_refused) {
  std::vector<RealtimeCost::Arrival> arrivals;
  arrivals.reserve(measurements.size());
  for (const FusedMeasurement& m : measurements) {
    arrivals.push_back({keyOf(m), m.time_s + m.network_delay_s});
  }
  return RealtimeCost(scenario, switch_time_s).of(std::move(arrivals), max_refused);
}

std::uint64_t faultyRejections(const RejectionCounts& rejected) {
  std::uint64_t total = 0;
  for (const auto& [reason, count] : rejected) {
    if (reason != kNetworkDuplicate) total += count;
  }
  return total;
}

EpisodeFusion::EpisodeFusion(const Scenario& scenario, const EmulatedPlant& plant,
                             const ScheduleBook& book, std::uint32_t episode,
                             BracketOf bracket_of, BracketOf delivered_bracket_of)
    : scenario_(scenario),
      plant_(plant),
      book_(book),
      episode_(episode),
      bracket_of_(std::move(bracket_of)),
      delivered_bracket_of_(std::move(delivered_bracket_of)),
      filter_(scenario),
      tallies_(static_cast<std::size_t>(scenario.sensorCount())),
      sent_at_least_(tallies_.size(), 0),
      failed_at_(tallies_.size()),
      failed_before_(tallies_.size(), false),
      failed_silent_(tallies_.size(), false) {
  filter_.cacheSteps(stepSlots(scenario));
  seen_.resize(tallies_.size());
  refused_seqs_.resize(tallies_.size());
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

std::optional<Rejection> malformedMeasurement(const Scenario& scenario,
                                              const FusedMeasurement& m) {
  const std::string who = "sensor " + std::to_string(m.sensor);
  if (m.sensor < 0 || m.sensor >= scenario.sensorCount()) {
    return Rejection{reasonText(RejectionReason::UnknownSensor),
                     who + " is not a sensor of the scenario"};
  }
  const auto rows = scenario.sensors[static_cast<std::size_t>(m.sensor)].H.rows();
  if (m.z.size() != rows || !m.z.allFinite()) {
    return Rejection{reasonText(RejectionReason::Malformed),
                     who + ": z must hold " + std::to_string(rows) + " finite values"};
  }
  if (!(m.time_s >= 0.0 && m.time_s <= scenario.horizon_s)) {
    return Rejection{reasonText(RejectionReason::Malformed), who + ": time outside [0, T]"};
  }
  if (!(m.network_delay_s >= 0.0 && std::isfinite(m.network_delay_s))) {
    return Rejection{reasonText(RejectionReason::Malformed),
                     who + ": network delay not a finite number >= 0"};
  }
  return std::nullopt;
}

bool EpisodeFusion::SeenSeqs::insert(std::uint64_t seq) {
  if (seq < below) return false;
  if (seq > below) return above.insert(seq).second;
  ++below;
  while (!above.empty() && *above.begin() == below) {
    above.erase(above.begin());
    ++below;
  }
  return true;
}

std::optional<Rejection> EpisodeFusion::add(FusedMeasurement m) {
  if (auto rejection = malformedMeasurement(scenario_, m)) {
    ++rejected_[rejection->reason];
    // A sent sample of a sensor of the scenario: accounted for once, however many copies come.
    // A well-formed copy of the seq that comes later is received instead. One at or past the
    // count the sensor's tally gives was never sent by it: refused, not accounted for.
    if (m.sensor >= 0 && m.sensor < scenario_.sensorCount()) {
      const auto j = static_cast<std::size_t>(m.sensor);
      const SensorTally& tally = tallies_[j];
      const bool beyond_tally = tally.tallied && m.seq >= tally.sent;
      if (!beyond_tally && !seen_[j].has(m.seq) && refused_seqs_[j].insert(m.seq).second) {
        ++tallies_[j].refused;
        sent_at_least_[j] = std::max(sent_at_least_[j], m.seq + 1);
      }
    }
    return rejection;
  }
  const std::string who = "sensor " + std::to_string(m.sensor);
  const auto j = static_cast<std::size_t>(m.sensor);
  SensorTally& tally = tallies_[j];
  if (!seen_[j].insert(m.seq)) {
    // Counted by finish(): the network's copies and the rest apart, once the tally says how many
    // copies the network made.
    ++tally.duplicates;
    return Rejection{reasonText(RejectionReason::Duplicate),
                     who + ": duplicate seq " + std::to_string(m.seq)};
  }
  if (refused_seqs_[j].erase(m.seq) > 0) --tally.refused;
  ++tally.received;
  sent_at_least_[j] = std::max(sent_at_least_[j], m.seq + 1);
  const std::size_t index = all_.size();
  const Key key{m.time_s, m.sensor, m.seq};
  const bool late = m.time_s < filter_.time();
  if (late) {
    ++tally.late;
    replay_ = true;  // fused again, in order, by finish()
  } else {
    pending_.emplace_back(key, index);
    std::push_heap(pending_.begin(), pending_.end(), std::greater<>());
  }
  all_.push_back(std::move(m));
  arrived_late_.push_back(late);
  return std::nullopt;
}

void EpisodeFusion::setTally(int sensor, const EpisodeCount& count) {
  if (sensor < 0 || sensor >= scenario_.sensorCount()) return;
  SensorTally& tally = tallies_[static_cast<std::size_t>(sensor)];
  tally.tallied = true;
  tally.sent = count.sent;
  tally.dropped_by_network = count.dropped_by_network;
  tally.duplicated_by_network = count.duplicated_by_network;
  // Malformed samples numbered at or past what the sensor sent were not its own.
  auto& refused = refused_seqs_[static_cast<std::size_t>(sensor)];
  refused.erase(refused.lower_bound(count.sent), refused.end());
  tally.refused = refused.size();
}

void EpisodeFusion::noteSentAtLeast(int sensor, std::uint64_t sent) {
  if (sensor < 0 || sensor >= scenario_.sensorCount()) return;
  auto& at_least = sent_at_least_[static_cast<std::size_t>(sensor)];
  at_least = std::max(at_least, sent);
}

void EpisodeFusion::sensorFailedAt(int sensor, double at_s) {
  if (sensor < 0 || sensor >= scenario_.sensorCount()) return;
  const auto j = static_cast<std::size_t>(sensor);
  if (failed_before_[j]) return;
  if (!failed_at_[j] || at_s < *failed_at_[j]) failed_at_[j] = at_s;
}

void EpisodeFusion::sensorFellSilentAt(int sensor, double last_heard_s) {
  if (sensor < 0 || sensor >= scenario_.sensorCount()) return;
  const auto j = static_cast<std::size_t>(sensor);
  if (failed_before_[j]) return;
  if (!failed_at_[j] || last_heard_s < *failed_at_[j]) {
    failed_at_[j] = last_heard_s;
    failed_silent_[j] = true;
  }
}

void EpisodeFusion::sensorFailedBefore(int sensor) {
  if (sensor < 0 || sensor >= scenario_.sensorCount()) return;
  const auto j = static_cast<std::size_t>(sensor);
  if (!failed_at_[j]) failed_before_[j] = true;
}

bool EpisodeFusion::failed(int sensor) const {
  const auto j = static_cast<std::size_t>(sensor);
  return failed_before_[j] || failed_at_[j].has_value();
}

bool EpisodeFusion::failedBefore(int sensor) const {
  return sensor >= 0 && sensor < scenario_.sensorCount() &&
         failed_before_[static_cast<std::size_t>(sensor)];
}

bool EpisodeFusion::settled(int sensor) const {
  if (failed(sensor)) return true;
  const SensorTally& t = tallies_[static_cast<std::size_t>(sensor)];
  return t.tallied && t.received + t.dropped_by_network + t.refused >= t.sent;
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
  while (!pending_.empty() && std::get<0>(pending_.front().first) <= t) {
    fuse(all_[pending_.front().second]);
    std::pop_heap(pending_.begin(), pending_.end(), std::greater<>());
    pending_.pop_back();
  }
}

CostBracket EpisodeFusion::bracketAfterSwitch(const RateSchedule& schedule) const {
  RolloutOptions options;
  options.start_time = switch_time_s_;
  options.start_covariance = at_switch_->second;
  const CostBracket rest = computeBracket(scenario_, schedule, options);
  return {at_switch_->first + rest.info, at_switch_->first + rest.cov};
}

bool EpisodeFusion::anyFailed() const {
  for (int j = 0; j < scenario_.sensorCount(); ++j) {
    if (failed(j)) return true;
  }
  return false;
}

RateSchedule EpisodeFusion::deliveredScheduleOf(const RateSchedule& schedule) const {
  const RateSchedule through_network =
      scenario_.network ? deliveredSchedule(schedule, *scenario_.network, episode_) : schedule;
  if (!anyFailed()) return through_network;
  std::vector<std::optional<double>> silent_from(failed_at_.size());
  for (std::size_t j = 0; j < silent_from.size(); ++j) {
    if (failed_before_[j]) silent_from[j] = 0.0;
    else silent_from[j] = failed_at_[j];
  }
  return silencedSchedule(through_network, silent_from);
}

CostBracket EpisodeFusion::deliveredBracket() const {
  if (segments_.empty()) return {};
  const ScheduleVersion& last = *segments_.back().version;
  if (at_switch_) return bracketAfterSwitch(deliveredScheduleOf(last.schedule));
  if (delivered_bracket_of_ && !anyFailed()) return delivered_bracket_of_(last);
  return computeBracket(scenario_, deliveredScheduleOf(last.schedule));
}

std::string EpisodeFusion::incompleteReason() const {
  std::string reason;
  const auto add = [&reason](const std::string& part) {
    reason += (reason.empty() ? "" : "; ") + part;
  };
  for (std::size_t j = 0; j < failed_at_.size(); ++j) {
    if (!failed_at_[j]) continue;
    char at[32];
    std::snprintf(at, sizeof at, "%.6g", *failed_at_[j]);
    const bool during = *failed_at_[j] < scenario_.horizon_s;
    add("sensor " + std::to_string(j) +
        (!during           ? " failed after the episode's end, before its count arrived"
         : failed_silent_[j] ? " failed after " + std::string(at) + " s (last heard then)"
                             : " failed at " + std::string(at) + " s"));
  }
  for (std::size_t j = 0; j < tallies_.size(); ++j) {
    const std::uint64_t refused = tallies_[j].refused;
    if (refused == 0) continue;
    add("sensor " + std::to_string(j) + ": " + std::to_string(refused) +
        (refused == 1 ? " sample" : " samples") + " refused (malformed)");
  }
  for (const int j : unsettled()) {
    const SensorTally& t = tallies_[static_cast<std::size_t>(j)];
    add("sensor " + std::to_string(j) + ": " +
        (t.tallied ? std::to_string(t.received) + " of " + std::to_string(t.sent) +
                         " sent measurements arrived"
                   : "no count (" + std::to_string(t.received) + " measurements arrived)"));
  }
  return reason;
}

double EpisodeFusion::receivedRealtimeCost(double realtime_cost) const {
  // As a delay: a measurement received at received_s arrives at time_s + (received_s - time_s).
  // The instant it was received is taken up to the plant's next tick, the grid measurements are
  // taken on (it counts as arrived at most a tick later: 2.9 µs when T = 3 s). Then the pass
  // goes over whole ticks only, and its steps repeat.
  const auto receivedAt = [this](const FusedMeasurement& m) {
    if (!(m.received_s < scenario_.horizon_s)) return m.received_s;  // after T stays after T
    std::int64_t tick = plant_.tickAt(m.received_s);
    if (plant_.timeOf(tick) < m.received_s) ++tick;
    return plant_.timeOf(tick);
  };
  bool any_late = false;
  std::vector<RealtimeCost::Arrival> arrivals;
  arrivals.reserve(all_.size());
  for (const FusedMeasurement& m : all_) {
    const double due = m.time_s + m.network_delay_s;
    const double received = m.received_s > 0.0 ? receivedAt(m) : 0.0;
    any_late = any_late || received > due;
    arrivals.push_back({keyOf(m), std::max(due, received)});
  }
  if (!any_late) return realtime_cost;
  // Bounded: under overload the fusion center receives whole bursts of one sensor after later
  // measurements of others, and each such measurement re-fuses everything after it.
  const std::size_t max_refused = 2 * arrivals.size() + 10000;
  return RealtimeCost(scenario_, switch_time_s_).of(std::move(arrivals), max_refused);
}

// Measurements their sensor never sent: a sequence number at or past the count its tally gives
// (a forged sample, or another participant's, for a sensor that sent fewer or none). Refused
// once the tally says how many it sent; the episode is then fused again in order without them,
// so its cost is that of what the sensor sent.
void EpisodeFusion::refuseBeyondTallies() {
  const auto beyond = [this](const FusedMeasurement& m) {
    const SensorTally& t = tallies_[static_cast<std::size_t>(m.sensor)];
    return t.tallied && m.seq >= t.sent;
  };
  if (std::none_of(all_.begin(), all_.end(), beyond)) return;
  std::vector<FusedMeasurement> kept;
  std::vector<bool> kept_late;
  for (std::size_t i = 0; i < all_.size(); ++i) {
    if (!beyond(all_[i])) {
      kept.push_back(std::move(all_[i]));
      kept_late.push_back(arrived_late_[i]);
      continue;
    }
    SensorTally& t = tallies_[static_cast<std::size_t>(all_[i].sensor)];
    --t.received;
    if (arrived_late_[i]) --t.late;
    ++rejected_[std::string(wordOf(RejectionReason::BeyondTally))];
  }
  all_ = std::move(kept);
  arrived_late_ = std::move(kept_late);
  replay_ = true;
}

EpisodeResult EpisodeFusion::finish() {
  refuseBeyondTallies();
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
  // Without delay the two costs are the same number (realtimeCost takes the hindsight steps).
  const bool delayed = std::any_of(all_.begin(), all_.end(), [](const FusedMeasurement& m) {
    return m.network_delay_s > 0.0;
  });
  result.realtime_cost = delayed ? realtimeCost(scenario_, switch_time_s_, all_) : result.realized_cost;
  result.received_realtime_cost = receivedRealtimeCost(result.realtime_cost);
  for (const ScheduleSegment& segment : segments_) result.versions.push_back(segment.version->version);
  result.switch_time_s = switch_time_s_;
  if (at_switch_) {
    result.bracket = bracketAfterSwitch(segments_.back().version->schedule);
  } else if (!segments_.empty()) {
    result.bracket = bracket_of_(*segments_.front().version);
  }
  // What the schedule could deliver: thinned by the network, nothing from a dead sensor.
  result.delivered_bracket =
      scenario_.network || anyFailed() ? deliveredBracket() : result.bracket;
  const Eigen::VectorXd error = plant_.stateAt(episode_, plant_.tickCount()) - filter_.mean();
  result.nees = error.dot(filter_.covariance().llt().solve(error));
  result.incomplete_reason = incompleteReason();
  result.complete = result.incomplete_reason.empty();
  for (int j = 0; j < scenario_.sensorCount(); ++j) {
    if (failed(j)) result.failed_sensors.push_back(j);
  }
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
    const std::uint64_t accounted = tally.received + tally.dropped_by_network + tally.refused;
    tally.lost = tally.sent > accounted ? tally.sent - accounted : 0;
    const std::uint64_t by_network = std::min(tally.duplicates, tally.duplicated_by_network);
    if (by_network > 0) result.rejected[kNetworkDuplicate] += by_network;
    if (tally.duplicates > by_network) {
      result.rejected[reasonText(RejectionReason::Duplicate)] += tally.duplicates - by_network;
    }
    result.sensors.push_back(tally);
  }
  double delay_sum_s = 0.0;
  result.earliest_latency_s.assign(tallies.size(), std::numeric_limits<double>::infinity());
  for (const FusedMeasurement& m : all_) {
    const double latency_s = 1e-9 * static_cast<double>(m.receive_wall_ns - m.publish_wall_ns);
    result.latencies_s.push_back(latency_s);
    if (m.sensor >= 0 && static_cast<std::size_t>(m.sensor) < tallies.size()) {
      double& earliest = result.earliest_latency_s[static_cast<std::size_t>(m.sensor)];
      earliest = std::min(earliest, latency_s);
    }
    delay_sum_s += m.network_delay_s;
    result.network_delay_max_s = std::max(result.network_delay_max_s, m.network_delay_s);
  }
  if (!all_.empty()) result.network_delay_mean_s = delay_sum_s / static_cast<double>(all_.size());
  return result;
}

}  // namespace sensornet::emulator
