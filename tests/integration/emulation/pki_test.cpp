// `sensornet pki init` on a shared machine (issue 30): the CA's private key stays out of what
// any process receives, nothing is written through a planted symbolic link, and a folder that
// another user owns or may write is refused.
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <set>
#include <string>
#include <vector>

#include "launch_fixture.hpp"

namespace sensornet {
namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;
using testing::ProcessResult;
using testing::runProcess;

constexpr int kExitBadInput = 2;
// The roles, and one identity per sensor process: init() asks for sensors 0 to 2.
const std::vector<std::string> kRoles = {"coordinator", "fusion_center", "operator", "launcher",
                                         "sensor-0",    "sensor-1",      "sensor-2"};

std::string textOf(const fs::path& file) {
  std::ifstream in(file);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

class PkiInit : public testing::LaunchTest {
 protected:
  ProcessResult init(const fs::path& dir, std::vector<std::string> extra = {}) {
    std::vector<std::string> argv = {testing::kLauncher, "pki", "init", dir.string(), "--days",
                                     "30", "--sensors", "3"};
    argv.insert(argv.end(), extra.begin(), extra.end());
    return runProcess(argv, 120s);
  }
  // A refusal: exit 2, one line naming `file` and saying `why`.
  static void expectRefused(const ProcessResult& r, const fs::path& file, const std::string& why) {
    EXPECT_EQ(r.exit_code, kExitBadInput) << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
    EXPECT_NE(r.err.find(file.string()), std::string::npos) << r.err;
    EXPECT_NE(r.err.find(why), std::string::npos) << r.err;
  }
};

// Every file under `dir` that holds a PEM private key.
std::set<fs::path> privateKeysUnder(const fs::path& dir) {
  std::set<fs::path> keys;
  for (const auto& entry : fs::recursive_directory_iterator(dir)) {
    if (entry.is_regular_file() && textOf(entry.path()).find("PRIVATE KEY-----") != std::string::npos) {
      keys.insert(entry.path());
    }
  }
  return keys;
}

TEST_F(PkiInit, EachRoleFolderHoldsItsOwnFilesOnlyAndTheCaKeyStaysApart) {
  const fs::path dir = dir_ / "pki";
  const ProcessResult r = init(dir);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  std::set<fs::path> expected_keys = {dir / "ca" / "ca.key"};
  for (const std::string& role : kRoles) {
    std::set<std::string> names;
    for (const auto& entry : fs::directory_iterator(dir / role)) names.insert(entry.path().filename());
    EXPECT_EQ(names, (std::set<std::string>{"ca.pem", "governance.p7s", "identity.pem", "key.pem",
                                            "permissions.p7s"}))
        << role;
    expected_keys.insert(dir / role / "key.pem");
    EXPECT_EQ(textOf(dir / role / "ca.pem"), textOf(dir / "ca.pem")) << role;
  }
  EXPECT_EQ(privateKeysUnder(dir), expected_keys);

  // With --ca-dir elsewhere, no CA key is anywhere under DIR; a second init signs with that CA.
  const fs::path offline = dir_ / "offline-ca";
  const fs::path other = dir_ / "pki2";
  ASSERT_EQ(init(other, {"--ca-dir", offline.string()}).exit_code, 0);
  EXPECT_FALSE(fs::exists(other / "ca"));
  for (const fs::path& key : privateKeysUnder(other)) EXPECT_EQ(key.filename(), "key.pem") << key;
  EXPECT_TRUE(fs::exists(offline / "ca.key"));
  const fs::path third = dir_ / "pki3";
  ASSERT_EQ(init(third, {"--ca-dir", offline.string()}).exit_code, 0);
  EXPECT_EQ(textOf(third / "ca.pem"), textOf(other / "ca.pem")) << "the same CA signed both";
}

// A sensor process's identity may publish the sensor topics in its own block's partition only
// (and nothing else); the launcher's and the operator's Command each in their own partition.
// With --scenario the blocks are those `sensornet launch` starts.
TEST_F(PkiInit, EachSensorProcessMayPublishInItsOwnPartitionOnly) {
  const fs::path dir = dir_ / "pki";
  const ProcessResult r = init(dir, {"--scenario", testing::kDefaultScenario,
                                     "--sensors-per-process", "2"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  std::set<std::string> sensors;
  for (const auto& entry : fs::directory_iterator(dir)) {
    const std::string name = entry.path().filename();
    if (name.rfind("sensor", 0) == 0) sensors.insert(name);
  }
  EXPECT_EQ(sensors, (std::set<std::string>{"sensor-0-1", "sensor-2-3", "sensor-4-5"}));
  const std::string permissions = textOf(dir / "sensor-2-3" / "permissions.p7s");
  const std::size_t publish = permissions.find("<publish>");
  const std::size_t subscribe = permissions.find("<subscribe>");
  ASSERT_NE(publish, std::string::npos);
  ASSERT_NE(subscribe, std::string::npos);
  const std::string published = permissions.substr(publish, subscribe - publish);
  EXPECT_NE(published.find("<partition>sensornet/*/sensors/2-3</partition>"), std::string::npos)
      << published;
  EXPECT_EQ(published.find("<partition>sensornet/*</partition>"), std::string::npos) << published;
  EXPECT_NE(permissions.find("<subject_name>CN=sensor-2-3,O=sensornet</subject_name>"),
            std::string::npos);
  EXPECT_NE(textOf(dir / "operator" / "permissions.p7s")
                .find("<partition>sensornet/*/operator</partition>"),
            std::string::npos);
  EXPECT_NE(textOf(dir / "launcher" / "permissions.p7s")
                .find("<partition>sensornet/*/launcher</partition>"),
            std::string::npos);
}

TEST_F(PkiInit, ForceWritesNothingThroughAPlantedLink) {
  const fs::path dir = dir_ / "pki";
  ASSERT_EQ(init(dir).exit_code, 0);
  const fs::path precious = dir_ / "precious.txt";
  std::ofstream(precious) << "precious\n";
  // A link planted where the sensor's private key goes: refused, the target untouched.
  fs::remove(dir / "sensor-0" / "key.pem");
  fs::create_symlink(precious, dir / "sensor-0" / "key.pem");
  expectRefused(init(dir, {"--force"}), dir / "sensor-0" / "key.pem", "symbolic link");
  EXPECT_EQ(textOf(precious), "precious\n");
  // A link planted as the log of earlier versions: not a file it makes, so never opened.
  const fs::path fresh = dir_ / "fresh";
  fs::create_directories(fresh);
  fs::permissions(fresh, fs::perms::owner_all);
  fs::create_symlink(precious, fresh / ".openssl.log");
  const ProcessResult r = init(fresh, {"--force"});
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(textOf(precious), "precious\n");
  // The folder itself as a link: refused.
  fs::create_directory_symlink(fresh, dir_ / "linked");
  expectRefused(init(dir_ / "linked", {"--force"}), dir_ / "linked", "not a symbolic link");
}

TEST_F(PkiInit, RefusesAFolderAnotherUserOwnsOrMayWrite) {
  const fs::path shared = dir_ / "shared";
  fs::create_directories(shared);
  fs::permissions(shared, fs::perms::all);  // 0777
  expectRefused(init(shared), shared, "writable");
  EXPECT_FALSE(fs::exists(shared / "ca.pem"));
  if (::geteuid() != 0) GTEST_SKIP() << "not root: cannot give a folder to another user";
  const fs::path theirs = dir_ / "theirs";
  fs::create_directories(theirs);
  ASSERT_EQ(::chown(theirs.c_str(), 65534, 65534), 0);  // nobody
  expectRefused(init(theirs), theirs, "belongs to uid 65534");
  EXPECT_FALSE(fs::exists(theirs / "ca.pem"));
}

}  // namespace
}  // namespace sensornet
