#pragma once
// The emulated plant of a run: one ground truth x(t) of dx = A x dt + dw (E[dw dw'] = Q dt,
// x(0) ~ N(m0, P0)) per episode that every process computes for itself and gets bit for bit
// the same, from the run seed and the episode number alone (docs/ARCHITECTURE.md, "Numerical
// ground rules"). Sensors sample it at their arrival instants; the fusion center at T for the NEES.
//
//   const EmulatedPlant plant(scenario, seed);
//   const std::int64_t tick = plant.tickAt(1.234);             // arrival instants fall on ticks
//   Eigen::VectorXd x = plant.stateAt(episode, tick);
//   EmulatedPlant::Path path;                                  // for many ticks of one episode
//   for (std::int64_t t : sorted_ticks) use(plant.stateAt(episode, t, path));
//   Eigen::VectorXd z = plant.measure(x, sensor, episode, seq);  // H_j x + v_j, v_j ~ N(0, R_j)
//
// Construction (Lévy's bridge, exact for a linear SDE): the horizon is cut into 2^L ticks.
// x(0) and x(T) are drawn first (x(T) = Φ(T) x(0) + N(0, Qd(T))); then, level by level, the
// midpoint c of every dyadic block [a, b] of half-length h is drawn from its exact law given
// the two ends: with Φ = Φ(h), Qh = Qd(h),
//   x(c) | x(a), x(b) ~ N(Φ x(a) + K (x(b) - Φ Φ x(a)),  Qh - K Φ Qh),
//   K = Qh Φ' (Φ Qh Φ' + Qh)^+,
// whose matrices depend only on the level. The normal deviates of each block come from a
// stream keyed by (seed, episode, level, block), so any tick costs L small matrix-vector
// products and never depends on which other ticks were asked for. The joint law of the states
// at any set of ticks is exactly that of the SDE.
//
// A Path remembers the blocks the last descent went through: the next tick of the same episode
// starts from the smallest of them that holds it, and nearby ticks share all but the last few
// levels (at 100,000 arrivals per 3 s episode, about 3 of 20). Every state is computed the same
// way whichever descent reaches it, so the values do not depend on the Path: bit for bit those
// of a descent from the top.

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "sensornet/core/scenario.hpp"

namespace sensornet {

inline constexpr std::uint64_t kPlantTruthStream = 0x706c2d7472757468ULL;   // "pl-truth"
inline constexpr std::uint64_t kSensorNoiseStream = 0x736e2d6e6f697365ULL;  // "sn-noise"

class EmulatedPlant {
 public:
  // 2^20 ticks: 2.9 µs for T = 3 s. Throws InputError for tick_levels outside [1, 40].
  static constexpr int kDefaultTickLevels = 20;

  EmulatedPlant(const Scenario& scenario, std::uint64_t seed,
                int tick_levels = kDefaultTickLevels);

  [[nodiscard]] std::int64_t tickCount() const { return std::int64_t{1} << levels_; }
  [[nodiscard]] double tickSeconds() const { return horizon_s_ / static_cast<double>(tickCount()); }
  // The last tick at or before t, clamped to [0, tickCount()] (so an arrival drawn before a
  // schedule switch that falls on a tick stays before it).
  [[nodiscard]] std::int64_t tickAt(double t) const;
  [[nodiscard]] double timeOf(std::int64_t tick) const {
    return static_cast<double>(tick) * tickSeconds();
  }

  // What a descent went through, for the next one to start from (see above). Belongs to one
  // caller: using it is not thread-safe, and it may go from one plant or episode to another
  // (it then starts from the top).
  class Path {
   private:
    friend class EmulatedPlant;
    struct Block {  // [a, b] at one depth, with x(a) and x(b)
      std::int64_t a = 0;
      std::int64_t b = 0;
      Eigen::VectorXd left;
      Eigen::VectorXd right;
    };
    const EmulatedPlant* plant_ = nullptr;
    std::uint32_t episode_ = 0;
    // blocks_[d], d < depth_: the block of depth d the last tick fell in; those beyond are kept
    // with their vectors, so that a descent allocates nothing.
    std::vector<Block> blocks_;
    std::size_t depth_ = 0;
    Eigen::VectorXd xi_, from_left_, from_right_, noise_;  // one level's terms
  };

  // x at `tick` (0 <= tick <= tickCount()) of `episode`.
  [[nodiscard]] Eigen::VectorXd stateAt(std::uint32_t episode, std::int64_t tick) const;
  // The same value, from where `path` parts from the last descent it went through; the
  // reference is into `path`, valid until its next use.
  [[nodiscard]] const Eigen::VectorXd& stateAt(std::uint32_t episode, std::int64_t tick,
                                               Path& path) const;

  // z = H_j x + v_j with v_j ~ N(0, R_j) keyed by (seed, episode, sensor, seq).
  [[nodiscard]] Eigen::VectorXd measure(const Eigen::VectorXd& x, int sensor,
                                        std::uint32_t episode, std::uint64_t seq) const;

 private:
  struct Level {  // the bridge of a block of half-length h = T / 2^level
    Eigen::MatrixXd from_left;   // Φ - K Φ Φ: multiplies x(a)
    Eigen::MatrixXd from_right;  // K: multiplies x(b)
    Eigen::MatrixXd noise;       // a square root of Qh - K Φ Qh
  };

  std::uint64_t seed_;
  int levels_;
  double horizon_s_;
  Eigen::VectorXd m0_;
  Eigen::MatrixXd p0_root_;     // P0 = L L'
  Eigen::MatrixXd phi_horizon_;  // Φ(T)
  Eigen::MatrixXd qd_root_;      // a square root of Qd(T)
  std::vector<Level> bridge_;    // bridge_[d - 1] for depth d = 1..L
  std::vector<Eigen::MatrixXd> sensor_h_;
  std::vector<Eigen::MatrixXd> sensor_noise_root_;  // R_j = L L'
};

}  // namespace sensornet
