// The files of a run's report (report_files.hpp): a folder where the report should be is not a
// report (and reading it does not throw), and an unfinished run is one whose episode log exists
// without its final report.

#include "sensornet/report/report_files.hpp"

#include <gtest/gtest.h>

#include <filesystem>

#include "../../support/scratch_dir.hpp"

namespace sensornet::report {
namespace {

TEST(ReportFiles, AFolderIsNoReport) {
  testing::ScratchDir dir;
  std::filesystem::create_directory(dir.file("report.json"));
  EXPECT_EQ(readReport(dir.file("report.json")).problem, ReportFile::Problem::Unreadable);
  EXPECT_EQ(readReport(dir.file("absent.json")).problem, ReportFile::Problem::Unreadable);
  EXPECT_EQ(readReport(dir.write("text.json", "not json")).problem, ReportFile::Problem::NotJson);
}

TEST(ReportFiles, AnUnfinishedRunHasALogAndNoReport) {
  testing::ScratchDir dir;
  const std::string report = dir.file("report.json");
  EXPECT_FALSE(unfinishedRunAt(report));  // nothing yet: a fresh start
  {
    EpisodeLog log(episodeLogPath(report));
    log.append({{"episode", 0}});
  }
  EXPECT_TRUE(unfinishedRunAt(report));   // the fusion center died
  dir.write("report.json", "{}");
  EXPECT_FALSE(unfinishedRunAt(report));  // it finished: a new start is not a resume
}

}  // namespace
}  // namespace sensornet::report
