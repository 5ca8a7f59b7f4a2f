// A secured run (issue 12, part 3), with real processes over Cyclone DDS on loopback:
// - without DDS Security, a second writer claiming a sensor that already has a live writer is
//   kept out and reported (rejected as foreign_writer, a fault, status degraded, exit 3), and the
//   realized costs are those of a clean run with the same seed;
// - `sensornet pki init` and `--security`: a secured run's costs equal an unsecured run's; a
//   participant without a certificate that publishes a Schedule with a higher version and
//   Measurements claiming sensor 0 changes nothing (the run completes clean); one with a
//   sensor's certificate cannot even create its Schedule writer (access control), and its
//   Measurements are kept out by the second-writer rule (degraded, exit 3); an expired
//   certificate and one signed by another CA are refused before anything starts (exit 2, one
//   line naming the file and why).
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
#include <string>
#include <vector>

#include "launch_fixture.hpp"
#include "sensornet/dds/participant.hpp"
#include "sensornet/dds/topics.hpp"
#include "sensornet/dds/wire.hpp"
#include "sensornet/dds/dds_error.hpp"
#include "sensornet/dds/writer.hpp"
#include "sensornet/emulator/messages.hpp"
#include "sensornet/io/scenario_file.hpp"
#include "sensornet/emulator/run_options.hpp"

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

