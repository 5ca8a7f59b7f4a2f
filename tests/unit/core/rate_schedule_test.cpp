#include "sensornet/core/rate_schedule.hpp"

#include <gtest/gtest.h>

namespace sensornet {
namespace {

Scenario twoSensorScenario() {
  RandomPlantSpec spec;
  spec.state_dim = 2;
  spec.sensor_count = 3;
  spec.intervals = 4;
  spec.horizon_s = 2.0;
  Scenario s = generateRandomScenario(spec);
  // Overlapping coupling constraints of Section II-B: sensors (1,2) and (2,3).
  s.constraints.C = (Eigen::MatrixXd(2, 3) << 1, 1, 0, 0, 1, 1).finished();
  s.constraints.b = (Eigen::VectorXd(2) << 4.0, 6.0).finished();
  return s;
}

TEST(RateSchedule, UniformScheduleIsTheLargestEqualRateMeetingEveryRow) {
  const Scenario s = twoSensorScenario();
  const RateSchedule uniform = uniformSchedule(s);
  // Row sums 2 and 2, so r = min(4/2, 6/2) = 2.
  EXPECT_DOUBLE_EQ(uniform.rate(0, 0), 2.0);
  EXPECT_TRUE(checkFeasibility(uniform, s).feasible);
  Eigen::MatrixXd bigger = uniform.rates().array() + 1e-6;
  EXPECT_FALSE(checkFeasibility(RateSchedule(s.horizon_s, bigger), s).feasible);
}

TEST(RateSchedule, FeasibilityNamesTheViolatedRowAndInterval) {
  const Scenario s = twoSensorScenario();
  Eigen::MatrixXd rates = Eigen::MatrixXd::Zero(4, 3);
  rates(2, 0) = 3.0;
  rates(2, 1) = 1.5;  // row 0: 4.5 > 4
  const Feasibility f = checkFeasibility(RateSchedule(s.horizon_s, rates), s);
  EXPECT_FALSE(f.feasible);
  EXPECT_NEAR(f.max_violation, 0.5, 1e-12);
  EXPECT_NE(f.reason.find("interval 2"), std::string::npos) << f.reason;
  EXPECT_NE(f.reason.find("row 0"), std::string::npos) << f.reason;

  rates.setZero();
  rates(1, 2) = -0.25;
  const Feasibility negative = checkFeasibility(RateSchedule(s.horizon_s, rates), s);
  EXPECT_FALSE(negative.feasible);
  EXPECT_NE(negative.reason.find("negative"), std::string::npos);
}

TEST(RateSchedule, IntervalLookupAndExpectedCounts) {
  Eigen::MatrixXd rates(2, 1);
  rates << 1.0, 3.0;
  const RateSchedule s(2.0, rates);
  EXPECT_EQ(s.intervalAt(0.0), 0);
  EXPECT_EQ(s.intervalAt(0.999), 0);
  EXPECT_EQ(s.intervalAt(1.0), 1);
  EXPECT_EQ(s.intervalAt(2.0), 1);
  EXPECT_NEAR(s.expectedCounts(0.5, 1.5)(0), 0.5 * 1.0 + 0.5 * 3.0, 1e-12);
}

}  // namespace
}  // namespace sensornet
