#include "sensornet/planning/surrogate_transcription.hpp"

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <system_error>
#include <thread>
#include <utility>
#include <vector>

#include "sensornet/core/input_error.hpp"

namespace sensornet {
namespace {

constexpr const char* kSource = "surrogate transcription";
constexpr double kInfinity = std::numeric_limits<double>::infinity();

using Eigen::Index;
using Eigen::MatrixXd;
using Eigen::VectorXd;

// The one place where symmetry is restored on purpose (products such as X Q X are symmetric in
// exact arithmetic only). Symmetrization is linear and self-adjoint, and every adjoint below is
// symmetric, so the reverse pass needs no counterpart.
void symmetrize(MatrixXd& m) {
  for (Index j = 0; j < m.cols(); ++j) {
    for (Index i = 0; i < j; ++i) {
      const double mean = 0.5 * (m(i, j) + m(j, i));
      m(i, j) = mean;
      m(j, i) = mean;
    }
  }
}

// Measurement rows whitened by the noise: with R_j = L L', H̃_j = L^{-1} H_j, so that
// S_j = H̃_j' H̃_j (eq. 10) and g_j(P) = B' (B H̃_j' + I)^{-1} B with B = H̃_j P (eq. 4).
struct WhitenedRows {
  MatrixXd rows;                  // Σ_j p_j x n, sensor by sensor
  std::vector<Index> first_row;   // M + 1 offsets into rows
  Index sensorCount() const { return static_cast<Index>(first_row.size()) - 1; }
  Index rowCount(Index j) const {
    return first_row[static_cast<std::size_t>(j + 1)] - first_row[static_cast<std::size_t>(j)];
  }
  Index firstRow(Index j) const { return first_row[static_cast<std::size_t>(j)]; }
};

WhitenedRows whitenedRows(const Scenario& scenario) {
  WhitenedRows w;
  Index total = 0;
  w.first_row.push_back(0);
  for (const auto& sensor : scenario.sensors) {
    total += sensor.H.rows();
    w.first_row.push_back(total);
  }
  w.rows.resize(total, scenario.stateDim());
  for (std::size_t j = 0; j < scenario.sensors.size(); ++j) {
    const auto& sensor = scenario.sensors[j];
    const Eigen::LLT<MatrixXd> llt(sensor.R);
    if (llt.info() != Eigen::Success) {
      throw InputError(kSource, "sensors[" + std::to_string(j) + "].R", "positive definite");
    }
    w.rows.middleRows(w.first_row[j], sensor.H.rows()) =
        llt.matrixL().solve(sensor.H);
  }
  return w;
}

// A piece of [start_time, T] on which the rates are constant.
struct Segment {
  double start;
  double end;
  int interval;
};

// TranscriptionOptions::threads = 0: the hardware concurrency, at most 2.
int automaticThreads() {
  return static_cast<int>(std::clamp(std::thread::hardware_concurrency(), 1u, 2u));
}

// Per-row values summed into per-sensor values.
VectorXd sumPerSensor(const WhitenedRows& w, const VectorXd& per_row) {
  VectorXd per_sensor(w.sensorCount());
  for (Index j = 0; j < w.sensorCount(); ++j) {
    per_sensor(j) = per_row.segment(w.firstRow(j), w.rowCount(j)).sum();
  }
  return per_sensor;
}

// Information-form surrogate, eq. (11): f(Y) = -Y A - A' Y - Y Q Y + U, U = Σ_j λ_j S_j, with
// running cost rate <W, Y^{-1}> and terminal cost <W_T, Y^{-1}> (eq. 12).
class InformationDynamics {
 public:
  InformationDynamics(const Scenario& s, WhitenedRows rows)
      : n_(s.stateDim()),
        A_(s.plant.A),
        Q_(s.plant.Q),
        W_(s.cost.W),
        WT_(s.cost.WT),
        q_is_identity_(s.plant.Q.isIdentity(0.0)),
        weighted_(!s.cost.W.isZero(0.0)),
        rows_(std::move(rows)),
        U_(n_, n_),
        xa_(n_, n_),
        xq_(n_, n_),
        inverse_(n_, n_),
        rate_adjoint_(n_, n_),
        // Factored once here so that every member is initialized before the object is moved
        // (a default-constructed LLT leaves its status and norm indeterminate).
        llt_(MatrixXd::Identity(n_, n_)) {}

