// A full disk where the report goes (issue 49): the report's folder is a small tmpfs. At 12 KiB
// it takes the episode log of six episodes but not the report; at 4 KiB not even the whole log.
// Either way nothing the run measured is lost and every closing line says the truth: a
// write_failed fault names the file and the cause (the run is degraded, exit 3: every episode
// ran, a file is not where it was asked for), the latency is measured, and the report is beside
// the logs, where the closing line says, with all six episodes and every measurement accounted
// for. The test mounts a tmpfs (root with CAP_SYS_ADMIN), skips where it cannot, always unmounts.

#include <gtest/gtest.h>
#include <sys/mount.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <string>

#include "launch_fixture.hpp"
#include "sensornet/report/report_files.hpp"

namespace sensornet {
namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;
using testing::LeftoverGuard;
using testing::ProcessResult;
using testing::runProcess;

// A tmpfs of `kib` KiB at `at`, unmounted when the scope ends.
class SmallDisk {
 public:
  SmallDisk(const fs::path& at, int kib) : at_(at) {
    fs::create_directories(at);
    const std::string options = "size=" + std::to_string(kib) + "k,mode=0755";
    mounted_ = ::mount("tmpfs", at.c_str(), "tmpfs", 0, options.c_str()) == 0;
    if (!mounted_) error_ = std::strerror(errno);
  }
  ~SmallDisk() {
    if (mounted_) ::umount2(at_.c_str(), MNT_DETACH);
  }
  SmallDisk(const SmallDisk&) = delete;
  SmallDisk& operator=(const SmallDisk&) = delete;
  [[nodiscard]] bool mounted() const { return mounted_; }
  [[nodiscard]] const std::string& error() const { return error_; }

 private:
  fs::path at_;
  bool mounted_ = false;
  std::string error_;
};

class DiskFull : public testing::LaunchTest {
 protected:
  // Six episodes with the report on a tmpfs of `kib` KiB: the launch's result and its report.
  void runOnDiskOf(int kib, bool log_refused) {
    const LeftoverGuard guard(run_id_);
    const fs::path full = dir_ / "full";
    const SmallDisk disk(full, kib);
    if (!disk.mounted()) GTEST_SKIP() << "cannot mount a tmpfs here: " << disk.error();
    const fs::path logs = dir_ / "logs";
    const fs::path asked = full / "report.json";
    const ProcessResult r = runProcess(launchArgs(6, "4", asked, logs), 120s);

    EXPECT_EQ(r.exit_code, 3) << r.out << r.err;
    EXPECT_NE(r.out.find("fault: write_failed in fusion_center"), std::string::npos) << r.out;
    EXPECT_NE(
        r.out.find("cannot write the run report " + asked.string() + ": No space left on device"),
        std::string::npos)
        << r.out;
    EXPECT_EQ(r.out.find("process_failed"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("latency publish-to-fusion: median "), std::string::npos) << r.out;

    // The report is beside the logs, as the closing line says, whole.
    const fs::path elsewhere = logs / (run_id_ + "-report.json");
    EXPECT_NE(r.out.find("report: " + elsewhere.string() + ", not at its path"), std::string::npos)
        << r.out;
    EXPECT_FALSE(fs::exists(asked));
    const nlohmann::json report = testing::readJson(elsewhere);
    EXPECT_EQ(report.at("status"), "degraded");
    std::size_t refused_log = 0;
    for (const nlohmann::json& f : report.at("faults")) {
      if (f.at("kind") == "write_failed" &&
          f.at("detail").get<std::string>().find(
              sensornet::report::episodeLogPath(asked).string()) != std::string::npos) {
        ++refused_log;
      }
    }
    EXPECT_EQ(refused_log, log_refused ? 1u : 0u) << report.at("faults").dump(1);
    // Every episode, and every measurement sent accounted for, recomputed from the episodes.
    ASSERT_EQ(report.at("per_episode").size(), 6u) << report.at("faults").dump(1);
    std::uint64_t sent = 0, received = 0, lost = 0;
    for (std::size_t k = 0; k < 6; ++k) {
      const nlohmann::json& e = report.at("per_episode").at(k);
      EXPECT_EQ(e.at("episode"), k);
      for (const auto& n : e.at("sent")) sent += n.get<std::uint64_t>();
      for (const auto& n : e.at("received")) received += n.get<std::uint64_t>();
      for (const auto& n : e.at("lost")) lost += n.get<std::uint64_t>();
    }
    EXPECT_GT(sent, 0u);
    EXPECT_EQ(sent, received + lost);
    EXPECT_NE(r.out.find("measurements: " + std::to_string(sent) + " sent, " +
                         std::to_string(received) + " received"),
              std::string::npos)
        << r.out;
  }
};

TEST_F(DiskFull, AReportItsFolderCannotTakeGoesBesideTheLogs) { runOnDiskOf(12, false); }

TEST_F(DiskFull, AnEpisodeLogCutShortLosesNoEpisode) { runOnDiskOf(4, true); }

// The log folder full (16 KiB: the processes' logs take its pages before the coordinator's
// journal): the coordinator will not run what a restart could not resume, so the run is
// `failed`, exit 1 (the coordinator gave up, docs/ARCHITECTURE.md "Run outcome"), with one
// cause naming the journal's file and the disk's error, the report where it was asked for (its
// folder has room), and no process left.
TEST_F(DiskFull, ALogFolderThatCannotTakeTheJournalFailsTheRunNamingIt) {
  const LeftoverGuard guard(run_id_);
  const fs::path logs = dir_ / "logs";
  const SmallDisk disk(logs, 16);
  if (!disk.mounted()) GTEST_SKIP() << "cannot mount a tmpfs here: " << disk.error();
  const fs::path report_path = dir_ / "report.json";
  const ProcessResult r = runProcess(launchArgs(6, "4", report_path, logs), 120s);
  EXPECT_EQ(r.exit_code, 1) << r.out << r.err;
  const std::string journal = (logs / "coordinator-state.json").string();
  EXPECT_NE(r.out.find("cannot write the coordinator journal " + journal + ": No space left on device"),
            std::string::npos)
      << r.out;
  const nlohmann::json report = testing::readJson(report_path);
  ASSERT_TRUE(report.is_object()) << r.out;
  EXPECT_EQ(report.at("status"), "failed");
  std::size_t causes = 0;
  for (const nlohmann::json& f : report.at("faults")) {
    if (f.contains("caused_by")) continue;
    ++causes;
    EXPECT_EQ(f.at("kind"), "run_aborted") << f.dump();
    EXPECT_EQ(f.at("process"), "coordinator") << f.dump();
  }
  EXPECT_EQ(causes, 1u) << report.at("faults").dump(1);
  EXPECT_TRUE(testing::waitUntil([&] { return testing::processesMentioning(run_id_).empty(); }, 10s));
}

}  // namespace
}  // namespace sensornet
