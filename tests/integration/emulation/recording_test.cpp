// Recording a run (`sensornet launch --record RUN.mcap`, recording/run_recorder.hpp), read back by
// @mcap/core, the format's reference reader (tests/integration/recording/read_with_mcap_core.cjs,
// installed by scripts/install-deps.sh), indexed and streamed with every CRC checked: every
// channel has its schema (the project's IDL, omgidl), the counts per topic are what the report
// and the schedule say were sent, the summary's statistics are right, and a run interrupted with
// Ctrl-C still leaves a complete file. `sensornet replay --info` (our own reader) agrees.
#include <gtest/gtest.h>
#include <signal.h>

#include <chrono>
#include <cmath>
#include <cstdlib>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <algorithm>
#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "launch_fixture.hpp"

namespace sensornet {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using namespace std::chrono_literals;
using testing::LeftoverGuard;
using testing::readJson;
using testing::RunningProgram;
using testing::runProcess;

class Recording : public testing::LaunchTest {
 protected:
  // What @mcap/core read, as read_with_mcap_core.cjs prints it.
  json readWithMcapCore(const fs::path& file) {
    const testing::ProcessResult r = runProcess(
        {"/usr/bin/env", "NODE_PATH=" SENSORNET_NODE_MODULES, SENSORNET_NODE,
         SENSORNET_SOURCE_DIR "/tests/integration/recording/read_with_mcap_core.cjs", file.string()},
        60s);
    EXPECT_EQ(r.exit_code, 0) << r.err;
    return r.exit_code == 0 ? json::parse(r.out) : json();
  }
  // Message counts per topic of what @mcap/core read, checked against its summary; `partitions`
  // gets each topic's writers' partitions (a channel per writer).
  std::map<std::string, std::uint64_t> countsOf(const json& read,
                                                std::map<std::string, std::vector<std::string>>* partitions = nullptr) {
    EXPECT_TRUE(read.at("streamDone").get<bool>());
    EXPECT_TRUE(read.at("footer").get<bool>());
    EXPECT_EQ(read.at("profile"), "sensornet");
    std::map<std::string, std::uint64_t> counts;
    std::uint64_t total = 0;
    const json& stats = read.at("statistics");
    for (const json& c : read.at("channels")) {
      const std::string id = std::to_string(c.at("id").get<int>());
      const std::uint64_t indexed = read.at("indexed").value(id, std::uint64_t{0});
      EXPECT_EQ(read.at("streamed").value(id, std::uint64_t{0}), indexed) << c.dump();
      EXPECT_EQ(stats.at("channelMessageCounts").value(id, std::uint64_t{0}), indexed) << c.dump();
      counts[c.at("topic").get<std::string>()] += indexed;
      if (partitions != nullptr) {
        (*partitions)[c.at("topic").get<std::string>()].push_back(
            c.at("metadata").at("partition").get<std::string>());
      }
      EXPECT_EQ(c.at("metadata").at("writer").get<std::string>().size(), 32u) << c.dump();
      total += indexed;
      // Its schema: the type of its topic, from the project's IDL.
      const std::string topic = c.at("topic").get<std::string>();
      EXPECT_EQ(c.at("messageEncoding"), "cdr");
      EXPECT_EQ(c.at("schema").at("encoding"), "omgidl");
      EXPECT_EQ(c.at("schema").at("name"), "sensornet::" + topic.substr(topic.find('/') + 1));
      EXPECT_EQ(c.at("schema").at("bytes").get<std::uintmax_t>(), idlBytes());
    }
    EXPECT_EQ(stats.at("messageCount").get<std::uint64_t>(), total);
    EXPECT_EQ(stats.at("chunkCount").get<int>(), read.at("chunkIndexes").get<int>());
    return counts;
  }
  static std::uintmax_t idlBytes() {
    return fs::file_size(fs::path(SENSORNET_SOURCE_DIR) / "idl" / "sensornet.idl");
  }
};

TEST_F(Recording, TheReferenceReaderReadsEveryTopicWithTheCountsTheReportGives) {
  const LeftoverGuard guard(run_id_);
  constexpr int kEpisodes = 3;
  const fs::path file = dir_ / "run.mcap";
  std::vector<std::string> argv = launchArgs(kEpisodes, "5");
  argv.insert(argv.end(), {"--seed", "7", "--no-html", "--record", file.string()});
  const testing::ProcessResult r = runProcess(argv, 120s);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("recorded "), std::string::npos) << r.err;
  const json report = readJson(dir_ / "report.json");
  ASSERT_TRUE(report.is_object());
  const json read = readWithMcapCore(file);
  ASSERT_TRUE(read.is_object());
  std::map<std::string, std::vector<std::string>> partitions;
  const auto counts = countsOf(read, &partitions);