  [[nodiscard]] bool weighted() const { return weighted_; }

  [[nodiscard]] MatrixXd stateFromCovariance(const MatrixXd& P) const {
    MatrixXd Y = P.llt().solve(MatrixXd::Identity(n_, n_));
    symmetrize(Y);
    return Y;
  }

  // U = Σ_j λ_j S_j over the sensors with a nonzero rate (at large M most rates of a plan are
  // zero, and the others cost p_j n² each).
  void useRates(const Eigen::Ref<const VectorXd>& rates) {
    Index active = 0;
    for (Index j = 0; j < rows_.sensorCount(); ++j) active += rates(j) != 0.0 ? rows_.rowCount(j) : 0;
    active_rows_.resize(active, n_);
    row_rates_.resize(active);
    Index r = 0;
    for (Index j = 0; j < rows_.sensorCount(); ++j) {
      if (rates(j) == 0.0) continue;
      const Index p = rows_.rowCount(j);
      active_rows_.middleRows(r, p) = rows_.rows.middleRows(rows_.firstRow(j), p);
      row_rates_.segment(r, p).setConstant(rates(j));
      r += p;
    }
    scaled_rows_.noalias() = row_rates_.asDiagonal() * active_rows_;
    U_.noalias() = active_rows_.transpose() * scaled_rows_;
    symmetrize(U_);
  }
  // The reverse pass needs no rates: (∂f/∂Y)' does not involve U.
  void useRatesInReverse(const Eigen::Ref<const VectorXd>&) {}

  // F = f(Y); running_rate = <W, Y^{-1}>. False when Y is not positive definite and the running
  // cost needs its inverse.
  bool evaluate(const MatrixXd& Y, MatrixXd& F, double& running_rate) {
    xa_.noalias() = Y * A_;
    F = U_ - xa_ - xa_.transpose();
    if (q_is_identity_) {
      F.noalias() -= Y * Y;
    } else {
      xq_.noalias() = Y * Q_;
      F.noalias() -= xq_ * Y;
    }
    symmetrize(F);
    running_rate = 0.0;
    if (!weighted_) return true;
    if (!invert(Y)) return false;
    running_rate = W_.cwiseProduct(inverse_).sum();
    return true;
  }

  // Ȳ = (∂f/∂Y)' k̄ + weight ∇<W, Y^{-1}>, with
  // (∂f/∂Y)' k̄ = -k̄ A' - A k̄ - k̄ Y Q - Q Y k̄ and ∇<W, Y^{-1}> = -Y^{-1} W Y^{-1};
  // and the rate adjoint: ∂f/∂λ_j = S_j does not depend on Y, so the stage adjoints are summed
  // and paired with S_j once per interval (finishInterval).
  void reverseStage(const MatrixXd& Y, const MatrixXd& kbar, double running_weight,
                    MatrixXd& Ybar) {
    xa_.noalias() = kbar * A_.transpose();
    Ybar = -xa_ - xa_.transpose();
    if (q_is_identity_) {
      xq_.noalias() = kbar * Y;
    } else {
      xa_.noalias() = kbar * Y;
      xq_.noalias() = xa_ * Q_;
    }
    Ybar -= xq_ + xq_.transpose();
    if (weighted_ && running_weight != 0.0 && invert(Y)) {
      xa_.noalias() = inverse_ * W_;
      Ybar.noalias() -= running_weight * (xa_ * inverse_);
    }
    rate_adjoint_ += kbar;
  }

  void beginInterval() { rate_adjoint_.setZero(); }

  // Keeps G = Σ_stages k̄ of the interval in `slot`; rateGradients pairs it with every S_j.
  void finishInterval(std::size_t slot) {
    if (interval_adjoints_.size() <= slot) interval_adjoints_.resize(slot + 1);
    interval_adjoints_[slot] = rate_adjoint_;
  }

