// What a user's test suite does with sensornet::testing: launch a run of the shipped default
// scenario, check its results against numbers recomputed from its own per-episode entries, and
// rely on the fixture to leave nothing behind, also when a test stops early.
#include <gtest/gtest.h>
#include <signal.h>

#include <cerrno>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <sensornet/testing/installed.hpp>
#include <sensornet/testing/launched_run.hpp>
#include <string>
#include <thread>

namespace {

using namespace std::chrono_literals;
namespace st = sensornet::testing;

st::LaunchOptions defaultRun(int episodes) {
  st::LaunchOptions options;
  options.program = st::installedProgram();
  options.scenario = st::installedScenario("default.yaml");
  options.episodes = episodes;
  options.time_scale = 4.0;
  options.seed = 11;
  return options;
}

// Processes whose command line names `run_id` (the launcher passes it to every child).
int processesOf(const std::string& run_id) {
  int found = 0;
  for (const auto& entry : std::filesystem::directory_iterator("/proc")) {
    std::ifstream in(entry.path() / "cmdline");
    std::string cmdline((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    if (cmdline.find(run_id) != std::string::npos) ++found;
  }
  return found;
}

TEST(LaunchedRun, ARunOfTheDefaultScenarioCompletesAndAccountsForEveryMeasurement) {
  st::LaunchedRun run(defaultRun(3));
  const st::RunResult& r = run.wait();
  ASSERT_EQ(r.exit_code, 0) << r.errors;
  EXPECT_EQ(r.status, "completed");
  ASSERT_EQ(r.episodes.size(), 3u);
  double sum = 0.0;
  for (const st::EpisodeResult& e : r.episodes) {
    EXPECT_TRUE(e.complete) << e.incomplete_reason;
    ASSERT_TRUE(e.realized_cost.has_value());
    sum += *e.realized_cost;
    ASSERT_EQ(e.sent.size(), e.received.size());
    for (std::size_t j = 0; j < e.sent.size(); ++j) {
      EXPECT_EQ(e.sent[j], e.received[j] + e.lost[j]) << "episode " << e.episode << " sensor " << j;
      EXPECT_EQ(e.lost[j], 0u);
    }
  }
  ASSERT_TRUE(r.mean.has_value());
  EXPECT_NEAR(*r.mean, sum / 3.0, 1e-9 * sum);
  ASSERT_TRUE(r.bracket_lower && r.bracket_upper);
  EXPECT_LT(*r.bracket_lower, *r.bracket_upper);
  EXPECT_TRUE(r.faults.empty());
}

TEST(LaunchedRun, ARunLeftBeforeItEndsIsStoppedAndLeavesNoProcess) {
  std::string run_id;
  pid_t launcher = -1;
  {
    st::LaunchedRun run(defaultRun(50));
    run_id = run.runId();
    launcher = run.launcherPid();
    std::this_thread::sleep_for(3s);
    ASSERT_GT(processesOf(run_id), 1) << "the run's processes are up";
  }  // a test that failed here would leave the same way
  EXPECT_EQ(::kill(launcher, 0), -1);
  EXPECT_EQ(errno, ESRCH);
  const auto until = std::chrono::steady_clock::now() + 10s;
  while (processesOf(run_id) > 0 && std::chrono::steady_clock::now() < until) {
    std::this_thread::sleep_for(100ms);
  }
  EXPECT_EQ(processesOf(run_id), 0);
}

TEST(LaunchedRun, ARequirementThatFailsIsExitFour) {
  st::LaunchOptions options = defaultRun(2);
  options.require = "mean<=0.001";
  st::LaunchedRun run(options);
  const st::RunResult& r = run.wait();
  EXPECT_EQ(r.exit_code, 4) << r.errors;
  EXPECT_EQ(r.status, "completed");
}

}  // namespace
