// libsensornet_world through its C ABI alone (sensornet/world.h), against computations of its
// own: the truth's transitions have the law of the SDE (dx = A x dt + dw: x(t + h) - Φ(h) x(t) ~
// N(0, Qd(h)), Φ and Qd from Van Loan's matrix exponential), the noise is N(0, R), a measurement
// is H x + v, Poisson counts have the schedule's means, and bad input is refused with a reason.
// Statistical checks: fixed seeds, each a chi-square or Poisson sum within 4.5 standard
// deviations of its mean (a false alarm of about 7e-6 each). That our agents send exactly these
// values is ExternalRoles.SensorsWrittenInCDrawingAsOursMakeTheSameRun (NEES equal to the bit).

#include "sensornet/world.h"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <string>
#include <unsupported/Eigen/MatrixFunctions>
#include <vector>

namespace {

// Three states, a non-symmetric drift, full Q; sensor 1 measures two values with correlated
// noise.
constexpr const char* kScenario = R"(name: world
horizon: 2.0
intervals: 4
plant:
  A: [[-0.3, 0.8, 0.0], [0.0, 0.2, 0.6], [0.4, 0.0, -0.5]]
  Q: [[0.4, 0.1, 0], [0.1, 0.6, 0], [0, 0, 0.3]]
  P0: [[9, 0, 0], [0, 4, 0], [0, 0, 1]]
sensors:
  - H: [[1, 0, 0]]
    R: [[0.3]]
  - H: [[0.5, 0, 1], [0, 1, 0]]
    R: [[1.0, 0.2], [0.2, 0.8]]
cost:
  W: [[1, 0, 0], [0, 1, 0], [0, 0, 1]]
  WT: [[1, 0, 0], [0, 1, 0], [0, 0, 1]]
constraints:
  C: [[1, 1]]
  b: [20]
)";

const Eigen::Matrix3d kA = (Eigen::Matrix3d() << -0.3, 0.8, 0.0, 0.0, 0.2, 0.6, 0.4, 0.0, -0.5)
                               .finished();
const Eigen::Matrix3d kQ = (Eigen::Matrix3d() << 0.4, 0.1, 0, 0.1, 0.6, 0, 0, 0, 0.3).finished();

class World : public ::testing::Test {
 protected:
  void SetUp() override {
    char why[256];
    world_ = sn_world_open(kScenario, 42, why, sizeof why);
    ASSERT_NE(world_, nullptr) << why;
  }
  void TearDown() override { sn_world_close(world_); }
  sn_world* world_ = nullptr;
};

// |sum - mean| <= 4.5 sd.
void expectWithin(double sum, double mean, double variance, const std::string& what) {
  EXPECT_LE(std::abs(sum - mean), 4.5 * std::sqrt(variance)) << what << ": " << sum << " vs "
                                                              << mean;
}

TEST_F(World, DescribesTheScenario) {
  EXPECT_EQ(sn_world_abi_version(), SN_WORLD_ABI_VERSION);
  EXPECT_EQ(sn_world_states(world_), 3u);
  EXPECT_EQ(sn_world_sensors(world_), 2u);
  EXPECT_EQ(sn_world_horizon(world_), 2.0);
  EXPECT_EQ(sn_world_measurement_dim(world_, 1), 2u);
  EXPECT_EQ(sn_world_measurement_dim(world_, 2), 0u);
  const double tick = 2.0 / (1 << 20);
  EXPECT_EQ(sn_world_on_tick(world_, 3.5 * tick), 3.0 * tick);
}

// Van Loan: exp([[-A, Q], [0, A']] h) = [[., Φ^{-1} Qd], [0, Φ']].
TEST_F(World, TheTruthMovesAsTheSdeDoes) {
  const double h = 0.5;
  Eigen::MatrixXd big = Eigen::MatrixXd::Zero(6, 6);
  big.topLeftCorner(3, 3) = -kA * h;
  big.topRightCorner(3, 3) = kQ * h;
  big.bottomRightCorner(3, 3) = kA.transpose() * h;
  const Eigen::MatrixXd e = big.exp();
  const Eigen::Matrix3d phi = e.bottomRightCorner(3, 3).transpose();
  const Eigen::Matrix3d qd = phi * e.topRightCorner(3, 3);
  const Eigen::LLT<Eigen::Matrix3d> qd_llt(0.5 * (qd + qd.transpose()));
  constexpr int kEpisodes = 3000;
  double sum = 0.0;
  Eigen::Vector3d a, b;
  for (std::uint32_t episode = 0; episode < kEpisodes; ++episode) {
    ASSERT_EQ(sn_world_state(world_, episode, 1.0, a.data()), 0) << sn_world_error(world_);
    ASSERT_EQ(sn_world_state(world_, episode, 1.5, b.data()), 0);
    const Eigen::Vector3d step = b - phi * a;
    sum += step.dot(qd_llt.solve(step));
  }
  // chi-square(3 K): mean 3K, variance 6K.
  expectWithin(sum, 3.0 * kEpisodes, 6.0 * kEpisodes, "transitions over 0.5 s");
  // The same instant asked twice, and through another instant in between, is the same state.
  Eigen::Vector3d again, other;
  ASSERT_EQ(sn_world_state(world_, 7, 1.0, a.data()), 0);
  ASSERT_EQ(sn_world_state(world_, 7, 0.3, other.data()), 0);
  ASSERT_EQ(sn_world_state(world_, 7, 1.0, again.data()), 0);
  EXPECT_EQ(a, again);
}

