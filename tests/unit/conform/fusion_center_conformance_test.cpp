// The rules of a fusion center's role (checkFusionCenter) on made-up runs: Reports equal to the
// reference's pass every rule; each way of breaking one rule fails that rule and no other.

#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "sensornet/conform/sensor_conformance.hpp"
#include "sensornet/core/scenario.hpp"

namespace sensornet::conform {
namespace {

constexpr std::int64_t kSecond = 1'000'000'000;
constexpr std::int64_t kT0 = 1'700'000'000LL * kSecond;

class FusionCenterConformanceTest : public ::testing::Test {
 protected:
  FusionCenterConformanceTest() {
    RandomPlantSpec spec;
    spec.state_dim = 2;
    spec.sensor_count = 2;
    spec.seed = 3;
    const Scenario scenario = generateRandomScenario(spec);
    emulator::RunInputState::Update update;
    run_.inputs.onScenario({scenario, "digest", "yaml", 1}, update);
    run_.first_ns = kT0;
    run_.time_scale = 2.0;
    const auto episode_ns = static_cast<std::int64_t>(scenario.horizon_s / 2.0 * kSecond);
    for (std::uint32_t k = 0; k < 3; ++k) {
      const std::int64_t start = kT0 + kSecond + k * (episode_ns + kSecond / 10);
      run_.starts_ns[k] = start;
      RecordedReport r{k,
                       1.5 + k,
                       1.0,
                       2.5,
                       1.9,
                       true,
                       {{10, 10, 0}, {4 + k, 4 + k, 0}},
                       start + episode_ns + kSecond / 100};
      run_.reports.push_back(r);
      r.received_ns += 1000;
      run_.reference_reports.push_back(r);
    }
    run_.shutdown_ns = run_.starts_ns.at(2) + episode_ns + kSecond;
    report::RunRecord record;
    record.status = emulator::RunStatus::Completed;
    facts_.launcher_exit = 0;
    facts_.report = record;
    facts_.program_exit = 0;
  }

  void expectOnlyFails(const std::string& rule) const {
    std::vector<std::string> failing;
    for (const RuleCheck& r : checkFusionCenter(run_, facts_, 1e-9)) {
      if (!r.pass) failing.push_back(r.rule + ": " + r.evidence);
    }
    ASSERT_EQ(failing.size(), 1u) << ::testing::PrintToString(failing);
    EXPECT_EQ(failing[0].rfind(rule + ":", 0), 0u) << failing[0];
  }

  RecordedRun run_;
  RunFacts facts_;
};

TEST_F(FusionCenterConformanceTest, ReportsEqualToTheReferencePassEveryRule) {
  const std::vector<RuleCheck> rules = checkFusionCenter(run_, facts_, 1e-9);
  EXPECT_EQ(rules.size(), 7u);
  for (const RuleCheck& r : rules) EXPECT_TRUE(r.pass) << r.rule << ": " << r.evidence;
}

TEST_F(FusionCenterConformanceTest, ACostOffByMoreThanTheToleranceFailsTheCosts) {
  run_.reports[1].realized_cost *= 1.0 + 1e-6;
  expectOnlyFails("costs");
}

TEST_F(FusionCenterConformanceTest, AMissingOrEarlyOrRepeatedReportFailsReportPerEpisode) {
  run_.reports.erase(run_.reports.begin() + 2);
  expectOnlyFails("report-per-episode");
  run_.reports.push_back(run_.reports[1]);  // episode 1 twice
  expectOnlyFails("report-per-episode");
  run_.reports.pop_back();
  run_.reports.push_back(run_.reference_reports[2]);
  run_.reports.back().received_ns = run_.starts_ns.at(2) + kSecond / 10;  // before its end
  expectOnlyFails("report-per-episode");
}

TEST_F(FusionCenterConformanceTest, AnotherBracketFailsTheBracket) {
  run_.reports[0].bracket_upper = 2.6;
  expectOnlyFails("bracket");
}

TEST_F(FusionCenterConformanceTest, OtherCountsOrCompletenessFailTheCounts) {
  run_.reports[2].counts[1].received -= 1;
  run_.reports[2].counts[1].lost += 1;
  expectOnlyFails("counts");
  run_.reports[2].counts = run_.reference_reports[2].counts;
  run_.reports[0].complete = false;
  expectOnlyFails("counts");
}

TEST_F(FusionCenterConformanceTest, StayingAfterTheShutdownFailsLeaving) {
  facts_.program_exit.reset();
  facts_.program_end = "was still running 5 s after the run ended: stopped";
  expectOnlyFails("leaving");
}

}  // namespace
}  // namespace sensornet::conform
