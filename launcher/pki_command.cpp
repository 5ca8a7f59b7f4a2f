#include "pki_command.hpp"

#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstring>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "sensornet/core/input_error.hpp"
#include "sensornet/dds/security.hpp"

extern char** environ;

namespace sensornet::launcher {
namespace {

namespace fs = std::filesystem;
using dds::SecurityRole;

struct PkiOptions {
  std::string dir;
  bool force = false;
  int days = 365;
  std::string key = "ec";
  int rsa_bits = 2048;
};

// Who writes and who reads which topic (each program's writers and readers).
struct TopicRights {
  std::vector<const char*> publish;
  std::vector<const char*> subscribe;
};

TopicRights rightsOf(SecurityRole role) {
  switch (role) {
    case SecurityRole::Coordinator:
      return {{"Scenario", "Schedule", "EpisodeControl", "CommandReply"},
              {"Scenario", "Schedule", "EpisodeControl", "Command", "SensorStatus", "Report",
               "FusionState"}};
    case SecurityRole::Sensor:
      return {{"Measurement", "EpisodeTally", "SensorStatus"},
              {"Scenario", "Schedule", "EpisodeControl"}};
    case SecurityRole::FusionCenter:
      return {{"Report", "FusionState"},
              {"Scenario", "Schedule", "EpisodeControl", "Measurement", "EpisodeTally",
               "SensorStatus"}};
    case SecurityRole::Operator:
    case SecurityRole::Launcher:  // it sends the sensors' failure notices as Commands
      return {{"Command"},
              {"Scenario", "Schedule", "EpisodeControl", "SensorStatus", "Report", "FusionState",
               "CommandReply"}};
  }
  return {};
}

// Domain ids of every run: hashed into 1..230, or 0..230 with --domain-id.
const char* const kDomains =
    "<domains><id_range><min>0</min><max>230</max></id_range></domains>";

std::string governanceXml() {
  return std::string(R"(<?xml version="1.0" encoding="UTF-8"?>
<dds xmlns:xsi="http://www.w3.org/2001/XMLSchema-instance"
     xsi:noNamespaceSchemaLocation="http://www.omg.org/spec/DDS-SECURITY/20170901/omg_shared_ca_governance.xsd">
  <domain_access_rules>
    <domain_rule>
      )") + kDomains + R"(
      <allow_unauthenticated_participants>false</allow_unauthenticated_participants>
      <enable_join_access_control>true</enable_join_access_control>
      <discovery_protection_kind>ENCRYPT</discovery_protection_kind>
      <liveliness_protection_kind>ENCRYPT</liveliness_protection_kind>
      <rtps_protection_kind>NONE</rtps_protection_kind>
      <topic_access_rules>
        <topic_rule>
          <topic_expression>*</topic_expression>
          <enable_discovery_protection>true</enable_discovery_protection>
          <enable_liveliness_protection>true</enable_liveliness_protection>
          <enable_read_access_control>true</enable_read_access_control>
          <enable_write_access_control>true</enable_write_access_control>
          <metadata_protection_kind>SIGN</metadata_protection_kind>
          <data_protection_kind>ENCRYPT</data_protection_kind>
        </topic_rule>
      </topic_access_rules>
    </domain_rule>
  </domain_access_rules>
</dds>
)";
}

std::string subjectOf(SecurityRole role) {
  return "CN=" + std::string(dds::securityRoleName(role)) + ",O=sensornet";
}

// 2026-11-30T21:00:00 in UTC, `days` from now.
std::string utcIn(int days) {
  const std::time_t t = std::chrono::system_clock::to_time_t(std::chrono::system_clock::now() +
                                                             std::chrono::hours(24 * days));
  std::tm utc{};
  gmtime_r(&t, &utc);
  char text[32];
  std::strftime(text, sizeof text, "%Y-%m-%dT%H:%M:%S", &utc);
  return text;
}

std::string topicList(const std::vector<const char*>& topics) {
  std::string xml = "<topics>";
  for (const char* t : topics) xml += std::string("<topic>sensornet/") + t + "</topic>";
  return xml + "</topics><partitions><partition>sensornet/*</partition></partitions>";
}

std::string permissionsXml(SecurityRole role, int days) {
  const TopicRights rights = rightsOf(role);
  return std::string(R"(<?xml version="1.0" encoding="UTF-8"?>
<dds xmlns:xsi="http://www.w3.org/2001/XMLSchema-instance"
     xsi:noNamespaceSchemaLocation="http://www.omg.org/spec/DDS-SECURITY/20170901/omg_shared_ca_permissions.xsd">
  <permissions>
    <grant name="sensornet_)") +
         std::string(dds::securityRoleName(role)) + R"(">
      <subject_name>)" + subjectOf(role) + R"(</subject_name>
      <validity><not_before>)" + utcIn(-1) + "</not_before><not_after>" + utcIn(days) +
         R"(</not_after></validity>
      <allow_rule>
        )" + kDomains + R"(
        <publish>)" + topicList(rights.publish) + R"(</publish>
        <subscribe>)" + topicList(rights.subscribe) + R"(</subscribe>
      </allow_rule>
      <default>DENY</default>
    </grant>
  </permissions>
</dds>
)";
}