  // ∂cost/∂λ_j of every interval: <G_k, S_j> = Σ_rows of j  h̃' G_k h̃, O(Σ_j p_j n²) per
  // interval. The intervals are independent, so they are split over the threads (`threads`
  // as TranscriptionOptions::threads); each interval is computed by the same code whichever
  // thread runs it, so the result does not depend on the thread count.
  void rateGradients(const std::vector<Segment>& segments, int threads, MatrixXd& gradient) const {
    const std::size_t count = segments.size();
    // In blocks of kRowBlock rows, so that neither the product nor Eigen's packing buffers are
    // heap blocks above glibc's mmap threshold, which every program fixes (kMmapThresholdBytes,
    // sensornet/io/command_line.hpp): a block above it is mapped and faulted in afresh per
    // interval and evaluation (the unblocked product of M sensor rows grows past it with M).
    constexpr Index kRowBlock = 128;
    const Index total_rows = rows_.rows.rows();
    const auto work = [&](std::size_t begin, std::size_t end) {
      MatrixXd product(std::min(kRowBlock, total_rows), n_);
      VectorXd per_row(total_rows);
      for (std::size_t slot = begin; slot < end; ++slot) {
        for (Index first = 0; first < total_rows; first += kRowBlock) {
          const Index block_rows = std::min(kRowBlock, total_rows - first);
          const auto block = rows_.rows.middleRows(first, block_rows);
          product.topRows(block_rows).noalias() = block * interval_adjoints_[slot];
          per_row.segment(first, block_rows) =
              (product.topRows(block_rows).array() * block.array()).rowwise().sum();
        }
        gradient.row(segments[slot].interval) = sumPerSensor(rows_, per_row).transpose();
      }
    };
    // Chosen automatically, a second thread is used from about a million multiply-adds.
    const double flops = static_cast<double>(count) * static_cast<double>(rows_.rows.rows()) *
                         static_cast<double>(n_ * n_);
    const std::size_t parts = std::min<std::size_t>(
        count, static_cast<std::size_t>(threads > 0 ? threads : automaticThreads()));
    if (parts < 2 || (threads == 0 && flops < 1e6)) {
      work(0, count);
      return;
    }
    std::vector<std::thread> helpers;
    for (std::size_t part = 1; part < parts; ++part) {
      const std::size_t begin = part * count / parts, end = (part + 1) * count / parts;
      try {
        helpers.emplace_back(work, begin, end);
      } catch (const std::system_error&) {  // no thread to be had: do that part here
        work(begin, end);
      }
    }
    work(0, count / parts);
    for (std::thread& helper : helpers) helper.join();
  }

  // <W_T, Y^{-1}> and its gradient -Y^{-1} W_T Y^{-1}; +inf when Y is not positive definite.
  double terminalCost(const MatrixXd& Y, MatrixXd& gradient) {
    if (!invert(Y)) return kInfinity;
    xa_.noalias() = inverse_ * WT_;
    gradient.noalias() = -(xa_ * inverse_);
    symmetrize(gradient);
    return WT_.cwiseProduct(inverse_).sum();
  }

  bool admissible(const MatrixXd& Y) {
    llt_.compute(Y);
    return llt_.info() == Eigen::Success;
  }

 private:
  bool invert(const MatrixXd& Y) {
    llt_.compute(Y);
    if (llt_.info() != Eigen::Success) return false;
    inverse_.setIdentity();
    llt_.solveInPlace(inverse_);
    symmetrize(inverse_);
    return true;
  }

  Index n_;
  MatrixXd A_;
  MatrixXd Q_;
  MatrixXd W_;
  MatrixXd WT_;
  bool q_is_identity_;
  bool weighted_;
  WhitenedRows rows_;
  MatrixXd active_rows_;  // rows of the sensors with a nonzero rate in the current interval
  VectorXd row_rates_;    // their rates, row by row
  MatrixXd scaled_rows_;
  MatrixXd U_, xa_, xq_, inverse_, rate_adjoint_;
  std::vector<MatrixXd> interval_adjoints_;  // G of every segment, by slot
  Eigen::LLT<MatrixXd> llt_;
};

// Covariance-form surrogate, eq. (15): f(P) = A P + P A' + Q - Σ_j λ_j g_j(P), with running cost
// rate <W, P> and terminal cost <W_T, P>. Single-row sensors are handled together, row-wise;
// sensors with several rows one by one.
class CovarianceDynamics {
 public:
  CovarianceDynamics(const Scenario& s, const WhitenedRows& rows)
      : n_(s.stateDim()),
        A_(s.plant.A),
        Q_(s.plant.Q),
        W_(s.cost.W),
        WT_(s.cost.WT),
        weighted_(!s.cost.W.isZero(0.0)),
        sensor_count_(rows.sensorCount()),
        ap_(n_, n_),
        kpd_(n_, n_),
        D_(n_, n_),
        E_(n_, n_),
        rate_adjoint_(VectorXd::Zero(sensor_count_)) {
    Index scalar_count = 0;
    for (Index j = 0; j < sensor_count_; ++j) scalar_count += rows.rowCount(j) == 1 ? 1 : 0;
    scalar_rows_.resize(scalar_count, n_);
    for (Index j = 0; j < sensor_count_; ++j) {
      if (rows.rowCount(j) == 1) {
        scalar_rows_.row(static_cast<Index>(scalar_sensor_.size())) =
            rows.rows.row(rows.firstRow(j));
        scalar_sensor_.push_back(j);
      } else {
        blocks_.push_back({j, rows.rows.middleRows(rows.firstRow(j), rows.rowCount(j)), 0.0});
      }
    }
    scalar_rate_.resize(scalar_count);
  }

