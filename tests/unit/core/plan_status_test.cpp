// How a plan ended, as a word: every status reads back as itself with today's spelling, solved()
// holds for exactly the endings a plan is published or written without a warning, and a failure
// keeps its reason in the text.
#include "sensornet/core/plan_status.hpp"

#include <gtest/gtest.h>

#include <string>

namespace sensornet {
namespace {

TEST(PlanStatus, EveryStatusReadsBackWithItsSpelling) {
  const std::pair<PlanStatus, std::string> spelled[] = {
      {PlanStatus::Optimal, "optimal"},
      {PlanStatus::Acceptable, "acceptable"},
      {PlanStatus::MaxIterations, "max_iterations"},
      {PlanStatus::TimeLimit, "time_limit"},
      {PlanStatus::Stalled, "stalled"},
      {PlanStatus::Stopped, "stopped"},
      {PlanStatus::NotOptimized, "not_optimized"},
      {PlanStatus::Failed, "failed"},
      {PlanStatus::Improved, "improved"},
      {PlanStatus::KeptStart, "kept_start"}};
  ASSERT_EQ(std::size(spelled), Words<PlanStatus>::kTable.size());
  for (const auto& [status, text] : spelled) {
    EXPECT_EQ(wordOf(status), text);
    EXPECT_EQ(lookUpWord<PlanStatus>(text), status) << text;
  }
  EXPECT_FALSE(lookUpWord<PlanStatus>("solved").has_value());
}

TEST(PlanStatus, SolvedAreTheEndingsAPlanIsPublishedWith) {
  for (const PlanStatus s : {PlanStatus::Optimal, PlanStatus::Acceptable, PlanStatus::NotOptimized,
                             PlanStatus::Improved, PlanStatus::KeptStart}) {
    EXPECT_TRUE(solved(s)) << wordOf(s);
  }
  for (const PlanStatus s : {PlanStatus::MaxIterations, PlanStatus::TimeLimit, PlanStatus::Stalled,
                             PlanStatus::Stopped, PlanStatus::Failed}) {
    EXPECT_FALSE(solved(s)) << wordOf(s);
  }
}

TEST(PlanStatus, AFailureSaysWhyInItsText) {
  EXPECT_EQ(statusText(PlanStatus::Failed, "locally infeasible"), "failed: locally infeasible");
  EXPECT_EQ(statusText(PlanStatus::Failed, ""), "failed");
  // Only a failure carries a reason.
  EXPECT_EQ(statusText(PlanStatus::Stalled, "ignored"), "stalled");
}

}  // namespace
}  // namespace sensornet
