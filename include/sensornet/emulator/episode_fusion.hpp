#pragma once
// The fusion center's work on one episode: the exact CD-KF over the measurements of all
// sensors in timestamp order, the realized cost J(P) of eq. (6), the bracket of the schedule
// actually in force, the NEES against the emulated truth, and the counts per sensor.
//
//   EpisodeFusion fusion(scenario, plant, book, episode, bracketOf);
//   fusion.add(measurement);           // any order; returns the rejection when it refuses one
//   fusion.fuseUpTo(watermark_s);      // online: fuse what can no longer be overtaken
//   fusion.setTally(j, {sent, dropped, duplicated});  // sensor j's end-of-episode tally
//   fusion.sensorFailedAt(k, 1.25);    // sensor k died: nobody waits for its tally
//   if (fusion.allSettled()) ...;      // every tally in, and every sent measurement received
//   EpisodeResult r = fusion.finish(); // fuse the rest, propagate to T, bracket, account
//
// Timestamp order: measurements are fused in order of (emulated time, sensor, seq) whatever
// order they arrive in. One that arrives after the filter has passed its time ("late") is kept
// and the whole episode is re-fused in order at finish(). The filter only ever moves from one
// measurement to the next (and to the switch point and T), never to a wall-clock watermark, so
// the realized cost is the same floating-point number whatever the arrival order and timing:
// a run with a stall fuses exactly what a run without one does.
//
// Two costs. The hindsight cost (`realized_cost`) is J(P) of the filter over every measurement
// in timestamp order. The real-time cost is ∫_0^T <W, P_rt(t)> dt + <W_T, P_rt(T)>, where
// P_rt(t) is the covariance of the filter over the measurements that had arrived by t: a
// measurement taken at time_s that the emulated network held back network_delay_s arrives at
// a = time_s + network_delay_s (after T: never). The covariance depends only on which
// measurements and when, so finish() computes it exactly: in arrival order, the set is fixed on
// [a_i, a_i+1) and its covariance at a_i is the filter over that set in timestamp order, re-run
// from the covariance kept after the last measurement before the inserted one (realtimeCost
// below). It takes the steps the hindsight filter takes, so with every delay 0 the two costs are
// the same number; finish() then takes the hindsight cost as it is. The work is one filter step
// per measurement plus one per measurement it overtakes: about N (1 + λ d) steps for N
// measurements at a total rate λ with delays around d.
//
// The real-time cost depends on the emulated network only, so a run reproduces it exactly. What
// the fusion center really had by each instant is `received_realtime_cost`: the same cost with
// each measurement arriving at max(time_s + network_delay_s, received_s), the instant it was
// received on the episode's clock, taken up to the emulated plant's next tick (at most 2.9 µs
// later when T = 3 s; it keeps every step a whole number of ticks long, and such steps repeat).
// It adds the real network's delay (a netem delay, a cut link) and any stall of a process, and
// at high time scales the loopback latency times the scale.
//
// Accounting, per sensor (docs/ARCHITECTURE.md):
//   sent = received + lost + dropped_by_network + refused.
// `sent` is the sensor's own end-of-episode tally; without one, the best lower bound known (its last status,
// the highest seq received + 1), and the episode is incomplete. The emulated network (the
// scenario's `network:`) drops some measurements before they are written and writes some twice:
// the tally says how many. Dropped ones are not lost (the episode can still be complete); of the
// copies refused as "duplicate", up to the tally's duplicated_by_network are counted as
// "network_duplicate" instead: a scripted impairment, not a fault. Rejected samples are counted
// by reason and never fused nor received; a sent one refused on its face (malformed) is also
// `refused` for its sensor, once per seq: accounted for, so the episode is not held open for it,
// but incomplete ("sensor 2: 1 sample refused (malformed)").
//
// Failed sensors (their process died) are never awaited. One that died during the episode
// (sensorFailedAt) leaves it incomplete ("sensor 3 failed at 1.25 s"), with its sent count the
// best lower bound; one that was dead before it (sensorFailedBefore) sends and receives nothing
// and does not make it incomplete (its expected count still shows what the schedule asked).
//
// The bracket in force: with one schedule version over the episode, [J(P_info), J(P_cov)] of
// that version from P0 (Corollary 1 of the first paper). When versions switched during the
// episode, at s = the last switch: the realized ∫<W, P> over [0, s] plus the two surrogates of
// the version in force after s, started from the fused P(s). Conditioned on what happened up to
// s, the schedule from s on is fixed, so Corollary 1 brackets E[J | F_s] and, averaged over
// episodes, E[J].
//
// The delivered bracket: the same, for the schedule the emulated network lets through in this
// episode (deliveredSchedule of network.hpp: rates thinned by loss, zero in the episode's
// outages) instead of the planned one; without a `network:` section it is the bracket.