TEST_F(World, AMeasurementIsHxPlusTheNoiseAndTheNoiseHasCovarianceR) {
  const Eigen::Matrix2d r = (Eigen::Matrix2d() << 1.0, 0.2, 0.2, 0.8).finished();
  Eigen::Matrix<double, 2, 3> h;
  h << 0.5, 0, 1, 0, 1, 0;
  const Eigen::LLT<Eigen::Matrix2d> r_llt(r);
  constexpr int kDraws = 4000;
  double sum = 0.0;
  Eigen::Vector2d v, z;
  Eigen::Vector3d x;
  for (std::uint64_t seq = 0; seq < kDraws; ++seq) {
    ASSERT_EQ(sn_world_noise(world_, 3, 1, seq, v.data()), 0);
    sum += v.dot(r_llt.solve(v));
  }
  expectWithin(sum, 2.0 * kDraws, 4.0 * kDraws, "v' R^-1 v");
  ASSERT_EQ(sn_world_state(world_, 3, 0.75, x.data()), 0);
  ASSERT_EQ(sn_world_noise(world_, 3, 1, 17, v.data()), 0);
  ASSERT_EQ(sn_world_measure(world_, 3, 1, 17, 0.75, z.data()), 0);
  EXPECT_LE((z - (h * x + v)).cwiseAbs().maxCoeff(), 1e-12);
  // Another seq, episode or sensor draws other noise.
  Eigen::Vector2d w;
  ASSERT_EQ(sn_world_noise(world_, 3, 1, 18, w.data()), 0);
  EXPECT_NE(v, w);
  ASSERT_EQ(sn_world_noise(world_, 4, 1, 17, w.data()), 0);
  EXPECT_NE(v, w);
}

// Rates 3 Hz then 0 then 5 Hz then 1 Hz for sensor 0 over four 0.5 s intervals: K episodes'
// counts sum to Poisson(K (1.5 + 0 + 2.5 + 0.5)); none falls in the silent interval; every
// instant is on a tick, in order, drawn by version 1.
TEST_F(World, ArrivalsFollowTheSchedule) {
  const std::vector<double> rates = {3, 1, 0, 1, 5, 1, 1, 1};  // 4 intervals x 2 sensors
  ASSERT_EQ(sn_world_add_schedule(world_, 1, 0, 0.0, rates.data(), 4), 0) << sn_world_error(world_);
  constexpr int kEpisodes = 400;
  std::vector<double> times(64);
  std::vector<std::uint32_t> versions(64);
  double total = 0.0;
  for (std::uint32_t episode = 0; episode < kEpisodes; ++episode) {
    long n = sn_world_arrivals(world_, episode, 0, times.data(), versions.data(), times.size());
    ASSERT_GE(n, 0) << sn_world_error(world_);
    if (static_cast<std::size_t>(n) > times.size()) {
      times.resize(static_cast<std::size_t>(n));
      versions.resize(static_cast<std::size_t>(n));
      n = sn_world_arrivals(world_, episode, 0, times.data(), versions.data(), times.size());
    }
    for (long i = 0; i < n; ++i) {
      const double t = times[static_cast<std::size_t>(i)];
      EXPECT_FALSE(t >= 0.5 && t < 1.0) << t;
      EXPECT_EQ(sn_world_on_tick(world_, t), t);
      EXPECT_EQ(versions[static_cast<std::size_t>(i)], 1u);
      if (i > 0) {
        EXPECT_LE(times[static_cast<std::size_t>(i - 1)], t);
      }
    }
    total += static_cast<double>(n);
  }
  const double mean = kEpisodes * 4.5;
  expectWithin(total, mean, mean, "arrival counts");
  // Asking with no room gives the count and writes nothing.
  EXPECT_EQ(sn_world_arrivals(world_, 0, 0, nullptr, nullptr, 0),
            sn_world_arrivals(world_, 0, 0, times.data(), nullptr, times.size()));
}

TEST_F(World, BadInputIsRefusedWithItsReason) {
  double x[3];
  EXPECT_EQ(sn_world_state(world_, 0, 2.5, x), -1);
  EXPECT_NE(std::string(sn_world_error(world_)).find("outside [0, T"), std::string::npos)
      << sn_world_error(world_);
  EXPECT_EQ(sn_world_measure(world_, 0, 5, 0, 1.0, x), -1);
  EXPECT_NE(std::string(sn_world_error(world_)).find("sensor 5"), std::string::npos);
  EXPECT_EQ(sn_world_state(world_, 0, 1.0, x), 0);
  EXPECT_STREQ(sn_world_error(world_), "");
  const std::vector<double> negative = {1, -1, 1, 1, 1, 1, 1, 1};
  EXPECT_EQ(sn_world_add_schedule(world_, 1, 0, 0.0, negative.data(), 4), -1);
  EXPECT_NE(std::string(sn_world_error(world_)).find("rates[0][1]"), std::string::npos)
      << sn_world_error(world_);
  const std::vector<double> three_intervals = {1, 1, 1, 1, 1, 1};  // the scenario has 4
  EXPECT_EQ(sn_world_add_schedule(world_, 1, 0, 0.0, three_intervals.data(), 3), -1);
  EXPECT_NE(std::string(sn_world_error(world_)).find("the scenario's 4 intervals"),
            std::string::npos)
      << sn_world_error(world_);
  EXPECT_EQ(sn_world_set_arrivals(world_, "sometimes"), -1);
  EXPECT_EQ(sn_world_set_arrivals(world_, "timetable"), 0);
  char why[256];
  EXPECT_EQ(sn_world_open("horizon: 2.0\nplant: {A: [[1]]}\n", 1, why, sizeof why), nullptr);
  EXPECT_GT(std::string(why).size(), 10u) << why;
  EXPECT_EQ(sn_world_open(nullptr, 1, why, sizeof why), nullptr);
}

}  // namespace
