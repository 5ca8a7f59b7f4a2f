// A secured run (issue 12, part 3), with real processes over Cyclone DDS on loopback:
// - without DDS Security, a second writer claiming a sensor that already has a live writer is
//   kept out and reported (rejected as foreign_writer, a fault, status degraded, exit 3), and the
//   realized costs are those of a clean run with the same seed;
// - `sensornet pki init` and `--security`: a secured run's costs equal an unsecured run's; a
//   participant without a certificate that publishes a Schedule with a higher version and
//   Measurements claiming sensor 0 changes nothing (the run completes clean); an expired
//   certificate and one signed by another CA are refused before anything starts (exit 2, one
//   line naming the file and why);
// - a stolen credential (issue 30): with sensor 1's process identity an attacker cannot create a
//   Schedule writer nor write in another sensor's partition, and what it writes in its own for
//   sensor 0 before the agents (the pre-launch impostor), for sensor 4 and a forged tally of
//   sensor 2 are all kept out as wrong_identity while the real agents' samples are fused (costs
//   of a clean run); with the operator's, a forged failure notice for a live sensor is refused
//   by right (command_refused) and the sensor goes on delivering.
//
// Costs are compared with a clean launch of the same seed and schedule in the same test: the
// fusion takes the same floating-point steps whatever the arrival timing, so they are equal bit
// for bit. Every test uses its own run id and temporary folder (LaunchTest).

#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "launch_fixture.hpp"
#include "sensornet/dds/participant.hpp"
#include "sensornet/dds/topics.hpp"
#include "sensornet/dds/wire.hpp"
#include "sensornet/dds/dds_error.hpp"
#include "sensornet/dds/writer.hpp"
#include "sensornet/dds/reader.hpp"
#include "sensornet/wire/messages.hpp"
#include "sensornet/wire/run_options.hpp"
#include "sensornet/emulator/run_partitions.hpp"
#include "sensornet/io/scenario_file.hpp"

namespace sensornet {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using namespace std::chrono_literals;
using testing::LeftoverGuard;
using testing::readJson;
using testing::readJsonLines;
using testing::RunningProgram;
using testing::runProcess;
using testing::waitUntil;

constexpr int kExitCompleted = 0;
constexpr int kExitBadInput = 2;
constexpr int kExitDegraded = 3;
constexpr int kEpisodes = 4;
constexpr const char* kSeed = "17";

std::vector<double> realizedCosts(const json& report) {
  std::vector<double> costs;
  for (const json& e : report.at("per_episode")) costs.push_back(e.at("realized_cost").get<double>());
  return costs;
}

// Within the default scenario's budget (C = [1 1 1 1 1 1; 0 0 2 1 0 0], b = [12, 6]).
json uniformSchedule() {
  json rates = json::array();
  for (int i = 0; i < 30; ++i) rates.push_back({2.0, 2.0, 1.5, 2.0, 2.0, 2.0});
  return {{"horizon", 3.0}, {"intervals", 30}, {"rates", rates}};
}

class Security : public testing::LaunchTest {
 protected:
  void SetUp() override {
    LaunchTest::SetUp();
    schedule_ = (dir_ / "schedule.json").string();
    std::ofstream(schedule_) << uniformSchedule().dump();
  }

  // A launch of the default scenario with this test's seed and schedule, report into `name`.json.
  [[nodiscard]] std::vector<std::string> launch(const std::string& name,
                                                const std::string& time_scale,
                                                const std::vector<std::string>& extra = {}) const {
    std::vector<std::string> argv =
        launchArgs(kEpisodes, time_scale, dir_ / (name + ".json"), dir_ / (name + "-logs"));
    argv.insert(argv.end(), {"--seed", kSeed, "--schedule", schedule_, "--no-html"});
    argv.insert(argv.end(), extra.begin(), extra.end());
    return argv;
  }

