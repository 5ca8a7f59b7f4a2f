#include "sensornet/core/arrival_timetable.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include "sensornet/core/input_error.hpp"

namespace sensornet {
namespace {

// The rate of sensor j at t, looked up from the matrix by hand (not through RateSchedule).
double rateByHand(const Eigen::MatrixXd& rates, double horizon, int j, double t) {
  const auto n = static_cast<int>(rates.rows());
  const int k = std::min(n - 1, static_cast<int>(t / (horizon / n)));
  return rates(k, j);
}

// Λ_j(t) by the composite midpoint rule on `steps` cells: exact inside a constant piece, off by
// at most rate * cell width in a cell that straddles a rate change.
double integrateNumerically(const Eigen::MatrixXd& rates, double horizon, int j, double t,
                            int steps) {
  const double h = t / steps;
  double sum = 0.0;
  for (int i = 0; i < steps; ++i) sum += rateByHand(rates, horizon, j, (i + 0.5) * h) * h;
  return sum;
}

TEST(ArrivalTimetable, ConstantRateGivesHalfIntegerInstantsInClosedForm) {
  // λ = 3.7 Hz over T = 2 s: Λ = 7.4, instants (k - 1/2) / 3.7 for k = 1..7 (7.5 > 7.4).
  const RateSchedule schedule(2.0, Eigen::MatrixXd::Constant(4, 1, 3.7));
  const std::vector<double> got = sensorTimetable(schedule, 0, 0.0, 2.0);
  ASSERT_EQ(got.size(), 7U);
  for (std::size_t k = 1; k <= got.size(); ++k) {
    EXPECT_NEAR(got[k - 1], (static_cast<double>(k) - 0.5) / 3.7, 1e-12) << "k = " << k;
  }
}

TEST(ArrivalTimetable, TwoPieceScheduleMatchesItsClosedForm) {
  // a = 2 Hz on [0, 1.5), b = 5 Hz on [1.5, 3): Λ(1.5) = 3, Λ(3) = 10.5.
  Eigen::MatrixXd rates(2, 1);
  rates << 2.0, 5.0;
  const RateSchedule schedule(3.0, rates);
  const std::vector<double> got = sensorTimetable(schedule, 0, 0.0, 3.0);
  ASSERT_EQ(got.size(), 10U);  // half-integers 0.5 .. 9.5 lie below 10.5; 10.5 is at T itself
  for (std::size_t k = 1; k <= got.size(); ++k) {
    const double m = static_cast<double>(k) - 0.5;
    const double expected = m < 3.0 ? m / 2.0 : 1.5 + (m - 3.0) / 5.0;
    EXPECT_NEAR(got[k - 1], expected, 1e-12) << "k = " << k;
  }
}

TEST(ArrivalTimetable, RandomScheduleInstantsSitWhereTheIntegratedRateIsAHalfInteger) {
  std::mt19937_64 gen(20261130);
  std::uniform_real_distribution<double> rate(0.0, 6.0);
  const double horizon = 3.0;
  Eigen::MatrixXd rates(30, 5);
  for (Eigen::Index k = 0; k < rates.rows(); ++k) {
    for (Eigen::Index j = 0; j < rates.cols(); ++j) rates(k, j) = (k % 7 == 3) ? 0.0 : rate(gen);
  }
  const RateSchedule schedule(horizon, rates);
  constexpr int kSteps = 200'000;  // cell 1.5e-5 s: Λ off by < 6 * 1.5e-5 = 9e-5
  for (int j = 0; j < 5; ++j) {
    const std::vector<double> got = sensorTimetable(schedule, j, 0.0, horizon);
    const double total = integrateNumerically(rates, horizon, j, horizon, kSteps);
    EXPECT_EQ(static_cast<double>(got.size()), std::floor(total + 0.5)) << "sensor " << j;
    for (std::size_t k = 1; k <= got.size(); ++k) {
      EXPECT_NEAR(integrateNumerically(rates, horizon, j, got[k - 1], kSteps),
                  static_cast<double>(k) - 0.5, 2e-4)
          << "sensor " << j << ", instant " << k;
    }
    EXPECT_NEAR(integratedIntensity(schedule, j, 0.0, horizon), total, 2e-4);
  }
}

TEST(ArrivalTimetable, WindowsOfOneScheduleTileTheWholeTimetable) {
  Eigen::MatrixXd rates(3, 2);
  rates << 1.3, 0.0, 4.1, 2.2, 0.7, 9.0;
  const RateSchedule schedule(3.0, rates);
  for (int j = 0; j < 2; ++j) {
    std::vector<double> tiled;
    for (const auto& [a, b] : std::vector<std::pair<double, double>>{{0, 0.4}, {0.4, 1.9}, {1.9, 3}}) {
      for (double t : sensorTimetable(schedule, j, a, b)) tiled.push_back(t);
    }
    const std::vector<double> whole = sensorTimetable(schedule, j, 0.0, 3.0);
    ASSERT_EQ(tiled.size(), whole.size());
    for (std::size_t i = 0; i < whole.size(); ++i) EXPECT_NEAR(tiled[i], whole[i], 1e-12);
  }
}

TEST(ArrivalTimetable, ASwitchContinuesFromTheIntegratedIntensityOfTheOldSchedule) {
  // Old: 2 Hz throughout; new: 6 Hz throughout; switch at s = 1.25 (mid-interval).
  // Composed Λ: 2 t before s (Λ(s) = 2.5), 2.5 + 6 (t - s) after; instants at Λ = 0.5 .. :
  // 0.25, 0.75, then 2.5 is reached at s exactly -> s, then s + (m - 2.5) / 6.
  const RateSchedule old_schedule(3.0, Eigen::MatrixXd::Constant(3, 1, 2.0));
  const RateSchedule new_schedule(3.0, Eigen::MatrixXd::Constant(3, 1, 6.0));
  const double s = 1.25;
  std::vector<double> got = sensorTimetable(old_schedule, 0, 0.0, s);
  const double at_s = integratedIntensity(old_schedule, 0, 0.0, s);
  EXPECT_DOUBLE_EQ(at_s, 2.5);
  for (double t : sensorTimetable(new_schedule, 0, s, 3.0, at_s)) got.push_back(t);
  // Λ(3) = 2.5 + 6 * 1.75 = 13: half-integers 0.5 .. 12.5 -> 13 instants.
  ASSERT_EQ(got.size(), 13U);
  for (std::size_t k = 1; k <= got.size(); ++k) {
    const double m = static_cast<double>(k) - 0.5;
    const double expected = m < 2.5 ? m / 2.0 : s + (m - 2.5) / 6.0;
    EXPECT_NEAR(got[k - 1], expected, 1e-12) << "k = " << k;
  }
}

TEST(ArrivalTimetable, MergedArrivalsAreEverySensorsInstantsSorted) {
  Eigen::MatrixXd rates(2, 3);
  rates << 1.0, 0.0, 3.0, 2.0, 0.0, 1.0;
  const RateSchedule schedule(2.0, rates);
  const std::vector<Arrival> all = timetableArrivals(schedule);
  // Λ(2) per sensor: 3, 0, 4 -> 3 + 0 + 4 instants (3 and 4 are not half-integers).
  ASSERT_EQ(all.size(), 7U);
  for (std::size_t i = 1; i < all.size(); ++i) EXPECT_LE(all[i - 1].time, all[i].time);
  int per_sensor[3] = {0, 0, 0};
  for (const Arrival& a : all) ++per_sensor[a.sensor];
  EXPECT_EQ(per_sensor[0], 3);
  EXPECT_EQ(per_sensor[1], 0);
  EXPECT_EQ(per_sensor[2], 4);
}

TEST(ArrivalTimetable, ModeNamesRoundTripAndBadInputIsRefused) {
  EXPECT_EQ(parseArrivalMode("poisson", "f", "arrivals"), ArrivalMode::Poisson);
  EXPECT_EQ(parseArrivalMode("timetable", "f", "arrivals"), ArrivalMode::Timetable);
  EXPECT_EQ(arrivalModeName(ArrivalMode::Timetable), "timetable");
  EXPECT_EQ(arrivalModeName(ArrivalMode::Poisson), "poisson");
  try {
    (void)parseArrivalMode("Timetable", "s.yaml:3", "arrivals");
    FAIL() << "accepted a wrong spelling";
  } catch (const InputError& e) {
    EXPECT_EQ(e.field(), "arrivals");
    EXPECT_NE(std::string(e.what()).find("s.yaml:3"), std::string::npos);
  }
  const RateSchedule schedule(1.0, Eigen::MatrixXd::Constant(2, 2, 1.0));
  EXPECT_THROW((void)sensorTimetable(schedule, 2, 0.0, 1.0), InputError);
  EXPECT_THROW((void)sensorTimetable(schedule, 0, 0.5, 0.2), InputError);
  EXPECT_THROW((void)sensorTimetable(schedule, 0, 0.0, 1.5), InputError);
  EXPECT_THROW((void)sensorTimetable(schedule, 0, 0.0, 1.0, -1.0), InputError);
  EXPECT_THROW((void)sensorTimetable(RateSchedule(1.0, Eigen::MatrixXd::Constant(1, 1, -1.0)),
                                     0, 0.0, 1.0),
               InputError);
}

}  // namespace
}  // namespace sensornet
