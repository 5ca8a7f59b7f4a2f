// `sensornet launch` as a gate that can be trusted (issue 10), with real processes over Cyclone
// DDS on loopback:
// - what would lose or misplace results is refused with exit 2 before any process starts, and
//   left as it was: a report path that is a device, a FIFO, a directory or a link, in a folder
//   where no file can be created; a scratch folder that is a link, another user's or writable
//   by others; out-of-range options and bad seeds;
// - one run per id: a second launch of a live run is refused at once, and the first run's
//   results are those of a clean run with the same seed;
// (Process deaths, which a run survives, are tested in faults_test.cpp.)
//
// Every test uses its own run id and temporary folder (LaunchTest, launch_fixture.hpp);
// LeftoverGuard kills whatever still carries the run id when a test ends.

#include <fcntl.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/stat.h>
#include <sys/sysmacros.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <optional>
#include <set>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "launch_fixture.hpp"

namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using sensornet::testing::kLauncher;
using sensornet::testing::LeftoverGuard;
using sensornet::testing::readJson;
using sensornet::testing::readJsonLines;
using sensornet::testing::readText;
using sensornet::testing::waitUntil;
using sensornet::testing::processesMentioning;
using sensornet::testing::ProcessResult;
using sensornet::testing::runProcess;
using sensornet::testing::RunningProgram;
using namespace std::chrono_literals;

const std::string kScenario = sensornet::testing::kDefaultScenario;
constexpr int kExitFailed = 1;
constexpr int kExitBadInput = 2;

std::vector<double> realizedCosts(const json& report) {
  std::vector<double> costs;
  for (const json& e : report["per_episode"]) costs.push_back(e["realized_cost"].get<double>());
  return costs;
}

class LauncherTrust : public sensornet::testing::LaunchTest {
 protected:
  // A launch refused before anything started: exit 2 within a few seconds, one line naming
  // `named`, no log folder, no process of the run.
  void expectRefusedAtOnce(const std::vector<std::string>& argv, const std::string& named,
                           const std::string& why) {
    const auto started = std::chrono::steady_clock::now();
    const ProcessResult r = runProcess(argv, 20s);
    EXPECT_EQ(r.exit_code, kExitBadInput) << why << "\n" << r.err;
    EXPECT_LT(std::chrono::steady_clock::now() - started, 5s) << why;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << why << "\n" << r.err;
    EXPECT_NE(r.err.find(named), std::string::npos) << why << "\n" << r.err;
    EXPECT_NE(r.err.find(why), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(dir_ / "logs")) << why << ": nothing may be created";
    EXPECT_TRUE(processesMentioning(run_id_).empty()) << why;
  }
};

TEST_F(LauncherTrust, HelpTeachesTheExitCodesAndTheSeed) {
  const ProcessResult r = runProcess({kLauncher, "launch", "--help"}, 10s);
  ASSERT_EQ(r.exit_code, 0);
  for (const char* text : {"0  completed", "3  degraded", "1  failed or interrupted",
                           "2  bad input", "--seed", "report.jsonl", "SENSORNET_SCRATCH_DIR"}) {
    EXPECT_NE(r.out.find(text), std::string::npos) << text << "\n" << r.out;
  }
}

TEST_F(LauncherTrust, ReportPathThatIsADeviceIsRefusedAndLeftAlone) {
  // A device node of our own, like /dev/full (char 1, 7): writes to it fail with ENOSPC.
  const fs::path device = dir_ / "full.json";
  if (::mknod(device.c_str(), S_IFCHR | 0666, ::makedev(1, 7)) != 0) {
    GTEST_SKIP() << "cannot make a device node here (needs root): " << std::strerror(errno);
  }
  expectRefusedAtOnce(launchArgs(1, "10", device, dir_ / "logs"), device.string(),
                      "character device");
  struct stat after {};
  ASSERT_EQ(::lstat(device.c_str(), &after), 0);
  EXPECT_TRUE(S_ISCHR(after.st_mode));
  EXPECT_EQ(after.st_rdev, ::makedev(1, 7));
  EXPECT_FALSE(fs::exists(dir_ / "full.json.tmp"));
}

TEST_F(LauncherTrust, ReportPathThatLinksToDevFullIsRefusedAndLeftAlone) {
  const fs::path link = dir_ / "report.json";
  fs::create_symlink("/dev/full", link);
  expectRefusedAtOnce(launchArgs(1, "10", link, dir_ / "logs"), link.string(), "symbolic link");
  EXPECT_TRUE(fs::is_symlink(link));
  EXPECT_TRUE(fs::is_character_file("/dev/full"));
}

TEST_F(LauncherTrust, ReportPathThatIsAFifoIsRefusedWithoutOpeningIt) {
  const fs::path fifo = dir_ / "report.json";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  expectRefusedAtOnce(launchArgs(1, "10", fifo, dir_ / "logs"), fifo.string(), "FIFO");
  EXPECT_TRUE(fs::is_fifo(fifo));
}

