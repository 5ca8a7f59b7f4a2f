// Time per solve of optimalInstants (the Brownian optimal measurement instants), as the median
// over many random problems of the mean time of repeated solves of each problem.
//
//   build/bench/brownian_bench            # default problem counts
//   build/bench/brownian_bench 500        # 500 problems per n = 1, 2 row
//
// Rows: n = 1 (closed form), n = 2 on the paper's Fig. 10 setting (σ² = 1, T = 10,
// v0, v1, v2 uniform in [1, 10]; the paper keeps only the regime-3 draws, about three quarters
// of them, we keep all) and on parameters spread over decades (all three regimes), then
// n = 3..8 (dynamic programme plus Newton refinement). The target for n = 2 is under 10 µs per
// solve. Columns: median, 90th percentile and largest µs per solve over the problems, the
// median and largest iteration count (coordinate-descent sweeps for n = 2, Newton iterations
// for n >= 3), and how many problems fell in each regime (0 = not classified, n >= 3).

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <vector>

#include "sensornet/core/brownian_instants.hpp"
#include "sensornet/core/random.hpp"

namespace {

using sensornet::BrownianProblem;
using sensornet::BrownianSchedule;
using sensornet::Rng;

double logUniform(Rng& rng, double low, double high) {
  return std::exp(std::log(low) + (std::log(high) - std::log(low)) * rng.uniform());
}

BrownianProblem spreadProblem(Rng& rng, int n) {
  BrownianProblem p;
  p.sigma2 = logUniform(rng, 0.1, 10.0);
  p.horizon_s = logUniform(rng, 0.01, 10.0);
  p.v0 = logUniform(rng, 0.01, 10.0);
  for (int k = 0; k < n; ++k) p.variances.push_back(logUniform(rng, 0.01, 10.0));
  return p;
}

BrownianProblem fig10Problem(Rng& rng) {
  BrownianProblem p;
  p.sigma2 = 1.0;
  p.horizon_s = 10.0;
  p.v0 = 1.0 + 9.0 * rng.uniform();
  p.variances = {1.0 + 9.0 * rng.uniform(), 1.0 + 9.0 * rng.uniform()};
  return p;
}

struct Row {
  std::vector<double> micros;  // mean µs per solve, one entry per problem
  std::vector<int> iterations;
  int regimes[4] = {0, 0, 0, 0};
};

double percentile(std::vector<double> values, double q) {
  std::sort(values.begin(), values.end());
  return values[static_cast<std::size_t>(q * static_cast<double>(values.size() - 1))];
}

Row timeRow(const std::function<BrownianProblem(Rng&)>& make, int problems, int repeats,
            std::uint64_t seed) {
  Rng rng(seed);
  Row row;
  volatile double sink = 0.0;  // keeps the solves from being optimised away
  for (int i = 0; i < problems; ++i) {
    const BrownianProblem p = make(rng);
    BrownianSchedule schedule;
    const auto start = std::chrono::steady_clock::now();
    for (int r = 0; r < repeats; ++r) {
      schedule = sensornet::optimalInstants(p);
      sink = sink + schedule.cost;
    }
    const std::chrono::duration<double, std::micro> elapsed =
        std::chrono::steady_clock::now() - start;
    row.micros.push_back(elapsed.count() / repeats);
    row.iterations.push_back(schedule.iterations);
    ++row.regimes[std::clamp(schedule.regime, 0, 3)];
  }
  return row;
}

void print(const char* name, const Row& row) {
  std::vector<double> iterations(row.iterations.begin(), row.iterations.end());
  std::printf("%-34s %8zu %12.2f %12.2f %12.2f %9.0f %9.0f   %d/%d/%d/%d\n", name,
              row.micros.size(), percentile(row.micros, 0.5), percentile(row.micros, 0.9),
              percentile(row.micros, 1.0), percentile(iterations, 0.5), percentile(iterations, 1.0),
              row.regimes[0], row.regimes[1], row.regimes[2], row.regimes[3]);
}

}  // namespace

int main(int argc, char** argv) {
  const int problems = argc > 1 ? std::max(1, std::atoi(argv[1])) : 2000;
  std::printf("%-34s %8s %12s %12s %12s %9s %9s   %s\n", "case", "problems", "median us", "p90 us",
              "max us", "med iter", "max iter", "regime 0/1/2/3");
  print("n=1 closed form",
        timeRow([](Rng& rng) { return spreadProblem(rng, 1); }, problems, 200, 1));
  print("n=2 Fig.10 setting (regime 3)", timeRow(fig10Problem, problems, 100, 2));
  print("n=2 spread parameters",
        timeRow([](Rng& rng) { return spreadProblem(rng, 2); }, problems, 100, 3));
  for (int n = 3; n <= 8; ++n) {
    char name[64];
    std::snprintf(name, sizeof name, "n=%d DP + Newton refinement", n);
    print(name, timeRow([n](Rng& rng) { return spreadProblem(rng, n); }, std::max(1, problems / 40),
                        1, 10 + static_cast<std::uint64_t>(n)));
  }
  return 0;
}
