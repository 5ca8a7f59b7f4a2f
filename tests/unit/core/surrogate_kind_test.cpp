// The surrogates by name: a schedule version's kind spells a planner's surrogate as the planner
// does, "file" names a schedule read from a file, and the two enums convert into each other.
#include "sensornet/core/surrogate_kind.hpp"

#include <gtest/gtest.h>

#include <string>

namespace sensornet {
namespace {

TEST(SurrogateKind, EveryKindReadsBackWithItsSpelling) {
  const std::pair<SurrogateKind, std::string> spelled[] = {{SurrogateKind::Information, "info"},
                                                           {SurrogateKind::Covariance, "cov"},
                                                           {SurrogateKind::Uniform, "uniform"},
                                                           {SurrogateKind::MonteCarlo, "mc"},
                                                           {SurrogateKind::File, "file"}};
  ASSERT_EQ(std::size(spelled), Words<SurrogateKind>::kTable.size());
  for (const auto& [kind, text] : spelled) {
    EXPECT_EQ(wordOf(kind), text);
    EXPECT_EQ(lookUpWord<SurrogateKind>(text), kind) << text;
  }
}

TEST(SurrogateKind, APlannedKindIsItsPlannerSurrogateAndFileIsNone) {
  for (const WordOf<PlanSurrogate>& w : Words<PlanSurrogate>::kTable) {
    const SurrogateKind kind = surrogateKindOf(w.value);
    EXPECT_EQ(wordOf(kind), w.text);
    EXPECT_EQ(plannedSurrogate(kind), w.value) << w.text;
  }
  EXPECT_FALSE(plannedSurrogate(SurrogateKind::File).has_value());
  // A schedule file is no planner's surrogate: `--surrogate file` stays refused.
  EXPECT_FALSE(lookUpWord<PlanSurrogate>("file").has_value());
}

}  // namespace
}  // namespace sensornet
