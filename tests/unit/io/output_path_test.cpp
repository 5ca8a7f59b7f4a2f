// The one rule for output paths (io/output_path.hpp): missing folders are made, each made one is
// the user's own and writable by nobody else, and nothing is made where someone else could swap
// it. Checked with stat on what is on disk, not with the helper's own answers.
#include "sensornet/io/output_path.hpp"

#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "sensornet/core/input_error.hpp"
#include "../../support/scratch_dir.hpp"

namespace sensornet {
namespace {

namespace fs = std::filesystem;

class OutputPath : public ::testing::Test {
 protected:
  // The error message of `f`, or "" when it did not throw InputError.
  template <class F>
  static std::string refusal(F f) {
    try {
      f();
    } catch (const InputError& e) {
      return e.what();
    }
    return "";
  }

  sensornet::testing::ScratchDir scratch_;
  const fs::path root_ = scratch_.path();
};

mode_t modeOf(const fs::path& p) {
  struct stat info {};
  EXPECT_EQ(::lstat(p.c_str(), &info), 0) << p;
  return info.st_mode;
}

TEST_F(OutputPath, MakesTheMissingFoldersOfAFileOwnedByYouAndWritableByNobodyElse) {
  const fs::path file = root_ / "a" / "b" / "report.json";
  makeParentFolders(file, "--report");
  for (const fs::path& dir : {root_ / "a", root_ / "a" / "b"}) {
    const mode_t mode = modeOf(dir);
    EXPECT_TRUE(S_ISDIR(mode)) << dir;
    EXPECT_EQ(mode & (S_IWGRP | S_IWOTH), 0u) << dir;
  }
  EXPECT_FALSE(fs::exists(file)) << "only the folders are made";
  makeParentFolders(file, "--report");           // again: nothing to do
  makeParentFolders("report.json", "--report");  // a bare name: the current folder
}

TEST_F(OutputPath, MakesAFolderItselfForAFolderOption) {
  makeFolders(root_ / "tables" / "run-1" / "", "--csv");
  EXPECT_TRUE(fs::is_directory(root_ / "tables" / "run-1"));
}

TEST_F(OutputPath, RefusesAFolderThatAppearsAsASymbolicLinkWhenItIsMade) {
  // A dangling link where the folder is to be made: what another user wins a race with.
  fs::create_symlink(root_ / "elsewhere", root_ / "new");
  const std::string why = refusal([&] { makeParentFolders(root_ / "new" / "r.json", "--report"); });
  EXPECT_NE(why.find("--report " + (root_ / "new" / "r.json").string()), std::string::npos) << why;
  EXPECT_NE(why.find("symbolic link"), std::string::npos) << why;
  EXPECT_FALSE(fs::exists(root_ / "elsewhere")) << "nothing made through the link";
}

TEST_F(OutputPath, RefusesToMakeFoldersInAWorldWritableFolderThatIsNotSticky) {
  fs::create_directories(root_ / "open");
  ::chmod((root_ / "open").c_str(), 0777);
  const std::string why = refusal([&] { makeFolders(root_ / "open" / "mine", "--log-dir"); });
  EXPECT_NE(why.find("may be written by anyone and is not sticky"), std::string::npos) << why;
  EXPECT_FALSE(fs::exists(root_ / "open" / "mine"));
  // Sticky, as /tmp is: nobody else can rename or remove what is made there.
  ::chmod((root_ / "open").c_str(), 01777);
  makeFolders(root_ / "open" / "mine", "--log-dir");
  EXPECT_TRUE(fs::is_directory(root_ / "open" / "mine"));
}

TEST_F(OutputPath, RefusesToMakeFoldersInAnotherUsersFolder) {
  if (::geteuid() != 0) GTEST_SKIP() << "needs root to give a folder to another user";
  fs::create_directories(root_ / "theirs");
  ASSERT_EQ(::chown((root_ / "theirs").c_str(), 4242, 4242), 0);
  const std::string why =
      refusal([&] { makeParentFolders(root_ / "theirs" / "x" / "r.json", "--out"); });
  EXPECT_NE(why.find("belongs to uid 4242"), std::string::npos) << why;
  EXPECT_FALSE(fs::exists(root_ / "theirs" / "x"));
}

TEST_F(OutputPath, RefusesAFileInTheWay) {
  std::ofstream(root_ / "file") << "x";
  const std::string why = refusal([&] { makeParentFolders(root_ / "file" / "r.json", "--html"); });
  EXPECT_NE(why.find("is not a directory"), std::string::npos) << why;
}

}  // namespace
}  // namespace sensornet
