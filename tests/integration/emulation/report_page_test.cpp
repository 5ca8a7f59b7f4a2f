// `sensornet report` on the report of a real short run: the CSV tables hold the report's own
// counts, the page opens in headless Chromium without console errors and every plot has drawn
// marks (counted by the page's inline script into the dumped DOM); bad input exits 2 with one
// line naming the file. Without a `chromium` on PATH the browser test is skipped (install-deps
// installs it; CI has it).

#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include "launch_fixture.hpp"
#include "support/csv_rows.hpp"

namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using namespace std::chrono_literals;
using sensornet::testing::ProcessResult;
using sensornet::testing::readText;
using sensornet::testing::runProcess;

// The first `chromium` (or chromium-browser) on PATH; empty when there is none.
std::string findChromium() {
  const char* path = std::getenv("PATH");
  std::stringstream dirs(path != nullptr ? path : "");
  std::string dir;
  while (std::getline(dirs, dir, ':')) {
    for (const char* name : {"chromium", "chromium-browser"}) {
      const fs::path candidate = fs::path(dir) / name;
      if (::access(candidate.c_str(), X_OK) == 0) return candidate.string();
    }
  }
  return {};
}

using sensornet::testing::csvRows;

class ReportPage : public sensornet::testing::LaunchTest {
 protected:
  // One short real run per test (3 episodes at 10x): its report.
  json runOnce() {
    const ProcessResult r = runProcess(launchArgs(3, "10"), 90s);
    EXPECT_EQ(r.exit_code, 0) << r.err;
    return json::parse(readText(dir_ / "report.json"), nullptr, false);
  }
};

TEST_F(ReportPage, CsvTablesHoldTheReportsCountsAndThePageOpensInChromiumWithEveryPlotDrawn) {
  const sensornet::testing::LeftoverGuard guard(run_id_);
  const json report = runOnce();
  ASSERT_TRUE(report.is_object());
  // What the page draws is in the report: histogram, rates, traces of the first episodes.
  EXPECT_TRUE(report.at("latency_s").at("histogram").is_object());
  EXPECT_EQ(report.at("schedule_versions").at(0).at("rates").size(), 30u);
  EXPECT_EQ(report.at("covariance_traces").at("episodes").size(), 3u);
  EXPECT_EQ(report.at("covariance_traces").at("episodes").at(0).at("values").size(), 200u);
  EXPECT_FALSE(report.at("covariance_traces").at("surrogates").empty());
  // The launcher wrote the page beside the report by default.
  EXPECT_TRUE(fs::exists(dir_ / "report.html"));

  const fs::path page = dir_ / "page.html";
  const ProcessResult made = runProcess({sensornet::testing::kLauncher, "report",
                                         (dir_ / "report.json").string(), "--html", page.string(),
                                         "--csv", (dir_ / "tables").string()});
  ASSERT_EQ(made.exit_code, 0) << made.err;

  const auto sensors = csvRows(readText(dir_ / "tables" / "sensors.csv"));
  ASSERT_EQ(sensors.size(), report.at("sensors").size() + 1);
  for (std::size_t j = 0; j < report.at("sensors").size(); ++j) {
    const json& s = report.at("sensors")[j];
    for (std::size_t c = 0; c < sensors[0].size(); ++c) {
      EXPECT_DOUBLE_EQ(std::stod(sensors[j + 1][c]), s.at(sensors[0][c]).get<double>())
          << "sensor " << j << " " << sensors[0][c];
    }
  }
  const auto episodes = csvRows(readText(dir_ / "tables" / "episodes.csv"));
  ASSERT_EQ(episodes.size(), 4u);
  for (std::size_t i = 1; i < episodes.size(); ++i) {
    const json& e = report.at("per_episode")[i - 1];
    EXPECT_DOUBLE_EQ(std::stod(episodes[i][2]), e.at("realized_cost").get<double>());
    double received = 0.0;
    for (const json& v : e.at("received")) received += v.get<double>();
    EXPECT_DOUBLE_EQ(std::stod(episodes[i][12]), received);
  }

  const std::string chromium = findChromium();
  if (chromium.empty()) GTEST_SKIP() << "no chromium on PATH (scripts/install-deps.sh installs it)";
  const ProcessResult browser =
      runProcess({"/usr/bin/env", "HOME=" + dir_.string(), chromium, "--headless", "--disable-gpu",
                  "--no-sandbox", "--enable-logging=stderr", "--v=0",
                  "--user-data-dir=" + (dir_ / "chromium").string(), "--dump-dom",
                  "file://" + page.string()},
                 90s);
  ASSERT_EQ(browser.exit_code, 0) << browser.err;
  const std::string& dom = browser.out;
  // No console message of the page (errors are logged as CONSOLE lines with --enable-logging).
  EXPECT_EQ(browser.err.find("CONSOLE"), std::string::npos) << browser.err;
  EXPECT_NE(dom.find("data-errors=\"0\""), std::string::npos) << dom.substr(0, 2000);
  // Every plot (cost, one map per version, sensors, latency, traces) counted its drawn marks.
  const std::string html = readText(page);
  std::size_t plots = 0;
  for (std::size_t at = html.find("<svg "); at != std::string::npos; at = html.find("<svg ", at + 1)) {
    ++plots;
  }
  EXPECT_GE(plots, 5u);
  EXPECT_NE(dom.find("data-plots=\"" + std::to_string(plots) + "\""), std::string::npos);
  const std::regex marks("<svg[^>]*class=\"plot\"[^>]*id=\"([a-z0-9-]+)\"[^>]*data-marks=\"([0-9]+)\"");
  std::size_t counted = 0;
  for (auto it = std::sregex_iterator(dom.begin(), dom.end(), marks); it != std::sregex_iterator(); ++it) {
    ++counted;
    EXPECT_GT(std::stoi((*it)[2]), 0) << "no drawn mark in " << (*it)[1];
  }
  EXPECT_EQ(counted, plots) << dom.substr(0, 3000);
}