  const std::string run = "sensornet/" + run_id_;
  std::uint64_t sent = 0;
  for (const json& e : report.at("per_episode")) {
    for (const json& s : e.at("sent")) sent += s.get<std::uint64_t>();
  }
  const std::uint64_t sensor_count = report.at("scenario").at("sensors").get<std::uint64_t>();
  // Every measurement sent was recorded once (no emulated network: no copies, no drops).
  EXPECT_EQ(counts.at("sensornet/Measurement"), sent);
  EXPECT_EQ(counts.at("sensornet/EpisodeTally"), kEpisodes * sensor_count);
  EXPECT_EQ(counts.at("sensornet/Report"), static_cast<std::uint64_t>(kEpisodes));
  EXPECT_EQ(counts.at("sensornet/Scenario"), 1u);
  EXPECT_EQ(counts.at("sensornet/Schedule"), report.at("schedule_versions").size());
  // Each episode's start, and the shutdown.
  EXPECT_EQ(counts.at("sensornet/EpisodeControl"), kEpisodes + 1u);
  EXPECT_GT(counts.at("sensornet/SensorStatus"), sensor_count);
  EXPECT_GT(counts.at("sensornet/FusionState"), 0u);
  EXPECT_FALSE(counts.contains("sensornet/Command")) << "nobody sent a command";
  // A channel per writer, named by the partition it wrote in: one agent per sensor here, each
  // with a status channel, and a measurement channel for each sensor that sent any.
  std::vector<std::string> every_sensor, sending;
  for (std::uint64_t j = 0; j < sensor_count; ++j) {
    every_sensor.push_back(run + "/sensors/" + std::to_string(j));
    std::uint64_t sent_by_j = 0;
    for (const json& e : report.at("per_episode")) sent_by_j += e.at("sent").at(j).get<std::uint64_t>();
    if (sent_by_j > 0) sending.push_back(every_sensor.back());
  }
  ASSERT_GE(sending.size(), 2u) << "the schedule must use several sensors";
  for (const auto& [topic, want] : {std::pair{"sensornet/Measurement", sending},
                                    std::pair{"sensornet/SensorStatus", every_sensor},
                                    std::pair{"sensornet/EpisodeTally", every_sensor}}) {
    std::vector<std::string> got = partitions.at(topic);
    std::sort(got.begin(), got.end());
    EXPECT_EQ(got, want) << topic;
  }
  EXPECT_EQ(partitions.at("sensornet/Report"), std::vector<std::string>{run});

  EXPECT_EQ(read.at("metadata").at("run").at("run_id"), run_id_);
  EXPECT_EQ(read.at("metadata").at("run").at("seed"), "7");
  EXPECT_EQ(read.at("metadata").at("run-end").at("status"), "completed");

  // Our own reader says the same.
  const testing::ProcessResult info =
      runProcess({testing::kLauncher, "replay", file.string(), "--info", "--json"}, 30s);
  ASSERT_EQ(info.exit_code, 0) << info.err;
  const json ours = json::parse(info.out);
  EXPECT_EQ(ours.at("messages"), read.at("statistics").at("messageCount"));
  std::map<std::string, std::uint64_t> ours_per_topic;
  for (const json& c : ours.at("channels")) {
    ours_per_topic[c.at("topic").get<std::string>()] += c.at("messages").get<std::uint64_t>();
  }
  EXPECT_EQ(ours_per_topic, counts);
}

