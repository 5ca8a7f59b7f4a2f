#pragma once
// Sensor rate schedules λ(t): piecewise constant on N equal intervals of [0, T] (eq. 5), and the
// deterministic alternative, a timetable of measurement instants per sensor.
//
//   RateSchedule s = uniformSchedule(scenario);
//   double rate = s.rateAt(1.234, /*sensor=*/2);

#include <Eigen/Core>
#include <string>
#include <vector>

#include "sensornet/core/scenario.hpp"

namespace sensornet {

class RateSchedule {
 public:
  RateSchedule() = default;
  // rates_hz is N x M: row k holds λ_1..λ_M on [k T/N, (k+1) T/N).
  RateSchedule(double horizon_s, Eigen::MatrixXd rates_hz);

  [[nodiscard]] double horizon() const { return horizon_s_; }
  [[nodiscard]] int intervals() const { return static_cast<int>(rates_hz_.rows()); }
  [[nodiscard]] int sensorCount() const { return static_cast<int>(rates_hz_.cols()); }
  [[nodiscard]] double intervalLength() const { return horizon_s_ / intervals(); }
  [[nodiscard]] double intervalStart(int k) const { return k * intervalLength(); }
  // Index of the interval containing t (t = T belongs to the last interval).
  [[nodiscard]] int intervalAt(double t) const;
  [[nodiscard]] double rate(int interval, int sensor) const { return rates_hz_(interval, sensor); }
  [[nodiscard]] double rateAt(double t, int sensor) const { return rate(intervalAt(t), sensor); }
  [[nodiscard]] const Eigen::MatrixXd& rates() const { return rates_hz_; }
  // Expected number of arrivals of each sensor over [t0, t1] (∫ λ_j dt).
  [[nodiscard]] Eigen::VectorXd expectedCounts(double t0, double t1) const;

 private:
  double horizon_s_ = 0.0;
  Eigen::MatrixXd rates_hz_;
};

struct Feasibility {
  bool feasible = true;
  double max_violation = 0.0;  // largest (C λ_k - b)_i or -λ_kj, 0 when feasible
  std::string reason;          // empty when feasible, else names interval and row or sensor
};

// Checks C λ_k <= b + tol and λ_k >= -tol for every interval k, the energy budgets
// ∫_0^T λ_j dt <= E_j + tol max(1, T) of every sensor that has one, and that the shape matches.
[[nodiscard]] Feasibility checkFeasibility(const RateSchedule& schedule,
                                           const Scenario& scenario, double tol = 1e-9);

// The largest rate r, equal for all sensors and constant in time, with C (r 1) <= b:
// r = min_i b_i / Σ_j C_ij; a sensor with an energy budget E_j gets min(r, E_j / T), constant in
// time too.
[[nodiscard]] RateSchedule uniformSchedule(const Scenario& scenario);

// Deterministic measurement instants, one sorted list per sensor.
struct Timetable {
  double horizon_s = 0.0;
  std::vector<std::vector<double>> instants;  // instants[j] sorted, within [0, horizon_s]
};

}  // namespace sensornet
