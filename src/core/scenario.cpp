#include "sensornet/core/scenario.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/QR>
#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

#include "sensornet/core/input_error.hpp"
#include "sensornet/core/network.hpp"
#include "sensornet/core/random.hpp"
#include "sensornet/core/transition.hpp"

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
    // Halves first and decomposed divided by its scale, so that entries near the largest
    // double overflow neither the sum nor the eigensolver.
    const Eigen::MatrixXd sym = 0.5 * m_ + 0.5 * m_.transpose();
    const double scale = std::max(1.0, sym.cwiseAbs().maxCoeff());
    const double smallest_scaled = Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(
                                       sym / scale, Eigen::EigenvaluesOnly)
                                       .eigenvalues()
                                       .minCoeff();
    const double smallest = smallest_scaled * scale;
    const bool ok = strict ? smallest_scaled > 1e-12 : smallest_scaled >= -1e-12;
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

// Numbers in messages: %g, so that 1e308 reads as 1e+308.
std::string number(double value) {
  std::ostringstream text;
  text << value;
  return text.str();
}

// The largest eigenvalue of P I for symmetric positive definite P and symmetric I: the largest
// eigenvalue of L' I L with P = L L'. Infinity when it cannot be computed.
double largestRelativeEigenvalue(const Eigen::MatrixXd& P, const Eigen::MatrixXd& I) {
  const Eigen::LLT<Eigen::MatrixXd> llt(P);
  if (llt.info() != Eigen::Success) return std::numeric_limits<double>::infinity();
  const Eigen::MatrixXd L = llt.matrixL();
  const Eigen::MatrixXd M = L.transpose() * I * L;
  if (!M.allFinite()) return std::numeric_limits<double>::infinity();
  const double largest = Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(0.5 * (M + M.transpose()),
                                                                        Eigen::EigenvaluesOnly)
                             .eigenvalues()
                             .maxCoeff();
  return std::isfinite(largest) ? largest : std::numeric_limits<double>::infinity();
}

// A T, Q T and the open-loop transition over the horizon (no measurements): what every
// rollout starts from. Returns the open-loop covariance at T.
Eigen::MatrixXd checkPlantOverHorizon(const Scenario& s, const std::string& source) {
  const double T = s.horizon_s;
  const Plant& plant = s.plant;
  const std::string horizon = ", T = " + number(T) + " s";
  const double largest_a = plant.A.cwiseAbs().maxCoeff();
  if (!(plant.A * T).allFinite()) {
    throw InputError(source, "plant.A",
                     "entries with |A| T finite, got max |A_ij| = " + number(largest_a) + horizon);
  }
  const double span = Eigen::JacobiSVD<Eigen::MatrixXd>(plant.A).singularValues()(0) * T;
  if (!(span <= kMaxDynamicsSpan)) {
    throw InputError(source, "plant.A",
                     "dynamics the rollouts can resolve over the horizon: ||A||_2 T <= " +
                         number(kMaxDynamicsSpan) + ", got " + number(span));
  }
  const double growth =
      Eigen::EigenSolver<Eigen::MatrixXd>(plant.A, false).eigenvalues().real().maxCoeff() * T;
  if (!(growth <= kMaxGrowthExponent)) {
    throw InputError(source, "plant.A",
                     "max Re eig(A) T <= " + number(kMaxGrowthExponent) +
                         " (the covariance without measurements grows like exp(2 max Re eig(A) "
                         "T), which overflows a double beyond exp(709)), got " +
                         number(growth));
  }
  if (!(plant.Q * T).allFinite()) {
    throw InputError(source, "plant.Q",
                     "entries with |Q| T finite, got max |Q_ij| = " +
                         number(plant.Q.cwiseAbs().maxCoeff()) + horizon);
  }
  IntervalTransition step;
  try {
    step = LtiTransition(plant.A, plant.Q, s.cost.W).over(T);
  } catch (const std::exception& e) {
    throw InputError(source, "plant.A",
                     std::string("a plant whose transition over the horizon can be computed (") +
                         e.what() + ")");
  }
  const std::string overflows = " over the horizon overflows a double";
  if (!step.Phi.allFinite()) {
    throw InputError(source, "plant.A", "a finite transition exp(A T), but exp(A T)" + overflows);
  }
  if (!step.Qd.allFinite()) {
    throw InputError(source, "plant.Q",
                     "finite process noise over the horizon, but the accumulated noise "
                     "covariance (the integral of exp(A s) Q exp(A s)')" +
                         overflows);
  }
  if (!step.cost_gramian.allFinite() || !std::isfinite(step.noise_cost)) {
    throw InputError(source, "cost.W", "a finite running cost, but its integral" + overflows);
  }
  const Eigen::MatrixXd open_loop = step.Phi * plant.P0 * step.Phi.transpose() + step.Qd;
  if (!open_loop.allFinite()) {
    throw InputError(source, "plant.P0",
                     "a covariance that stays finite without measurements, but exp(A T) P0 "
                     "exp(A T)' + Qd" +
                         overflows);
  }
  const double running = plant.P0.cwiseProduct(step.cost_gramian).sum() + step.noise_cost;
  if (!std::isfinite(running)) {
    throw InputError(source, "cost.W", "a finite running cost, but its integral" + overflows);
  }
  if (!std::isfinite(s.cost.WT.cwiseProduct(open_loop).sum())) {
    throw InputError(source, "cost.WT",
                     "a finite terminal cost, but <WT, P(T)> without measurements overflows");
  }
  return open_loop;
}