// Runs openssl with `args`; its output goes to `log`. InputError when openssl is not there,
// std::runtime_error with openssl's last words when it fails.
void openssl(const std::vector<std::string>& args, const fs::path& log) {
  std::vector<std::string> argv = {"openssl"};
  argv.insert(argv.end(), args.begin(), args.end());
  std::vector<char*> raw;
  for (std::string& a : argv) raw.push_back(a.data());
  raw.push_back(nullptr);
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, STDIN_FILENO, "/dev/null", O_RDONLY, 0);
  posix_spawn_file_actions_addopen(&actions, STDOUT_FILENO, log.c_str(),
                                   O_WRONLY | O_CREAT | O_TRUNC, 0600);
  posix_spawn_file_actions_adddup2(&actions, STDOUT_FILENO, STDERR_FILENO);
  pid_t pid = 0;
  const int error = posix_spawnp(&pid, "openssl", &actions, nullptr, raw.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  if (error == ENOENT) {
    throw InputError("sensornet pki init", "openssl",
                     "the openssl program on PATH (not found: apt-get install openssl)");
  }
  if (error != 0) throw std::runtime_error("cannot run openssl: " + std::string(std::strerror(error)));
  int status = 0;
  while (::waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0) {
    std::ifstream in(log);
    std::string line, last;
    while (std::getline(in, line)) {
      if (!line.empty()) last = line;
    }
    throw std::runtime_error("openssl " + args.front() + " failed: " + last);
  }
}

void writeText(const fs::path& path, const std::string& text) {
  std::ofstream out(path, std::ios::trunc);
  out << text;
  if (!out) throw InputError(path.string(), "", "a file that can be written");
}

class PkiMaker {
 public:
  explicit PkiMaker(PkiOptions options)
      : options_(std::move(options)), dir_(fs::absolute(options_.dir).lexically_normal()),
        log_(dir_ / ".openssl.log") {}

  int make() {
    prepareFolder();
    newKey(dir_ / "ca.key");
    openssl({"req", "-x509", "-new", "-key", path("ca.key"), "-days", days(), "-subj",
             "/O=sensornet/CN=sensornet CA", "-out", path("ca.pem")},
            log_);
    writeText(dir_ / "governance.xml", governanceXml());
    sign(dir_ / "governance.xml", dir_ / "governance.p7s");
    for (const SecurityRole role : dds::kSecurityRoles) makeRole(role);
    fs::remove(log_);
    fs::remove(dir_ / "ca.srl");
    std::printf("security files in %s: ca.pem, governance.p7s and, per role (%s), identity.pem, "
                "key.pem, permissions.p7s; valid %d days. Use: sensornet launch SCENARIO "
                "--security %s\n",
                dir_.c_str(), roleNames().c_str(), options_.days, dir_.c_str());
    return kExitOk;
  }

 private:
  void prepareFolder() {
    std::error_code error;
    if (fs::exists(dir_, error) && !fs::is_directory(dir_, error)) {
      throw InputError(dir_.string(), "", "a folder (it is a file)");
    }
    if (fs::is_directory(dir_, error) && !fs::is_empty(dir_, error) && !options_.force) {
      throw InputError(dir_.string(), "",
                       "a new or empty folder (it holds files; --force overwrites the security "
                       "files in it)");
    }
    fs::create_directories(dir_, error);
    if (error) throw InputError(dir_.string(), "", "a folder that can be made: " + error.message());
    fs::permissions(dir_, fs::perms::owner_all, error);  // private keys inside
  }

