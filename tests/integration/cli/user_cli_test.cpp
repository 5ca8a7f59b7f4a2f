// The small things a new user trips on (issue 24): word options that show their words and refuse
// a bad one in one line, an unknown option named in one line, output folders made for every
// output option, `coordinator plan --out -`, and `sensornet runs` over a scratch folder with a
// finished, a live and a broken run. Runs the real programs.

#include <fcntl.h>
#include <gtest/gtest.h>
#include <sys/file.h>
#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include "support/process.hpp"
#include "support/scratch_dir.hpp"

namespace sensornet {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using sensornet::testing::ProcessResult;
using sensornet::testing::runProcess;

const std::string kCoordinator = SENSORNET_COORDINATOR;
const std::string kFusionCenter = SENSORNET_FUSION_CENTER;
const std::string kLauncher = SENSORNET_LAUNCHER;
const std::string kDefaultScenario = std::string(SENSORNET_SOURCE_DIR) + "/scenarios/default.yaml";

class UserCli : public ::testing::Test {
 protected:

  static std::string readText(const fs::path& path) {
    std::ifstream in(path);
    std::stringstream text;
    text << in.rdbuf();
    return text.str();
  }

  sensornet::testing::ScratchDir scratch_;
  const fs::path dir_ = scratch_.path();
};

void expectOneLine(const ProcessResult& r, const std::string& line) {
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_EQ(r.err, line + "\n");
  EXPECT_TRUE(r.out.empty()) << r.out;
}

// ---- word options ------------------------------------------------------------------------

TEST_F(UserCli, EveryWordOptionShowsItsWordsInHelp) {
  const std::vector<std::vector<std::string>> helps = {
      {kCoordinator, "serve", "--help"},     {kCoordinator, "plan", "--help"},
      {kFusionCenter, "evaluate", "--help"}, {kLauncher, "launch", "--help"},
      {kLauncher, "replan", "--help"},       {kLauncher, "pki", "init", "--help"}};
  for (const auto& argv : helps) {
    const ProcessResult r = runProcess(argv);
    ASSERT_EQ(r.exit_code, 0) << argv[0] << " " << argv[1] << ": " << r.err;
    // What CLI11 shows by itself: "ENUM:value in {continue->1,replan->0,stop->2}", "TEXT:{a,b}".
    EXPECT_FALSE(std::regex_search(r.out, std::regex("[a-z]->[0-9]"))) << argv[1] << ":\n" << r.out;
    EXPECT_EQ(r.out.find("ENUM"), std::string::npos) << argv[1] << ":\n" << r.out;
    EXPECT_EQ(r.out.find(":{"), std::string::npos) << argv[1] << ":\n" << r.out;
  }
  const ProcessResult serve = runProcess({kCoordinator, "serve", "--help"});
  EXPECT_NE(serve.out.find("--on-sensor-failure {replan,continue,stop} [replan]"),
            std::string::npos)
      << serve.out;
  EXPECT_NE(serve.out.find("--surrogate {info,cov,uniform,mc} [cov]"), std::string::npos)
      << serve.out;
  EXPECT_NE(serve.out.find("--arrivals {poisson,timetable}"), std::string::npos) << serve.out;
  const ProcessResult launch = runProcess({kLauncher, "launch", "--help"});
  EXPECT_NE(launch.out.find("--network-aware {auto,yes,no} [auto]"), std::string::npos)
      << launch.out;
  const ProcessResult plan = runProcess({kCoordinator, "plan", "--help"});
  EXPECT_NE(plan.out.find("--method {pqn,ipopt} [pqn]"), std::string::npos) << plan.out;
}

TEST_F(UserCli, ABadWordIsOneLineNamingTheWords) {
  expectOneLine(runProcess({kCoordinator, "serve", "--scenario", kDefaultScenario, "--run-id", "x",
                            "--on-sensor-failure", "x"}),
                "coordinator: error: --on-sensor-failure: 'x' is not one of replan, continue, "
                "stop (see --help)");
  expectOneLine(runProcess({kLauncher, "launch", kDefaultScenario, "--surrogate", "covariance"}),
                "sensornet: error: --surrogate: 'covariance' is not one of info, cov, uniform, "
                "mc (see --help)");
  expectOneLine(runProcess({kFusionCenter, "evaluate", "--scenario", kDefaultScenario, "--runs",
                            "10", "--seed", "1", "--arrivals", "regular"}),
                "fusion_center: error: --arrivals: 'regular' is not one of poisson, timetable "
                "(see --help)");
  expectOneLine(runProcess({kCoordinator, "plan", "--scenario", kDefaultScenario, "--out",
                            (dir_ / "p.json").string(), "--method", "newton"}),
                "coordinator: error: --method: 'newton' is not one of pqn, ipopt (see --help)");
}

TEST_F(UserCli, AWordInAnotherCaseIsTaken) {
  const ProcessResult r = runProcess({kCoordinator, "plan", "--scenario", kDefaultScenario,
                                      "--surrogate", "UNIFORM", "--out", "-"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(json::parse(r.out).at("surrogate"), "uniform");
}

// ---- an unknown option -----------------------------------------------------------------------

TEST_F(UserCli, AnUnknownOptionIsOneLineNamingItAndTheNearestOne) {
  // CLI11 says "The following arguments were not expected: /tmp/x/report.html --html".
  expectOneLine(runProcess({kLauncher, "launch", kDefaultScenario, "--html",
                            (dir_ / "x" / "report.html").string()}),
                "sensornet: error: unknown option --html (did you mean --no-html?) (see --help)");
  EXPECT_FALSE(fs::exists(dir_ / "x"));
}

// ---- output folders ------------------------------------------------------------------------

TEST_F(UserCli, PlanOutMakesTheMissingFolders) {
  const fs::path out = dir_ / "new" / "plans" / "uniform.json";
  const ProcessResult r = runProcess({kCoordinator, "plan", "--scenario", kDefaultScenario,
                                      "--surrogate", "uniform", "--out", out.string()});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(json::parse(readText(out)).contains("rates"));
}

TEST_F(UserCli, ReportHtmlAndCsvMakeTheMissingFolders) {
  // The smallest report `sensornet report` reads: no episode, no sensor.
  const fs::path report = dir_ / "report.json";
  std::ofstream(report) << R"({"run_id": "r", "status": "failed", "per_episode": [],
                               "sensors": [], "summary": {}})";
  const fs::path page = dir_ / "pages" / "run" / "report.html";
  const fs::path tables = dir_ / "tables" / "run";
  const ProcessResult r = runProcess(
      {kLauncher, "report", report.string(), "--html", page.string(), "--csv", tables.string()});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(readText(page).find("<html"), std::string::npos);
  EXPECT_TRUE(fs::exists(tables / "episodes.csv"));
  // A folder where one is to be made is refused in one line, and nothing is written.
  std::ofstream(dir_ / "file") << "x";
  const ProcessResult refused = runProcess(
      {kLauncher, "report", report.string(), "--html", (dir_ / "file" / "p.html").string()});
  EXPECT_EQ(refused.exit_code, 2);
  EXPECT_NE(refused.err.find("--html " + (dir_ / "file" / "p.html").string()), std::string::npos)
      << refused.err;
  EXPECT_EQ(std::count(refused.err.begin(), refused.err.end(), '\n'), 1) << refused.err;
}

// ---- plan --out - --------------------------------------------------------------------------

TEST_F(UserCli, PlanOutDashWritesTheScheduleFileToStandardOutputAndNothingElse) {
  const fs::path file = dir_ / "plan.json";
  const ProcessResult to_file = runProcess({kCoordinator, "plan", "--scenario", kDefaultScenario,
                                            "--surrogate", "uniform", "--out", file.string()});
  ASSERT_EQ(to_file.exit_code, 0) << to_file.err;
  const ProcessResult r = runProcess({kCoordinator, "plan", "--scenario", kDefaultScenario,
                                      "--surrogate", "uniform", "--out", "-"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  // The whole of standard output is the schedule file, as --out FILE writes it.
  EXPECT_EQ(json::parse(r.out), json::parse(readText(file)));
  EXPECT_FALSE(fs::exists("-")) << "no file named -";
  EXPECT_NE(r.err.find("written    to standard output"), std::string::npos) << r.err;
  // It reads back as a schedule: evaluate takes it.
  const fs::path copy = dir_ / "copy.json";
  std::ofstream(copy) << r.out;
  const ProcessResult evaluated =
      runProcess({kFusionCenter, "evaluate", "--scenario", kDefaultScenario, "--schedule",
                  copy.string(), "--runs", "10", "--seed", "1", "--json"});
  EXPECT_EQ(evaluated.exit_code, 0) << evaluated.err;
  expectOneLine(
      runProcess({kCoordinator, "plan", "--scenario", kDefaultScenario, "--out", "-", "--json"}),
      "coordinator: error: command line: --json: expected no --json with --out - (the "
      "schedule file takes standard output; the summary goes to standard error)");
}

// ---- sensornet runs ------------------------------------------------------------------------

class Runs : public UserCli {
 protected:
  Runs() : scratch_(dir_ / "scratch") {
    fs::create_directories(scratch_);
    fs::permissions(scratch_, fs::perms::owner_all);
  }
  ~Runs() override {
    if (lock_fd_ >= 0) ::close(lock_fd_);
  }

  ProcessResult runs(std::vector<std::string> args) const {
    std::vector<std::string> argv = {"/usr/bin/env", "SENSORNET_SCRATCH_DIR=" + scratch_.string(),
                                     kLauncher, "runs"};
    argv.insert(argv.end(), args.begin(), args.end());
    return runProcess(argv);
  }
  void write(const fs::path& path, const std::string& text) const {
    fs::create_directories(path.parent_path());
    std::ofstream(path) << text;
  }
  json record(const std::string& id, const std::string& scenario, int episodes,
              const std::string& started) const {
    return {{"run_id", id},           {"scenario", scenario},
            {"episodes", episodes},   {"report", (scratch_ / id / "report.json").string()},
            {"launcher_pid", 999999}, {"started_at", started}};
  }
  // A finished run (its report says degraded, 4 of 5 episodes), a live one whose launch lock
  // this test holds (2 episodes in its log so far), and a broken one (a log, nothing else).
  void makeThreeRuns() {
    write(scratch_ / "run-done" / "run.json",
          record("run-done", "/s/lossy.yaml", 5, "2026-12-01T10:00:00Z").dump());
    write(scratch_ / "run-done" / "launch.lock", "123\n");
    write(scratch_ / "run-done" / "report.json",
          R"({"run_id": "run-done", "status": "degraded", "episodes": 4, "episodes_planned": 5,)"
          R"( "summary": {}, "per_episode": []})");
    write(scratch_ / "run-live" / "run.json",
          record("run-live", "/s/default.yaml", 20, "2026-12-01T11:00:00Z").dump());
    write(scratch_ / "run-live" / "report.jsonl", "{\"episode\": 0}\n{\"episode\": 1}\n");
    write(scratch_ / "run-live" / "launch.lock", std::to_string(::getpid()) + "\n");
    lock_fd_ = ::open((scratch_ / "run-live" / "launch.lock").c_str(), O_RDWR | O_CLOEXEC);
    ASSERT_GE(lock_fd_, 0);
    ASSERT_EQ(::flock(lock_fd_, LOCK_EX | LOCK_NB), 0);
    write(scratch_ / "run-broken" / "coordinator.log", "[coordinator] info: ...\n");
    write(scratch_ / "current-run", "{}");  // a file, not a run
  }

  fs::path scratch_;
  int lock_fd_ = -1;
};

TEST_F(Runs, ListsEachRunWithItsStatusStartEpisodesAndScenario) {
  makeThreeRuns();
  const ProcessResult r = runs({"--json"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const json doc = json::parse(r.out);
  EXPECT_EQ(doc.at("scratch"), scratch_.string());
  ASSERT_EQ(doc.at("runs").size(), 3u) << doc.dump(2);
  std::map<std::string, json> by_id;
  for (const json& run : doc.at("runs")) by_id[run.at("run_id").get<std::string>()] = run;
  const json& done = by_id.at("run-done");
  EXPECT_EQ(done.at("state"), "finished");
  EXPECT_EQ(done.at("status"), "degraded");
  EXPECT_EQ(done.at("episodes"), 4);
  EXPECT_EQ(done.at("episodes_planned"), 5);
  EXPECT_EQ(done.at("scenario"), "/s/lossy.yaml");
  EXPECT_EQ(done.at("started_at"), "2026-12-01T10:00:00Z");
  const json& live = by_id.at("run-live");
  EXPECT_EQ(live.at("state"), "live");
  EXPECT_TRUE(live.at("status").is_null());
  EXPECT_EQ(live.at("episodes"), 2) << "the lines of its episode log";
  EXPECT_EQ(live.at("episodes_planned"), 20);
  const json& broken = by_id.at("run-broken");
  EXPECT_EQ(broken.at("state"), "unknown");
  EXPECT_TRUE(broken.at("scenario").is_null());

  const ProcessResult table = runs({});
  ASSERT_EQ(table.exit_code, 0) << table.err;
  std::vector<std::string> lines;
  std::stringstream text(table.out);
  for (std::string line; std::getline(text, line);) lines.push_back(line);
  ASSERT_EQ(lines.size(), 4u) << table.out;
  EXPECT_EQ(lines[0].rfind("RUN", 0), 0u) << table.out;
  // Oldest start first, the run without a start time last.
  EXPECT_EQ(lines[1].rfind("run-done ", 0), 0u) << table.out;
  EXPECT_NE(lines[1].find("degraded"), std::string::npos) << table.out;
  EXPECT_NE(lines[1].find(" 4/5 "), std::string::npos) << table.out;
  EXPECT_EQ(lines[2].rfind("run-live ", 0), 0u) << table.out;
  EXPECT_NE(lines[2].find("live"), std::string::npos) << table.out;
  EXPECT_NE(lines[2].find(" 2/20 "), std::string::npos) << table.out;
  EXPECT_EQ(lines[3].rfind("run-broken ", 0), 0u) << table.out;
  EXPECT_NE(lines[3].find("unknown"), std::string::npos) << table.out;
}

TEST_F(Runs, RemoveFinishedRemovesOnlyTheFinishedRun) {
  makeThreeRuns();
  const ProcessResult r = runs({"--remove-finished"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.out, "removed run-done (degraded)\n");
  EXPECT_FALSE(fs::exists(scratch_ / "run-done"));
  EXPECT_TRUE(fs::exists(scratch_ / "run-live" / "report.jsonl"));
  EXPECT_TRUE(fs::exists(scratch_ / "run-broken" / "coordinator.log"));
}

TEST_F(Runs, RmNeverRemovesALiveRunAndRefusesAnUnknownId) {
  makeThreeRuns();
  const ProcessResult live = runs({"rm", "run-broken", "run-live"});
  EXPECT_EQ(live.exit_code, 2) << live.err;
  EXPECT_NE(live.err.find("run-live is (its launch lock is held); nothing was removed"),
            std::string::npos)
      << live.err;
  EXPECT_TRUE(fs::exists(scratch_ / "run-live" / "report.jsonl"));
  EXPECT_TRUE(fs::exists(scratch_ / "run-broken")) << "nothing removed";
  const ProcessResult unknown = runs({"rm", "../scratch"});
  EXPECT_EQ(unknown.exit_code, 2);
  const ProcessResult removed = runs({"rm", "run-broken", "--json"});
  ASSERT_EQ(removed.exit_code, 0) << removed.err;
  EXPECT_EQ(json::parse(removed.out).at("removed").at(0).at("run_id"), "run-broken");
  EXPECT_FALSE(fs::exists(scratch_ / "run-broken"));
  // Once its launch ends (the lock is released) the run is no longer live.
  ::close(lock_fd_);
  lock_fd_ = -1;
  const ProcessResult after = runs({"--json"});
  const json listed = json::parse(after.out);  // kept: a loop over a temporary's member dangles
  for (const json& run : listed.at("runs")) {
    if (run.at("run_id") == "run-live") {
      EXPECT_EQ(run.at("state"), "unknown");
    }
  }
}

TEST_F(Runs, AnEmptyOrMissingScratchFolderHasNoRuns) {
  EXPECT_EQ(runs({}).out, "no runs in " + scratch_.string() + "\n");
  fs::remove_all(scratch_);
  EXPECT_EQ(runs({}).out, "no runs in " + scratch_.string() + " (it does not exist)\n");
}

}  // namespace
}  // namespace sensornet