// H_j' R_j^-1 H_j, its size relative to the covariances it updates, and λ̄_j T.
void checkSensorsOverHorizon(const Scenario& s, const Eigen::MatrixXd& open_loop,
                             const std::string& source) {
  const std::vector<Eigen::MatrixXd> information = s.informationIncrements();
  for (std::size_t j = 0; j < information.size(); ++j) {
    const std::string field = "sensors[" + std::to_string(j) + "].H";
    if (!information[j].allFinite()) {
      throw InputError(source, field,
                       "entries whose information H' R^-1 H is finite, but it overflows (max "
                       "|H_ij| = " +
                           number(s.sensors[j].H.cwiseAbs().maxCoeff()) + ")");
    }
    const double relative = std::max(largestRelativeEigenvalue(s.plant.P0, information[j]),
                                     largestRelativeEigenvalue(open_loop, information[j]));
    if (!(relative <= kMaxMeasurementInformation)) {
      throw InputError(
          source, field,
          "a measurement at most " + number(kMaxMeasurementInformation) +
              " times as informative as the prior (largest eigenvalue of P H' R^-1 H for P = P0 "
              "and the covariance at T without measurements; beyond, the covariance update "
              "loses every digit), got " +
              number(relative));
    }
  }
  const Eigen::VectorXd max_rates = s.maxRates();
  for (Eigen::Index j = 0; j < max_rates.size(); ++j) {
    const double count = max_rates(j) * s.horizon_s;
    if (!(count <= kMaxMeasurementsPerHorizon)) {
      throw InputError(source, "constraints.b",
                       "budgets that allow at most " + number(kMaxMeasurementsPerHorizon) +
                           " expected measurements per sensor in one horizon (largest rate "
                           "min_i b_i / C_ij times T), got sensor " +
                           std::to_string(j) + ": " + number(max_rates(j)) + " Hz x " +
                           number(s.horizon_s) + " s = " + number(count));
    }
  }
}

// Emulated seconds within [0, T] (or (0, T]).
void checkSeconds(double seconds, double horizon_s, bool positive, const std::string& source,
                  const std::string& field) {
  const bool low_ok = positive ? seconds > 0.0 : seconds >= 0.0;
  if (!std::isfinite(seconds) || !low_ok || seconds > horizon_s) {
    throw InputError(source, field,
                     std::string("seconds in ") + (positive ? "(0, " : "[0, ") +
                         number(horizon_s) + "] (at most the horizon), got " + number(seconds));
  }
}

void checkProbability(double p, const std::string& source, const std::string& field) {
  if (!(p >= 0.0 && p < 1.0)) {
    throw InputError(source, field, "a probability in [0, 1), got " + number(p));
  }
}

void checkSensorIndex(int sensor, int sensors, const std::string& source,
                      const std::string& field) {
  if (sensor < 0 || sensor >= sensors) {
    throw InputError(source, field,
                     "a sensor index from 0 to " + std::to_string(sensors - 1) + ", got " +
                         std::to_string(sensor));
  }
}

void checkLink(const LinkSpec& link, double horizon_s, const std::string& source,
               const std::string& field) {
  checkProbability(link.loss, source, field + ".loss");
  checkProbability(link.duplicate, source, field + ".duplicate");
  checkSeconds(link.delay_fixed_s, horizon_s, false, source, field + ".delay.fixed");
  if (link.jitter != Jitter::None) {
    checkSeconds(link.jitter_mean_s, horizon_s, true, source, field + ".delay.mean");
  }
  if (link.jitter == Jitter::Lognormal &&
      !(link.jitter_sigma > 0.0 && link.jitter_sigma <= kMaxLognormalSigma)) {
    throw InputError(source, field + ".delay.sigma",
                     "a number in (0, " + number(kMaxLognormalSigma) + "], got " +
                         number(link.jitter_sigma));
  }
}