  void newKey(const fs::path& key) const {
    if (options_.key == "rsa") {
      openssl({"genpkey", "-algorithm", "RSA", "-pkeyopt",
               "rsa_keygen_bits:" + std::to_string(options_.rsa_bits), "-out", key.string()},
              log_);
    } else {
      openssl({"genpkey", "-algorithm", "EC", "-pkeyopt", "ec_paramgen_curve:prime256v1", "-out",
               key.string()},
              log_);
    }
    fs::permissions(key, fs::perms::owner_read | fs::perms::owner_write);
  }

  void sign(const fs::path& document, const fs::path& signed_document) const {
    openssl({"smime", "-sign", "-text", "-in", document.string(), "-out",
             signed_document.string(), "-signer", path("ca.pem"), "-inkey", path("ca.key")},
            log_);
  }

  void makeRole(SecurityRole role) const {
    const fs::path own = dir_ / dds::securityRoleName(role);
    fs::create_directories(own);
    newKey(own / "key.pem");
    const std::string name(dds::securityRoleName(role));
    openssl({"req", "-new", "-key", (own / "key.pem").string(), "-subj",
             "/O=sensornet/CN=" + name, "-out", (own / "identity.csr").string()},
            log_);
    openssl({"x509", "-req", "-in", (own / "identity.csr").string(), "-CA", path("ca.pem"),
             "-CAkey", path("ca.key"), "-CAcreateserial", "-CAserial", path("ca.srl"), "-days",
             days(), "-out", (own / "identity.pem").string()},
            log_);
    fs::remove(own / "identity.csr");
    writeText(own / "permissions.xml", permissionsXml(role, options_.days));
    sign(own / "permissions.xml", own / "permissions.p7s");
  }

  [[nodiscard]] std::string path(const char* name) const { return (dir_ / name).string(); }
  [[nodiscard]] std::string days() const { return std::to_string(options_.days); }
  static std::string roleNames() {
    std::string names;
    for (const SecurityRole role : dds::kSecurityRoles) {
      names += (names.empty() ? "" : ", ") + std::string(dds::securityRoleName(role));
    }
    return names;
  }

  PkiOptions options_;
  fs::path dir_;
  fs::path log_;
};

}  // namespace

Subcommand addPkiCommand(CLI::App& app) {
  auto options = std::make_shared<PkiOptions>();
  CLI::App* pki = app.add_subcommand(
      "pki", "The files of a secured run (DDS Security): `sensornet pki init DIR`.");
  pki->require_subcommand(1);
  CLI::App* init = pki->add_subcommand(
      "init",
      "Make, with openssl, a certificate authority, an identity and signed permissions per role "
      "(coordinator, fusion_center, sensor, operator for replan/status/watch, launcher) and a "
      "signed governance document for DIR; then run with --security DIR. Only the coordinator "
      "may write Scenario, Schedule and EpisodeControl, only sensors Measurement, EpisodeTally "
      "and SensorStatus, only the fusion center Report and FusionState, only the operator and "
      "the launcher Command. Example:\n  sensornet pki init run-pki && sensornet launch "
      "scenarios/default.yaml --security run-pki");
  init->add_option("DIR", options->dir, "folder for the files (made if missing)")->required();
  init->add_flag("--force", options->force,
                 "overwrite the security files of a folder that is not empty");
  init->add_option("--days", options->days, "validity of certificates and permissions (days)")
      ->capture_default_str()
      ->check(CLI::Range(1, 36500));
  init->add_option("--key", options->key, "key type: ec (prime256v1) or rsa")
      ->capture_default_str()
      ->check(CLI::IsMember({"ec", "rsa"}));
  init->add_option("--rsa-bits", options->rsa_bits, "RSA key size with --key rsa")
      ->capture_default_str()
      ->check(CLI::IsMember({2048, 3072, 4096}));
  return {init, [options] { return PkiMaker(*options).make(); }};
}

}  // namespace sensornet::launcher
