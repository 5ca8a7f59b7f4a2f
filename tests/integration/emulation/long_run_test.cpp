// A run of many episodes keeps no episode in memory (issue 15): the fusion center streams each
// finished episode to the episode log and writes report.json by reading the log back. Checked
// here on what the run leaves behind: report.json carries every episode once, in the log's
// order and equal to its lines, and its totals are the sums over those entries.

#include <gtest/gtest.h>

#include <chrono>
#include <cstdint>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <set>
#include <string>
#include <vector>

#include "launch_fixture.hpp"
#include "support/process.hpp"

namespace {

using nlohmann::json;
using sensornet::testing::LaunchTest;
using sensornet::testing::LeftoverGuard;
using sensornet::testing::readJson;
using sensornet::testing::readJsonLines;
using sensornet::testing::runProcess;
using namespace std::chrono_literals;

class LongRun : public LaunchTest {};

std::uint64_t sumOf(const json& values) {
  std::uint64_t total = 0;
  for (const json& v : values) total += v.get<std::uint64_t>();
  return total;
}

TEST_F(LongRun, TheReportReadsEveryEpisodeBackFromTheEpisodeLog) {
  const LeftoverGuard guard(run_id_);
  constexpr int kEpisodes = 120;
  std::vector<std::string> argv = launchArgs(kEpisodes, "1000");
  argv.insert(argv.end(), {"--surrogate", "uniform", "--no-html"});
  const sensornet::testing::ProcessResult r = runProcess(argv, 240s);
  ASSERT_EQ(r.exit_code, 0) << r.err.substr(r.err.size() > 4000 ? r.err.size() - 4000 : 0);

  const json report = readJson(dir_ / "report.json");
  ASSERT_TRUE(report.is_object());
  const std::vector<json> logged = readJsonLines(dir_ / "report.jsonl");
  ASSERT_EQ(logged.size(), static_cast<std::size_t>(kEpisodes));
  const json& per_episode = report.at("per_episode");
  ASSERT_EQ(per_episode.size(), logged.size());
  std::set<std::uint32_t> episodes;
  std::uint64_t sent = 0, received = 0;
  for (std::size_t i = 0; i < logged.size(); ++i) {
    EXPECT_EQ(per_episode[i], logged[i]) << "entry " << i;
    episodes.insert(per_episode[i].at("episode").get<std::uint32_t>());
    sent += sumOf(per_episode[i].at("sent"));
    received += sumOf(per_episode[i].at("received"));
  }
  EXPECT_EQ(episodes.size(), static_cast<std::size_t>(kEpisodes));
  EXPECT_EQ(*episodes.rbegin(), static_cast<std::uint32_t>(kEpisodes - 1));
  EXPECT_EQ(report.at("episodes"), kEpisodes);
  EXPECT_EQ(report.at("summary").at("sent"), sent);
  EXPECT_EQ(report.at("summary").at("received"), received);
  EXPECT_GT(received, 0u);
  EXPECT_GT(report.at("latency_s").at("median").get<double>(), 0.0);
}

}  // namespace