// Outage windows inside [0, T], and together on the grid refined by at most
// kMaxOutageRefinement (the outage that breaks it is named).
void checkOutages(const Scenario& s, const std::string& source) {
  const std::vector<Outage>& outages = s.network->outages;
  for (std::size_t i = 0; i < outages.size(); ++i) {
    const Outage& outage = outages[i];
    const std::string field = "network.outages[" + std::to_string(i) + "]";
    checkSensorIndex(outage.sensor, s.sensorCount(), source, field + ".sensor");
    if (!(std::isfinite(outage.from_s) && outage.from_s >= 0.0 && outage.from_s < s.horizon_s)) {
      throw InputError(source, field + ".from",
                       "seconds in [0, " + number(s.horizon_s) + ") (within the horizon), got " +
                           number(outage.from_s));
    }
    if (!(std::isfinite(outage.to_s) && outage.to_s > outage.from_s &&
          outage.to_s <= s.horizon_s)) {
      throw InputError(source, field + ".to",
                       "seconds in (from, T] = (" + number(outage.from_s) + ", " +
                           number(s.horizon_s) + "], got " + number(outage.to_s));
    }
    const std::vector<Outage> so_far(outages.begin(), outages.begin() + static_cast<long>(i) + 1);
    if (outageRefinement(s.horizon_s, s.intervals, so_far) == 0) {
      throw InputError(source, field,
                       "edges on the rate grid (T/N = " + number(s.intervalLength()) +
                           " s) divided into at most " + std::to_string(kMaxOutageRefinement) +
                           " equal steps, together with the outages before it, got from " +
                           number(outage.from_s) + ", to " + number(outage.to_s));
    }
  }
}

void checkNetworkAndFaults(const Scenario& s, const std::string& source) {
  if (s.network) {
    if (s.network->links.size() != s.sensors.size()) {
      throw InputError(source, "network",
                       "one link per sensor (" + std::to_string(s.sensors.size()) + "), got " +
                           std::to_string(s.network->links.size()));
    }
    for (std::size_t j = 0; j < s.network->links.size(); ++j) {
      checkLink(s.network->links[j], s.horizon_s, source,
                "network.links[" + std::to_string(j) + "]");
    }
    checkOutages(s, source);
  }
  for (std::size_t i = 0; i < s.faults.size(); ++i) {
    const std::string field = "faults[" + std::to_string(i) + "]";
    checkSensorIndex(s.faults[i].sensor, s.sensorCount(), source, field + ".sensor");
    checkSeconds(s.faults[i].at_s, s.horizon_s, false, source, field + ".at");
  }
}

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
  const Eigen::VectorXd& energy = s.constraints.energy;
  if (energy.size() > 0) {
    if (energy.size() != m) {
      throw InputError(source, "constraints.energy",
                       std::to_string(m) + " values (one per sensor) or one for all, got " +
                           std::to_string(energy.size()));
    }
    for (Eigen::Index j = 0; j < m; ++j) {
      if (!(energy(j) > 0.0)) {
        throw InputError(source, "constraints.energy[" + std::to_string(j) + "]",
                         "a number of expected measurements over the horizon > 0 (.inf for no "
                         "budget), got " + std::to_string(energy(j)));
      }
    }
  }

  const Eigen::MatrixXd open_loop = checkPlantOverHorizon(s, source);
  checkSensorsOverHorizon(s, open_loop, source);
  checkNetworkAndFaults(s, source);
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
  if (spec.energy < std::numeric_limits<double>::infinity()) {
    s.constraints.energy = Eigen::VectorXd::Constant(spec.sensor_count, spec.energy);
  }
  return s;
}

Scenario withBudget(Scenario scenario, double budget, const std::string& source) {
  if (scenario.constraints.C.rows() != 1) {
    throw InputError(source, "budget",
                     "a scenario with one constraint row (this one has " +
                         std::to_string(scenario.constraints.C.rows()) + "; change its C and b instead)");
  }
  if (!(budget > 0.0) || !std::isfinite(budget)) {
    throw InputError(source, "budget", "a number > 0, got " + std::to_string(budget));
  }
  scenario.constraints.b(0) = budget;
  validateScenario(scenario, source);
  return scenario;
}

Scenario withEnergy(Scenario scenario, const Eigen::VectorXd& energy, const std::string& source) {
  const Eigen::Index m = scenario.sensorCount();
  if (energy.size() != 1 && energy.size() != m) {
    throw InputError(source, "energy",
                     "one budget for every sensor or " + std::to_string(m) +
                         " (one per sensor), got " + std::to_string(energy.size()));
  }
  scenario.constraints.energy =
      energy.size() == 1 ? Eigen::VectorXd::Constant(m, energy(0)) : energy;
  validateScenario(scenario, source);
  return scenario;
}

}  // namespace sensornet