#include <cstddef>
#include <limits>
#include <Eigen/Core>
#include <cstdint>
#include <functional>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "sensornet/core/cdkf.hpp"
#include "sensornet/core/emulated_plant.hpp"
#include "sensornet/core/scenario.hpp"
#include "sensornet/core/surrogate.hpp"
#include "sensornet/emulator/schedule_book.hpp"
#include "sensornet/emulator/vocabulary.hpp"

namespace sensornet::emulator {

struct FusedMeasurement {
  int sensor = 0;
  std::uint64_t seq = 0;
  double time_s = 0.0;
  std::uint32_t version = 0;  // the schedule version the sensor drew it under
  Eigen::VectorXd z;
  std::int64_t publish_wall_ns = 0;
  std::int64_t receive_wall_ns = 0;
  double network_delay_s = 0.0;  // emulated seconds the emulated network held it back
  // The emulated instant the fusion center received it (its receipt on the episode's clock;
  // 0: not known, taken as time_s + network_delay_s). Differs from time_s + network_delay_s by
  // what the real network and the processes added: real delay, a link cut, a stall.
  double received_s = 0.0;
};

// What a sensor says of one episode at its end (the EpisodeTally topic).
struct EpisodeCount {
  std::uint64_t sent = 0;                   // seq 0 .. sent-1
  std::uint64_t dropped_by_network = 0;     // of those, never written (the emulated network)
  std::uint64_t duplicated_by_network = 0;  // written twice by the emulated network
};

struct SensorTally {
  std::uint64_t sent = 0;           // the sensor's tally, else the best lower bound (see above)
  std::uint64_t received = 0;
  std::uint64_t lost = 0;           // sent - received - dropped_by_network - refused
  std::uint64_t dropped_by_network = 0;     // from the tally
  std::uint64_t duplicated_by_network = 0;  // from the tally
  std::uint64_t duplicates = 0;     // copies of a received seq refused (network's or not)
  double expected = 0.0;            // ∫ λ_j dt under the versions in force
  std::uint64_t late = 0;           // arrived after the filter had passed their time
  std::uint64_t wrong_version = 0;  // drawn under another version than the one in force
  bool tallied = false;             // its end-of-episode tally arrived
  // Sent samples refused on their face (malformed: z of the wrong size or not finite, a time
  // outside [0, T], ...), once per seq however many copies came: accounted for, not lost.
  std::uint64_t refused = 0;
};

// Rejected samples by reason ("malformed", "duplicate", "other_run", "finished_episode", ...).
using RejectionCounts = std::map<std::string, std::uint64_t>;

// The rejection reason of a copy the emulated network made on purpose: counted, never a fault.
inline constexpr const char* kNetworkDuplicate = wordOf(RejectionReason::NetworkDuplicate).data();
// The rejected samples that are faults: every reason but kNetworkDuplicate.
[[nodiscard]] std::uint64_t faultyRejections(const RejectionCounts& rejected);

// Why a sample was refused: a short key for the counts, and one line for the log.
struct Rejection {
  std::string reason;
  std::string detail;
};

struct EpisodeResult {
  std::uint32_t episode = 0;
  double realized_cost = 0.0;           // hindsight: every measurement, in timestamp order
  double realtime_cost = 0.0;           // what had arrived by each instant (see above)
  // What had been received by each instant (see above); NaN when its computation would fuse
  // more than 2 N + 10,000 of the N measurements a second time (an overloaded fusion center).
  double received_realtime_cost = 0.0;
  CostBracket bracket;
  CostBracket delivered_bracket;        // of what the schedule delivers: network, dead sensors
  std::vector<std::uint32_t> versions;  // in force during the episode, in time order
  double switch_time_s = 0.0;           // the last switch (0 when none)
  double nees = 0.0;                    // e(T)' P(T)^{-1} e(T) against the emulated truth
  std::vector<SensorTally> sensors;
  std::vector<double> latencies_s;      // publish to fusion, one per measurement
  std::vector<double> earliest_latency_s;  // per sensor, the smallest of its latencies (+inf: none)
  // The emulated network's delay of the measurements received (emulated seconds; not in the
  // latencies, which start when the sensor writes the delayed measurement).
  double network_delay_mean_s = 0.0;
  double network_delay_max_s = 0.0;
  RejectionCounts rejected;
  bool complete = false;                // every tally in and every sent measurement received
  std::string incomplete_reason;        // why not complete ("sensor 3 failed at 1.25 s; ...")
  std::vector<int> failed_sensors;      // dead during or before the episode
  // Filled in by the fusion center: wall seconds from the later of the episode's end and the
  // last tally's publication until everything owed was in, less its own stalls; the largest
  // number of measurements waiting for its main loop during the episode.
  double drain_s = 0.0;
  std::uint64_t backlog = 0;
};

// Why the fusion refuses `m` on its face ("unknown_sensor" or "malformed": z of the wrong size or
// not finite, time outside [0, T], a network delay that is not a finite number >= 0), or nullopt
// when it is well formed for `scenario`. Counts nothing; EpisodeFusion::add counts what it refuses.
[[nodiscard]] std::optional<Rejection> malformedMeasurement(const Scenario& scenario,
                                                            const FusedMeasurement& m);

// The real-time cost of an episode's measurements (see above) for `scenario`, stepping as
// EpisodeFusion's filter does with its last switch point at switch_time_s (0: none); NaN when
// it would have to fuse more than max_refused measurements a second time (arrivals far out of
// timestamp order).
[[nodiscard]] double realtimeCost(
    const Scenario& scenario, double switch_time_s,
    const std::vector<FusedMeasurement>& measurements,
    std::size_t max_refused = std::numeric_limits<std::size_t>::max());

class EpisodeFusion {
 public:
  using BracketOf = std::function<CostBracket(const ScheduleVersion&)>;

