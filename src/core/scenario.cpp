#include "sensornet/core/scenario.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/QR>
#include <cmath>
#include <limits>
#include <sstream>

#include "sensornet/core/input_error.hpp"
#include "sensornet/core/random.hpp"

namespace sensornet {
namespace {

std::string shapeOf(const Eigen::MatrixXd& m) {
  return std::to_string(m.rows()) + " x " + std::to_string(m.cols());
}

// Validates one matrix field; each check throws InputError naming `field`.
class MatrixCheck {
 public:
  MatrixCheck(const std::string& source, std::string field, const Eigen::MatrixXd& m)
      : source_(source), field_(std::move(field)), m_(m) {}

  const MatrixCheck& shape(Eigen::Index rows, Eigen::Index cols) const {
    if (m_.rows() != rows || m_.cols() != cols) {
      fail(std::to_string(rows) + " x " + std::to_string(cols) + " matrix, got " + shapeOf(m_));
    }
    return *this;
  }
  const MatrixCheck& finite() const {
    if (!m_.allFinite()) fail("finite numbers, got NaN or infinity");
    return *this;
  }
  const MatrixCheck& symmetric() const {
    const double scale = std::max(1.0, m_.cwiseAbs().maxCoeff());
    const double asym = (m_ - m_.transpose()).cwiseAbs().maxCoeff();
    if (asym > 1e-9 * scale) {
      std::ostringstream what;
      what << "a symmetric matrix, got max |X - X'| = " << asym;
      fail(what.str());
    }
    return *this;
  }
  // Positive semidefinite (strict = false) or positive definite (strict = true).
  const MatrixCheck& definite(bool strict) const {
    const Eigen::MatrixXd sym = 0.5 * (m_ + m_.transpose());
    const double smallest = Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(
                                sym, Eigen::EigenvaluesOnly)
                                .eigenvalues()
                                .minCoeff();
    const double scale = std::max(1.0, sym.cwiseAbs().maxCoeff());
    const bool ok = strict ? smallest > 1e-12 * scale : smallest >= -1e-12 * scale;
    if (!ok) {
      std::ostringstream what;
      what << (strict ? "positive definite" : "positive semidefinite")
           << " matrix, got smallest eigenvalue " << smallest;
      fail(what.str());
    }
    return *this;
  }