// Well-formed measurements claiming sensor 0 (one value, times in [0, T], version 1) of the
// episodes from `first` to the last, written by `writer`.
void writeClaimsOfSensor0(dds::Writer<sensornet_Measurement>& writer, const std::string& run_id,
                          std::uint32_t first) {
  const std::vector<double> z = {1e3};
  for (std::uint32_t episode = first; episode < kEpisodes; ++episode) {
    for (std::uint64_t i = 0; i < 20; ++i) {
      sensornet_Measurement m{};
      m.sensor_id = 0;
      m.run_id = dds::borrowString(run_id);
      m.episode = episode;
      m.seq = 100000 + i;
      m.emulated_time_s = 0.1 + 0.14 * static_cast<double>(i);
      m.schedule_version = 1;
      m.publish_wall_time_ns = emulator::wallNowNs();
      dds::borrowSequence(m.z, z);
      ASSERT_EQ(writer.write(m), dds::WriteResult::Written);
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
  v.surrogate = "file";
  return emulator::publishSchedule(writer, run_id, emulator::digestOf(yaml), v);
}

// Makes the security files of a run in `dir` with `sensornet pki init`.
void pkiInit(const fs::path& dir) {
  const testing::ProcessResult r =
      runProcess({testing::kLauncher, "pki", "init", dir.string(), "--days", "30"}, 120s);
  ASSERT_EQ(r.exit_code, 0) << r.err;
}

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
  const fs::path sensor = dir / "sensor";
  ASSERT_EQ(runProcess({"/usr/bin/openssl", "req", "-new", "-key", (sensor / "key.pem").string(),
                        "-subj", "/O=sensornet/CN=sensor", "-out", (work / "sensor.csr").string()},
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
  emulator::RunOptions options;
  options.run_id = run_id_;
  dds::Domain domain(options.domainConfig());
  dds::Participant participant(domain);
  dds::Topic<sensornet_Measurement> topic(participant);
  dds::Writer<sensornet_Measurement> foreign(participant, topic);
  // Sensor 0's own writer has spoken once the first episode is logged.
  ASSERT_TRUE(waitUntil([&] { return readJsonLines(dir_ / "foreign.jsonl").size() >= 1; }, 60s));
  ASSERT_TRUE(foreign.waitForReaders(1, 10s));
  writeClaimsOfSensor0(foreign, run_id_, 1);
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
  emulator::RunOptions options;  // no --security: a plain participant on the run's domain
  options.run_id = run_id_;
  dds::Domain domain(options.domainConfig());
  dds::Participant participant(domain);
  dds::Topic<sensornet_Schedule> schedule_topic(participant);
  dds::Topic<sensornet_Measurement> measurement_topic(participant);
  dds::Writer<sensornet_Schedule> schedules(participant, schedule_topic);
  dds::Writer<sensornet_Measurement> measurements(participant, measurement_topic);
  ASSERT_TRUE(waitUntil([&] { return readJsonLines(dir_ / "intruded.jsonl").size() >= 1; }, 60s));
  EXPECT_EQ(schedules.matchedReaders(), 0u) << "an unauthenticated participant matched";
  EXPECT_EQ(writeHijackingSchedule(schedules, run_id_), dds::WriteResult::Written);
  writeClaimsOfSensor0(measurements, run_id_, 1);

  const testing::ProcessResult& r = launcher.result();
  EXPECT_EQ(r.exit_code, kExitCompleted) << r.err;
  const json report = readJson(dir_ / "intruded.json");
  ASSERT_TRUE(report.is_object()) << r.err;
  EXPECT_EQ(report.at("status"), "completed") << report.at("faults").dump();
  EXPECT_EQ(realizedCosts(report), clean);
  EXPECT_EQ(report.at("summary").at("rejected"), 0);
  EXPECT_EQ(report.at("schedule_versions").size(), 1u) << report.at("schedule_versions").dump();
}

// The sensor's certificate allows Measurements (the second-writer rule keeps them out: one
// foreign_writer fault, degraded, exit 3), never a Schedule (access control refuses the writer).
TEST_F(SecuredRun, ParticipantWithASensorCertificateCannotScheduleNorSpeakForSensor0) {
  const LeftoverGuard guard(run_id_);
  const std::vector<double> clean = cleanCosts();
  RunningProgram launcher(secured("sensor-cert", "2"), 120s);
  emulator::RunOptions options;
  options.run_id = run_id_;
  options.security_dir = pki_.string();
  options.security_role = dds::SecurityRole::Sensor;
  dds::Domain domain(options.domainConfig());
  dds::Participant participant(domain);
  dds::Topic<sensornet_Schedule> schedule_topic(participant);
  dds::Topic<sensornet_Measurement> measurement_topic(participant);
  EXPECT_THROW(dds::Writer<sensornet_Schedule>(participant, schedule_topic), dds::DdsError);
  dds::Writer<sensornet_Measurement> measurements(participant, measurement_topic);
  ASSERT_TRUE(
      waitUntil([&] { return readJsonLines(dir_ / "sensor-cert.jsonl").size() >= 1; }, 60s));
  ASSERT_TRUE(measurements.waitForReaders(1, 10s));
  writeClaimsOfSensor0(measurements, run_id_, 1);
  ASSERT_TRUE(measurements.waitForAcks(10s));

  const testing::ProcessResult& r = launcher.result();
  EXPECT_EQ(r.exit_code, kExitDegraded) << r.err;
  const json report = readJson(dir_ / "sensor-cert.json");
  ASSERT_TRUE(report.is_object()) << r.err;
  EXPECT_EQ(report.at("status"), "degraded");
  EXPECT_EQ(realizedCosts(report), clean);
  EXPECT_GT(report.at("summary").at("rejected_by_reason").value("foreign_writer", 0), 0);
  EXPECT_EQ(report.at("schedule_versions").size(), 1u);
  for (const json& e : report.at("per_episode")) EXPECT_TRUE(e.at("complete").get<bool>());
}

TEST_F(SecuredRun, ExpiredCertificateIsRefusedAtStart) {
  const LeftoverGuard guard(run_id_);
  expireSensorCertificate(pki_);
  expectRefusedAtStart(pki_, pki_ / "sensor" / "identity.pem", "expired");
}

TEST_F(SecuredRun, CertificateOfAnotherAuthorityIsRefusedAtStart) {
  const LeftoverGuard guard(run_id_);
  const fs::path other = dir_ / "other-pki";
  pkiInit(other);
  fs::copy_file(other / "sensor" / "identity.pem", pki_ / "sensor" / "identity.pem",
                fs::copy_options::overwrite_existing);
  fs::copy_file(other / "sensor" / "key.pem", pki_ / "sensor" / "key.pem",
                fs::copy_options::overwrite_existing);
  expectRefusedAtStart(pki_, pki_ / "sensor" / "identity.pem", "not signed by that CA");
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
  const fs::path file = pki_ / "sensor" / "governance.p7s";
  changeOneByte(file, "<data_protection_kind>ENCRYPT", "<data_protection_kind>ENCRYPU");
  expectRefusedAtStart(pki_, file, "signature does not verify");
}

TEST_F(SecuredRun, ACaKeyInARolesFolderIsRefusedAtStart) {
  fs::copy_file(pki_ / "ca" / "ca.key", pki_ / "sensor" / "ca.key");
  expectRefusedAtStart(pki_, pki_ / "sensor" / "ca.key", "no private key but the role's own");
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
  EXPECT_TRUE(fs::exists(dir / "sensor" / "permissions.p7s"));
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
