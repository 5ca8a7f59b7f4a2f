// Your code in the loop (issue 25): `sensornet launch --external-sensors IDS` starts no agent
// for those sensors and waits for a participant that speaks for them in their partition
// (docs/wire-protocol.md, "Sensor"). Here the participant is a sensor_agent the test starts
// itself, outside the launch, so its arrivals are drawn as ours are: the run must be the same run
// as one where the launcher started every agent (costs and counts per episode to the bit). A
// participant that never comes fails the run naming the sensors; an id the scenario does not
// have is bad input before anything starts.
//
// `--external-fusion-center` starts no fusion center: here the user's is our fusion_center
// started by the test (the run must equal one with ours, episode by episode), or a relay in this
// process that republishes the reference's Reports with the cost off by a known factor (the
// comparison `--reference-fusion` adds must measure that factor, and `--require
// fusion-agreement` must fail on it).

#include <gtest/gtest.h>
#include <signal.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <thread>
#include <vector>
#include <yaml-cpp/yaml.h>

#include "launch_fixture.hpp"
#include "sensornet/dds/participant.hpp"
#include "sensornet/dds/reader.hpp"
#include "sensornet/dds/topics.hpp"
#include "sensornet/dds/writer.hpp"
#include "sensornet/wire/run_options.hpp"
#include "sensornet/emulator/run_partitions.hpp"

namespace sensornet {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using namespace std::chrono_literals;
using testing::LeftoverGuard;
using testing::readJson;
using testing::RunningProgram;
using testing::runProcess;

constexpr int kEpisodes = 3;
const std::string kSensorAgentProgram = SENSORNET_SENSOR_AGENT;
const std::string kFusionCenterProgram = SENSORNET_FUSION_CENTER;

// The mean of the realized costs of the complete episodes of a report's per_episode.
double meanOfComplete(const json& per_episode) {
  double sum = 0.0;
  int count = 0;
  for (const json& e : per_episode) {
    if (!e.at("complete").get<bool>()) continue;
    sum += e.at("realized_cost").get<double>();
    ++count;
  }
  return count > 0 ? sum / count : std::nan("");
}

// An external fusion center that is off by a known factor: it reads the reference fusion
// center's Reports and FusionStates (partition P/reference) and republishes them in the run's
// partition with every realized cost multiplied by `factor`; it reads EpisodeControl as a fusion
// center must, to count as present.
class SkewedRelay {
 public:
  SkewedRelay(const std::string& run_id, double factor)
      : options_(optionsOf(run_id)),
        domain_(options_.domainConfig()),
        participant_(domain_),
        reports_(participant_),
        states_(participant_),
        controls_(participant_),
        reference_reports_(participant_, reports_,
                           dds::endpointQosIn<sensornet_Report>(
                               emulator::referencePartition(participant_.partition()))),
        reference_states_(participant_, states_,
                          dds::endpointQosIn<sensornet_FusionState>(
                              emulator::referencePartition(participant_.partition()))),
        control_reader_(participant_, controls_),
        report_writer_(participant_, reports_, dds::reportWriterQos()),
        state_writer_(participant_, states_),
        factor_(factor),
        thread_([this] { relay(); }) {}
  SkewedRelay(const SkewedRelay&) = delete;
  SkewedRelay& operator=(const SkewedRelay&) = delete;
  ~SkewedRelay() {
    stop_ = true;
    thread_.join();
  }

 private:
  static wire::RunOptions optionsOf(const std::string& run_id) {
    wire::RunOptions options;
    options.run_id = run_id;
    return options;
  }

  void relay() {
    while (!stop_) {
      for (const auto& s : reference_reports_.take(16).samples) {
        sensornet_Report skewed = *s.sample;  // borrows the loaned sample's strings
        skewed.realized_cost *= factor_;
        (void)report_writer_.write(skewed);
      }
      for (const auto& s : reference_states_.take(16).samples) {
        (void)state_writer_.write(*s.sample);
      }
      (void)control_reader_.take(16);
      std::this_thread::sleep_for(5ms);
    }
  }