  // The realized costs of a clean launch (exit 0, every episode complete).
  std::vector<double> cleanCosts(const std::vector<std::string>& extra = {}) {
    const testing::ProcessResult r = runProcess(launch("clean", "10", extra), 120s);
    EXPECT_EQ(r.exit_code, kExitCompleted) << r.err;
    const json report = readJson(dir_ / "clean.json");
    EXPECT_EQ(report.value("status", ""), "completed") << report.dump();
    const std::vector<double> costs = realizedCosts(report);
    EXPECT_EQ(costs.size(), static_cast<std::size_t>(kEpisodes));
    return costs;
  }

  std::string schedule_;
};

constexpr std::uint64_t kClaimsPerEpisode = 20;

// Well-formed measurements claiming `sensor` (one value, times in [0, T], version 1) of the
// episodes from `first` to the last, written by `writer`: kClaimsPerEpisode per episode.
void writeClaimsOf(dds::Writer<sensornet_Measurement>& writer, const std::string& run_id,
                   std::uint32_t first, std::uint32_t sensor = 0) {
  const std::vector<double> z = {1e3};
  for (std::uint32_t episode = first; episode < kEpisodes; ++episode) {
    for (std::uint64_t i = 0; i < kClaimsPerEpisode; ++i) {
      sensornet_Measurement m{};
      m.sensor_id = sensor;
      m.run_id = dds::borrowString(run_id);
      m.episode = episode;
      m.seq = 100000 + i;
      m.emulated_time_s = 0.1 + 0.14 * static_cast<double>(i);
      m.schedule_version = 1;
      m.publish_wall_time_ns = emulator::wallNowNs();
      dds::borrowSequence(m.z, z);
      // A reliable keep-all writer blocks when its readers lag (a loaded machine) and times out
      // after max_blocking_time; like a sensor agent, the writer retries (up to 10 s).
      dds::WriteResult result = writer.write(m);
      for (int attempt = 0; attempt < 100 && result == dds::WriteResult::TimedOut; ++attempt) {
        result = writer.write(m);
      }
      ASSERT_EQ(result, dds::WriteResult::Written);
    }
  }
}

// A well-formed Schedule of the run's scenario, version 2 from episode 1: every measurement on
// sensor 0 (C's second row does not involve it), which would change every later cost.
dds::WriteResult writeHijackingSchedule(dds::Writer<sensornet_Schedule>& writer,
                                        const std::string& run_id) {
  const std::string yaml = testing::readText(testing::kDefaultScenario);
  const Scenario scenario = parseScenarioYaml(yaml, testing::kDefaultScenario);
  emulator::ScheduleVersion v;
  v.version = 2;
  v.effective_episode = 1;
  Eigen::MatrixXd rates = Eigen::MatrixXd::Zero(30, scenario.sensorCount());
  rates.col(0).setConstant(12.0);
  v.schedule = RateSchedule(scenario.horizon_s, rates);
  v.surrogate = SurrogateKind::File;
  return wire::publishSchedule(writer, run_id, digestOf(yaml), v);
}

// Makes the security files of a run of the default scenario in `dir` with `sensornet pki init`
// (one identity per sensor process, as the launch starts them).
void pkiInit(const fs::path& dir) {
  const testing::ProcessResult r =
      runProcess({testing::kLauncher, "pki", "init", dir.string(), "--days", "30", "--scenario",
                  testing::kDefaultScenario},
                 120s);
  ASSERT_EQ(r.exit_code, 0) << r.err;
}

// The identity a stolen credential of sensor 1's host gives: its process's folder.
const char* const kStolenSensor = "sensor-1";

// Replaces the sensor identity in `dir` with one signed by its CA that expired in 2021
// (`openssl ca` with explicit dates; `x509 -days` cannot go back in time).
void expireSensorCertificate(const fs::path& dir) {
  const fs::path work = dir / "expired";
  fs::create_directories(work);
  std::ofstream(work / "ca.cnf")
      << "[ca]\ndefault_ca = this\n[this]\ndatabase = " << (work / "index.txt").string()
      << "\nnew_certs_dir = " << work.string() << "\nserial = " << (work / "serial").string()
      << "\ndefault_md = sha256\npolicy = any\n[any]\norganizationName = optional\n"
         "commonName = supplied\n";
  std::ofstream(work / "index.txt");
  std::ofstream(work / "serial") << "1000\n";
  const fs::path sensor = dir / kStolenSensor;
  ASSERT_EQ(runProcess({"/usr/bin/openssl", "req", "-new", "-key", (sensor / "key.pem").string(),
                        "-subj", "/O=sensornet/CN=" + std::string(kStolenSensor), "-out",
                        (work / "sensor.csr").string()},
                       30s)
                .exit_code,
            0);
  const testing::ProcessResult r = runProcess(
      {"/usr/bin/openssl", "ca", "-batch", "-config", (work / "ca.cnf").string(), "-cert",
       (dir / "ca" / "ca.pem").string(), "-keyfile", (dir / "ca" / "ca.key").string(), "-in",
       (work / "sensor.csr").string(), "-out", (sensor / "identity.pem").string(), "-notext",
       "-startdate", "20200101000000Z", "-enddate", "20210101000000Z"},
      30s);
  ASSERT_EQ(r.exit_code, 0) << r.err;
}

TEST_F(Security, SecondWriterClaimingASensorIsKeptOutAndReported) {
  const LeftoverGuard guard(run_id_);
  const std::vector<double> clean = cleanCosts();

  RunningProgram launcher(launch("foreign", "2"), 120s);
  wire::RunOptions options;
  options.run_id = run_id_;
  dds::Domain domain(options.domainConfig());
  dds::Participant participant(domain);
  dds::Topic<sensornet_Measurement> topic(participant);
  // Without security anyone may write in sensor 0's partition: the one-writer rule holds.
  dds::Writer<sensornet_Measurement> foreign(
      participant, topic,
      dds::endpointQosIn<sensornet_Measurement>(
          emulator::sensorPartition(participant.partition(), {0})));
  // Sensor 0's own writer has spoken once the first episode is logged.
  ASSERT_TRUE(waitUntil([&] { return readJsonLines(dir_ / "foreign.jsonl").size() >= 1; }, 60s));
  ASSERT_TRUE(foreign.waitForReaders(1, 10s));
  writeClaimsOf(foreign, run_id_, 1);
  ASSERT_TRUE(foreign.waitForAcks(10s));

  const testing::ProcessResult& r = launcher.result();
  EXPECT_EQ(r.exit_code, kExitDegraded) << r.err;
  const json report = readJson(dir_ / "foreign.json");
  ASSERT_TRUE(report.is_object()) << r.err;
  EXPECT_EQ(report.at("status"), "degraded");
  EXPECT_EQ(realizedCosts(report), clean);
  const json& by_reason = report.at("summary").at("rejected_by_reason");
  EXPECT_GT(by_reason.value("foreign_writer", 0), 0) << by_reason.dump();
  int named = 0;
  for (const json& f : report.at("faults")) named += f.at("kind") == "foreign_writer" ? 1 : 0;
  EXPECT_EQ(named, 1) << "one fault per foreign writer: " << report.at("faults").dump();
  for (const json& e : report.at("per_episode")) EXPECT_TRUE(e.at("complete").get<bool>());
}

class SecuredRun : public Security {
 protected:
  void SetUp() override {
    Security::SetUp();
    pki_ = dir_ / "pki";
    pkiInit(pki_);
  }