  // The book must hold the version in force at time 0 of `episode`; the references must
  // outlive this object. Versions added to the book later are picked up by scheduleChanged().
  // bracket_of: the bracket of a version over [0, T] from P0 (a caller may cache it);
  // delivered_bracket_of: the same of the version's delivered schedule in this episode, computed
  // here when not given.
  EpisodeFusion(const Scenario& scenario, const EmulatedPlant& plant, const ScheduleBook& book,
                std::uint32_t episode, BracketOf bracket_of, BracketOf delivered_bracket_of = {});

  [[nodiscard]] std::uint32_t episode() const { return episode_; }
  // Call after the book got a version: the stretches of the episode are recomputed. If the
  // filter has already passed the new switch point, finish() re-fuses the episode in order.
  void scheduleChanged();
  // Accepts a measurement (nullopt) or rejects it (and counts it by reason).
  std::optional<Rejection> add(FusedMeasurement m);
  // Counts a sample of this episode refused before it got here.
  void countRejected(const std::string& reason) { ++rejected_[reason]; }
  // The end-of-episode tally of `sensor`: it published `count.sent` measurements (seq
  // 0..sent-1), of which the emulated network dropped and duplicated the given numbers.
  void setTally(int sensor, const EpisodeCount& count);
  // A lower bound of what `sensor` published, from its status (used when no tally comes).
  void noteSentAtLeast(int sensor, std::uint64_t sent);
  // `sensor` died at emulated time at_s of this episode (at_s >= T: after its end, before its
  // tally came); the earliest time given counts.
  void sensorFailedAt(int sensor, double at_s);
  // `sensor` died, last heard at emulated time last_heard_s of this episode: the notice came
  // too late to date the death ("sensor 3 failed after 0.58 s (last heard then)").
  void sensorFellSilentAt(int sensor, double last_heard_s);
  // `sensor` was dead before this episode began.
  void sensorFailedBefore(int sensor);
  [[nodiscard]] bool failed(int sensor) const;
  // Dead since before the episode began (sensorFailedBefore): nothing of it can be this
  // episode's.
  [[nodiscard]] bool failedBefore(int sensor) const;
  // Its tally is in and every measurement it sent was received or dropped by the network, or it
  // failed (a dead sensor is not awaited).
  [[nodiscard]] bool settled(int sensor) const;
  [[nodiscard]] bool allSettled() const;
  [[nodiscard]] std::vector<int> unsettled() const;
  [[nodiscard]] const SensorTally& tally(int sensor) const {
    return tallies_[static_cast<std::size_t>(sensor)];
  }

