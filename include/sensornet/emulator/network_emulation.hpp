#pragma once
// What the emulated network (the scenario's `network:`, network.hpp) does to one measurement on
// its way from a sensor to the fusion center: drop it (by the link's loss, or because an outage
// of that episode covers its emulated time), hold it back by a delay (fixed + jitter), or deliver
// it twice. Each decision is drawn from its own stream keyed by (run seed, sensor, episode, seq),
// so it depends on nothing else: the same seed gives the same decisions whatever the process
// layout, the order of the calls or the timing. No DDS here; the sensor agent applies it.
//
//   const NetworkDecision d = decideDelivery(*scenario.network, seed, sensor, episode, seq, t);
//   if (d.dropped()) ++tally.dropped_by_network;            // never written
//   else line.hold(clock.wallAt(t + d.delay_s), {sensor, seq, t, version, z, d.delay_s},
//                  d.duplicated ? 2 : 1);
//
// DelayLine holds the measurements of one episode that the network delays: each waits until its
// wall time and then goes out, earliest first (in the order they were held among equal times);
// a duplicated one goes out twice.
//
//   for (const HeldMeasurement& m : line.takeDue(wallNowNs())) write(m);
//   const auto wake = line.nextDueWallNs();   // the wait loop wakes for it

#include <Eigen/Core>
#include <cstdint>
#include <optional>
#include <queue>
#include <vector>

#include "sensornet/core/network_spec.hpp"

namespace sensornet::emulator {

inline constexpr std::uint64_t kNetworkStream = 0x6e742d6c696e6b73ULL;  // "nt-links"

enum class DropCause { None, Loss, Outage };

struct NetworkDecision {
  DropCause drop = DropCause::None;
  double delay_s = 0.0;     // emulated seconds it is held back (0 when dropped)
  bool duplicated = false;  // delivered twice (never when dropped)
  [[nodiscard]] bool dropped() const { return drop != DropCause::None; }
};

// The fate of measurement `seq` of `sensor` in `episode`, drawn at emulated time
// `emulated_time_s`. A sensor without a link in `network` (or an empty spec) has a perfect one.
[[nodiscard]] NetworkDecision decideDelivery(const NetworkSpec& network, std::uint64_t seed,
                                             int sensor, std::uint32_t episode, std::uint64_t seq,
                                             double emulated_time_s);

// Whether `network` can change anything at all (a link that is not perfect, or an outage).
[[nodiscard]] bool impairs(const NetworkSpec& network);

// A measurement the network holds back, with what its write needs.
struct HeldMeasurement {
  int sensor = 0;
  std::uint64_t seq = 0;
  double time_s = 0.0;  // emulated instant of the measurement
  std::uint32_t version = 0;
  Eigen::VectorXd z;
  double delay_s = 0.0;  // emulated seconds the network held it back
};

// The delayed measurements of one episode, by the wall time they are due (see the top).
class DelayLine {
 public:
  // Holds `copies` writes of `measurement` until `due_wall_ns`.
  void hold(std::int64_t due_wall_ns, HeldMeasurement measurement, int copies);
  // Every write due at or before `wall_ns`, earliest first; they leave the line.
  [[nodiscard]] std::vector<HeldMeasurement> takeDue(std::int64_t wall_ns);
  // Everything still held, earliest first (an episode that ends early flushes it).
  [[nodiscard]] std::vector<HeldMeasurement> takeAll();
  [[nodiscard]] std::optional<std::int64_t> nextDueWallNs() const;
  [[nodiscard]] bool empty() const { return queue_.empty(); }
  [[nodiscard]] std::size_t size() const { return queue_.size(); }

 private:
  struct Entry {
    std::int64_t due_wall_ns = 0;
    std::uint64_t order = 0;
    HeldMeasurement measurement;
  };
  struct LaterFirst {
    bool operator()(const Entry& a, const Entry& b) const {
      return a.due_wall_ns != b.due_wall_ns ? a.due_wall_ns > b.due_wall_ns : a.order > b.order;
    }
  };
  std::priority_queue<Entry, std::vector<Entry>, LaterFirst> queue_;
  std::uint64_t next_order_ = 0;
};

}  // namespace sensornet::emulator
