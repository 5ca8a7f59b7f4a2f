// The page of a sweep (sweep_page.hpp): a plot for each axis that varies, its points the mean
// of the cells at each value with a 95% Student-t interval over them (checked against the
// interval computed here from the t table), and every cell in the table, failed ones with why.

#include "sensornet/report/sweep_page.hpp"

#include <gtest/gtest.h>

#include <string>
#include <vector>

namespace sensornet::report {
namespace {

using nlohmann::json;

json cell(const std::string& planner, double budget, int seed, double mean) {
  return {{"key", planner + std::to_string(budget) + std::to_string(seed)},
          {"scenario", "random"},
          {"states", 5},
          {"sensors", 30},
          {"scenario_seed", seed},
          {"noise_scale", 1.0},
          {"budget", budget},
          {"planner", planner},
          {"surrogate", planner},
          {"seed", seed},
          {"runs", 100},
          {"status", "ok"},
          {"mean", mean},
          {"ci95", 0.5},
          {"bracket_info", mean - 3.0},
          {"bracket_cov", mean + 3.0},
          {"plan_status", "optimal"}};
}

TEST(SweepPage, PlotsEachAxisThatVariesWithTheIntervalOverItsCells) {
  std::vector<json> rows = {cell("info", 2, 1, 10.0),    cell("info", 2, 2, 14.0),
                            cell("info", 4, 1, 6.0),     cell("info", 4, 2, 6.0),
                            cell("uniform", 2, 1, 20.0), cell("uniform", 4, 1, 9.0)};
  json failed = cell("cov", 2, 1, 0.0);
  failed["status"] = "failed";
  failed["reason"] = "plan <did not> converge";
  rows.push_back(failed);
  const std::string page = sweepPage("test & co", rows);
  EXPECT_NE(page.find("<title>sensornet sweep test &amp; co</title>"), std::string::npos);
  EXPECT_NE(page.find("7 cells · 6 ok · 1 failed"), std::string::npos);
  EXPECT_NE(page.find("id=\"fig-budget\""), std::string::npos);
  EXPECT_EQ(page.find("id=\"fig-sensors\""), std::string::npos);  // one value: no plot
  // info at budget 2: cells 10 and 14, mean 12, s = 2.828427, t(0.975, 1) = 12.7062047:
  // half-width 12.7062047 * 2.828427 / sqrt(2) = 25.4124094.
  EXPECT_NE(page.find("info at 2: 12 [-13.4124, 37.4124] over 2 cells; bracket [9, 15]"),
            std::string::npos)
      << page.substr(0, 4000);
  // One cell at a value: its own Monte Carlo interval.
  EXPECT_NE(page.find("uniform at 4: 9 [8.5, 9.5] over 1 cell; bracket [6, 12]"),
            std::string::npos);
  // The failed cell is in the table, its reason escaped; it is in no plot.
  EXPECT_NE(page.find("failed: plan &lt;did not&gt; converge"), std::string::npos);
  EXPECT_EQ(page.find("cov at 2"), std::string::npos);
}

TEST(SweepPage, NothingThatVariesIsSaidNotPlotted) {
  const std::string page = sweepPage("one", {cell("info", 2, 1, 10.0)});
  EXPECT_NE(page.find("No axis of this experiment takes two values or more"), std::string::npos);
  EXPECT_EQ(page.find("<svg"), std::string::npos);
}

}  // namespace
}  // namespace sensornet::report