  [[nodiscard]] bool weighted() const { return weighted_; }
  [[nodiscard]] MatrixXd stateFromCovariance(const MatrixXd& P) const { return P; }

  void useRates(const Eigen::Ref<const VectorXd>& rates) {
    Index active = 0;
    for (std::size_t r = 0; r < scalar_sensor_.size(); ++r) {
      scalar_rate_(static_cast<Index>(r)) = rates(scalar_sensor_[r]);
      if (rates(scalar_sensor_[r]) != 0.0) ++active;
    }
    active_rows_.resize(active, n_);
    active_rate_.resize(active);
    Index a = 0;
    for (std::size_t r = 0; r < scalar_sensor_.size(); ++r) {
      const double rate = scalar_rate_(static_cast<Index>(r));
      if (rate == 0.0) continue;
      active_rows_.row(a) = scalar_rows_.row(static_cast<Index>(r));
      active_rate_(a) = rate;
      ++a;
    }
    for (Block& block : blocks_) block.rate = rates(block.sensor);
  }

  // F = f(P); running_rate = <W, P>. Only sensors with a nonzero rate take part. False when an
  // innovation covariance is not positive definite (P far outside the cone).
  bool evaluate(const MatrixXd& P, MatrixXd& F, double& running_rate) {
    ap_.noalias() = A_ * P;
    F = ap_ + ap_.transpose() + Q_;
    if (active_rows_.rows() > 0) {
      hp_.noalias() = active_rows_ * P;
      innovation_ = (hp_.array() * active_rows_.array()).rowwise().sum() + 1.0;
      if (!(innovation_.array() > 0.0).all()) return false;
      weighted_hp_ = hp_.array().colwise() * (active_rate_.array() / innovation_.array());
      F.noalias() -= hp_.transpose() * weighted_hp_;
    }
    for (const Block& block : blocks_) {
      if (block.rate == 0.0) continue;
      const MatrixXd hp = block.rows * P;
      const Eigen::LLT<MatrixXd> llt(hp * block.rows.transpose() +
                                     MatrixXd::Identity(block.rows.rows(), block.rows.rows()));
      if (llt.info() != Eigen::Success) return false;
      F.noalias() -= block.rate * (hp.transpose() * llt.solve(hp));
    }
    symmetrize(F);
    running_rate = weighted_ ? W_.cwiseProduct(P).sum() : 0.0;
    return true;
  }

