// A full disk where the report goes (issue 49): the report's folder is a 12 KiB tmpfs, which
// takes the episode log of six episodes but not the report. Every closing line must say the
// truth: the fault names the cause and the file (not only "exited with status 1"), the latency
// is not called unmeasured while measurements arrived, and the report is written beside the
// logs, where the closing line says, with every measurement accounted for. The test needs to
// mount a tmpfs (root with CAP_SYS_ADMIN) and skips where it cannot; it always unmounts.

#include <gtest/gtest.h>
#include <sys/mount.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <string>

#include "launch_fixture.hpp"

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

class DiskFull : public testing::LaunchTest {};

TEST_F(DiskFull, TheReportsFolderFillingUpIsToldTruthfullyAndNothingIsLost) {
  const LeftoverGuard guard(run_id_);
  const fs::path full = dir_ / "full";
  const SmallDisk disk(full, 12);
  if (!disk.mounted()) GTEST_SKIP() << "cannot mount a tmpfs here: " << disk.error();
  const fs::path logs = dir_ / "logs";
  const ProcessResult r = runProcess(launchArgs(6, "4", full / "report.json", logs), 120s);

  // The fusion center could not write its report: it failed, and the fault says why and where.
  EXPECT_EQ(r.exit_code, 1) << r.out << r.err;
  EXPECT_NE(r.out.find("fault: process_failed in fusion_center: exited with status 1: cannot "
                       "write the run report " +
                       (full / "report.json").string() + ": No space left on device"),
            std::string::npos)
      << r.out;
  // Measurements arrived: their latency is not known, not "not measured".
  EXPECT_EQ(r.out.find("no measurement arrived"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("latency publish-to-fusion: not known"), std::string::npos) << r.out;

  // The report is beside the logs, as the closing line says, whole.
  const fs::path elsewhere = logs / (run_id_ + "-report.json");
  EXPECT_NE(r.out.find("report: " + elsewhere.string()), std::string::npos) << r.out;
  EXPECT_FALSE(fs::exists(full / "report.json"));
  const nlohmann::json report = testing::readJson(elsewhere);
  EXPECT_EQ(report.at("status"), "failed");
  // Every measurement sent is accounted for, recomputed from the episodes themselves.
  ASSERT_EQ(report.at("per_episode").size(), 6u) << report.dump(1).substr(0, 2000);
  std::uint64_t sent = 0, received = 0, lost = 0;
  for (const nlohmann::json& e : report.at("per_episode")) {
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

}  // namespace
}  // namespace sensornet
