#include "sensornet/core/emulated_plant.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/QR>
#include <algorithm>
#include <cmath>
#include <string>

#include "sensornet/core/input_error.hpp"
#include "sensornet/core/random.hpp"
#include "sensornet/core/transition.hpp"

namespace sensornet {
namespace {

using Eigen::MatrixXd;
using Eigen::VectorXd;

constexpr const char* kSource = "emulated plant";

// A square root S S' = X of a symmetric positive semi-definite X (eigenvalues that rounding
// made slightly negative count as zero).
MatrixXd semidefiniteRoot(const MatrixXd& X) {
  const Eigen::SelfAdjointEigenSolver<MatrixXd> solver(0.5 * (X + X.transpose()));
  const VectorXd roots = solver.eigenvalues().cwiseMax(0.0).cwiseSqrt();
  return solver.eigenvectors() * roots.asDiagonal();
}

// xi (resized to count) filled with standard normal deviates of rng, in order.
void fillNormals(Rng& rng, Eigen::Index count, VectorXd& xi) {
  xi.resize(count);
  for (Eigen::Index i = 0; i < count; ++i) xi(i) = rng.normal();
}

VectorXd normals(Rng& rng, Eigen::Index count) {
  VectorXd xi;
  fillNormals(rng, count, xi);
  return xi;
}

}  // namespace

EmulatedPlant::EmulatedPlant(const Scenario& scenario, std::uint64_t seed, int tick_levels)
    : seed_(seed), levels_(tick_levels), horizon_s_(scenario.horizon_s) {
  if (tick_levels < 1 || tick_levels > 40) {
    throw InputError(kSource, "tick_levels", "an integer in [1, 40], got " +
                                                 std::to_string(tick_levels));
  }
  const Plant& plant = scenario.plant;
  const Eigen::Index n = plant.A.rows();
  m0_ = plant.m0.size() == n ? plant.m0 : VectorXd::Zero(n);
  const Eigen::LLT<MatrixXd> p0(plant.P0);
  p0_root_ = p0.info() == Eigen::Success ? MatrixXd(p0.matrixL()) : semidefiniteRoot(plant.P0);

  const LtiTransition transition(plant.A, plant.Q, MatrixXd::Zero(n, n));
  const IntervalTransition whole = transition.over(horizon_s_);
  phi_horizon_ = whole.Phi;
  qd_root_ = semidefiniteRoot(whole.Qd);

  for (int depth = 1; depth <= levels_; ++depth) {
    const double half = horizon_s_ / std::ldexp(1.0, depth);
    const IntervalTransition step = transition.over(half);
    const MatrixXd& Phi = step.Phi;
    const MatrixXd& Qh = step.Qd;
    const MatrixXd S = Phi * Qh * Phi.transpose() + Qh;  // Cov(x(b) | x(a))
    const MatrixXd K = Qh * Phi.transpose() * S.completeOrthogonalDecomposition().pseudoInverse();
    Level level;
    level.from_left = Phi - K * Phi * Phi;
    level.from_right = K;
    level.noise = semidefiniteRoot(Qh - K * Phi * Qh);
    bridge_.push_back(std::move(level));
  }

  for (const SensorModel& sensor : scenario.sensors) {
    sensor_h_.push_back(sensor.H);
    const Eigen::LLT<MatrixXd> r(sensor.R);
    sensor_noise_root_.push_back(r.info() == Eigen::Success ? MatrixXd(r.matrixL())
                                                            : semidefiniteRoot(sensor.R));
  }
}

std::int64_t EmulatedPlant::tickAt(double t) const {
  if (!(t > 0.0)) return 0;
  const double ticks = std::floor(t / tickSeconds());
  return std::min(static_cast<std::int64_t>(std::min(ticks, 9.0e18)), tickCount());
}

Eigen::VectorXd EmulatedPlant::stateAt(std::uint32_t episode, std::int64_t tick) const {
  Path path;
  return stateAt(episode, tick, path);
}

const Eigen::VectorXd& EmulatedPlant::stateAt(std::uint32_t episode, std::int64_t tick,
                                              Path& path) const {
  if (tick < 0 || tick > tickCount()) {
    throw InputError(kSource, "tick",
                     "an integer in [0, " + std::to_string(tickCount()) + "], got " +
                         std::to_string(tick));
  }
  std::vector<Path::Block>& blocks = path.blocks_;
  if (path.plant_ != this || path.episode_ != episode || path.depth_ == 0) {
    const Eigen::Index n = m0_.size();
    Rng start = Rng::keyed(seed_, kPlantTruthStream, episode, 0, 0);
    VectorXd left = m0_ + p0_root_ * normals(start, n);
    Rng end = Rng::keyed(seed_, kPlantTruthStream, episode, 0, 1);
    VectorXd right = phi_horizon_ * left + qd_root_ * normals(end, n);
    blocks.resize(static_cast<std::size_t>(levels_) + 1);
    blocks[0] = Path::Block{0, tickCount(), std::move(left), std::move(right)};
    path.depth_ = 1;
    path.plant_ = this;
    path.episode_ = episode;
  }
  // The smallest block of the last descent that holds `tick` (the whole horizon always does).
  std::size_t depth = path.depth_ - 1;
  while (tick < blocks[depth].a || tick > blocks[depth].b) --depth;
  path.depth_ = depth + 1;
  while (tick != blocks[path.depth_ - 1].a && tick != blocks[path.depth_ - 1].b) {
    const Path::Block& outer = blocks[path.depth_ - 1];
    Path::Block& inner = blocks[path.depth_];
    const std::int64_t a = outer.a;
    const std::int64_t b = outer.b;
    const std::int64_t c = a + (b - a) / 2;
    const int inner_depth = static_cast<int>(path.depth_);
    const std::int64_t block = a >> (levels_ - inner_depth + 1);  // index of [a, b]
    const Level& level = bridge_[static_cast<std::size_t>(inner_depth - 1)];
    Rng rng = Rng::keyed(seed_, kPlantTruthStream, episode, inner_depth, block);
    // from_left x(a) + from_right x(b) + noise xi, each product evaluated on its own and then
    // summed left to right, as Eigen evaluates the one expression of these three products.
    fillNormals(rng, m0_.size(), path.xi_);
    path.from_left_.noalias() = level.from_left * outer.left;
    path.from_right_.noalias() = level.from_right * outer.right;
    path.noise_.noalias() = level.noise * path.xi_;
    Eigen::VectorXd& middle = tick < c ? inner.right : inner.left;
    middle = path.from_left_ + path.from_right_ + path.noise_;
    if (tick < c) {
      inner.a = a;
      inner.b = c;
      inner.left = outer.left;
    } else {
      inner.a = c;
      inner.b = b;
      inner.right = outer.right;
    }
    ++path.depth_;
  }
  const Path::Block& last = blocks[path.depth_ - 1];
  return tick == last.a ? last.left : last.right;
}

Eigen::VectorXd EmulatedPlant::measure(const Eigen::VectorXd& x, int sensor, std::uint32_t episode,
                                       std::uint64_t seq) const {
  if (sensor < 0 || sensor >= static_cast<int>(sensor_h_.size())) {
    throw InputError(kSource, "sensor",
                     "an index in [0, " + std::to_string(sensor_h_.size()) + "), got " +
                         std::to_string(sensor));
  }
  const auto j = static_cast<std::size_t>(sensor);
  Rng rng = Rng::keyed(seed_, kSensorNoiseStream, episode, sensor, seq);
  return sensor_h_[j] * x + sensor_noise_root_[j] * normals(rng, sensor_h_[j].rows());
}

}  // namespace sensornet