  // P̄ = (∂f/∂P)' k̄ + weight W, with, for g_j(P) = P H̃' S^{-1} H̃ P (S = H̃ P H̃' + I):
  //   (∂f/∂P)' k̄ = A' k̄ + k̄ A - (k̄ P D + D P k̄) + Σ_j λ_j H̃_j' S_j^{-1} B_j k̄ B_j' S_j^{-1} H̃_j,
  //   D = Σ_j λ_j H̃_j' S_j^{-1} H̃_j, B_j = H̃_j P;
  // and the rate adjoint ∂/∂λ_j <k̄, f> = -<k̄, g_j(P)> = -tr(S_j^{-1} B_j k̄ B_j') for EVERY
  // sensor, active or not: this is the state-dependent control direction of the covariance form.
  void reverseStage(const MatrixXd& P, const MatrixXd& kbar, double running_weight,
                    MatrixXd& Pbar) {
    Pbar.noalias() = A_.transpose() * kbar;
    Pbar += Pbar.transpose().eval();
    D_.setZero();
    E_.setZero();
    if (scalar_rows_.rows() > 0) {
      hp_.noalias() = scalar_rows_ * P;
      innovation_ = (hp_.array() * scalar_rows_.array()).rowwise().sum() + 1.0;
      weighted_hp_.noalias() = hp_ * kbar;
      const Eigen::ArrayXd quadratic = (weighted_hp_.array() * hp_.array()).rowwise().sum();
      const Eigen::ArrayXd gain = scalar_rate_.array() / innovation_.array();
      for (std::size_t r = 0; r < scalar_sensor_.size(); ++r) {
        const Index i = static_cast<Index>(r);
        rate_adjoint_(scalar_sensor_[r]) -= quadratic(i) / innovation_(i);
      }
      weighted_hp_ = scalar_rows_.array().colwise() * gain;
      D_.noalias() += scalar_rows_.transpose() * weighted_hp_;
      weighted_hp_ = scalar_rows_.array().colwise() * (gain * quadratic / innovation_.array());
      E_.noalias() += scalar_rows_.transpose() * weighted_hp_;
    }
    for (const Block& block : blocks_) {
      const MatrixXd hp = block.rows * P;
      const Eigen::LLT<MatrixXd> llt(hp * block.rows.transpose() +
                                     MatrixXd::Identity(block.rows.rows(), block.rows.rows()));
      const MatrixXd v = llt.solve(hp);  // S^{-1} B
      const MatrixXd vk = v * kbar;
      rate_adjoint_(block.sensor) -= (vk.array() * hp.array()).sum();
      if (block.rate == 0.0) continue;
      D_.noalias() += block.rate * (block.rows.transpose() * llt.solve(block.rows));
      E_.noalias() += block.rate * (block.rows.transpose() * (vk * v.transpose()) * block.rows);
    }
    ap_.noalias() = kbar * P;
    kpd_.noalias() = ap_ * D_;
    Pbar -= kpd_ + kpd_.transpose();
    Pbar += E_;
    if (weighted_ && running_weight != 0.0) Pbar += running_weight * W_;
    symmetrize(Pbar);
  }

  void useRatesInReverse(const Eigen::Ref<const VectorXd>& rates) { useRates(rates); }

  void beginInterval() { rate_adjoint_.setZero(); }
  // The covariance form pairs every stage with g_j(P_stage) as it goes (reverseStage): the
  // gradient of an interval is complete here, and is kept in `slot`.
  void finishInterval(std::size_t slot) {
    if (interval_gradients_.size() <= slot) interval_gradients_.resize(slot + 1);
    interval_gradients_[slot] = rate_adjoint_;
  }
  void rateGradients(const std::vector<Segment>& segments, int /*threads*/,
                     MatrixXd& gradient) const {
    for (std::size_t slot = 0; slot < segments.size(); ++slot) {
      gradient.row(segments[slot].interval) = interval_gradients_[slot].transpose();
    }
  }

  double terminalCost(const MatrixXd& P, MatrixXd& gradient) {
    gradient = WT_;
    return WT_.cwiseProduct(P).sum();
  }

  bool admissible(const MatrixXd& P) {
    llt_.compute(P);
    return llt_.info() == Eigen::Success;
  }

 private:
  struct Block {
    Index sensor;
    MatrixXd rows;  // whitened p_j x n
    double rate;
  };