  wire::RunOptions options_;
  dds::Domain domain_;
  dds::Participant participant_;
  dds::Topic<sensornet_Report> reports_;
  dds::Topic<sensornet_FusionState> states_;
  dds::Topic<sensornet_EpisodeControl> controls_;
  dds::Reader<sensornet_Report> reference_reports_;
  dds::Reader<sensornet_FusionState> reference_states_;
  dds::Reader<sensornet_EpisodeControl> control_reader_;
  dds::Writer<sensornet_Report> report_writer_;
  dds::Writer<sensornet_FusionState> state_writer_;
  double factor_;
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

class ExternalRoles : public testing::LaunchTest {
 protected:
  // The report of a run of seed 7 with every role ours: what a run with external roles that
  // behave as ours must equal. Null when that run failed.
  json cleanRun() {
    std::vector<std::string> clean =
        launchArgs(kEpisodes, "5", dir_ / "clean.json", dir_ / "clean-logs");
    clean.insert(clean.end(), {"--seed", "7", "--no-html"});
    const testing::ProcessResult c = runProcess(clean, 120s);
    EXPECT_EQ(c.exit_code, 0) << c.err;
    return c.exit_code == 0 ? readJson(dir_ / "clean.json") : json();
  }
};

TEST_F(ExternalRoles, SensorsSpokenForByAParticipantOfTheUsersMakeTheSameRun) {
  const LeftoverGuard guard(run_id_);
  const json expected = cleanRun();
  ASSERT_TRUE(expected.is_object()) << "the clean run of seed 7 failed";

  std::vector<std::string> argv = launchArgs(kEpisodes, "5", dir_ / "ext.json", dir_ / "ext-logs");
  argv.insert(argv.end(), {"--seed", "7", "--no-html", "--external-sensors", "2,5"});
  RunningProgram launcher(argv, 120s);
  // The user's participant: it speaks for sensors 2 and 5 only, and leaves with the run.
  RunningProgram external({kSensorAgentProgram, "--run-id", run_id_, "--sensors", "2,5"}, 120s);
  const testing::ProcessResult& r = launcher.result();
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(external.result().exit_code, 0) << external.result().err;
  EXPECT_NE(r.err.find("sensors 2,5 are external"), std::string::npos) << r.err;
  EXPECT_EQ(r.err.find("sensor_agent-2"), std::string::npos) << "an agent was started for sensor 2";
  EXPECT_EQ(r.err.find("sensor_agent-5"), std::string::npos) << "an agent was started for sensor 5";

  const json report = readJson(dir_ / "ext.json");
  ASSERT_TRUE(report.is_object()) << r.err;
  EXPECT_EQ(report.at("status"), "completed") << report.at("faults").dump();
  EXPECT_EQ(report.at("external").at("sensors"), json::array({2, 5}));
  const json& got = report.at("per_episode");
  const json& want = expected.at("per_episode");
  ASSERT_EQ(got.size(), want.size());
  for (std::size_t k = 0; k < got.size(); ++k) {
    EXPECT_EQ(got[k].at("realized_cost").get<double>(), want[k].at("realized_cost").get<double>())
        << "episode " << k;
    EXPECT_EQ(got[k].at("received"), want[k].at("received")) << "episode " << k;
    EXPECT_EQ(got[k].at("sent"), got[k].at("received")) << "episode " << k;
  }
}

TEST_F(ExternalRoles, AnExternalSensorThatLeavesMidRunIsADeathThePolicyAnswers) {
  const LeftoverGuard guard(run_id_);
  constexpr int kRunEpisodes = 6;
  std::vector<std::string> argv = launchArgs(kRunEpisodes, "2");
  argv.insert(argv.end(), {"--seed", "7", "--no-html", "--external-sensors", "2,5",
                           "--on-sensor-failure", "replan"});
  RunningProgram launcher(argv, 180s);
  RunningProgram external({kSensorAgentProgram, "--run-id", run_id_, "--sensors", "2,5"}, 180s);
  ASSERT_TRUE(testing::waitUntil(
      [&] { return testing::readJsonLines(dir_ / "report.jsonl").size() >= 2; }, 60s));
  const std::optional<pid_t> victim = testing::processOf(run_id_, kSensorAgentProgram, "2,5");
  ASSERT_TRUE(victim.has_value());
  ASSERT_EQ(::kill(*victim, SIGKILL), 0);
  const testing::ProcessResult& r = launcher.result();
  // A sensor's death the run survived: degraded, exit 3 (README, "Exit status").
  EXPECT_EQ(r.exit_code, 3) << r.err;
  const json report = readJson(dir_ / "report.json");
  ASSERT_TRUE(report.is_object()) << r.err;
  EXPECT_EQ(report.at("status"), "degraded");
  bool named = false;
  for (const json& f : report.at("faults")) {
    named |= f.at("kind") == "sensor_died" && f.at("process") == "external" &&
             f.value("sensors", json::array()) == json::array({2, 5}) &&
             f.at("detail").get<std::string>().find("left the run") != std::string::npos;
  }
  EXPECT_TRUE(named) << report.at("faults").dump();
  for (const json& f : report.at("faults")) {
    EXPECT_NE(f.at("kind"), "overload") << "waiting for the notice is not the fusion center's "
                                           "backlog: "
                                        << f.dump();
  }
  // The policy re-planned without them: the last version gives sensors 2 and 5 no rate at all.
  const json& versions = report.at("schedule_versions");
  ASSERT_GE(versions.size(), 2u) << "no re-plan after the death";
  for (const json& row : versions.back().at("rates")) {
    EXPECT_EQ(row.at(2).get<double>(), 0.0);
    EXPECT_EQ(row.at(5).get<double>(), 0.0);
  }
  // Every episode ran; the last one heard nothing of them.
  const json& episodes = report.at("per_episode");
  ASSERT_EQ(episodes.size(), static_cast<std::size_t>(kRunEpisodes));
  EXPECT_EQ(episodes.back().at("sent").at(2), 0);
  EXPECT_EQ(episodes.back().at("sent").at(5), 0);
}

#ifdef SENSORNET_EXTERNAL_SENSOR_EXAMPLE
// examples/c/external_sensor.c takes sensor 1 of the default scenario (p = 1). It draws its own
// arrivals, so the costs are another draw; what must hold is the accounting and its counts
// against the schedule (expectExternalSensorTookItsRole).
TEST_F(ExternalRoles, ASensorWrittenInCTakesItsRole) {
  const LeftoverGuard guard(run_id_);
  const std::string domain = std::to_string(160 + ::getpid() % 60);
  const std::string config =
      "file://" + (fs::path(SENSORNET_SOURCE_DIR) / "config" / "cyclonedds-loopback.xml").string();
  ::setenv("CYCLONEDDS_URI", config.c_str(), 1);  // for the example only: ours compile theirs in
  std::vector<std::string> argv = launchArgs(kEpisodes, "4");
  argv.insert(argv.end(), {"--seed", "7", "--no-html", "--external-sensors", "1", "--domain-id",
                           domain});
  RunningProgram launcher(argv, 120s);
  RunningProgram external({SENSORNET_EXTERNAL_SENSOR_EXAMPLE, "--run-id", run_id_, "--domain-id",
                           domain, "--sensor", "1", "--dim", "1", "--seed", "3"},
                          120s);
  const testing::ProcessResult& r = launcher.result();
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(external.result().exit_code, 0) << external.result().err;
  testing::expectExternalSensorTookItsRole(readJson(dir_ / "report.json"), kEpisodes, 1,
                                           external.result().out);
}

// A role left silent: after a few seconds the launcher says what an outside participant must
// have, with the C example's command line, and that line run as printed by a shell (no
// CYCLONEDDS_URI of ours in its environment: the line carries the run's configuration file)
// fills the role and the run completes with the sensor's every measurement fused. Told to send
// z = 0 (--measure zero), which measures nothing of the plant (x, y ~ N(0, 100 m^2)), the run
// still completes, and the report's NEES check says what it is worth.
TEST_F(ExternalRoles, TheLaunchersAdviceForASilentRoleWorksAsPrinted) {
  const LeftoverGuard guard(run_id_);
  ::unsetenv("CYCLONEDDS_URI");
  const std::string domain = std::to_string(160 + (::getpid() + 7) % 60);
  std::vector<std::string> argv = launchArgs(kEpisodes, "4");
  argv.insert(argv.end(), {"--seed", "7", "--no-html", "--external-sensors", "1", "--domain-id",
                           domain});
  testing::BackgroundProcess launcher(argv, (dir_ / "launch.log").string());
  const std::string lead = "fills sensor 1's role: ";
  ASSERT_TRUE(testing::waitUntil([&] { return launcher.log().find(lead) != std::string::npos; }, 30s))
      << launcher.log();
  const std::string log = launcher.log();
  EXPECT_NE(log.find("nothing has spoken for external sensors 1 yet"), std::string::npos) << log;
  EXPECT_NE(log.find("DDS domain " + domain + ", partition sensornet/" + run_id_), std::string::npos)
      << log;
  const std::size_t from = log.find(lead) + lead.size();
  std::string line = log.substr(from, log.find('\n', from) - from);
  const std::string program = " external_sensor ";
  ASSERT_NE(line.find(program), std::string::npos) << line;
  line.replace(line.find(program), program.size(),
               std::string(" ") + SENSORNET_EXTERNAL_SENSOR_EXAMPLE + " ");
  line += " --measure zero";
  const testing::ProcessResult external = runProcess({"/bin/sh", "-c", line}, 120s);
  EXPECT_EQ(external.exit_code, 0) << line << "\n" << external.err;
  ASSERT_EQ(launcher.waitForExit(60s), std::optional<int>(0)) << launcher.log();
  const json report = readJson(dir_ / "report.json");
  testing::expectExternalSensorTookItsRole(report, kEpisodes, 1, external.out);
  EXPECT_EQ(report.at("summary").at("nees_consistent"), false) << report.at("summary").dump();
  EXPECT_NE(launcher.log().find("OUTSIDE the 99.9% band"), std::string::npos) << launcher.log();
}

// Without --seed the C example draws its arrivals exactly as our agents do (keyed by the run
// seed, examples/c/schedule_book.c, written apart from our C++), and it measures the emulated
// plant through the world library (sensornet/world.h): two of them speaking for sensors 2 (p = 2)
// and 5 make the same run as our agents, every episode's cost, NEES and counts equal to the bit
// to a launch with our agents and the same seed (the NEES depends on every value measured).
TEST_F(ExternalRoles, SensorsWrittenInCDrawingAsOursMakeTheSameRun) {
  const LeftoverGuard guard(run_id_);
  const json expected = cleanRun();
  ASSERT_TRUE(expected.is_object()) << "the clean run of seed 7 failed";
  const std::string domain = std::to_string(160 + ::getpid() % 60);
  const std::string config =
      "file://" + (fs::path(SENSORNET_SOURCE_DIR) / "config" / "cyclonedds-loopback.xml").string();
  ::setenv("CYCLONEDDS_URI", config.c_str(), 1);  // for the example only: ours compile theirs in
  std::vector<std::string> argv = launchArgs(kEpisodes, "5", dir_ / "ext.json", dir_ / "ext-logs");
  argv.insert(argv.end(), {"--seed", "7", "--no-html", "--external-sensors", "2,5", "--domain-id",
                           domain});
  RunningProgram launcher(argv, 120s);
  RunningProgram camera({SENSORNET_EXTERNAL_SENSOR_EXAMPLE, "--run-id", run_id_, "--domain-id",
                         domain, "--sensor", "2", "--dim", "2"},
                        120s);
  RunningProgram cheap({SENSORNET_EXTERNAL_SENSOR_EXAMPLE, "--run-id", run_id_, "--domain-id",
                        domain, "--sensor", "5", "--dim", "1"},
                       120s);
  const testing::ProcessResult& r = launcher.result();
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(camera.result().exit_code, 0) << camera.result().err;
  EXPECT_EQ(cheap.result().exit_code, 0) << cheap.result().err;
  const json report = readJson(dir_ / "ext.json");
  ASSERT_TRUE(report.is_object()) << r.err;
  EXPECT_EQ(report.at("status"), "completed") << report.at("faults").dump();
  const json& got = report.at("per_episode");
  const json& want = expected.at("per_episode");
  ASSERT_EQ(got.size(), want.size());
  std::uint64_t spoken = 0;
  for (std::size_t k = 0; k < got.size(); ++k) {
    EXPECT_EQ(got[k].at("realized_cost").get<double>(), want[k].at("realized_cost").get<double>())
        << "episode " << k;
    EXPECT_EQ(got[k].at("received"), want[k].at("received")) << "episode " << k;
    EXPECT_EQ(got[k].at("nees").get<double>(), want[k].at("nees").get<double>()) << "episode " << k;
    spoken += got[k].at("sent").at(2).get<std::uint64_t>() + got[k].at("sent").at(5).get<std::uint64_t>();
  }
  EXPECT_GT(spoken, 0u) << "the schedule must give sensors 2 and 5 a rate for the test to mean "
                        << "something";
}

// examples/c/external_fusion_center.c is a user's estimator: the scalar CD-KF in closed form, with
// no code of ours, its model given on its command line, here read from the scenario file. It
// carries the run (its Reports pace it and make the report), and beside it our fusion center
// fuses the same measurements as the reference: two independent computations of each episode's
// cost, which must agree to rounding (1e-9 relative; measured 2e-16), recomputed here from the
// reference's own report file and from what the example printed.
TEST_F(ExternalRoles, AFusionCenterWrittenInCCarriesTheRun) {
  const LeftoverGuard guard(run_id_);
  const fs::path scenario = fs::path(SENSORNET_SOURCE_DIR) / "examples" / "c" / "scalar.yaml";
  const YAML::Node doc = YAML::LoadFile(scenario.string());
  const std::string domain = std::to_string(160 + ::getpid() % 60);
  const std::string config =
      "file://" + (fs::path(SENSORNET_SOURCE_DIR) / "config" / "cyclonedds-loopback.xml").string();
  ::setenv("CYCLONEDDS_URI", config.c_str(), 1);  // for the example only: ours compile theirs in
  std::vector<std::string> argv = launchArgs(kEpisodes, "4", dir_ / "report.json",
                                             dir_ / "logs", scenario.string());
  argv.insert(argv.end(), {"--seed", "7", "--no-html", "--external-fusion-center",
                           "--reference-fusion", "--require", "fusion-agreement<=1e-9",
                           "--domain-id", domain});
  RunningProgram launcher(argv, 120s);
  std::vector<std::string> example = {SENSORNET_EXTERNAL_FUSION_CENTER_EXAMPLE, "--run-id",
                                      run_id_, "--domain-id", domain};
  for (const std::string& a : testing::scalarModelArgs(scenario)) example.push_back(a);
  RunningProgram external(example, 120s);
  const testing::ProcessResult& l = launcher.result();
  const testing::ProcessResult& x = external.result();
  EXPECT_EQ(l.exit_code, 0) << l.err;
  EXPECT_EQ(x.exit_code, 0) << x.err;
  const json report = readJson(dir_ / "report.json");
  ASSERT_TRUE(report.is_object()) << l.err;
  EXPECT_EQ(report.at("status"), "completed") << report.at("faults").dump();
  EXPECT_EQ(report.at("external").at("fusion_center"), true);
  const json& got = report.at("per_episode");
  ASSERT_EQ(got.size(), static_cast<std::size_t>(kEpisodes)) << x.out;
  const json reference = readJson(dir_ / "logs" / "reference-report.json");
  ASSERT_TRUE(reference.is_object());
  const json& ours = reference.at("per_episode");
  ASSERT_EQ(ours.size(), got.size());
  double largest = 0.0;
  std::vector<int> used(doc["sensors"].size(), 0);
  for (std::size_t k = 0; k < got.size(); ++k) {
    const json& e = got[k];
    EXPECT_TRUE(e.at("complete").get<bool>()) << e.dump();
    EXPECT_EQ(e.at("received"), e.at("sent")) << "episode " << k;
    EXPECT_EQ(e.at("received"), ours[k].at("received")) << "episode " << k;
    EXPECT_TRUE(e.at("nees").is_null()) << "the example computes no NEES: " << e.dump();
    for (std::size_t j = 0; j < used.size(); ++j) used[j] += e.at("sent").at(j).get<int>();
    // What crossed the wire is what the example computed (printed with 17 digits).
    const double theirs = e.at("realized_cost").get<double>();
    char printed[128];
    std::snprintf(printed, sizeof printed, "episode %zu realized cost %.17g", k, theirs);
    EXPECT_NE(x.out.find(printed), std::string::npos) << printed << " in\n" << x.out;
    const double exact = ours[k].at("realized_cost").get<double>();
    largest = std::max(largest, std::abs(theirs - exact) / exact);
  }
  EXPECT_LE(largest, 1e-9);
  for (std::size_t j = 0; j < used.size(); ++j) {
    EXPECT_GT(used[j], 0) << "sensor " << j << " never measured: the plan must use every sensor "
                          << "for the model's order to be checked";
  }
  const json& comparison = report.at("reference_fusion");
  EXPECT_EQ(comparison.at("episodes_compared"), kEpisodes);
  EXPECT_EQ(comparison.at("max_relative_difference").get<double>(), largest);
  EXPECT_TRUE(report.at("summary").at("nees_mean").is_null()) << report.at("summary").dump();
  EXPECT_DOUBLE_EQ(report.at("summary").at("mean").get<double>(), meanOfComplete(got));
}
#endif

TEST_F(ExternalRoles, AnExternalSensorNobodySpeaksForFailsTheRunNamingIt) {
  const LeftoverGuard guard(run_id_);
  std::vector<std::string> argv = launchArgs(2, "5");
  argv.insert(argv.end(), {"--no-html", "--external-sensors", "3", "--ready-timeout", "3"});
  const testing::ProcessResult r = runProcess(argv, 90s);
  EXPECT_EQ(r.exit_code, 1) << r.err;
  const std::string why = "no participant spoke for the external sensors 3 (--external-sensors)";
  EXPECT_NE(r.err.find(why), std::string::npos) << r.err;
  const json report = readJson(dir_ / "report.json");
  ASSERT_TRUE(report.is_object()) << r.err;
  EXPECT_EQ(report.at("status"), "failed");
  EXPECT_EQ(report.at("episodes_planned"), 2) << "the plan is what the launch asked for";
  EXPECT_NE(r.out.find("episodes: 0 complete, 0 incomplete, of 2 planned"), std::string::npos)
      << r.out;
  bool named = false;
  for (const json& f : report.at("faults")) {
    named |= f.at("process") == "coordinator" &&
             f.at("detail").get<std::string>().find(why) != std::string::npos;
  }
  EXPECT_TRUE(named) << report.at("faults").dump();
}

TEST_F(ExternalRoles, AnExternalFusionCenterCarriesTheRunAndItsReportsMakeTheReport) {
  const LeftoverGuard guard(run_id_);
  const json expected = cleanRun();
  ASSERT_TRUE(expected.is_object()) << "the clean run of seed 7 failed";

  std::vector<std::string> argv = launchArgs(kEpisodes, "5", dir_ / "ext.json", dir_ / "ext-logs");
  argv.insert(argv.end(), {"--seed", "7", "--no-html", "--external-fusion-center",
                           "--reference-fusion", "--require", "fusion-agreement<=1e-12"});
  RunningProgram launcher(argv, 120s);
  // The user's fusion center: ours, started outside the launch, with a report of its own.
  RunningProgram external({kFusionCenterProgram, "serve", "--run-id", run_id_, "--report",
                           (dir_ / "users.json").string()},
                          120s);
  const testing::ProcessResult& r = launcher.result();
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(external.result().exit_code, 0) << external.result().err;
  EXPECT_NE(r.err.find("the fusion center is external"), std::string::npos) << r.err;
  EXPECT_EQ(r.err.find("started fusion_center"), std::string::npos) << r.err;

  const json report = readJson(dir_ / "ext.json");
  ASSERT_TRUE(report.is_object()) << r.err;
  EXPECT_EQ(report.at("status"), "completed") << report.at("faults").dump();
  EXPECT_EQ(report.at("external").at("fusion_center"), true);
  const json& got = report.at("per_episode");
  const json& want = expected.at("per_episode");
  const json users = readJson(dir_ / "users.json").at("per_episode");
  ASSERT_EQ(got.size(), want.size());
  ASSERT_EQ(users.size(), want.size());
  for (std::size_t k = 0; k < got.size(); ++k) {
    // What went over the wire is what the user's fusion center computed, and the same run as ours.
    EXPECT_EQ(got[k].at("realized_cost").get<double>(), users[k].at("realized_cost").get<double>())
        << "episode " << k;
    EXPECT_EQ(got[k].at("realized_cost").get<double>(), want[k].at("realized_cost").get<double>())
        << "episode " << k;
    EXPECT_EQ(got[k].at("received"), want[k].at("received")) << "episode " << k;
  }
  // The summary from those entries, recomputed here.
  EXPECT_DOUBLE_EQ(report.at("summary").at("mean").get<double>(), meanOfComplete(got));
  EXPECT_EQ(report.at("summary").at("episodes_complete"), kEpisodes);
  // The reference fused the same measurements: its own report file says the same costs.
  const json reference = readJson(dir_ / "ext-logs" / "reference-report.json");
  ASSERT_TRUE(reference.is_object());
  const json& comparison = report.at("reference_fusion");
  EXPECT_EQ(comparison.at("episodes_compared"), kEpisodes);
  for (std::size_t k = 0; k < got.size(); ++k) {
    EXPECT_EQ(reference.at("per_episode")[k].at("realized_cost").get<double>(),
              want[k].at("realized_cost").get<double>());
    EXPECT_EQ(comparison.at("per_episode")[k].at("relative_difference").get<double>(), 0.0);
  }
  EXPECT_EQ(comparison.at("max_relative_difference").get<double>(), 0.0);
}

// In a secured run the external fusion center presents the fusion center's identity of `pki
// init` and carries the run; with a sensor's identity it cannot take the role (governance: a
// sensor may not write Reports), and the run fails naming the missing role.
TEST_F(ExternalRoles, ASecuredRunTakesAnExternalFusionCenterOnlyWithTheFusionCentersIdentity) {
  const LeftoverGuard guard(run_id_);
  const fs::path pki = dir_ / "pki";
  const testing::ProcessResult made = runProcess(
      {testing::kLauncher, "pki", "init", pki.string(), "--days", "30", "--scenario",
       testing::kDefaultScenario},
      120s);
  ASSERT_EQ(made.exit_code, 0) << made.err;
  const auto launchWith = [&](const std::string& identity, const std::string& name,
                              const std::string& ready_timeout) {
    std::vector<std::string> argv =
        launchArgs(2, "5", dir_ / (name + ".json"), dir_ / (name + "-logs"));
    argv.insert(argv.end(), {"--no-html", "--security", pki.string(), "--external-fusion-center",
                             "--ready-timeout", ready_timeout});
    RunningProgram launcher(argv, 120s);
    RunningProgram external({kFusionCenterProgram, "serve", "--run-id", run_id_, "--security",
                             (pki / identity).string(), "--report",
                             (dir_ / (name + "-users.json")).string()},
                            120s);
    testing::ProcessResult r = launcher.result();
    return std::pair{r, readJson(dir_ / (name + ".json"))};
  };
  const auto [good, good_report] = launchWith("fusion_center", "good", "30");
  EXPECT_EQ(good.exit_code, 0) << good.err;
  ASSERT_TRUE(good_report.is_object()) << good.err;
  EXPECT_EQ(good_report.at("status"), "completed") << good_report.at("faults").dump();
  EXPECT_EQ(good_report.at("per_episode").size(), 2u);

  const auto [stolen, stolen_report] = launchWith("sensor-1", "stolen", "4");
  EXPECT_EQ(stolen.exit_code, 1) << stolen.err;
  EXPECT_NE(stolen.err.find("no participant played the fusion center"), std::string::npos)
      << stolen.err;
  ASSERT_TRUE(stolen_report.is_object()) << stolen.err;
  EXPECT_EQ(stolen_report.at("status"), "failed");
  EXPECT_EQ(stolen_report.value("per_episode", json::array()).size(), 0u);
}

TEST_F(ExternalRoles, TheReferenceMeasuresHowFarAnExternalFilterIsOff) {
  const LeftoverGuard guard(run_id_);
  constexpr double kSkew = 1.0 + 1e-3;
  std::vector<std::string> argv = launchArgs(kEpisodes, "5");
  argv.insert(argv.end(), {"--seed", "3", "--no-html", "--external-fusion-center",
                           "--reference-fusion", "--require", "fusion-agreement<=1e-6"});
  const SkewedRelay relay(run_id_, kSkew);
  const testing::ProcessResult r = runProcess(argv, 120s);
  // The run itself completed; the criterion failed: exit 4 (README, "Exit status").
  EXPECT_EQ(r.exit_code, 4) << r.err;
  const json report = readJson(dir_ / "report.json");
  ASSERT_TRUE(report.is_object()) << r.err;
  EXPECT_EQ(report.at("status"), "completed") << report.at("faults").dump();
  const json reference = readJson(dir_ / "logs" / "reference-report.json");
  ASSERT_TRUE(reference.is_object()) << r.err;
  const json& got = report.at("per_episode");
  ASSERT_EQ(got.size(), static_cast<std::size_t>(kEpisodes));
  double largest = 0.0;
  for (std::size_t k = 0; k < got.size(); ++k) {
    const double ours = reference.at("per_episode")[k].at("realized_cost").get<double>();
    const double theirs = got[k].at("realized_cost").get<double>();
    EXPECT_EQ(theirs, ours * kSkew) << "episode " << k;
    largest = std::max(largest, std::abs(theirs - ours) / ours);
  }
  const json& comparison = report.at("reference_fusion");
  EXPECT_EQ(comparison.at("max_relative_difference").get<double>(), largest);
  EXPECT_NEAR(largest, kSkew - 1.0, 1e-12);
  const json& checks = report.at("requirements");
  ASSERT_EQ(checks.size(), 1u);
  EXPECT_EQ(checks[0].at("pass"), false);
}

TEST_F(ExternalRoles, AnExternalFusionCenterThatNeverComesFailsTheRunNamingIt) {
  const LeftoverGuard guard(run_id_);
  std::vector<std::string> argv = launchArgs(2, "5");
  argv.insert(argv.end(), {"--no-html", "--external-fusion-center", "--ready-timeout", "3"});
  const testing::ProcessResult r = runProcess(argv, 90s);
  EXPECT_EQ(r.exit_code, 1) << r.err;
  const std::string why = "no participant played the fusion center (--external-fusion-center)";
  EXPECT_NE(r.err.find(why), std::string::npos) << r.err;
  const json report = readJson(dir_ / "report.json");
  ASSERT_TRUE(report.is_object()) << r.err;
  EXPECT_EQ(report.at("status"), "failed");
  bool named = false;
  for (const json& f : report.at("faults")) {
    named |= f.at("process") == "coordinator" &&
             f.at("detail").get<std::string>().find(why) != std::string::npos;
  }
  EXPECT_TRUE(named) << report.at("faults").dump();
}

TEST_F(ExternalRoles, AReferenceWithoutAnExternalFusionCenterIsBadInput) {
  std::vector<std::string> argv = launchArgs(2, "5");
  argv.insert(argv.end(), {"--reference-fusion"});
  const testing::ProcessResult r = runProcess(argv, 30s);
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  EXPECT_NE(r.err.find("--external-fusion-center as well"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(dir_ / "logs")) << "nothing may start on bad input";
}

TEST_F(ExternalRoles, AnExternalSensorTheScenarioDoesNotHaveIsBadInput) {
  std::vector<std::string> argv = launchArgs(2, "5");
  argv.insert(argv.end(), {"--external-sensors", "2,9"});
  const testing::ProcessResult r = runProcess(argv, 30s);
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  EXPECT_NE(r.err.find("--external-sensors"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("got 9"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(dir_ / "logs")) << "nothing may start on bad input";
}

}  // namespace
}  // namespace sensornet
