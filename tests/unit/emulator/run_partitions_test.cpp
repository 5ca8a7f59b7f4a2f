// The partitions that name who wrote a sample (emulator/run_partitions.hpp): what a sensor
// process writes in reads back as its own sensors, and nothing else reads as a sensor block.
#include "sensornet/emulator/run_partitions.hpp"

#include <gtest/gtest.h>

#include <fnmatch.h>

namespace sensornet::emulator {
namespace {

const std::string kRun = "sensornet/demo";

TEST(RunPartitions, ASensorProcessPartitionReadsBackAsItsSensors) {
  const std::vector<int> block = {0, 1, 2, 5, 7, 8};
  const std::string mine = sensorPartition(kRun, block);
  EXPECT_EQ(mine, "sensornet/demo/sensors/0-2,5,7-8");
  EXPECT_EQ(sensorsOfPartition(kRun, mine), block);
  EXPECT_EQ(sensorsOfPartition(kRun, sensorPartition(kRun, {4})), std::vector<int>{4});
}

TEST(RunPartitions, TheReadersPatternMatchesEveryBlockOfTheRunAndNoOtherRun) {
  // The pattern as DDS matches partitions (fnmatch, '*' spanning '/').
  const std::string pattern = sensorPartitionPattern(kRun);
  EXPECT_EQ(fnmatch(pattern.c_str(), sensorPartition(kRun, {3}).c_str(), 0), 0);
  EXPECT_EQ(fnmatch(pattern.c_str(), sensorPartition(kRun, {0, 1}).c_str(), 0), 0);
  EXPECT_NE(fnmatch(pattern.c_str(), sensorPartition("sensornet/other", {3}).c_str(), 0), 0);
  EXPECT_NE(fnmatch(pattern.c_str(), kRun.c_str(), 0), 0);
  EXPECT_NE(fnmatch(pattern.c_str(), commandPartition(kRun, CommandSender::Operator).c_str(), 0),
            0);
}

TEST(RunPartitions, OnlyTheCanonicalBlockOfThisRunSpeaksForSensors) {
  EXPECT_FALSE(sensorsOfPartition(kRun, kRun));
  EXPECT_FALSE(sensorsOfPartition(kRun, kRun + "/sensors/"));
  EXPECT_FALSE(sensorsOfPartition(kRun, kRun + "/sensors/0,1"));   // canonical: 0-1
  EXPECT_FALSE(sensorsOfPartition(kRun, kRun + "/sensors/1,0"));
  EXPECT_FALSE(sensorsOfPartition(kRun, kRun + "/sensors/01"));
  EXPECT_FALSE(sensorsOfPartition(kRun, kRun + "/sensors/x"));
  // A name a permission pattern "sensornet/*/sensors/1" also allows must not read as sensor 9.
  EXPECT_FALSE(sensorsOfPartition(kRun, kRun + "/sensors/9/sensors/1"));
  EXPECT_FALSE(sensorsOfPartition(kRun, "sensornet/other/sensors/1"));
  EXPECT_FALSE(sensorsOfPartition(kRun, "sensornet/demo2/sensors/1"));
}

TEST(RunPartitions, AWriterInTwoSensorBlocksSpeaksForNone) {
  EXPECT_EQ(sensorsOfPartitions(kRun, {kRun, sensorPartition(kRun, {2})}), std::vector<int>{2});
  EXPECT_FALSE(sensorsOfPartitions(kRun, {sensorPartition(kRun, {2}), sensorPartition(kRun, {3})}));
  EXPECT_FALSE(sensorsOfPartitions(kRun, {kRun}));
  EXPECT_FALSE(sensorsOfPartitions(kRun, {}));
}

TEST(RunPartitions, CommandsOfTheLauncherAndOfAnOperatorComeInPartitionsOfTheirOwn) {
  EXPECT_EQ(commandPartition(kRun, CommandSender::Launcher), "sensornet/demo/launcher");
  EXPECT_EQ(commandPartition(kRun, CommandSender::Operator), "sensornet/demo/operator");
}

}  // namespace
}  // namespace sensornet::emulator