// `sensornet record --run-id ID` joins a run from outside: started before the launch, it takes
// the whole run, every count as the report gives it (recomputed here), ends by itself with the
// run (exit 0), and its file replays to the recorded costs bit for bit.
TEST_F(Recording, RecordJoinsARunAndTakesAllOfIt) {
  const LeftoverGuard guard(run_id_);
  constexpr int kEpisodes = 3;
  const fs::path file = dir_ / "joined.mcap";
  RunningProgram recorder({testing::kLauncher, "record", "--run-id", run_id_, file.string()}, 120s);
  ASSERT_TRUE(testing::waitUntil([&] { return fs::exists(file); }, 20s)) << "the recorder never began";
  std::vector<std::string> argv = launchArgs(kEpisodes, "5");
  argv.insert(argv.end(), {"--seed", "11", "--no-html"});
  const testing::ProcessResult run = runProcess(argv, 120s);
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const testing::ProcessResult& r = recorder.result();
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("of run " + run_id_ + " in " + file.string() + " (ended)"), std::string::npos)
      << r.out;
  const json report = readJson(dir_ / "report.json");
  ASSERT_TRUE(report.is_object());
  const auto counts = countsOf(readWithMcapCore(file));
  std::uint64_t sent = 0;
  for (const json& e : report.at("per_episode")) {
    for (const json& n : e.at("sent")) sent += n.get<std::uint64_t>();
  }
  const std::uint64_t sensors = report.at("scenario").at("sensors").get<std::uint64_t>();
  EXPECT_EQ(counts.at("sensornet/Measurement"), sent);
  EXPECT_EQ(counts.at("sensornet/EpisodeTally"), kEpisodes * sensors);
  EXPECT_EQ(counts.at("sensornet/Report"), static_cast<std::uint64_t>(kEpisodes));
  EXPECT_EQ(counts.at("sensornet/Scenario"), 1u);
  EXPECT_EQ(counts.at("sensornet/EpisodeControl"), kEpisodes + 1u);
  const testing::ProcessResult replay = runProcess(
      {testing::kLauncher, "replay", file.string(), "--report", (dir_ / "replay.json").string()},
      60s);
  EXPECT_EQ(replay.exit_code, 0) << replay.out << replay.err;
}

// A run id nobody answers for: one line saying so after --wait, exit 1, and still a valid file.
TEST_F(Recording, RecordOfARunThatNeverComesSaysSoAndExitsOne) {
  const fs::path file = dir_ / "nothing.mcap";
  const testing::ProcessResult r = runProcess(
      {testing::kLauncher, "record", "--run-id", run_id_, file.string(), "--wait", "1"}, 30s);
  EXPECT_EQ(r.exit_code, 1) << r.err;
  EXPECT_NE(r.err.find("nothing of run " + run_id_ + " answered within 1 s"), std::string::npos)
      << r.err;
  const json read = readWithMcapCore(file);
  ASSERT_TRUE(read.is_object());
  EXPECT_EQ(read.at("metadata").at("run-end").at("status"), "never answered");
}

TEST_F(Recording, ARunInterruptedWithCtrlCLeavesACompleteFile) {
  const LeftoverGuard guard(run_id_);
  const fs::path file = dir_ / "cut.mcap";
  std::vector<std::string> argv = launchArgs(40, "2");
  argv.insert(argv.end(), {"--no-html", "--record", file.string()});
  RunningProgram launcher(argv, 120s);
  ASSERT_TRUE(testing::waitUntil(
      [&] { return testing::readJsonLines(dir_ / "report.jsonl").size() >= 1; }, 60s));
  const std::optional<pid_t> pid = testing::processOf(run_id_, testing::kLauncher, "launch");
  ASSERT_TRUE(pid.has_value());
  ASSERT_EQ(::kill(*pid, SIGINT), 0);
  const testing::ProcessResult& r = launcher.result();
  EXPECT_EQ(r.exit_code, 1) << r.err;  // interrupted (README, "Exit status")
  const json read = readWithMcapCore(file);
  ASSERT_TRUE(read.is_object());
  const auto counts = countsOf(read);
  EXPECT_GE(counts.at("sensornet/Report"), 1u);
  EXPECT_EQ(read.at("metadata").at("run-end").at("status"), "interrupted");
}