  Index n_;
  MatrixXd A_;
  MatrixXd Q_;
  MatrixXd W_;
  MatrixXd WT_;
  bool weighted_;
  Index sensor_count_;
  MatrixXd scalar_rows_;
  std::vector<Index> scalar_sensor_;
  VectorXd scalar_rate_;
  MatrixXd active_rows_;
  VectorXd active_rate_;
  std::vector<Block> blocks_;
  MatrixXd ap_, kpd_, D_, E_;
  MatrixXd hp_, weighted_hp_;
  Eigen::ArrayXd innovation_;
  VectorXd rate_adjoint_;
  std::vector<VectorXd> interval_gradients_;  // by slot
  Eigen::LLT<MatrixXd> llt_;
};

// The pieces of [start_time, T] on which the rates are constant, as in the accurate rollout.
std::vector<Segment> segmentsFrom(const Scenario& scenario, double start_time) {
  const int count = scenario.intervals;
  const double horizon = scenario.horizon_s;
  const double h = scenario.intervalLength();
  auto boundary = [&](int k) { return k >= count ? horizon : k * h; };
  std::vector<Segment> segments;
  if (!(start_time < horizon)) return segments;
  int k = std::min(count - 1, static_cast<int>(std::floor(start_time / h)));
  while (k + 1 < count && boundary(k + 1) - start_time <= 1e-12 * horizon) ++k;
  segments.push_back({start_time, boundary(k + 1), k});
  for (int i = k + 1; i < count; ++i) segments.push_back({boundary(i), boundary(i + 1), i});
  return segments;
}

Eigen::MatrixXd checkedStartCovariance(const Scenario& scenario,
                                       const TranscriptionOptions& options) {
  if (options.substeps < 1) {
    throw InputError(kSource, "substeps", "an integer >= 1, got " +
                                              std::to_string(options.substeps));
  }
  if (options.threads < 0) {
    throw InputError(kSource, "threads", "an integer >= 0, got " +
                                             std::to_string(options.threads));
  }
  if (!std::isfinite(options.start_time) || options.start_time < 0.0 ||
      options.start_time > scenario.horizon_s) {
    throw InputError(kSource, "start_time",
                     "a time in [0, " + std::to_string(scenario.horizon_s) + "], got " +
                         std::to_string(options.start_time));
  }
  if (!options.start_covariance) {
    if (options.start_time > 0.0) {
      throw InputError(kSource, "start_covariance",
                       "the covariance at start_time when start_time > 0");
    }
    return scenario.plant.P0;
  }
  const MatrixXd& P = *options.start_covariance;
  const Index n = scenario.stateDim();
  if (P.rows() != n || P.cols() != n || !P.allFinite()) {
    throw InputError(kSource, "start_covariance",
                     "a finite " + std::to_string(n) + " x " + std::to_string(n) + " matrix");
  }
  const double scale = std::max(P.cwiseAbs().maxCoeff(), std::numeric_limits<double>::min());
  if ((P - P.transpose()).cwiseAbs().maxCoeff() > 1e-9 * scale) {
    throw InputError(kSource, "start_covariance", "a symmetric matrix");
  }
  MatrixXd start = 0.5 * (P + P.transpose());
  if (Eigen::LLT<MatrixXd>(start).info() != Eigen::Success) {
    throw InputError(kSource, "start_covariance", "a positive definite matrix");
  }
  return start;
}

// Single shooting with classical RK4, shared by both forms. One step of length h from X:
//   X1 = X, X2 = X + h/2 K1, X3 = X + h/2 K2, X4 = X + h K3, K_s = f(X_s),
//   X' = X + h/6 (K1 + 2 K2 + 2 K3 + K4),  c' = c + h/6 (w1 + 2 w2 + 2 w3 + w4),
// and its exact reverse: with X̄' the adjoint of X',
//   k̄4 = h/6 X̄',         X̄4 = pullback(X4, k̄4) + h/6 ∇w(X4)
//   k̄3 = h/3 X̄' + h X̄4,  X̄3 = pullback(X3, k̄3) + h/3 ∇w(X3)
//   k̄2 = h/3 X̄' + h/2 X̄3, ...,  k̄1 = h/6 X̄' + h/2 X̄2, ...
//   X̄ = X̄' + X̄1 + X̄2 + X̄3 + X̄4,   λ̄ += Σ_s (∂f/∂λ)(X_s)' k̄_s.
template <typename Dynamics>
class Shooting {
 public:
  // The dynamics are built in place from `dynamics_arguments` (they hold factorizations that
  // are not meant to be moved).
  template <typename... Arguments>
  Shooting(const Scenario& scenario, const TranscriptionOptions& options,
           Arguments&&... dynamics_arguments)
      : dynamics_(std::forward<Arguments>(dynamics_arguments)...),
        n_(scenario.stateDim()),
        intervals_(scenario.intervals),
        sensors_(scenario.sensorCount()),
        substeps_(options.substeps),
        threads_(options.threads),
        segments_(segmentsFrom(scenario, options.start_time)),
        start_(dynamics_.stateFromCovariance(checkedStartCovariance(scenario, options))),
        stages_(4 * segments_.size() * static_cast<std::size_t>(substeps_),
                MatrixXd(n_, n_)),
        slopes_(4, MatrixXd(n_, n_)),
        adjoints_(4, MatrixXd(n_, n_)),
        x_(n_, n_),
        xbar_(n_, n_),
        kbar_(n_, n_) {}

