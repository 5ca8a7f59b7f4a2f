// How the fusion center starts (fusion_center_start.hpp): a fresh process points its core at
// the episode log beside the report and reads nothing; a restarted one takes what the episode
// and fault logs beside the report hold, and an empty log (never none) when there is nothing.

#include "sensornet/emulator/fusion_center_start.hpp"

#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "../../support/scratch_dir.hpp"
#include "sensornet/report/report_files.hpp"

namespace sensornet::emulator {
namespace {

using nlohmann::json;

TEST(FusionCenterStart, AFreshProcessReadsNothing) {
  testing::ScratchDir dir;
  const std::string report = dir.file("report.json");
  {
    report::EpisodeLog log(report::episodeLogPath(report));
    log.append({{"episode", 0}});
  }
  FusionCenterConfig config;
  useLogsBeside(config, report, false);
  EXPECT_TRUE(config.episode_log);
  EXPECT_EQ(config.episode_log_path, dir.file("report.jsonl"));
  EXPECT_FALSE(config.resumed_log.has_value());
  EXPECT_TRUE(config.resumed_faults.empty());
}

TEST(FusionCenterStart, ARestartTakesTheEpisodesAndFaultsOfItsEarlierLives) {
  testing::ScratchDir dir;
  const std::string report = dir.file("report.json");
  {
    report::EpisodeLog log(report::episodeLogPath(report));
    log.append({{"episode", 0}, {"complete", true}});
    log.append({{"episode", 1}, {"complete", false}});
    report::EpisodeLog faults(report::faultLogPath(report));
    faults.append({{"kind", "stall"}, {"process", "sensor_agent-2"}});
  }
  FusionCenterConfig config;
  useLogsBeside(config, report, true);
  ASSERT_TRUE(config.resumed_log.has_value());
  ASSERT_EQ(config.resumed_log->size(), 2U);
  EXPECT_EQ(config.resumed_log->at(1).at("episode"), 1);
  ASSERT_EQ(config.resumed_faults.size(), 1U);
  EXPECT_EQ(config.resumed_faults[0].at("kind"), "stall");
}

TEST(FusionCenterStart, ARestartWithNothingToResumeFromStartsEmpty) {
  testing::ScratchDir dir;
  FusionCenterConfig with_path;
  useLogsBeside(with_path, dir.file("report.json"), true);  // no log written yet
  ASSERT_TRUE(with_path.resumed_log.has_value());
  EXPECT_TRUE(with_path.resumed_log->empty());
  FusionCenterConfig without;
  useLogsBeside(without, "", true);  // no --report
  EXPECT_FALSE(without.episode_log);
  ASSERT_TRUE(without.resumed_log.has_value());
  EXPECT_TRUE(without.resumed_log->empty());
}

}  // namespace
}  // namespace sensornet::emulator