TEST_F(LauncherTrust, ReportPathThatIsADirectoryIsRefused) {
  const fs::path folder = dir_ / "report.json";
  fs::create_directory(folder);
  expectRefusedAtOnce(launchArgs(1, "10", folder, dir_ / "logs"), folder.string(), "directory");
  EXPECT_TRUE(fs::is_directory(folder));
  EXPECT_TRUE(fs::is_empty(folder));
}

TEST_F(LauncherTrust, EpisodeLogBesideTheReportMustBeARegularFileToo) {
  const fs::path fifo = dir_ / "report.jsonl";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  expectRefusedAtOnce(launchArgs(1, "10"), fifo.string(), "FIFO");
  EXPECT_TRUE(fs::is_fifo(fifo));
}

TEST_F(LauncherTrust, ReportInAFolderWhereNoFileCanBeCreatedIsRefusedBeforeStart) {
  // Tests run as root, for whom permission bits do not stop a write: /proc refuses new files to
  // everyone, like a read-only mount.
  expectRefusedAtOnce(launchArgs(1, "10", "/proc/sensornet-trust.json", dir_ / "logs"),
                      "/proc/sensornet-trust.json", "no file can be created");
  // A missing folder is made (replan_include_test.cpp), but never where someone else could swap
  // it: not in a folder anyone may write to that is not sticky.
  const fs::path open = dir_ / "open";
  fs::create_directory(open);
  fs::permissions(open, fs::perms::all, fs::perm_options::replace);  // 0777
  const fs::path missing = open / "missing" / "report.json";
  expectRefusedAtOnce(launchArgs(1, "10", missing, dir_ / "logs"), missing.string(),
                      "may be written by anyone and is not sticky");
  EXPECT_FALSE(fs::exists(open / "missing"));
}

TEST_F(LauncherTrust, ScratchFolderThatIsALinkIsRefused) {
  const fs::path elsewhere = dir_ / "elsewhere";
  fs::create_directory(elsewhere);
  fs::permissions(elsewhere, fs::perms::owner_all, fs::perm_options::replace);
  fs::create_directory_symlink(elsewhere, dir_ / "scratch");
  // The default log folder (no --log-dir) lives in the scratch folder.
  expectRefusedAtOnce(launchArgs(1, "10", dir_ / "report.json", ""), (dir_ / "scratch").string(),
                      "symbolic link");
  EXPECT_TRUE(fs::is_empty(elsewhere)) << "nothing may be written through the link";
}

TEST_F(LauncherTrust, ScratchFolderWritableByOthersIsRefused) {
  fs::create_directory(dir_ / "scratch");
  fs::permissions(dir_ / "scratch", fs::perms::all, fs::perm_options::replace);  // 0777
  expectRefusedAtOnce(launchArgs(1, "10", dir_ / "report.json", ""), (dir_ / "scratch").string(),
                      "others may write to it (mode 0777)");
  EXPECT_TRUE(fs::is_empty(dir_ / "scratch"));
}

TEST_F(LauncherTrust, ScratchFolderOfAnotherUserIsRefused) {
  if (::geteuid() != 0) GTEST_SKIP() << "giving a folder to another user needs root";
  fs::create_directory(dir_ / "scratch");
  fs::permissions(dir_ / "scratch", fs::perms::owner_all, fs::perm_options::replace);
  ASSERT_EQ(::chown((dir_ / "scratch").c_str(), 65534, 65534), 0);
  expectRefusedAtOnce(launchArgs(1, "10", dir_ / "report.json", ""), (dir_ / "scratch").string(),
                      "owned by uid 65534");
  EXPECT_TRUE(fs::is_empty(dir_ / "scratch"));
}

TEST_F(LauncherTrust, OutOfRangeTimeScaleIsRefusedBeforeAnyProcessStarts) {
  expectRefusedAtOnce(launchArgs(1, "1e9"), "--time-scale",
                      "--time-scale: expected a number from 0.001 to 10000, got 1e+09");
  expectRefusedAtOnce(launchArgs(1, "0"), "--time-scale", "expected a number from 0.001 to 10000");
}

TEST_F(LauncherTrust, BadSeedIsRefusedBeforeAnyProcessStarts) {
  for (const char* seed : {"-1", "abc", "1.5", "0x10", "18446744073709551616", ""}) {
    std::vector<std::string> argv = launchArgs(1, "10");
    argv.insert(argv.end(), {"--seed", seed});
    expectRefusedAtOnce(argv, "--seed", "expected an integer from 0 to 18446744073709551615");
  }
}