// A recording that cannot be written whole (the disk fills: here a file-size limit of 160 KB on
// the launcher and its children, which the 75 KB report fits and a 3-episode recording does not:
// its first chunk alone, the IDL as the schema of each of its 10 types, is about 185 KB, so the
// very first write fails) is one `recording_incomplete` fault: the run is degraded (exit 3, the
// outcome table), every episode still complete with the costs of the same seed's run without
// --record, recomputed from both reports.
TEST_F(Recording, ARecordingThatCannotBeWrittenWholeIsOneFaultAndChangesNoCost) {
  const LeftoverGuard guard(run_id_);
  const fs::path file = dir_ / "short.mcap";
  std::vector<std::string> argv = launchArgs(3, "4");
  argv.insert(argv.end(), {"--no-html", "--record", file.string()});
  // SIGXFSZ ignored (inherited through exec): a write past the limit fails with EFBIG, as a
  // full disk fails with ENOSPC. sh's ulimit -f counts 512-byte blocks (POSIX).
  std::vector<std::string> limited = {"/bin/sh", "-c", "trap '' XFSZ; ulimit -f 320; exec \"$@\"",
                                      "sh"};
  limited.insert(limited.end(), argv.begin(), argv.end());
  const testing::ProcessResult r = runProcess(limited, 120s);
  EXPECT_EQ(r.exit_code, 3) << r.err;  // degraded (README, "Exit status")
  EXPECT_NE(r.out.find("the recording fell short"), std::string::npos) << r.out;
  const json report = readJson(dir_ / "report.json");
  ASSERT_TRUE(report.is_object()) << r.err;
  EXPECT_EQ(report.at("status"), "degraded");
  ASSERT_EQ(report.at("faults").size(), 1u) << report.at("faults").dump(2);
  const json& fault = report.at("faults")[0];
  EXPECT_EQ(fault.at("kind"), "recording_incomplete");
  EXPECT_NE(fault.at("detail").get<std::string>().find(file.string()), std::string::npos)
      << fault.dump();
  // The file ends after its last whole record, whose end the fault gives.
  const std::uintmax_t kept = fs::file_size(file);
  EXPECT_LT(kept, 160u * 1024u + 1u);
  EXPECT_NE(fault.at("detail").get<std::string>().find("(" + std::to_string(kept) + " bytes)"),
            std::string::npos)
      << fault.dump() << " vs " << kept;

  fs::rename(dir_ / "report.json", dir_ / "recorded.json");
  fs::remove(dir_ / "report.jsonl");
  fs::remove_all(dir_ / "logs");
  const testing::ProcessResult clean = runProcess(launchArgs(3, "4"), 120s);
  ASSERT_EQ(clean.exit_code, 0) << clean.err;
  const json reference = readJson(dir_ / "report.json");
  const json recorded_report = readJson(dir_ / "recorded.json");
  const json& recorded = recorded_report.at("per_episode");
  ASSERT_EQ(recorded.size(), 3u);
  ASSERT_EQ(reference.at("per_episode").size(), 3u);
  for (std::size_t e = 0; e < 3; ++e) {
    EXPECT_TRUE(recorded[e].at("complete").get<bool>()) << e;
    EXPECT_EQ(recorded[e].at("realized_cost").get<double>(),
              reference.at("per_episode")[e].at("realized_cost").get<double>())
        << "episode " << e;
  }
}