  [[nodiscard]] int firstInterval() const {
    return segments_.empty() ? intervals_ : segments_.front().interval;
  }

  double forward(const Eigen::Ref<const MatrixXd>& rates) {
    checkRates(rates);
    x_ = start_;
    double running = 0.0;
    std::size_t stage = 0;
    for (const Segment& segment : segments_) {
      dynamics_.useRates(rates.row(segment.interval).transpose());
      const double h = (segment.end - segment.start) / substeps_;
      for (int step = 0; step < substeps_; ++step, stage += 4) {
        double w[4];
        for (int s = 0; s < 4; ++s) {
          MatrixXd& xs = stages_[stage + static_cast<std::size_t>(s)];
          if (s == 0) {
            xs = x_;
          } else {
            xs = x_ + kNodes[s] * h * slopes_[static_cast<std::size_t>(s - 1)];
          }
          if (!dynamics_.evaluate(xs, slopes_[static_cast<std::size_t>(s)], w[s])) {
            return kInfinity;
          }
        }
        x_ += (h / 6.0) * (slopes_[0] + 2.0 * slopes_[1] + 2.0 * slopes_[2] + slopes_[3]);
        running += (h / 6.0) * (w[0] + 2.0 * w[1] + 2.0 * w[2] + w[3]);
      }
      if (!dynamics_.admissible(x_)) return kInfinity;
    }
    const double cost = running + dynamics_.terminalCost(x_, xbar_);
    return std::isfinite(cost) ? cost : kInfinity;
  }

  CostGradient costAndGradient(const Eigen::Ref<const MatrixXd>& rates) {
    CostGradient result;
    result.gradient = MatrixXd::Zero(intervals_, sensors_);
    result.cost = forward(rates);
    if (!std::isfinite(result.cost)) return result;
    // xbar_ holds the terminal gradient.
    std::size_t stage = stages_.size();
    for (std::size_t slot = segments_.size(); slot-- > 0;) {
      const Segment& segment = segments_[slot];
      dynamics_.useRatesInReverse(rates.row(segment.interval).transpose());
      dynamics_.beginInterval();
      const double h = (segment.end - segment.start) / substeps_;
      for (int step = 0; step < substeps_; ++step) {
        stage -= 4;
        reverseStep(stage, h);
      }
      dynamics_.finishInterval(slot);
    }
    dynamics_.rateGradients(segments_, threads_, result.gradient);
    return result;
  }

 private:
  static constexpr double kNodes[4] = {0.0, 0.5, 0.5, 1.0};
  static constexpr double kWeights[4] = {1.0 / 6.0, 1.0 / 3.0, 1.0 / 3.0, 1.0 / 6.0};

  void reverseStep(std::size_t stage, double h) {
    const double running_scale = dynamics_.weighted() ? h : 0.0;
    for (int s = 3; s >= 0; --s) {
      const auto i = static_cast<std::size_t>(s);
      kbar_ = (kWeights[s] * h) * xbar_;
      if (s < 3) kbar_ += (kNodes[s + 1] * h) * adjoints_[i + 1];
      dynamics_.reverseStage(stages_[stage + i], kbar_, running_scale * kWeights[s],
                             adjoints_[i]);
    }
    xbar_ += adjoints_[0] + adjoints_[1] + adjoints_[2] + adjoints_[3];
  }

  void checkRates(const Eigen::Ref<const MatrixXd>& rates) const {
    if (rates.rows() != intervals_ || rates.cols() != sensors_) {
      throw InputError(kSource, "rates",
                       "an " + std::to_string(intervals_) + " x " + std::to_string(sensors_) +
                           " matrix, got " + std::to_string(rates.rows()) + " x " +
                           std::to_string(rates.cols()));
    }
    if (!rates.bottomRows(intervals_ - firstInterval()).allFinite()) {
      throw InputError(kSource, "rates", "finite numbers");
    }
  }

