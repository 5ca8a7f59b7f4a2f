#pragma once
// The model of one emulation: plant (eq. 1), sensors (eq. 2), cost weights (eq. 6) and the
// pointwise resource constraints C λ(t) <= b (eq. 8) of the first paper, with an optional energy
// budget per sensor over the horizon, ∫_0^T λ_j(t) dt <= E_j, over a horizon cut into N equal
// intervals on which rates are constant.
//
//   Scenario s = ...;              // from a YAML file (sensornet/io) or generateRandomScenario
//   validateScenario(s, "my.yaml"); // throws InputError naming the bad field

#include <Eigen/Core>
#include <cstdint>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "sensornet/core/arrival_mode.hpp"
#include "sensornet/core/network_spec.hpp"

namespace sensornet {

struct Plant {
  Eigen::MatrixXd A;   // n x n drift
  Eigen::MatrixXd Q;   // n x n process noise spectral density Σw Σw'
  Eigen::MatrixXd P0;  // n x n initial covariance, positive definite
  Eigen::VectorXd m0;  // initial mean (zero by default)
};

struct SensorModel {
  Eigen::MatrixXd H;  // p_j x n
  Eigen::MatrixXd R;  // p_j x p_j, positive definite
};

struct CostWeights {
  Eigen::MatrixXd W;   // running weight, positive semidefinite
  Eigen::MatrixXd WT;  // terminal weight, positive semidefinite
};

struct ResourceConstraints {
  Eigen::MatrixXd C;  // n_c x M, nonnegative, every column with a positive entry
  Eigen::VectorXd b;  // n_c, strictly positive
  // Per-sensor energy budgets E_j over the horizon, ∫_0^T λ_j dt <= E_j, in expected
  // measurements (a battery or bandwidth that lasts E_j sends); empty when there are none, and
  // +infinity for a sensor without one. They couple the intervals, unlike C and b.
  Eigen::VectorXd energy;

  [[nodiscard]] bool hasEnergyBudgets() const {
    return energy.size() > 0 && (energy.array() < std::numeric_limits<double>::infinity()).any();
  }
};

struct Scenario {
  double horizon_s = 0.0;  // T
  int intervals = 0;       // N
  Plant plant;
  std::vector<SensorModel> sensors;
  CostWeights cost;
  ResourceConstraints constraints;
  std::optional<NetworkSpec> network;  // the emulated network, when the scenario has one
  std::vector<CrashFault> faults;      // scripted faults (network.hpp)
  // How every sensor's instants follow from its rates (the file's `arrivals:`, overridden by
  // --arrivals): Poisson, or the deterministic timetable of arrival_timetable.hpp.
  ArrivalMode arrivals = ArrivalMode::Poisson;

  [[nodiscard]] int stateDim() const { return static_cast<int>(plant.A.rows()); }
  [[nodiscard]] int sensorCount() const { return static_cast<int>(sensors.size()); }
  [[nodiscard]] double intervalLength() const { return horizon_s / intervals; }
  // Per-sensor upper bound λ̄_j = min_{i: C_ij > 0} b_i / C_ij (Section II-B).
  [[nodiscard]] Eigen::VectorXd maxRates() const;
  // Information increments S_j = H_j' R_j^{-1} H_j (eq. 10).
  [[nodiscard]] std::vector<Eigen::MatrixXd> informationIncrements() const;
};

// Bounds on quantities derived from the scenario that validateScenario enforces: beyond them
// the math cannot be done in double precision (or a rollout would never finish), so the
// scenario is refused up front instead of failing deep inside a rollout.
//
// Growth of the open-loop covariance over the horizon, max Re eig(A) T: it grows like
// exp(2 max Re eig(A) T), and exp overflows a double beyond 709.
inline constexpr double kMaxGrowthExponent = 350.0;
// Speed of the dynamics over the horizon, ||A||_2 T: the surrogate rollouts resolve the motion
// (a 3 s horizon at this bound is an oscillation of 5 kHz; a bracket takes seconds there).
inline constexpr double kMaxDynamicsSpan = 1e5;
// Information of one measurement relative to the covariance it updates, the largest eigenvalue
// of P H' R^-1 H for P = P0 and P = the open-loop covariance at T: beyond, the covariance update
// and the information-form rollout lose every significant digit (measured: 1e14 works, 9e14
// fails on the default scenario).
inline constexpr double kMaxMeasurementInformation = 1e12;
// Expected measurements of one sensor in one horizon at its largest rate, λ̄_j T.
inline constexpr double kMaxMeasurementsPerHorizon = 1e9;

// Checks every field for shape, symmetry, definiteness and finiteness, and the derived
// quantities the math forms from them (A T, Q T, the open-loop transition and covariance over
// the horizon, H_j' R_j^-1 H_j, λ̄_j T) against the bounds above, and the emulated network and
// faults (probabilities in [0, 1), delays and instants within the horizon, sensor indices below
// M, outage edges on the grid refined by at most kMaxOutageRefinement); throws InputError with
// `source` and the field path (for example "sensors[3].R") on the first problem found.
void validateScenario(const Scenario& scenario, const std::string& source);

// The paper's experimental protocol (Section V-A): a random plant with a balanced mix of stable
// and unstable modes, Q = I, P0 = 100 I, sensor rows orthonormal, R_j with eigenvalues uniform in
// [1, 10] in a random orthogonal basis, W = 0, W_T = I, one budget row 1'λ <= budget.
struct RandomPlantSpec {
  int state_dim = 5;
  int sensor_count = 30;
  int rows_per_sensor = 1;
  std::uint64_t seed = 1;
  double horizon_s = 3.0;
  int intervals = 30;
  double budget = 5.0;
  double noise_scale = 1.0;  // multiplies every R_j (the paper's R_scale sweep of Fig. 2)
  // Every sensor's energy budget ∫ λ_j dt <= energy (not in the paper; infinity: none).
  double energy = std::numeric_limits<double>::infinity();
};

[[nodiscard]] Scenario generateRandomScenario(const RandomPlantSpec& spec);

// The scenario with the bound of its one constraint row set to `budget` (the random plant's
// 1'λ <= budget), validated. Throws InputError naming `source` when the scenario has more than
// one row, or the budget is not a positive number.
[[nodiscard]] Scenario withBudget(Scenario scenario, double budget, const std::string& source);

// The scenario with energy budgets ∫_0^T λ_j dt <= energy_j (one per sensor, or one for every
// sensor; +infinity: none), validated. Throws InputError naming `source` for a count that is
// neither 1 nor M, or a budget that is not a number > 0.
[[nodiscard]] Scenario withEnergy(Scenario scenario, const Eigen::VectorXd& energy,
                                  const std::string& source);

}  // namespace sensornet