// The first run of an id goes on untouched by a second launch of it: refused at once whether
// it shares the first one's log folder and report (the folder's lock) or not (the live run on
// DDS), and the first run's realized costs are those of a clean run with the same seed (they
// depend on seed, scenario and schedule only: every random stream is keyed by the seed, never
// by the run id).
TEST_F(LauncherTrust, DuplicateRunIdIsRefusedWhileTheFirstRunGoesOnUnaffected) {
  const LeftoverGuard guard(run_id_);
  constexpr int kEpisodes = 6;
  std::vector<std::string> first_argv = launchArgs(kEpisodes, "3");
  first_argv.insert(first_argv.end(), {"--seed", "7"});
  RunningProgram first(first_argv, 90s);
  // Live: every process up and the first episode reported in the episode log.
  ASSERT_TRUE(waitUntil([&] { return !readJsonLines(dir_ / "report.jsonl").empty(); }, 30s))
      << "the first run never finished an episode";
  const std::string log_before = readText(dir_ / "report.jsonl");

  // Same log folder and report: the lock (or the DDS probe) refuses it.
  {
    const auto started = std::chrono::steady_clock::now();
    const ProcessResult r = runProcess(first_argv, 20s);
    EXPECT_EQ(r.exit_code, kExitBadInput) << r.err;
    EXPECT_LT(std::chrono::steady_clock::now() - started, 5s);
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
    EXPECT_NE(r.err.find("run " + run_id_ + " is"), std::string::npos) << r.err;
  }
  // Its own folder and report: the live run in the partition refuses it; it makes nothing.
  fs::create_directory(dir_ / "other");
  {
    const ProcessResult r = runProcess(
        launchArgs(kEpisodes, "3", dir_ / "other" / "report.json", dir_ / "other" / "logs"), 20s);
    EXPECT_EQ(r.exit_code, kExitBadInput) << r.err;
    EXPECT_NE(r.err.find("run " + run_id_ + " is live"), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(dir_ / "other" / "logs"));
    EXPECT_TRUE(fs::is_empty(dir_ / "other"));
  }
  // Another DDS domain (the probe sees nothing there) but the same log folder: the lock.
  {
    std::vector<std::string> argv = first_argv;
    argv.insert(argv.end(), {"--domain-id", "229"});
    const ProcessResult r = runProcess(argv, 20s);
    EXPECT_EQ(r.exit_code, kExitBadInput) << r.err;
    EXPECT_NE(r.err.find("run " + run_id_ + " is already going on"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("launch.lock"), std::string::npos) << r.err;
  }
  EXPECT_FALSE(first.done()) << "the first run must still be going on";
  EXPECT_TRUE(readText(dir_ / "report.jsonl").starts_with(log_before))
      << "the refused launches must not touch the first run's episode log";

  const ProcessResult& r = first.result();
  ASSERT_EQ(r.exit_code, 0) << r.out << r.err;
  const json report = readJson(dir_ / "report.json");
  ASSERT_TRUE(report.is_object());
  EXPECT_EQ(report["run_id"], run_id_);
  EXPECT_EQ(report["status"], "completed");
  ASSERT_EQ(report["per_episode"].size(), static_cast<std::size_t>(kEpisodes));

  // A clean run with another id and the same seed, in the default folders: the scratch folder
  // is made private on the way.
  const std::string clean_id = run_id_ + "-clean";
  const LeftoverGuard clean_guard(clean_id);
  std::vector<std::string> clean_argv = {
      kLauncher,  "launch", kScenario, "--episodes", std::to_string(kEpisodes), "--time-scale", "3",
      "--run-id", clean_id, "--seed",  "7"};
  const ProcessResult clean = runProcess(clean_argv, 90s);
  ASSERT_EQ(clean.exit_code, 0) << clean.out << clean.err;
  struct stat scratch {};
  ASSERT_EQ(::lstat((dir_ / "scratch").c_str(), &scratch), 0);
  EXPECT_TRUE(S_ISDIR(scratch.st_mode));
  EXPECT_EQ(scratch.st_mode & 0777, 0700u);
  EXPECT_EQ(scratch.st_uid, ::geteuid());
  const json clean_report = readJson(dir_ / "scratch" / clean_id / "report.json");
  ASSERT_TRUE(clean_report.is_object());
  const std::vector<double> costs = realizedCosts(report);
  const std::vector<double> clean_costs = realizedCosts(clean_report);
  ASSERT_EQ(costs.size(), clean_costs.size());
  // The same measurements fused in the same order: equal up to rounding of the JSON text
  // (written with 17 significant digits, so exactly; 1e-12 relative leaves room for ties of
  // equal timestamps fused in another order).
  for (std::size_t k = 0; k < costs.size(); ++k) {
    EXPECT_NEAR(costs[k], clean_costs[k], 1e-12 * std::abs(clean_costs[k])) << "episode " << k;
  }
}

}  // namespace