// Offline replay (`sensornet replay RUN.mcap`): the recorded samples through the fusion center's
// own decisions give every episode's realized cost equal to the bit to the run's own report,
// recomputed here from both report files: with a live re-plan in the middle of the run (a
// version switching inside an episode), and behind the lossy scenario's emulated network
// (delays, drops, copies).
TEST_F(Recording, AnOfflineReplayEqualsTheRecordedRunToTheBit) {
  const LeftoverGuard guard(run_id_);
  struct Case {
    std::string name, scenario;
    bool replan;
  };
  const fs::path scenarios = fs::path(SENSORNET_SOURCE_DIR) / "scenarios";
  for (const Case& c : {Case{"replanned", (scenarios / "default.yaml").string(), true},
                        Case{"lossy", (scenarios / "lossy.yaml").string(), false}}) {
    SCOPED_TRACE(c.name);
    const fs::path file = dir_ / (c.name + ".mcap");
    const fs::path report_path = dir_ / (c.name + ".json");
    std::vector<std::string> argv =
        launchArgs(c.replan ? 5 : 3, "3", report_path, dir_ / (c.name + "-logs"), c.scenario);
    argv.insert(argv.end(), {"--seed", "11", "--no-html", "--record", file.string()});
    RunningProgram launcher(argv, 180s);
    if (c.replan) {
      ASSERT_TRUE(testing::waitUntil(
          [&] { return testing::readJsonLines(dir_ / (c.name + ".jsonl")).size() >= 1; }, 60s));
      const testing::ProcessResult replan = runProcess(
          {testing::kLauncher, "replan", "--run-id", run_id_, "--surrogate", "info", "--timeout",
           "60"},
          70s);
      EXPECT_EQ(replan.exit_code, 0) << replan.err;
    }
    const testing::ProcessResult& r = launcher.result();
    ASSERT_TRUE(r.exit_code == 0 || r.exit_code == 3) << r.err;  // lossy: degraded by design
    const json recorded = readJson(report_path);
    ASSERT_TRUE(recorded.is_object());
    if (c.replan) {
      ASSERT_GE(recorded.at("schedule_versions").size(), 2u) << "no re-plan happened";
    }

    const fs::path replayed_path = dir_ / (c.name + ".replay.json");
    const testing::ProcessResult replay = runProcess(
        {testing::kLauncher, "replay", file.string(), "--report", replayed_path.string()}, 120s);
    EXPECT_EQ(replay.exit_code, 0) << replay.out << replay.err;
    const json replayed = readJson(replayed_path);
    ASSERT_TRUE(replayed.is_object()) << replay.err;
    const json& want = recorded.at("per_episode");
    const json& got = replayed.at("per_episode");
    ASSERT_EQ(got.size(), want.size());
    for (std::size_t k = 0; k < got.size(); ++k) {
      EXPECT_EQ(got[k].at("realized_cost"), want[k].at("realized_cost")) << "episode " << k;
      EXPECT_EQ(got[k].at("received"), want[k].at("received")) << "episode " << k;
      EXPECT_EQ(got[k].at("sent"), want[k].at("sent")) << "episode " << k;
      EXPECT_EQ(got[k].at("complete"), want[k].at("complete")) << "episode " << k;
      EXPECT_EQ(got[k].at("schedule_versions"), want[k].at("schedule_versions")) << "episode " << k;
    }
    EXPECT_EQ(replayed.at("summary").at("mean"), recorded.at("summary").at("mean"));
    EXPECT_NE(replay.out.find(std::to_string(want.size()) + " of " + std::to_string(want.size()) +
                              " episodes equal the recording to the bit"),
              std::string::npos)
        << replay.out;
  }
}

// Live replay (`sensornet replay RUN.mcap --live --run-id NEW`): the recorded run's own traffic
// republished into a new run at twice the recorded pace. Our fusion center of the new run gives
// every episode's cost equal to the bit to the recorded run's report, every episode complete,
// every recorded measurement received (its received counts are the recorded run's sent counts).
TEST_F(Recording, ALiveReplayIsTheRecordedRunForAFusionCenterOfANewRun) {
  const LeftoverGuard guard(run_id_);
  const fs::path file = dir_ / "live.mcap";
  std::vector<std::string> argv = launchArgs(3, "4", dir_ / "recorded.json", dir_ / "rec-logs");
  argv.insert(argv.end(), {"--seed", "13", "--no-html", "--record", file.string()});
  const testing::ProcessResult recorded_run = runProcess(argv, 120s);
  ASSERT_EQ(recorded_run.exit_code, 0) << recorded_run.err;
  const json recorded = readJson(dir_ / "recorded.json");
  ASSERT_TRUE(recorded.is_object());

  const std::string replayed_run = run_id_ + "-live";
  const LeftoverGuard replay_guard(replayed_run);
  RunningProgram fusion({SENSORNET_FUSION_CENTER, "serve", "--run-id", replayed_run, "--report",
                         (dir_ / "live.json").string()},
                        120s);
  const testing::ProcessResult replay = runProcess(
      {testing::kLauncher, "replay", file.string(), "--live", "--run-id", replayed_run,
       "--time-scale", "2"},
      120s);
  EXPECT_EQ(replay.exit_code, 0) << replay.err;
  EXPECT_EQ(fusion.result().exit_code, 0) << fusion.result().err;
  const json live = readJson(dir_ / "live.json");
  ASSERT_TRUE(live.is_object());
  EXPECT_EQ(live.at("status"), "completed") << live.at("faults").dump();
  const json& want = recorded.at("per_episode");
  const json& got = live.at("per_episode");
  ASSERT_EQ(got.size(), want.size());
  for (std::size_t k = 0; k < got.size(); ++k) {
    EXPECT_EQ(got[k].at("realized_cost"), want[k].at("realized_cost")) << "episode " << k;
    EXPECT_EQ(got[k].at("received"), want[k].at("sent")) << "episode " << k;
    EXPECT_TRUE(got[k].at("complete").get<bool>()) << got[k].dump();
  }
}

