// `sensornet replan --include` on a live run (issue 24): `--exclude` takes a sensor out of the
// plan and `--include` brings it back, as the published schedule versions in the report show;
// a sensor whose process died cannot be brought back, and the reply says so. The report goes
// into a folder that did not exist (the launcher makes it, as --csv always did).

#include <gtest/gtest.h>
#include <signal.h>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "launch_fixture.hpp"
#include "support/sanitizer.hpp"

namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using namespace std::chrono_literals;
using sensornet::testing::LeftoverGuard;
using sensornet::testing::ProcessResult;
using sensornet::testing::RunningProgram;
using sensornet::testing::runProcess;
using sensornet::testing::waitUntil;

class ReplanInclude : public sensornet::testing::LaunchTest {
 protected:
  ProcessResult replan(const std::vector<std::string>& change) const {
    std::vector<std::string> argv = {
        sensornet::testing::kLauncher, "replan", "--run-id", run_id_, "--timeout",
        sensornet::testing::scaledSeconds(60)};
    argv.insert(argv.end(), change.begin(), change.end());
    return runProcess(argv, 70s);
  }
};

// The largest rate of `sensor` in a report's schedule version entry.
double largestRate(const json& version, int sensor) {
  double largest = 0.0;
  for (const json& row : version.at("rates"))
    largest = std::max(largest, row.at(sensor).get<double>());
  return largest;
}

TEST_F(ReplanInclude, AnExcludedSensorComesBackAndADeadOneCannot) {
  const LeftoverGuard guard(run_id_);
  const fs::path report = dir_ / "new" / "reports" / "report.json";  // no such folder yet
  RunningProgram launcher(launchArgs(200, "1", report, dir_ / "logs"), 240s);
  const fs::path episode_log = report.parent_path() / "report.jsonl";
  ASSERT_TRUE(
      waitUntil([&] { return !sensornet::testing::readJsonLines(episode_log).empty(); }, 60s))
      << "no episode finished";

  const ProcessResult out = replan({"--exclude", "1"});
  ASSERT_EQ(out.exit_code, 0) << out.out << out.err;
  const ProcessResult back = replan({"--include", "1"});
  ASSERT_EQ(back.exit_code, 0) << back.out << back.err;
  EXPECT_EQ(back.out.rfind("accepted: version ", 0), 0u) << back.out;
  const ProcessResult again = replan({"--include", "1"});
  EXPECT_EQ(again.exit_code, 1);
  EXPECT_NE(again.out.find("sensor 1 is in service"), std::string::npos) << again.out;

  // Sensor 2's process dies: it cannot be brought back (the failure notice reaches the
  // coordinator through the launcher; until then the reply says it is in service).
  const std::optional<pid_t> agent =
      sensornet::testing::processOf(run_id_, SENSORNET_SENSOR_AGENT, "--sensors 2 ");
  ASSERT_TRUE(agent.has_value());
  ::kill(*agent, SIGKILL);
  std::string refusal;
  ASSERT_TRUE(waitUntil(
      [&] {
        const ProcessResult r = replan({"--include", "2"});
        refusal = r.out;
        return r.exit_code == 1 && r.out.find("failed (its process died)") != std::string::npos;
      },
      60s))
      << refusal;
  EXPECT_NE(refusal.find("refused: "), std::string::npos) << refusal;

  const std::optional<pid_t> launcher_pid =
      sensornet::testing::processOf(run_id_, sensornet::testing::kLauncher, "launch");
  ASSERT_TRUE(launcher_pid.has_value());
  ::kill(*launcher_pid, SIGINT);
  const ProcessResult& r = launcher.result();
  EXPECT_EQ(r.exit_code, 1) << r.err;  // interrupted
  const json doc = sensornet::testing::readJson(report);
  ASSERT_TRUE(doc.is_object()) << "the report is in the folder the launcher made";
  // Version 1 is planned with sensor 1; the exclusion's full-horizon version (the one just
  // before the inclusion's first) gives it rate zero throughout; every full-horizon version from
  // the inclusion on (the inclusion's, the failure policy's) gives it a rate again.
  const std::string accepted = "accepted: version ";
  const auto included_from =
      static_cast<std::uint32_t>(std::stoul(back.out.substr(accepted.size())));
  int full_versions_after = 0;
  for (const json& v : doc.at("schedule_versions")) {
    const auto number = v.at("version").get<std::uint32_t>();
    const bool full_horizon = v.at("effective_time_s").get<double>() == 0.0;
    if (number == 1) {
      EXPECT_GT(largestRate(v, 1), 0.0) << "sensor 1 was in the plan at first";
    }
    if (number + 1 == included_from) {
      EXPECT_TRUE(full_horizon) << v.dump();
      EXPECT_EQ(largestRate(v, 1), 0.0) << "excluded: rate zero";
    }
    if (number >= included_from && full_horizon) {
      ++full_versions_after;
      EXPECT_GT(largestRate(v, 1), 0.0) << "version " << number << ": sensor 1 is back";
    }
  }
  EXPECT_GE(full_versions_after, 1);
}

}  // namespace
