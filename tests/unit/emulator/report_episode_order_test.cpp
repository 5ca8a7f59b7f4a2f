// per_episode is ordered by episode (per_episode[k] is episode k), whatever order the episodes
// closed in: an episode that closed late is appended to the episode log after the next one.
// Each episode appears once, the first of repeated entries (a restarted fusion center may log
// one again); a torn last line is skipped.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <unistd.h>
#include <vector>

#include "sensornet/emulator/run_report.hpp"
#include "sensornet/report/report_files.hpp"
#include "../../support/scratch_dir.hpp"

namespace sensornet::emulator {
namespace {

using sensornet::report::EpisodeLog;
using sensornet::report::writeReportWithLog;

namespace fs = std::filesystem;
using nlohmann::json;

EpisodeResult episodeWithCost(std::uint32_t episode, double cost) {
  EpisodeResult r;
  r.episode = episode;
  r.realized_cost = r.realtime_cost = r.received_realtime_cost = cost;
  r.bracket = r.delivered_bracket = {1.0, 2.0};
  r.nees = 4.0;
  r.sensors.resize(2);
  r.complete = true;
  return r;
}

// (episode, realized_cost) of each per_episode entry, in order.
std::vector<std::pair<std::uint32_t, double>> episodesOf(const json& report) {
  std::vector<std::pair<std::uint32_t, double>> out;
  for (const json& e : report.at("per_episode")) {
    out.emplace_back(e.at("episode").get<std::uint32_t>(), e.at("realized_cost").get<double>());
  }
  return out;
}

class ReportEpisodeOrder : public ::testing::Test {
 protected:
  sensornet::testing::ScratchDir scratch_;
  const fs::path dir_ = scratch_.path();
};

const std::vector<std::pair<std::uint32_t, double>> kInEpisodeOrder{{0, 10.0}, {1, 11.0}, {2, 12.0}};

TEST_F(ReportEpisodeOrder, AnEpisodeThatClosedLateTakesItsPlaceInALoggedReport) {
  const fs::path log = dir_ / "report.jsonl";
  RunReport report("run", "digest", 2, 4, log);
  {
    EpisodeLog writer(log);
    for (const auto& [episode, cost] :
         std::vector<std::pair<std::uint32_t, double>>{{0, 10.0}, {2, 12.0}, {1, 11.0}, {1, 99.0}}) {
      const json entry = episodeEntry(episodeWithCost(episode, cost));
      writer.append(entry);
      report.add(entry);
    }
  }
  std::ofstream(log, std::ios::app) << R"({"episode": 3, "realized_cost)";  // torn by a crash
  EXPECT_EQ(episodesOf(report.toJson("completed", json::array(), json::array())), kInEpisodeOrder);

  // The launcher's rewrite streams the same entries in from the log.
  std::ostringstream written;
  writeReportWithLog(written, report.toJsonWithoutEpisodes("completed", json::array(), json::array()),
                     log, 2);
  EXPECT_EQ(episodesOf(json::parse(written.str())), kInEpisodeOrder);
}

TEST_F(ReportEpisodeOrder, AnEpisodeThatClosedLateTakesItsPlaceInAHeldReport) {
  RunReport report("run", "digest", 2, 4);  // no episode log: the entries are held
  for (const auto& [episode, cost] :
       std::vector<std::pair<std::uint32_t, double>>{{2, 12.0}, {0, 10.0}, {1, 11.0}, {2, 98.0}}) {
    report.add(episodeEntry(episodeWithCost(episode, cost)));
  }
  EXPECT_EQ(episodesOf(report.toJson("completed", json::array(), json::array())), kInEpisodeOrder);
}

}  // namespace
}  // namespace sensornet::emulator
