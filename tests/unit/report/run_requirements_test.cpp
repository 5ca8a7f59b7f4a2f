// --require: the grammar (what is accepted, what is refused with which message) and the checks
// against a report built here by hand, so every measured value is known independently.
#include "sensornet/report/run_requirements.hpp"

#include <gtest/gtest.h>

#include "sensornet/core/input_error.hpp"

namespace sensornet::report {
namespace {

using nlohmann::json;

// A degraded run of 4 planned episodes, 3 complete, 2 of 1000 measurements lost, p99 1.5 ms.
json sampleReport() {
  return {{"run_id", "sample"},
          {"status", "degraded"},
          {"episodes_planned", 4},
          {"faults", json::array({{{"kind", "lost"}}})},
          {"latency_s", {{"median", 0.0004}, {"p99", 0.0015}}},
          {"summary",
           {{"episodes", 4},
            {"episodes_complete", 3},
            {"episodes_incomplete", 1},
            {"mean", 2.5},
            {"realtime_mean", 2.75},
            {"ci95", 0.125},
            {"meets_bracket", true},
            {"meets_delivered_bracket", nullptr},
            {"sent", 1000},
            {"lost", 2},
            {"rejected", 0},
            {"late", 7}}}};
}

std::string errorOf(std::string_view spec) {
  try {
    (void)parseRequirements(spec);
  } catch (const InputError& e) {
    return e.what();
  }
  return "(accepted)";
}

bool passes(std::string_view spec, const json& report = sampleReport()) {
  const std::vector<RequirementCheck> checks = checkRequirements(parseRequirements(spec), report);
  EXPECT_EQ(checks.size(), 1u);
  return checks.at(0).pass;
}

TEST(RunRequirements, ParsesTheIssuesExample) {
  const std::vector<Requirement> r =
      parseRequirements("meets-bracket,no-loss,latency-p99<=5ms,episodes-complete");
  ASSERT_EQ(r.size(), 4u);
  EXPECT_EQ(r[0].name, "meets-bracket");
  EXPECT_EQ(r[0].comparison, Comparison::Holds);
  EXPECT_EQ(r[2].name, "latency-p99");
  EXPECT_EQ(r[2].comparison, Comparison::AtMost);
  EXPECT_DOUBLE_EQ(r[2].limit, 0.005);
  EXPECT_EQ(r[2].text, "latency-p99<=5ms");
}

TEST(RunRequirements, DurationsTakeMicrosecondsMillisecondsOrSeconds) {
  EXPECT_DOUBLE_EQ(parseRequirements("latency-median<500us")[0].limit, 500e-6);
  EXPECT_DOUBLE_EQ(parseRequirements("latency-median<=2.5ms")[0].limit, 2.5e-3);
  EXPECT_DOUBLE_EQ(parseRequirements("latency-median<=1s")[0].limit, 1.0);
  EXPECT_NE(errorOf("latency-p99<=5").find("a duration with its unit us, ms or s"),
            std::string::npos)
      << errorOf("latency-p99<=5");
  EXPECT_NE(errorOf("latency-p99<=5min").find("unit"), std::string::npos);
}

TEST(RunRequirements, RefusesWhatItDoesNotKnowBeforeTheRun) {
  const std::string unknown = errorOf("no-los");
  EXPECT_EQ(unknown.rfind("--require: no-los: expected one of the known criteria (", 0), 0u)
      << unknown;
  EXPECT_NE(unknown.find("no-loss"), std::string::npos) << unknown;
  EXPECT_NE(errorOf("").find("at least one criterion"), std::string::npos);
  EXPECT_NE(errorOf("no-loss,,meets-bracket").find("empty one"), std::string::npos);
  EXPECT_NE(errorOf("no-loss<=1").find("nothing to compare"), std::string::npos);
  EXPECT_NE(errorOf("lost").find("a comparison"), std::string::npos);
  EXPECT_NE(errorOf("lost<=1.5").find("whole number"), std::string::npos);
  EXPECT_NE(errorOf("lost<=-1").find("whole number"), std::string::npos);
  EXPECT_NE(errorOf("mean<=abc").find("a number after the comparison"), std::string::npos);
  EXPECT_NE(errorOf("mean<=3ms").find("a plain number"), std::string::npos);
}

TEST(RunRequirements, YesNoPropertiesReadTheReport) {
  EXPECT_FALSE(passes("completed"));  // degraded
  EXPECT_FALSE(passes("episodes-complete"));  // 3 of 4
  EXPECT_TRUE(passes("meets-bracket"));
  EXPECT_FALSE(passes("no-loss"));
  EXPECT_TRUE(passes("no-rejects"));
  EXPECT_FALSE(passes("no-faults"));

  json clean = sampleReport();
  clean["status"] = "completed";
  clean["summary"]["episodes_complete"] = 4;
  clean["summary"]["lost"] = 0;
  clean["faults"] = json::array();
  EXPECT_TRUE(passes("completed", clean));
  EXPECT_TRUE(passes("episodes-complete", clean));
  EXPECT_TRUE(passes("no-loss", clean));
  EXPECT_TRUE(passes("no-faults", clean));
}

TEST(RunRequirements, ComparisonsUseEachOperatorAtTheBoundary) {
  EXPECT_TRUE(passes("latency-p99<=1.5ms"));
  EXPECT_FALSE(passes("latency-p99<1.5ms"));
  EXPECT_TRUE(passes("latency-p99>=1500us"));
  EXPECT_FALSE(passes("latency-p99>1500us"));
  EXPECT_TRUE(passes("lost=2"));
  EXPECT_TRUE(passes("lost==2"));
  EXPECT_FALSE(passes("lost<=1"));
  EXPECT_TRUE(passes("episodes>=4"));
  EXPECT_TRUE(passes("mean<=2.5"));
  EXPECT_FALSE(passes("realtime-mean<=2.5"));
  EXPECT_TRUE(passes("ci95<0.2"));
  EXPECT_TRUE(passes("loss-fraction<=0.002"));   // 2 / 1000
  EXPECT_FALSE(passes("loss-fraction<0.002"));
  EXPECT_TRUE(passes("late<=7"));
  EXPECT_TRUE(passes("episodes-incomplete=1"));
}

TEST(RunRequirements, AValueTheReportLacksFailsAndSaysWhy) {
  const auto checks = checkRequirements(parseRequirements("meets-delivered-bracket"),
                                        sampleReport());
  ASSERT_EQ(checks.size(), 1u);
  EXPECT_FALSE(checks[0].pass);
  EXPECT_EQ(checks[0].measured, "not in the report (summary.meets_delivered_bracket is null)");
  json no_latency = sampleReport();
  no_latency.erase("latency_s");
  EXPECT_FALSE(passes("latency-p99<=1s", no_latency));
  json not_a_report = sampleReport();
  not_a_report.erase("run_id");
  const auto refused = checkRequirements(parseRequirements("no-faults"), not_a_report);
  EXPECT_FALSE(refused.at(0).pass);
  EXPECT_NE(refused.at(0).measured.find("run_id"), std::string::npos) << refused.at(0).measured;
}

TEST(RunRequirements, DescribesEachCheckWithTheMeasuredValue) {
  const auto checks =
      checkRequirements(parseRequirements("latency-p99<=5ms,no-loss,lost<=2"), sampleReport());
  ASSERT_EQ(checks.size(), 3u);
  EXPECT_EQ(describe(checks[0]), "require latency-p99<=5ms: pass (measured 1.5 ms)");
  EXPECT_EQ(describe(checks[1]), "require no-loss: FAIL (measured no)");
  EXPECT_EQ(describe(checks[2]), "require lost<=2: pass (measured 2)");
  const json j = toJson(checks);
  ASSERT_EQ(j.size(), 3u);
  EXPECT_EQ(j[1]["criterion"], "no-loss");
  EXPECT_EQ(j[1]["pass"], false);
}

TEST(RunRequirements, AFailedCriterionExitsFourUnlessTheRunFailedOutright) {
  const auto failing = checkRequirements(parseRequirements("no-loss"), sampleReport());
  const auto passing = checkRequirements(parseRequirements("no-rejects"), sampleReport());
  EXPECT_EQ(gatedExitCode(0, failing), kExitRequirementFailed);
  EXPECT_EQ(gatedExitCode(3, failing), kExitRequirementFailed);
  EXPECT_EQ(gatedExitCode(1, failing), 1);
  EXPECT_EQ(gatedExitCode(0, passing), 0);
  EXPECT_EQ(gatedExitCode(3, passing), 3);
}

TEST(RunRequirements, HelpListsEveryCriterion) {
  const std::string help = requirementsHelp();
  for (const char* name : {"meets-bracket", "no-loss", "latency-p99<=DURATION",
                           "episodes-complete", "lost<=COUNT", "mean<=NUMBER"}) {
    EXPECT_NE(help.find(name), std::string::npos) << name;
  }
}

}  // namespace
}  // namespace sensornet::report
