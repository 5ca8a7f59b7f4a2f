#include "sensornet/core/cdkf.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include "sensornet/core/input_error.hpp"

namespace sensornet {
namespace {

constexpr const char* kSource = "CdKalmanFilter";

// Takes any matrix or vector as it is and names the field only when it throws: reset() calls
// it for every re-fusion, where a temporary copy or string would be a heap allocation each.
template <typename Derived>
void requireShape(const Eigen::EigenBase<Derived>& m, Eigen::Index rows, Eigen::Index cols,
                  const char* field) {
  if (m.rows() != rows || m.cols() != cols) {
    throw InputError(kSource, field,
                     std::to_string(rows) + " x " + std::to_string(cols) + " matrix, got " +
                         std::to_string(m.rows()) + " x " + std::to_string(m.cols()));
  }
}

Eigen::MatrixXd weightOrZero(const Eigen::MatrixXd& W, Eigen::Index n) {
  return W.size() == 0 ? Eigen::MatrixXd::Zero(n, n) : W;
}

}  // namespace

CdKalmanFilter::CdKalmanFilter(const Scenario& scenario, TransitionMethod method)
    : transition_(scenario.plant.A, scenario.plant.Q,
                  weightOrZero(scenario.cost.W, scenario.plant.A.rows()), method),
      sensors_(scenario.sensors),
      steps_(transition_, 1) {
  const Eigen::Index n = scenario.plant.A.rows();
  requireShape(scenario.plant.P0, n, n, "plant.P0");
  initial_covariance_ = scenario.plant.P0;
  if (scenario.plant.m0.size() == 0) {
    initial_mean_ = Eigen::VectorXd::Zero(n);
  } else {
    requireShape(scenario.plant.m0, n, 1, "plant.m0");
    initial_mean_ = scenario.plant.m0;
  }
  if (scenario.cost.WT.size() == 0) {
    terminal_weight_ = Eigen::MatrixXd::Identity(n, n);
  } else {
    requireShape(scenario.cost.WT, n, n, "cost.WT");
    terminal_weight_ = 0.5 * (scenario.cost.WT + scenario.cost.WT.transpose());
  }
  for (std::size_t j = 0; j < sensors_.size(); ++j) {
    const std::string field = "sensors[" + std::to_string(j) + "]";
    const Eigen::Index p = sensors_[j].H.rows();
    if (p < 1) throw InputError(kSource, field + ".H", "at least one row");
    requireShape(sensors_[j].H, p, n, (field + ".H").c_str());
    requireShape(sensors_[j].R, p, p, (field + ".R").c_str());
  }
  Eigen::Index rows = 0;
  for (const SensorModel& sensor : sensors_) rows = std::max(rows, sensor.H.rows());
  update_work_.resize(static_cast<std::size_t>(rows) + 1);
  work_.resize(n, n);
  IKH_.resize(n, n);
  mean_work_.resize(n);
  reset();
}

void CdKalmanFilter::reset() {
  time_ = 0.0;
  mean_ = initial_mean_;
  covariance_ = initial_covariance_;
  running_cost_ = 0.0;
  symmetrizeCovariance();
}

void CdKalmanFilter::reset(double t, const Eigen::VectorXd& mean,
                           const Eigen::MatrixXd& covariance) {
  const Eigen::Index n = stateDim();
  if (!std::isfinite(t)) throw InputError(kSource, "reset.t", "a finite time");
  requireShape(mean, n, 1, "reset.mean");
  requireShape(covariance, n, n, "reset.covariance");
  time_ = t;
  mean_ = mean;
  covariance_ = covariance;
  running_cost_ = 0.0;
  symmetrizeCovariance();
}

void CdKalmanFilter::propagateTo(double t) {
  if (!(t >= time_) || !std::isfinite(t)) {
    throw InputError(
        kSource, "propagateTo.t",
        "a finite time >= time() = " + std::to_string(time_) + ", got " + std::to_string(t));
  }
  if (t == time_) return;
  propagateBy(steps_.over(t - time_), t - time_);
  time_ = t;  // exactly, not time_ + (t - time_)
}

void CdKalmanFilter::propagateBy(const IntervalTransition& step, double dt) {
  const Eigen::Index n = stateDim();
  if (!(dt >= 0.0) || !std::isfinite(dt)) {
    throw InputError(kSource, "propagateBy.dt", "a finite interval length >= 0");
  }
  if (step.Phi.rows() != n || step.Phi.cols() != n || step.Qd.rows() != n ||
      step.cost_gramian.rows() != n) {
    throw InputError(kSource, "propagateBy.step", "a transition of this filter's state size");
  }
  // ∫ <W, Phi(s) P Phi(s)' + Qd(s)> ds = <P, G> + noise_cost, from the interval's start P.
  running_cost_ += covariance_.cwiseProduct(step.cost_gramian).sum() + step.noise_cost;
  mean_work_.noalias() = step.Phi * mean_;
  mean_.swap(mean_work_);
  work_.noalias() = step.Phi * covariance_;
  covariance_.noalias() = work_ * step.Phi.transpose();
  covariance_ += step.Qd;
  symmetrizeCovariance();
  time_ += dt;
}

void CdKalmanFilter::update(int sensor, const Eigen::Ref<const Eigen::VectorXd>& z) {
  const SensorModel& model = sensorModel(sensor);
  if (z.size() != model.H.rows()) {
    throw InputError(kSource, "update.z",
                     std::to_string(model.H.rows()) + " values for sensor " +
                         std::to_string(sensor) + ", got " + std::to_string(z.size()));
  }
  UpdateWork& w = update_work_[static_cast<std::size_t>(model.H.rows())];
  w.innovation = z;
  w.innovation.noalias() -= model.H * mean_;
  applyUpdate(sensor, /*update_mean=*/true);
}

void CdKalmanFilter::updateCovariance(int sensor) { applyUpdate(sensor, /*update_mean=*/false); }

double CdKalmanFilter::terminalCost() const {
  return terminal_weight_.cwiseProduct(covariance_).sum();
}

const SensorModel& CdKalmanFilter::sensorModel(int sensor) const {
  if (sensor < 0 || sensor >= sensorCount()) {
    throw InputError(
        kSource, "sensor",
        "an index in [0, " + std::to_string(sensorCount()) + "), got " + std::to_string(sensor));
  }
  return sensors_[static_cast<std::size_t>(sensor)];
}

// Eq. (4) in Joseph form: P+ = (I - K H) P (I - K H)' + K R K' with K = P H' (H P H' + R)^{-1}.
// Algebraically P - g_j(P); numerically a sum of two PSD products, so rounding cannot push an
// eigenvalue of P+ below zero the way the subtraction in P - g_j(P) can.
void CdKalmanFilter::applyUpdate(int sensor, bool update_mean) {
  const SensorModel& model = sensorModel(sensor);
  const Eigen::MatrixXd& H = model.H;
  const Eigen::MatrixXd& R = model.R;

  UpdateWork& w = update_work_[static_cast<std::size_t>(H.rows())];
  w.PHt.noalias() = covariance_ * H.transpose();
  w.innovation_cov.noalias() = H * w.PHt;
  w.innovation_cov += R;
  w.innovation_llt.compute(w.innovation_cov);
  w.gain_t = w.PHt.transpose();
  w.innovation_llt.solveInPlace(w.gain_t);  // K' = (H P H' + R)^{-1} H P

  IKH_.setIdentity();
  IKH_.noalias() -= w.gain_t.transpose() * H;
  work_.noalias() = IKH_ * covariance_;
  covariance_.noalias() = work_ * IKH_.transpose();
  w.PHt.noalias() = w.gain_t.transpose() * R;
  covariance_.noalias() += w.PHt * w.gain_t;
  symmetrizeCovariance();

  if (update_mean) mean_.noalias() += w.gain_t.transpose() * w.innovation;
}

// The one place the covariance is made exactly symmetric, after every change to it.
void CdKalmanFilter::symmetrizeCovariance() {
  const Eigen::Index n = covariance_.rows();
  for (Eigen::Index j = 0; j < n; ++j) {
    for (Eigen::Index i = 0; i < j; ++i) {
      const double average = 0.5 * (covariance_(i, j) + covariance_(j, i));
      covariance_(i, j) = average;
      covariance_(j, i) = average;
    }
  }
}

}  // namespace sensornet