  // Fuses, in timestamp order, every buffered measurement with time <= t (t <= T); the filter
  // stays at the last measurement fused.
  void fuseUpTo(double t);
  [[nodiscard]] double fusedTime() const { return filter_.time(); }
  [[nodiscard]] const Eigen::MatrixXd& covariance() const { return filter_.covariance(); }
  // Every measurement accepted so far, in arrival order.
  [[nodiscard]] const std::vector<FusedMeasurement>& measurements() const { return all_; }

  // Fuses the rest (all of it again, in order, if any measurement was late), propagates to T.
  [[nodiscard]] EpisodeResult finish();

 private:
  using Key = std::tuple<double, int, std::uint64_t>;  // (time, sensor, seq)
  void fuse(const FusedMeasurement& m);
  void propagateTo(double t);  // stops at the last switch point to record P(s)
  [[nodiscard]] std::string incompleteReason() const;
  // The bracket of `schedule` on what is left after the last switch, plus the realized part.
  [[nodiscard]] CostBracket bracketAfterSwitch(const RateSchedule& schedule) const;
  void refuseBeyondTallies();
  [[nodiscard]] bool anyFailed() const;
  // `schedule` as this episode can deliver it: thinned and cut by the emulated network, and
  // silent from each dead sensor's death (silencedSchedule).
  [[nodiscard]] RateSchedule deliveredScheduleOf(const RateSchedule& schedule) const;
  [[nodiscard]] CostBracket deliveredBracket() const;
  // The real-time cost with each measurement arriving when it was received (see above), given
  // the emulated one (the same number when nothing was received later than it was due).
  [[nodiscard]] double receivedRealtimeCost(double realtime_cost) const;

  const Scenario& scenario_;
  const EmulatedPlant& plant_;
  const ScheduleBook& book_;
  std::uint32_t episode_;
  BracketOf bracket_of_;
  BracketOf delivered_bracket_of_;
  std::vector<ScheduleSegment> segments_;
  double switch_time_s_ = 0.0;
  std::optional<std::pair<double, Eigen::MatrixXd>> at_switch_;  // running cost, P(s)
  CdKalmanFilter filter_;
  std::vector<FusedMeasurement> all_;
  std::vector<bool> arrived_late_;  // per entry of all_: it came after the filter had passed it
  // The sequence numbers of one sensor that arrived: all below `below`, and those in `above`.
  // A sensor's seqs mostly arrive in order, so `above` stays empty and an arrival costs a
  // comparison.
  struct SeenSeqs {
    std::uint64_t below = 0;
    std::set<std::uint64_t> above;
    bool insert(std::uint64_t seq);  // false: it had arrived
    [[nodiscard]] bool has(std::uint64_t seq) const { return seq < below || above.count(seq) > 0; }
  };
  // Indices into all_ not fused yet, as a min-heap on the key (std::greater): fused in
  // timestamp order, and an arrival later than every buffered one (the usual case) costs O(1).
  std::vector<std::pair<Key, std::size_t>> pending_;
  std::vector<SeenSeqs> seen_;  // per sensor
  std::vector<std::set<std::uint64_t>> refused_seqs_;  // per sensor: malformed, not seen since
  std::vector<SensorTally> tallies_;
  std::vector<std::uint64_t> sent_at_least_;  // status and highest seq + 1
  std::vector<std::optional<double>> failed_at_;  // died during the episode, at this time
  std::vector<bool> failed_before_;               // dead before the episode
  std::vector<bool> failed_silent_;  // failed_at_ is when it was last heard, not the notice's
  RejectionCounts rejected_;
  bool replay_ = false;
};

}  // namespace sensornet::emulator