  [[nodiscard]] std::vector<std::string> secured(const std::string& name,
                                                 const std::string& time_scale) const {
    return launch(name, time_scale, {"--security", pki_.string()});
  }

  // A launch refused before anything started: exit 2, one line naming `file` and `why`.
  void expectRefusedAtStart(const fs::path& pki, const fs::path& file, const std::string& why) {
    const testing::ProcessResult r =
        runProcess(launch("refused", "10", {"--security", pki.string()}), 60s);
    EXPECT_EQ(r.exit_code, kExitBadInput) << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
    EXPECT_NE(r.err.find(file.string()), std::string::npos) << r.err;
    EXPECT_NE(r.err.find(why), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(dir_ / "refused-logs")) << "nothing may start";
  }

  fs::path pki_;
};

TEST_F(SecuredRun, CostsEqualThoseOfAnUnsecuredRunWithTheSameSeed) {
  const LeftoverGuard guard(run_id_);
  const std::vector<double> clean = cleanCosts();
  const testing::ProcessResult r = runProcess(secured("secured", "10"), 120s);
  EXPECT_EQ(r.exit_code, kExitCompleted) << r.err;
  const json report = readJson(dir_ / "secured.json");
  ASSERT_TRUE(report.is_object()) << r.err;
  EXPECT_EQ(report.at("status"), "completed") << report.at("faults").dump();
  EXPECT_EQ(realizedCosts(report), clean);
}

TEST_F(SecuredRun, ParticipantWithoutCertificateChangesNothing) {
  const LeftoverGuard guard(run_id_);
  const std::vector<double> clean = cleanCosts();
  RunningProgram launcher(secured("intruded", "2"), 120s);
  wire::RunOptions options;  // no --security: a plain participant on the run's domain
  options.run_id = run_id_;
  dds::Domain domain(options.domainConfig());
  dds::Participant participant(domain);
  dds::Topic<sensornet_Schedule> schedule_topic(participant);
  dds::Topic<sensornet_Measurement> measurement_topic(participant);
  dds::Writer<sensornet_Schedule> schedules(participant, schedule_topic);
  dds::Writer<sensornet_Measurement> measurements(
      participant, measurement_topic,
      dds::endpointQosIn<sensornet_Measurement>(
          emulator::sensorPartition(participant.partition(), {0})));
  ASSERT_TRUE(waitUntil([&] { return readJsonLines(dir_ / "intruded.jsonl").size() >= 1; }, 60s));
  EXPECT_EQ(schedules.matchedReaders(), 0u) << "an unauthenticated participant matched";
  EXPECT_EQ(writeHijackingSchedule(schedules, run_id_), dds::WriteResult::Written);
  writeClaimsOf(measurements, run_id_, 1);

  const testing::ProcessResult& r = launcher.result();
  EXPECT_EQ(r.exit_code, kExitCompleted) << r.err;
  const json report = readJson(dir_ / "intruded.json");
  ASSERT_TRUE(report.is_object()) << r.err;
  EXPECT_EQ(report.at("status"), "completed") << report.at("faults").dump();
  EXPECT_EQ(realizedCosts(report), clean);
  EXPECT_EQ(report.at("summary").at("rejected"), 0);
  EXPECT_EQ(report.at("schedule_versions").size(), 1u) << report.at("schedule_versions").dump();
}

// A well-formed tally of `sensor` for `episode` claiming `sent` measurements.
dds::WriteResult writeTally(dds::Writer<sensornet_EpisodeTally>& writer, const std::string& run_id,
                            std::uint32_t sensor, std::uint32_t episode, std::uint64_t sent) {
  sensornet_EpisodeTally t{};
  t.sensor_id = sensor;
  t.run_id = dds::borrowString(run_id);
  t.episode = episode;
  t.sent = sent;
  t.finished = true;
  t.wall_time_ns = emulator::wallNowNs();
  return writer.write(t);
}

// Stolen: the files of sensor 1's process. They allow no Schedule writer and no writer in
// another sensor's partition (access control refuses them); in its own partition the attacker
// speaks before any agent does, for sensor 0 (the pre-launch impostor), for sensor 4 and with a
// forged tally of sensor 2 claiming 500 sent. Every one of those samples is kept out as
// wrong_identity and named; the real agents' samples are fused: costs of a clean run, nothing
// lost, one schedule version. (Before identities were bound to sensors, the impostor owned
// sensor 0, the forged tally stalled every episode, and the run ended completed or failed.)
TEST_F(SecuredRun, AStolenSensorIdentitySpeaksForItsOwnSensorsOnlyWhateverItsOrder) {
  const LeftoverGuard guard(run_id_);
  const std::vector<double> clean = cleanCosts();
  wire::RunOptions options;
  options.run_id = run_id_;
  options.security_dir = (pki_ / kStolenSensor).string();
  options.security_identity = {dds::SecurityRole::Sensor, "1"};
  dds::Domain domain(options.domainConfig());
  dds::Participant participant(domain);
  dds::Topic<sensornet_Schedule> schedule_topic(participant);
  dds::Topic<sensornet_Measurement> measurement_topic(participant);
  dds::Topic<sensornet_EpisodeTally> tally_topic(participant);
  const std::string p = participant.partition();
  EXPECT_THROW(dds::Writer<sensornet_Schedule>(participant, schedule_topic), dds::DdsError);
  EXPECT_THROW(dds::Writer<sensornet_Measurement>(
                   participant, measurement_topic,
                   dds::endpointQosIn<sensornet_Measurement>(emulator::sensorPartition(p, {0}))),
               dds::DdsError)
      << "sensor 1's identity wrote in sensor 0's partition";
  dds::Writer<sensornet_Measurement> measurements(
      participant, measurement_topic,
      dds::endpointQosIn<sensornet_Measurement>(emulator::sensorPartition(p, {1})));
  dds::Writer<sensornet_EpisodeTally> tallies(
      participant, tally_topic,
      dds::endpointQosIn<sensornet_EpisodeTally>(emulator::sensorPartition(p, {1})));

  RunningProgram launcher(secured("stolen", "2"), 120s);
  // First to speak: as soon as the fusion center reads, before the first episode starts.
  ASSERT_TRUE(measurements.waitForReaders(1, 60s));
  ASSERT_TRUE(tallies.waitForReaders(1, 10s));
  writeClaimsOf(measurements, run_id_, 0, 0);
  writeClaimsOf(measurements, run_id_, 0, 4);
  ASSERT_EQ(writeTally(tallies, run_id_, 2, 0, 500), dds::WriteResult::Written);
  ASSERT_TRUE(measurements.waitForAcks(10s));
  ASSERT_TRUE(tallies.waitForAcks(10s));

  const testing::ProcessResult& r = launcher.result();
  EXPECT_EQ(r.exit_code, kExitDegraded) << r.err;
  const json report = readJson(dir_ / "stolen.json");
  ASSERT_TRUE(report.is_object()) << r.err;
  EXPECT_EQ(report.at("status"), "degraded");
  EXPECT_EQ(realizedCosts(report), clean);
  const json& by_reason = report.at("summary").at("rejected_by_reason");
  EXPECT_EQ(by_reason.value("wrong_identity", 0), 2 * kEpisodes * kClaimsPerEpisode + 1)
      << by_reason.dump();
  EXPECT_EQ(by_reason.value("foreign_writer", 0), 0) << by_reason.dump();
  EXPECT_EQ(report.at("summary").at("lost"), 0);
  EXPECT_EQ(report.at("summary").at("received"), report.at("summary").at("sent"));
  int named = 0;
  for (const json& f : report.at("faults")) {
    if (f.at("kind") != "wrong_identity") continue;
    ++named;
    EXPECT_NE(f.at("detail").get<std::string>().find("speaks for sensors 1"), std::string::npos)
        << f.dump();
  }
  EXPECT_EQ(named, 2) << "one per writer: " << report.at("faults").dump();
  EXPECT_EQ(report.at("schedule_versions").size(), 1u);
  for (const json& e : report.at("per_episode")) EXPECT_TRUE(e.at("complete").get<bool>());
}

// Stolen: the operator's files. Its Commands come in the operator's partition (it cannot write
// in the launcher's), so its failure notice for the live sensor 2 is refused by right: the
// reply says so, the fault names it, sensor 2 goes on delivering (costs of a clean run) and no
// schedule is re-planned.
TEST_F(SecuredRun, AFailureNoticeFromTheOperatorIsRefusedByRight) {
  const LeftoverGuard guard(run_id_);
  const std::vector<double> clean = cleanCosts();
  RunningProgram launcher(secured("forged-failure", "2"), 120s);
  wire::RunOptions options;
  options.run_id = run_id_;
  options.security_dir = pki_.string();
  options.security_identity = dds::SecurityRole::Operator;
  dds::Domain domain(options.domainConfig());
  dds::Participant participant(domain);
  dds::Topic<sensornet_Command> command_topic(participant);
  dds::Topic<sensornet_CommandReply> reply_topic(participant);
  const std::string p = participant.partition();
  EXPECT_THROW(dds::Writer<sensornet_Command>(
                   participant, command_topic,
                   dds::endpointQosIn<sensornet_Command>(
                       emulator::commandPartition(p, emulator::CommandSender::Launcher))),
               dds::DdsError)
      << "the operator wrote in the launcher's partition";
  dds::Writer<sensornet_Command> commands(
      participant, command_topic,
      dds::endpointQosIn<sensornet_Command>(
          emulator::commandPartition(p, emulator::CommandSender::Operator)));
  dds::Reader<sensornet_CommandReply> replies(participant, reply_topic);
  ASSERT_TRUE(
      waitUntil([&] { return readJsonLines(dir_ / "forged-failure.jsonl").size() >= 1; }, 60s));
  ASSERT_TRUE(commands.waitForReaders(1, 10s));
  const std::vector<std::uint32_t> victims = {2};
  const std::string issuer = "sensornet launch 1", detail = "sensor_agent-2 killed by signal 9";
  const std::string empty;
  sensornet_Command command{};
  command.run_id = dds::borrowString(run_id_);
  command.command_id = static_cast<std::uint64_t>(emulator::wallNowNs());
  command.kind = sensornet_COMMAND_SENSORS_FAILED;
  command.surrogate = dds::borrowString(empty);
  dds::borrowSequence(command.sensor_ids, victims);
  command.schedule_json = dds::borrowString(empty);
  command.issuer = dds::borrowString(issuer);  // free text: claims to be the launcher
  command.issued_wall_time_ns = emulator::wallNowNs();
  command.detail = dds::borrowString(detail);
  ASSERT_EQ(commands.write(command), dds::WriteResult::Written);
  std::optional<std::string> refusal;
  ASSERT_TRUE(waitUntil(
      [&] {
        for (auto& reply : replies.take(8).samples) {
          if (reply.sample->command_id != command.command_id) continue;
          EXPECT_FALSE(reply.sample->accepted);
          refusal = std::string(dds::viewString(reply.sample->reason));
        }
        return refusal.has_value();
      },
      20s));
  EXPECT_NE(refusal->find("only the launcher may report sensors failed"), std::string::npos)
      << *refusal;

  const testing::ProcessResult& r = launcher.result();
  EXPECT_EQ(r.exit_code, kExitDegraded) << r.err;
  const json report = readJson(dir_ / "forged-failure.json");
  ASSERT_TRUE(report.is_object()) << r.err;
  EXPECT_EQ(report.at("status"), "degraded");
  EXPECT_EQ(realizedCosts(report), clean);
  int refused = 0;
  for (const json& f : report.at("faults")) {
    EXPECT_NE(f.at("kind"), "sensor_died") << f.dump();
    refused += f.at("kind") == "command_refused" ? 1 : 0;
  }
  EXPECT_EQ(refused, 1) << report.at("faults").dump();
  EXPECT_EQ(report.at("schedule_versions").size(), 1u);
  for (const json& e : report.at("per_episode")) EXPECT_TRUE(e.at("complete").get<bool>());
}

// A launch whose sensor processes have no identity of their own in the folder is refused
// before anything starts, naming the missing folder and the `pki init` that makes it.
TEST_F(SecuredRun, ASensorProcessWithoutItsOwnIdentityIsRefusedAtStart) {
  const testing::ProcessResult r = runProcess(
      launch("refused", "10", {"--security", pki_.string(), "--sensors-per-process", "2"}), 60s);
  EXPECT_EQ(r.exit_code, kExitBadInput) << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  EXPECT_NE(r.err.find((pki_ / "sensor-0-1").string()), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("--sensors-per-process 2"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(dir_ / "refused-logs")) << "nothing may start";
}

TEST_F(SecuredRun, ExpiredCertificateIsRefusedAtStart) {
  const LeftoverGuard guard(run_id_);
  expireSensorCertificate(pki_);
  expectRefusedAtStart(pki_, pki_ / kStolenSensor / "identity.pem", "expired");
}

TEST_F(SecuredRun, CertificateOfAnotherAuthorityIsRefusedAtStart) {
  const LeftoverGuard guard(run_id_);
  const fs::path other = dir_ / "other-pki";
  pkiInit(other);
  fs::copy_file(other / kStolenSensor / "identity.pem", pki_ / kStolenSensor / "identity.pem",
                fs::copy_options::overwrite_existing);
  fs::copy_file(other / kStolenSensor / "key.pem", pki_ / kStolenSensor / "key.pem",
                fs::copy_options::overwrite_existing);
  expectRefusedAtStart(pki_, pki_ / kStolenSensor / "identity.pem", "not signed by that CA");
}

// One byte changed in a signed document: its S/MIME signature no longer verifies, and the launch
// is refused before anything starts, naming that file (it started every process before).
void changeOneByte(const fs::path& file, const std::string& from, const std::string& to) {
  std::ifstream in(file);
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const std::size_t at = text.find(from);
  ASSERT_NE(at, std::string::npos) << file;
  ASSERT_EQ(from.size(), to.size());
  text.replace(at, from.size(), to);
  std::ofstream(file, std::ios::trunc) << text;
}

TEST_F(SecuredRun, TamperedPermissionsAreRefusedAtStartNamingTheFile) {
  const fs::path file = pki_ / "coordinator" / "permissions.p7s";
  changeOneByte(file, "<topic>sensornet/Schedule</topic>", "<topic>sensornet/Schedulf</topic>");
  expectRefusedAtStart(pki_, file, "signature does not verify");
}

TEST_F(SecuredRun, TamperedGovernanceIsRefusedAtStartNamingTheFile) {
  const fs::path file = pki_ / kStolenSensor / "governance.p7s";
  changeOneByte(file, "<data_protection_kind>ENCRYPT", "<data_protection_kind>ENCRYPU");
  expectRefusedAtStart(pki_, file, "signature does not verify");
}

TEST_F(SecuredRun, ACaKeyInARolesFolderIsRefusedAtStart) {
  fs::copy_file(pki_ / "ca" / "ca.key", pki_ / kStolenSensor / "ca.key");
  expectRefusedAtStart(pki_, pki_ / kStolenSensor / "ca.key", "no private key but the role's own");
}

TEST_F(SecuredRun, MissingFileIsNamedAtStart) {
  fs::remove(pki_ / "fusion_center" / "permissions.p7s");
  expectRefusedAtStart(pki_, pki_ / "fusion_center" / "permissions.p7s", "missing");
}

TEST_F(Security, PkiInitRefusesAFolderThatIsNotEmptyUnlessForced) {
  const fs::path dir = dir_ / "full";
  fs::create_directories(dir);
  std::ofstream(dir / "notes.txt") << "mine\n";
  testing::ProcessResult r = runProcess({testing::kLauncher, "pki", "init", dir.string()}, 60s);
  EXPECT_EQ(r.exit_code, kExitBadInput);
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  EXPECT_NE(r.err.find(dir.string()), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(dir / "ca.pem"));
  r = runProcess({testing::kLauncher, "pki", "init", dir.string(), "--force", "--key", "rsa"}, 120s);
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(fs::exists(dir / "sensor-0" / "permissions.p7s"));
  EXPECT_TRUE(fs::exists(dir / "notes.txt")) << "--force overwrites only its own files";
}

TEST_F(Security, PkiInitWithoutOpensslSaysSo) {
  const char* path = std::getenv("PATH");
  const std::string saved = path != nullptr ? path : "";
  ::setenv("PATH", (dir_ / "empty").c_str(), 1);
  const testing::ProcessResult r =
      runProcess({testing::kLauncher, "pki", "init", (dir_ / "p").string()}, 60s);
  ::setenv("PATH", saved.c_str(), 1);
  EXPECT_EQ(r.exit_code, kExitBadInput);
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  EXPECT_NE(r.err.find("openssl"), std::string::npos) << r.err;
}

}  // namespace
}  // namespace sensornet