TEST_F(ReportPage, BadInputIsOneLineNamingTheFileAndExitsTwo) {
  const auto report = [&](const std::vector<std::string>& args) {
    std::vector<std::string> argv = {sensornet::testing::kLauncher, "report"};
    argv.insert(argv.end(), args.begin(), args.end());
    return runProcess(argv, 30s);
  };
  const std::string missing = (dir_ / "missing.json").string();
  ProcessResult r = report({missing, "--html", (dir_ / "a.html").string()});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find(missing), std::string::npos) << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;

  const fs::path broken = dir_ / "broken.json";
  { std::ofstream(broken) << "{\"run_id\": \"x\", "; }
  r = report({broken.string(), "--html", (dir_ / "a.html").string()});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find(broken.string() + ": expected JSON"), std::string::npos) << r.err;

  const fs::path wrong = dir_ / "wrong.json";
  { std::ofstream(wrong) << R"({"run_id": "x", "per_episode": 3, "sensors": [], "summary": {}})"; }
  r = report({wrong.string(), "--html", (dir_ / "a.html").string()});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("per_episode: expected an array"), std::string::npos) << r.err;

  const fs::path good = dir_ / "good.json";
  // The smallest report the page draws: what the record requires (run_id, status, summary).
  {
    std::ofstream(good) << R"({"run_id": "x", "status": "completed", "per_episode": [],)"
                           R"( "sensors": [], "summary": {}})";
  }
  r = report({good.string(), "--html", "/proc/sensornet-page.html"});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("/proc/sensornet-page.html"), std::string::npos) << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  r = report({good.string(), "--html", (dir_ / "ok.html").string()});
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(readText(dir_ / "ok.html").find("The run fused no episode"), std::string::npos);
}

}  // namespace