  Dynamics dynamics_;
  Index n_;
  int intervals_;
  int sensors_;
  int substeps_;
  int threads_;
  std::vector<Segment> segments_;
  MatrixXd start_;
  std::vector<MatrixXd> stages_;    // X1..X4 of every step, for the reverse pass
  std::vector<MatrixXd> slopes_;    // K1..K4 of the current step
  std::vector<MatrixXd> adjoints_;  // X̄1..X̄4 of the current step
  MatrixXd x_, xbar_, kbar_;
};

}  // namespace

struct SurrogateTranscription::Impl {
  SurrogateForm form;
  std::optional<Shooting<InformationDynamics>> information;
  std::optional<Shooting<CovarianceDynamics>> covariance;
  std::optional<MatrixXd> delivery;
};

namespace {

std::optional<MatrixXd> checkedDelivery(const Scenario& scenario,
                                        const TranscriptionOptions& options) {
  if (!options.delivery) return std::nullopt;
  const MatrixXd& delivery = *options.delivery;
  if (delivery.rows() != scenario.intervals || delivery.cols() != scenario.sensorCount()) {
    throw InputError(kSource, "delivery",
                     "an " + std::to_string(scenario.intervals) + " x " +
                         std::to_string(scenario.sensorCount()) + " matrix, got " +
                         std::to_string(delivery.rows()) + " x " +
                         std::to_string(delivery.cols()));
  }
  if (!delivery.allFinite() || (delivery.array() < 0.0).any() || (delivery.array() > 1.0).any()) {
    throw InputError(kSource, "delivery", "factors in [0, 1]");
  }
  return delivery;
}

}  // namespace

SurrogateTranscription::SurrogateTranscription(SurrogateForm form, const Scenario& scenario,
                                               const TranscriptionOptions& options)
    : impl_(std::make_unique<Impl>()) {
  impl_->form = form;
  impl_->delivery = checkedDelivery(scenario, options);
  WhitenedRows rows = whitenedRows(scenario);
  if (form == SurrogateForm::Information) {
    impl_->information.emplace(scenario, options, scenario, std::move(rows));
  } else {
    impl_->covariance.emplace(scenario, options, scenario, rows);
  }
}

SurrogateTranscription::~SurrogateTranscription() = default;
SurrogateTranscription::SurrogateTranscription(SurrogateTranscription&&) noexcept = default;
SurrogateTranscription& SurrogateTranscription::operator=(SurrogateTranscription&&) noexcept =
    default;

SurrogateForm SurrogateTranscription::form() const { return impl_->form; }

int SurrogateTranscription::firstInterval() const {
  return impl_->information ? impl_->information->firstInterval()
                            : impl_->covariance->firstInterval();
}

double SurrogateTranscription::cost(const Eigen::Ref<const Eigen::MatrixXd>& rates) {
  if (impl_->delivery && rates.rows() == impl_->delivery->rows() &&
      rates.cols() == impl_->delivery->cols()) {
    const MatrixXd delivered = rates.cwiseProduct(*impl_->delivery);
    return impl_->information ? impl_->information->forward(delivered)
                              : impl_->covariance->forward(delivered);
  }
  return impl_->information ? impl_->information->forward(rates)
                            : impl_->covariance->forward(rates);
}

CostGradient SurrogateTranscription::costAndGradient(
    const Eigen::Ref<const Eigen::MatrixXd>& rates) {
  if (impl_->delivery && rates.rows() == impl_->delivery->rows() &&
      rates.cols() == impl_->delivery->cols()) {
    // μ = D ⊙ λ, so ∂cost/∂λ = D ⊙ ∂cost/∂μ.
    const MatrixXd delivered = rates.cwiseProduct(*impl_->delivery);
    CostGradient cg = impl_->information ? impl_->information->costAndGradient(delivered)
                                         : impl_->covariance->costAndGradient(delivered);
    cg.gradient = cg.gradient.cwiseProduct(*impl_->delivery);
    return cg;
  }
  return impl_->information ? impl_->information->costAndGradient(rates)
                            : impl_->covariance->costAndGradient(rates);
}

}  // namespace sensornet
