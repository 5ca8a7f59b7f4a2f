// Time per exact interval transition LtiTransition::over(dt), and per CD-KF arrival
// (over(dt) + propagateBy + update), with fresh exponential dt every call as in a Monte Carlo
// episode. Each cell is the median over repeats of the mean time per call of a batch.
//
//   build/bench/transition_bench            # default batch sizes
//   build/bench/transition_bench 5          # 5x larger batches
//
// Rows: n = 5 and n = 20; A symmetric (real eigenvalues: real modal path), A a scaled Gaussian
// matrix (complex pairs: complex modal path), Van Loan forced on the same Gaussian A, and an
// integrator chain (nilpotent: polynomial path).
// The last row is the per-arrival cost on the paper's instance (n = 5, M = 30, p = 1).

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <vector>

#include "sensornet/core/cdkf.hpp"
#include "sensornet/core/random.hpp"
#include "sensornet/core/scenario.hpp"
#include "sensornet/core/transition.hpp"

namespace {

using sensornet::CdKalmanFilter;
using sensornet::IntervalTransition;
using sensornet::LtiTransition;
using sensornet::Rng;
using sensornet::TransitionMethod;

// Median over `repeats` of the mean nanoseconds per call of `batch` calls of `call`.
double medianNanoseconds(const std::function<void()>& call, int batch, int repeats = 11) {
  std::vector<double> samples;
  for (int r = 0; r < repeats; ++r) {
    const auto start = std::chrono::steady_clock::now();
    for (int k = 0; k < batch; ++k) call();
    const auto stop = std::chrono::steady_clock::now();
    samples.push_back(std::chrono::duration<double, std::nano>(stop - start).count() / batch);
  }
  std::nth_element(samples.begin(), samples.begin() + repeats / 2, samples.end());
  return samples[static_cast<std::size_t>(repeats / 2)];
}

Eigen::MatrixXd gaussian(int n, Rng& rng) {
  Eigen::MatrixXd m(n, n);
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < n; ++j) m(i, j) = rng.normal();
  }
  return m;
}

}  // namespace

int main(int argc, char** argv) {
  const int scale = argc > 1 ? std::max(1, std::atoi(argv[1])) : 1;
  Rng rng(1);
  volatile double sink = 0.0;

  std::printf("%-4s %-30s %12s\n", "n", "path", "ns/over(dt)");
  for (const int n : {5, 20}) {
    const Eigen::MatrixXd g = gaussian(n, rng) / std::sqrt(static_cast<double>(n));
    const Eigen::MatrixXd symmetric = 0.5 * (g + g.transpose());
    const Eigen::MatrixXd Q = Eigen::MatrixXd::Identity(n, n);
    const Eigen::MatrixXd W = Eigen::MatrixXd::Identity(n, n);
    Eigen::MatrixXd chain = Eigen::MatrixXd::Zero(n, n);  // nilpotent: ẋ_i = x_{i+1}
    for (int i = 0; i + 1 < n; ++i) chain(i, i + 1) = 1.0;
    struct Row {
      const char* label;
      LtiTransition transition;
      int batch;
    };
    const int batch = (n == 5 ? 20000 : 1000) * scale;
    const Row rows[] = {
        {"modal, real eigenvalues", LtiTransition(symmetric, Q, W), batch},
        {"modal, complex pairs", LtiTransition(g, Q, W), batch},
        {"Van Loan (forced)", LtiTransition(g, Q, W, TransitionMethod::kVanLoan), batch / 20},
        {"polynomial (integrator chain)", LtiTransition(chain, Q, W), batch},
    };
    for (const Row& row : rows) {
      IntervalTransition step;
      Rng gaps(2);
      const double ns = medianNanoseconds(
          [&] {
            row.transition.over(gaps.exponential(5.0), step);
            sink = sink + step.noise_cost;
          },
          row.batch);
      std::printf("%-4d %-30s %12.0f\n", n, row.label, ns);
    }
  }

  sensornet::RandomPlantSpec spec;  // the paper's instance: n = 5, M = 30, p = 1
  CdKalmanFilter filter(sensornet::generateRandomScenario(spec));
  IntervalTransition step;
  Eigen::VectorXd z(1);
  Rng arrivals(3);
  int count = 0;
  const double ns = medianNanoseconds(
      [&] {
        if (++count % 15 == 0) filter.reset();  // an episode has about 15 arrivals
        const double dt = arrivals.exponential(5.0);
        filter.transition().over(dt, step);
        filter.propagateBy(step, dt);
        z(0) = arrivals.normal();
        filter.update(static_cast<int>(arrivals.uniform() * 30), z);
      },
      20000 * scale);
  sink = sink + filter.cost();
  std::printf("\nper arrival, n = 5, M = 30 (over + propagateBy + update): %.0f ns\n", ns);
  return 0;
}
