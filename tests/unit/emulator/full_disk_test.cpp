// A disk that fills while the fusion center writes (issue 31, finding 3): the episode log never
// ends in half an entry, and a report that does not fit is a failure named with its reason, not
// "bad input", with no temporary file left behind. A file that cannot grow past a size limit
// (RLIMIT_FSIZE, with SIGXFSZ ignored: write(2) then takes what fits and refuses the rest with
// EFBIG) stands in for the full disk, as a full tmpfs takes what fits and then says ENOSPC.

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>

#include "sensornet/core/input_error.hpp"
#include "sensornet/emulator/run_report.hpp"
#include "sensornet/io/scenario_file.hpp"
#include "sensornet/report/report_files.hpp"
#include "support/file_size_limit.hpp"
#include "support/scratch_dir.hpp"

namespace sensornet::emulator {
namespace {

using sensornet::report::EpisodeLog;

namespace fs = std::filesystem;
using nlohmann::json;

using sensornet::testing::FileSizeLimit;

class FullDisk : public ::testing::Test {
 protected:

  static std::string readAll(const fs::path& path) {
    std::ifstream in(path, std::ios::binary);
    std::ostringstream text;
    text << in.rdbuf();
    return text.str();
  }

  sensornet::testing::ScratchDir scratch_;
  fs::path dir_ = scratch_.path();
};

json entryOf(int episode) {
  return {{"episode", episode}, {"complete", true}, {"padding", std::string(300, 'x')}};
}

TEST_F(FullDisk, EpisodeLogNeverEndsInHalfAnEntry) {
  const fs::path path = dir_ / "report.jsonl";
  constexpr rlim_t kLimit = 1000;  // room for 2 whole entries of 343 bytes and part of a third
  std::string error;
  int appended = 0;
  {
    const FileSizeLimit limit(kLimit);
    EpisodeLog log(path);
    try {
      for (; appended < 10; ++appended) log.append(entryOf(appended));
    } catch (const std::runtime_error& e) {
      error = e.what();
    }
  }
  ASSERT_EQ(appended, 2) << "each entry is " << entryOf(0).dump().size() + 1 << " bytes";
  EXPECT_NE(error.find(path.string()), std::string::npos) << error;
  EXPECT_NE(error.find("File too large"), std::string::npos) << error;
  // Every line whole: the third entry's first bytes were cut off again.
  const std::string text = readAll(path);
  ASSERT_FALSE(text.empty());
  EXPECT_EQ(text.back(), '\n') << "the log ends in half an entry: ..." << text.substr(text.size() - 20);
  std::istringstream lines(text);
  int count = 0;
  for (std::string line; std::getline(lines, line); ++count) {
    EXPECT_TRUE(json::parse(line, nullptr, false).is_object()) << "line " << count + 1;
  }
  EXPECT_EQ(count, 2);
  EXPECT_EQ(text.size(), 2 * (entryOf(0).dump().size() + 1));
}

TEST_F(FullDisk, AReportThatDoesNotFitFailsWithTheReasonAndLeavesNoTemporary) {
  const fs::path path = dir_ / "report.json";
  std::ofstream(path) << "{\"earlier\": true}\n";
  const json report = {{"status", "completed"}, {"padding", std::string(5000, 'x')}};
  bool bad_input = false;
  std::string error;
  {
    const FileSizeLimit limit(1000);
    try {
      writeJsonFile(path.string(), report, "run report");
    } catch (const InputError& e) {
      bad_input = true;
      error = e.what();
    } catch (const std::runtime_error& e) {
      error = e.what();
    }
  }
  EXPECT_FALSE(bad_input) << "a full disk is not bad input: " << error;
  EXPECT_NE(error.find(path.string()), std::string::npos) << error;
  EXPECT_NE(error.find("File too large"), std::string::npos) << error;
  for (const auto& entry : fs::directory_iterator(dir_)) {
    EXPECT_EQ(entry.path(), path) << "left behind: " << entry.path();
  }
  EXPECT_EQ(readAll(path), "{\"earlier\": true}\n");  // the earlier file is as it was
}

TEST_F(FullDisk, AFolderThatCannotBeWrittenIsStillBadInput) {
  EXPECT_THROW(writeJsonFile((dir_ / "missing" / "report.json").string(), json::object(),
                             "run report"),
               InputError);
}

}  // namespace
}  // namespace sensornet::emulator