// The same into an external fusion center: the C example (the scalar CD-KF in closed form) as
// the new run's fusion center, fed by a live replay of a recording of the scalar scenario that
// our fusion center fused: it receives every recorded measurement and its costs agree with the
// recorded run's to 1e-9 relative (two independent filters on identical data).
TEST_F(Recording, ALiveReplayFeedsAnExternalFusionCenterEveryMeasurement) {
  const LeftoverGuard guard(run_id_);
  const fs::path scenario = fs::path(SENSORNET_SOURCE_DIR) / "examples" / "c" / "scalar.yaml";
  const fs::path file = dir_ / "scalar.mcap";
  std::vector<std::string> argv =
      launchArgs(3, "4", dir_ / "recorded.json", dir_ / "rec-logs", scenario.string());
  argv.insert(argv.end(), {"--seed", "13", "--no-html", "--record", file.string()});
  const testing::ProcessResult recorded_run = runProcess(argv, 120s);
  ASSERT_EQ(recorded_run.exit_code, 0) << recorded_run.err;
  const json recorded = readJson(dir_ / "recorded.json");
  ASSERT_TRUE(recorded.is_object());

  const std::string replayed_run = run_id_ + "-c";
  const LeftoverGuard replay_guard(replayed_run);
  const std::string domain = std::to_string(160 + ::getpid() % 60);
  const std::string config =
      "file://" + (fs::path(SENSORNET_SOURCE_DIR) / "config" / "cyclonedds-loopback.xml").string();
  ::setenv("CYCLONEDDS_URI", config.c_str(), 1);  // for the example only: ours compile theirs in
  std::vector<std::string> example = {SENSORNET_EXTERNAL_FUSION_CENTER_EXAMPLE, "--run-id",
                                      replayed_run, "--domain-id", domain};
  for (const std::string& a : testing::scalarModelArgs(scenario)) example.push_back(a);
  RunningProgram external(example, 120s);
  const testing::ProcessResult replay = runProcess(
      {testing::kLauncher, "replay", file.string(), "--live", "--run-id", replayed_run,
       "--domain-id", domain, "--time-scale", "2"},
      120s);
  EXPECT_EQ(replay.exit_code, 0) << replay.err;
  const testing::ProcessResult& x = external.result();
  EXPECT_EQ(x.exit_code, 0) << x.err;
  const json& want = recorded.at("per_episode");
  for (std::size_t k = 0; k < want.size(); ++k) {
    const std::string line = "episode " + std::to_string(k) + " realized cost ";
    const auto at = x.out.find(line);
    ASSERT_NE(at, std::string::npos) << x.out;
    const double theirs = std::stod(x.out.substr(at + line.size()));
    const double ours = want[k].at("realized_cost").get<double>();
    EXPECT_LE(std::abs(theirs - ours), 1e-9 * ours) << "episode " << k;
  }
  EXPECT_NE(x.out.find("reported " + std::to_string(want.size()) + " episodes, " +
                       std::to_string(want.size()) + " complete"),
            std::string::npos)
      << "every episode complete: every recorded measurement arrived\n" << x.out;
}

TEST_F(Recording, AFileThatIsNotARecordingIsOneLineAndExitTwo) {
  const fs::path file = dir_ / "not.mcap";
  std::ofstream(file) << "hello";
  const testing::ProcessResult r =
      runProcess({testing::kLauncher, "replay", file.string(), "--info"}, 30s);
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  EXPECT_NE(r.err.find(file.string()), std::string::npos) << r.err;
}

}  // namespace
}  // namespace sensornet
