#pragma once
// A test's scratch folder: a fresh, private (0700) folder under the temporary directory, named
// after the running test, removed when it goes out of scope.
//
//   ScratchDir dir;                                   // /tmp/sensornet-Suite.Test-a1B2c3
//   const std::string scenario = dir.write("s.yaml", "...");
//   runProcess({kCoordinator, "plan", "--scenario", scenario, "--out", dir.file("plan.json")});
//
// It is kept, and its path printed, when the test has failed (to read what the programs left)
// or when the environment sets SENSORNET_KEEP_SCRATCH (to read it after a passing test too).

#include <gtest/gtest.h>

#include <cerrno>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <stdexcept>
#include <string>
#include <string_view>
#include <system_error>

namespace sensornet::testing {

class ScratchDir {
 public:
  // `what` tells apart the folders of one test (or names one made outside any test).
  explicit ScratchDir(std::string_view what = {}) {
    std::string name = "sensornet-";
    if (const ::testing::TestInfo* test = ::testing::UnitTest::GetInstance()->current_test_info()) {
      // A long name would crowd socket paths made in the folder.
      name += (std::string(test->test_suite_name()) + "." + test->name()).substr(0, 54);
    }
    if (!what.empty()) name += (name.back() == '-' ? "" : "-") + std::string(what);
    for (char& c : name) {  // parameterized tests have '/' in their names
      const bool plain = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') ||
                         (c >= '0' && c <= '9') || c == '.' || c == '-' || c == '_';
      if (!plain) c = '_';
    }
    std::string pattern = (std::filesystem::temp_directory_path() / (name + "-XXXXXX")).string();
    if (::mkdtemp(pattern.data()) == nullptr) {
      throw std::system_error(errno, std::generic_category(), "mkdtemp " + pattern);
    }
    path_ = pattern;
  }
  ~ScratchDir() {
    const bool failed = ::testing::UnitTest::GetInstance()->current_test_info() != nullptr &&
                        ::testing::Test::HasFailure();
    if (failed || std::getenv("SENSORNET_KEEP_SCRATCH") != nullptr) {
      std::cerr << "scratch folder kept: " << path_.string() << "\n";
      return;
    }
    std::error_code ignored;
    std::filesystem::remove_all(path_, ignored);
  }
  ScratchDir(const ScratchDir&) = delete;
  ScratchDir& operator=(const ScratchDir&) = delete;

  [[nodiscard]] const std::filesystem::path& path() const { return path_; }
  [[nodiscard]] std::filesystem::path operator/(const std::filesystem::path& name) const {
    return path_ / name;
  }
  // The path of `name` in the folder, as a string (for a program's argument).
  [[nodiscard]] std::string file(const std::filesystem::path& name) const {
    return (path_ / name).string();
  }
  // Writes `text` to `name` in the folder (making the folders on its way) and returns its path.
  std::string write(const std::filesystem::path& name, std::string_view text) const {
    const std::filesystem::path file = path_ / name;
    std::filesystem::create_directories(file.parent_path());
    std::ofstream out(file, std::ios::binary);
    out << text;
    if (!out.flush()) throw std::runtime_error("cannot write " + file.string());
    return file.string();
  }

 private:
  std::filesystem::path path_;
};

}  // namespace sensornet::testing