 private:
  [[noreturn]] void fail(const std::string& expected) const {
    throw InputError(source_, field_, expected);
  }
  const std::string& source_;
  std::string field_;
  const Eigen::MatrixXd& m_;
};

}  // namespace

Eigen::VectorXd Scenario::maxRates() const {
  const auto& C = constraints.C;
  Eigen::VectorXd bound = Eigen::VectorXd::Constant(sensorCount(),
                                                    std::numeric_limits<double>::infinity());
  for (int j = 0; j < C.cols(); ++j) {
    for (int i = 0; i < C.rows(); ++i) {
      if (C(i, j) > 0.0) bound(j) = std::min(bound(j), constraints.b(i) / C(i, j));
    }
  }
  return bound;
}

std::vector<Eigen::MatrixXd> Scenario::informationIncrements() const {
  std::vector<Eigen::MatrixXd> increments;
  increments.reserve(sensors.size());
  for (const auto& sensor : sensors) {
    increments.push_back(sensor.H.transpose() * sensor.R.llt().solve(sensor.H));
  }
  return increments;
}

void validateScenario(const Scenario& s, const std::string& source) {
  if (!std::isfinite(s.horizon_s) || s.horizon_s <= 0.0) {
    throw InputError(source, "horizon", "a finite number > 0, got " + std::to_string(s.horizon_s));
  }
  if (s.intervals < 1) {
    throw InputError(source, "intervals", "an integer >= 1, got " + std::to_string(s.intervals));
  }
  const Eigen::Index n = s.plant.A.rows();
  if (n < 1 || s.plant.A.cols() != n) {
    throw InputError(source, "plant.A", "a non-empty square matrix, got " + shapeOf(s.plant.A));
  }
  MatrixCheck(source, "plant.A", s.plant.A).shape(n, n).finite();
  MatrixCheck(source, "plant.Q", s.plant.Q).shape(n, n).finite().symmetric().definite(false);
  MatrixCheck(source, "plant.P0", s.plant.P0).shape(n, n).finite().symmetric().definite(true);
  MatrixCheck(source, "plant.m0", s.plant.m0).shape(n, 1).finite();

  if (s.sensors.empty()) throw InputError(source, "sensors", "at least one sensor");
  for (std::size_t j = 0; j < s.sensors.size(); ++j) {
    const std::string field = "sensors[" + std::to_string(j) + "]";
    const auto& sensor = s.sensors[j];
    const Eigen::Index p = sensor.H.rows();
    if (p < 1) throw InputError(source, field + ".H", "at least one row");
    MatrixCheck(source, field + ".H", sensor.H).shape(p, n).finite();
    MatrixCheck(source, field + ".R", sensor.R).shape(p, p).finite().symmetric().definite(true);
  }

  MatrixCheck(source, "cost.W", s.cost.W).shape(n, n).finite().symmetric().definite(false);
  MatrixCheck(source, "cost.WT", s.cost.WT).shape(n, n).finite().symmetric().definite(false);

  const auto& C = s.constraints.C;
  const auto m = static_cast<Eigen::Index>(s.sensors.size());
  if (C.rows() < 1) throw InputError(source, "constraints.C", "at least one row");
  MatrixCheck(source, "constraints.C", C).shape(C.rows(), m).finite();
  if ((C.array() < 0.0).any()) {
    throw InputError(source, "constraints.C", "nonnegative entries");
  }
  for (Eigen::Index j = 0; j < m; ++j) {
    if (!(C.col(j).array() > 0.0).any()) {
      throw InputError(source, "constraints.C",
                       "a positive entry in every column, column " + std::to_string(j) +
                           " (sensor " + std::to_string(j) + ") has none");
    }
  }
  MatrixCheck(source, "constraints.b", s.constraints.b).shape(C.rows(), 1).finite();
  for (Eigen::Index i = 0; i < s.constraints.b.size(); ++i) {
    if (s.constraints.b(i) <= 0.0) {
      throw InputError(source, "constraints.b[" + std::to_string(i) + "]",
                       "a number > 0, got " + std::to_string(s.constraints.b(i)));
    }
  }
}

namespace {

Eigen::MatrixXd randomOrthogonal(int dim, Rng& rng) {
  Eigen::MatrixXd g(dim, dim);
  for (int i = 0; i < dim; ++i)
    for (int j = 0; j < dim; ++j) g(i, j) = rng.normal();
  Eigen::HouseholderQR<Eigen::MatrixXd> qr(g);
  Eigen::MatrixXd q = qr.householderQ();
  // Fix column signs by R's diagonal so the draw is Haar-distributed.
  const Eigen::MatrixXd r = qr.matrixQR();
  for (int j = 0; j < dim; ++j) {
    if (r(j, j) < 0.0) q.col(j) = -q.col(j);
  }
  return q;
}

}  // namespace

Scenario generateRandomScenario(const RandomPlantSpec& spec) {
  if (spec.state_dim < 1 || spec.sensor_count < 1 || spec.rows_per_sensor < 1 ||
      spec.rows_per_sensor > spec.state_dim) {
    throw InputError("random plant", "state_dim/sensor_count/rows_per_sensor",
                     "state_dim >= 1, sensor_count >= 1, 1 <= rows_per_sensor <= state_dim");
  }
  const int n = spec.state_dim;
  Rng rng = Rng::keyed(spec.seed, 0x706c616e74ULL /* "plant" */);

  // Balanced modes: floor(n/2) unstable with eigenvalues in [0.1, 1], the rest stable in
  // [-1, -0.1], in a random orthogonal basis.
  Eigen::VectorXd modes(n);
  for (int i = 0; i < n; ++i) {
    const double magnitude = 0.1 + 0.9 * rng.uniform();
    modes(i) = (i < n / 2) ? magnitude : -magnitude;
  }
  const Eigen::MatrixXd basis = randomOrthogonal(n, rng);

  Scenario s;
  s.horizon_s = spec.horizon_s;
  s.intervals = spec.intervals;
  s.plant.A = basis * modes.asDiagonal() * basis.transpose();
  s.plant.Q = Eigen::MatrixXd::Identity(n, n);
  s.plant.P0 = 100.0 * Eigen::MatrixXd::Identity(n, n);
  s.plant.m0 = Eigen::VectorXd::Zero(n);
  const int p = spec.rows_per_sensor;
  for (int j = 0; j < spec.sensor_count; ++j) {
    SensorModel sensor;
    sensor.H = randomOrthogonal(n, rng).topRows(p);
    Eigen::VectorXd eig(p);
    for (int i = 0; i < p; ++i) eig(i) = 1.0 + 9.0 * rng.uniform();
    const Eigen::MatrixXd u = randomOrthogonal(p, rng);
    sensor.R = spec.noise_scale * u * eig.asDiagonal() * u.transpose();
    sensor.R = 0.5 * (sensor.R + sensor.R.transpose());
    s.sensors.push_back(std::move(sensor));
  }
  s.cost.W = Eigen::MatrixXd::Zero(n, n);
  s.cost.WT = Eigen::MatrixXd::Identity(n, n);
  s.constraints.C = Eigen::MatrixXd::Ones(1, spec.sensor_count);
  s.constraints.b = Eigen::VectorXd::Constant(1, spec.budget);
  return s;
}

}  // namespace sensornet
