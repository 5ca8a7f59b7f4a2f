// The files the launcher writes for the user (output_file.hpp): a path is checked before the run
// (a regular file or a new one in a writable folder), a file is replaced whole or not at all,
// keeps its permissions, and nothing that is not a regular file (a symbolic link, a FIFO, a
// folder) is ever written through or removed.

#include "sensornet/io/output_file.hpp"

#include <gtest/gtest.h>
#include <sys/stat.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <stdexcept>
#include <string>

#include "../../support/scratch_dir.hpp"
#include "sensornet/core/input_error.hpp"

namespace sensornet {
namespace {

namespace fs = std::filesystem;
using testing::ScratchDir;

std::string contents(const fs::path& path) {
  std::ifstream in(path);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

TEST(OutputFile, ANewOrRegularFileInAWritableFolderIsFine) {
  ScratchDir dir;
  EXPECT_FALSE(outputFileProblem(dir.file("new.json")).has_value());
  EXPECT_FALSE(outputFileProblem(dir.write("old.json", "{}")).has_value());
}

TEST(OutputFile, ProblemsNameWhatIsWrong) {
  ScratchDir dir;
  const auto missing = outputFileProblem(dir.file("absent/report.json"));
  ASSERT_TRUE(missing.has_value());
  EXPECT_NE(missing->find("does not exist"), std::string::npos) << *missing;
  fs::create_directory(dir.file("folder"));
  const auto folder = outputFileProblem(dir.file("folder"));
  ASSERT_TRUE(folder.has_value());
  EXPECT_NE(folder->find("directory"), std::string::npos) << *folder;
  try {
    checkOutputFile(dir.file("folder"), "--report");
    FAIL() << "a folder was taken for an output file";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("--report"), std::string::npos) << e.what();
  }
}

TEST(OutputFile, ReplacingKeepsThePermissions) {
  ScratchDir dir;
  const std::string path = dir.write("report.json", "old");
  fs::permissions(path, fs::perms::owner_read | fs::perms::owner_write);
  replaceFileAtomically(path, std::string("new\n"));
  EXPECT_EQ(contents(path), "new\n");
  EXPECT_EQ(fs::status(path).permissions() & fs::perms::all,
            fs::perms::owner_read | fs::perms::owner_write);
  EXPECT_EQ(std::distance(fs::directory_iterator(dir.path()), fs::directory_iterator()), 1)
      << "a temporary file stayed behind";
}

TEST(OutputFile, StreamedTextIsWrittenWhole) {
  ScratchDir dir;
  const std::string path = dir.file("big.json");
  replaceFileAtomically(path, [](std::ostream& out) {
    for (int i = 0; i < 100000; ++i) out << i << '\n';
  });
  const std::string text = contents(path);
  EXPECT_EQ(text.substr(text.size() - 6), "99999\n");
  EXPECT_EQ(std::count(text.begin(), text.end(), '\n'), 100000);
}

TEST(OutputFile, NeverWritesThroughALinkOrAFifo) {
  ScratchDir dir;
  const std::string target = dir.write("precious.txt", "keep me");
  const std::string link = dir.file("report.json");
  fs::create_symlink(target, link);
  EXPECT_THROW(replaceFileAtomically(link, std::string("x")), std::runtime_error);
  EXPECT_EQ(contents(target), "keep me");
  EXPECT_TRUE(fs::is_symlink(link));
  removeRegularFile(link);
  EXPECT_TRUE(fs::is_symlink(link));

  const std::string fifo = dir.file("fifo");
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  EXPECT_THROW(replaceFileAtomically(fifo, std::string("x")), std::runtime_error);
  EXPECT_TRUE(fs::is_fifo(fifo));
  EXPECT_TRUE(outputFileProblem(fifo).has_value());
}

TEST(OutputFile, RemovesOnlyARegularFile) {
  ScratchDir dir;
  const std::string stale = dir.write("stale.json", "{}");
  removeRegularFile(stale);
  EXPECT_FALSE(fs::exists(stale));
  fs::create_directory(dir.file("keep"));
  removeRegularFile(dir.file("keep"));
  EXPECT_TRUE(fs::is_directory(dir.file("keep")));
}

}  // namespace
}  // namespace sensornet
