// The tests' scratch folder (tests/support/scratch_dir.hpp): fresh and private, named after the
// test, gone after it unless SENSORNET_KEEP_SCRATCH asks to keep it.

#include "support/scratch_dir.hpp"

#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

namespace sensornet {
namespace {

namespace fs = std::filesystem;
using testing::ScratchDir;

TEST(ScratchDir, IsAFreshPrivateFolderNamedAfterTheTestAndGoneAfterIt) {
  fs::path kept;
  {
    const ScratchDir dir;
    const ScratchDir other("second");
    kept = dir.path();
    EXPECT_TRUE(fs::is_directory(dir.path()));
    EXPECT_TRUE(fs::is_empty(dir.path()));
    EXPECT_NE(dir.path(), other.path());
    EXPECT_EQ(dir.path().parent_path(), fs::temp_directory_path());
    EXPECT_EQ(dir.path().filename().string().rfind(
                  "sensornet-ScratchDir.IsAFreshPrivateFolderNamedAfterTheTe", 0),
              0u)
        << dir.path();
    EXPECT_NE(other.path().filename().string().find("-second-"), std::string::npos);
    EXPECT_EQ(fs::status(dir.path()).permissions(), fs::perms::owner_all);

    const std::string file = dir.write("sub/a.txt", "text");
    EXPECT_EQ(file, dir.file("sub/a.txt"));
    EXPECT_EQ(dir / "sub/a.txt", fs::path(file));
    std::ostringstream read;
    read << std::ifstream(file).rdbuf();
    EXPECT_EQ(read.str(), "text");
  }
  EXPECT_FALSE(fs::exists(kept));
}

TEST(ScratchDir, StaysWhenTheEnvironmentAsksToKeepIt) {
  ::setenv("SENSORNET_KEEP_SCRATCH", "1", 1);
  fs::path kept;
  {
    const ScratchDir dir;
    kept = dir.path();
    dir.write("left.txt", "for the reader");
  }
  ::unsetenv("SENSORNET_KEEP_SCRATCH");
  EXPECT_TRUE(fs::exists(kept / "left.txt"));
  fs::remove_all(kept);
}

}  // namespace
}  // namespace sensornet
