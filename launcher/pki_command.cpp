#include "pki_command.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstring>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <functional>
#include <memory>
#include <optional>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "sensornet/launcher/host_placement.hpp"
#include "sensornet/launcher/launch_plan.hpp"
#include "sensornet/launcher/security_policy.hpp"
#include "sensornet/core/input_error.hpp"
#include "sensornet/core/xml_text.hpp"
#include "sensornet/dds/security.hpp"
#include "sensornet/launcher/hosts_file.hpp"
#include "sensornet/emulator/sensor_ids.hpp"
#include "sensornet/io/scenario_file.hpp"
#include "sensornet/io/output_path.hpp"
#include "sensornet/io/utc_time.hpp"
#include "sensornet/io/word_option.hpp"

extern char** environ;

namespace sensornet::launcher {
namespace {

namespace fs = std::filesystem;
using dds::SecurityRole;

struct PkiOptions {
  std::string dir;
  std::string ca_dir;  // where the CA's key is kept (default DIR/ca)
  // The sensor processes' identities: those `sensornet launch SCENARIO` starts with the same
  // --sensors-per-process and --hosts, or without a scenario one per sensor 0..sensors-1.
  std::string scenario;
  std::string sensors_per_process = "auto";
  std::string hosts;
  int sensors = 16;
  std::vector<std::string> sensor_blocks;  // --sensor-block, beside those (sensor_agent --sensors)
  bool force = false;
  int days = 365;
  std::string key = "ec";
  int rsa_bits = 2048;
  bool json = false;
};

using dds::SecurityIdentity;

// 2026-11-30T21:00:00 in UTC, `days` from now.
std::string utcIn(int days) {
  return utcText(std::chrono::system_clock::now() + std::chrono::hours(24 * days), UtcForm::NoZone);
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

// Writes a new file (never through a symbolic link, never over an existing file).
void writeText(const fs::path& path, const std::string& text) {
  const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_NOFOLLOW | O_CLOEXEC, 0600);
  if (fd < 0) {
    throw InputError(path.string(), "", "a new file (" + std::string(std::strerror(errno)) + ")");
  }
  std::size_t done = 0;
  while (done < text.size()) {
    const ssize_t n = ::write(fd, text.data() + done, text.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      ::close(fd);
      throw InputError(path.string(), "", "a file that can be written");
    }
    done += static_cast<std::size_t>(n);
  }
  ::close(fd);
}

// A folder the caller may keep private keys in: a real folder (not a symbolic link), owned by
// the caller, writable by nobody else. Made (0700) when missing.
void checkOwnedFolder(const fs::path& dir) {
  struct stat st {};
  if (::lstat(dir.c_str(), &st) != 0) {
    if (errno != ENOENT) throw InputError(dir.string(), "", "a folder: " + std::string(std::strerror(errno)));
    makeParentFolders(dir, "pki init");
    if (::mkdir(dir.c_str(), 0700) != 0) {
      throw InputError(dir.string(), "", "a folder that can be made: " + std::string(std::strerror(errno)));
    }
    return;
  }
  if (S_ISLNK(st.st_mode)) throw InputError(dir.string(), "", "a folder, not a symbolic link");
  if (!S_ISDIR(st.st_mode)) throw InputError(dir.string(), "", "a folder (it is a file)");
  if (st.st_uid != ::geteuid()) {
    throw InputError(dir.string(), "", "a folder of yours (it belongs to uid " +
                                           std::to_string(st.st_uid) + ": another user could "
                                           "replace the files in it)");
  }
  if ((st.st_mode & (S_IWGRP | S_IWOTH)) != 0) {
    throw InputError(dir.string(), "", "a folder only you can write (it is group- or "
                                       "world-writable: chmod go-w it)");
  }
}

// What an earlier `pki init` made in `dir`, for --force to remove: files first, then their
// folders. Refuses a symbolic link or a folder of another owner where it writes. In DIR
// (`folders`) other files are left alone; in a role's or the CA's folder, which a process
// receives whole, anything else is refused. Nothing is removed before everything is checked.
void collectEarlierFiles(const fs::path& dir, PkiFolder kind, std::vector<fs::path>& files,
                         std::vector<fs::path>& dirs) {
  const bool folders = kind == PkiFolder::Root;
  const auto made = [kind](const std::string& name) { return madeByPkiInit(kind, name); };
  std::error_code error;
  for (const fs::directory_entry& entry : fs::directory_iterator(dir, error)) {
    const fs::path& path = entry.path();
    const std::string name = path.filename().string();
    struct stat st {};
    if (folders && name.rfind(".pki-", 0) == 0 && ::lstat(path.c_str(), &st) == 0 &&
        S_ISDIR(st.st_mode) && st.st_uid == ::geteuid()) {
      dirs.push_back(path);  // the staging folder of an init that failed
      continue;
    }
    if (folders && !made(name)) continue;  // not ours: left as it is
    if (!made(name) || ::lstat(path.c_str(), &st) != 0 || S_ISLNK(st.st_mode)) {
      throw InputError(path.string(), "",
                       "only files `pki init` made in " + dir.string() +
                           " (this one it did not make, or it is a symbolic link: --force "
                           "replaces only its own files; remove it yourself)");
    }
    if (S_ISDIR(st.st_mode)) {
      if (!folders) throw InputError(path.string(), "", "a file `pki init` made, not a folder");
      checkOwnedFolder(path);
      collectEarlierFiles(path, name == "ca" ? PkiFolder::Ca : PkiFolder::Identity, files, dirs);
      dirs.push_back(path);
    } else if (S_ISREG(st.st_mode)) {
      files.push_back(path);
    } else {
      throw InputError(path.string(), "", "a regular file `pki init` made");
    }
  }
}

void removeEarlierFiles(const fs::path& dir) {
  std::vector<fs::path> files, dirs;
  collectEarlierFiles(dir, PkiFolder::Root, files, dirs);
  for (const fs::path& f : files) ::unlink(f.c_str());
  std::error_code error;
  for (const fs::path& d : dirs) fs::remove_all(d, error);  // emptied above, or our staging
}

bool isEmptyFolder(const fs::path& dir) {
  std::error_code error;
  return fs::is_empty(dir, error) && !error;
}

class PkiMaker {
 public:
  explicit PkiMaker(PkiOptions options)
      : options_(std::move(options)),
        dir_(fs::absolute(options_.dir).lexically_normal()),
        ca_dir_(options_.ca_dir.empty() ? dir_ / "ca"
                                        : fs::absolute(options_.ca_dir).lexically_normal()),
        identities_(identitiesOf(options_)) {}

  int make() {
    prepare();
    try {
      makeAll();
    } catch (...) {
      std::error_code error;
      fs::remove_all(staging_, error);
      throw;
    }
    printSummary();
    return kExitOk;
  }

 private:
  void makeAll() {
    makeCa();
    writeText(stage("governance.xml"), governanceXml());
    sign(stage("governance.xml"), stage("governance.p7s"));
    for (const SecurityIdentity& identity : identities_) makeRole(identity);
    place();
  }

  void printSummary() const {
    if (options_.json) {
      nlohmann::json roles = nlohmann::json::object();
      for (const SecurityIdentity& identity : identities_) {
        roles[identity.name()] = (dir_ / identity.name()).string();
      }
      printJson({{"dir", dir_.string()},
                 {"roles", roles},
                 {"ca_key", (ca_dir_ / "ca.key").string()},
                 {"days", options_.days},
                 {"key", options_.key}});
      return;
    }
    std::printf(
        "security files in %s: per identity (%s) a folder with identity.pem, key.pem, "
        "permissions.p7s, ca.pem and governance.p7s: what one process of that identity "
        "receives, and nothing else; a sensor process's identity speaks for its sensors only. "
        "Valid %d days. The CA's private key is in %s: it never goes to a run's processes "
        "(keep it offline with --ca-dir). Use: sensornet launch %s --security %s\n",
        dir_.c_str(), identityNames().c_str(), options_.days, (ca_dir_ / "ca.key").c_str(),
        options_.scenario.empty() ? "SCENARIO" : options_.scenario.c_str(), dir_.c_str());
  }

  // The folders are the caller's and hold only what an earlier `pki init` made; the files are
  // made in a private staging folder (openssl writes there) and moved into place at the end.
  void prepare() {
    checkOwnedFolder(dir_);
    const bool reuse_ca = !options_.ca_dir.empty() && fs::exists(ca_dir_ / "ca.key");
    if (!isEmptyFolder(dir_)) {
      if (!options_.force) {
        throw InputError(dir_.string(), "",
                         "a new or empty folder (it holds files; --force replaces the files an "
                         "earlier `pki init` made there, and nothing else)");
      }
      removeEarlierFiles(dir_);
    }
    if (!options_.ca_dir.empty()) {
      checkOwnedFolder(ca_dir_);
      if (!reuse_ca && !isEmptyFolder(ca_dir_)) {
        throw InputError(ca_dir_.string(), "", "a new or empty folder, or one that holds a CA "
                                               "(ca.key and ca.pem) to sign with");
      }
    }
    std::string templ = (dir_ / ".pki-XXXXXX").string();
    if (::mkdtemp(templ.data()) == nullptr) {
      throw InputError(dir_.string(), "", "a folder where files can be made");
    }
    staging_ = templ;
    log_ = staging_ / "openssl.log";
  }

  void makeCa() {
    if (!options_.ca_dir.empty() && fs::exists(ca_dir_ / "ca.key")) {
      for (const char* name : {"ca.key", "ca.pem"}) {
        struct stat st {};
        if (::lstat((ca_dir_ / name).c_str(), &st) != 0 || !S_ISREG(st.st_mode)) {
          throw InputError((ca_dir_ / name).string(), "", "a regular file (the CA to sign with)");
        }
      }
      ca_key_ = ca_dir_ / "ca.key";
      ca_pem_ = ca_dir_ / "ca.pem";
      return;
    }
    newKey(stage("ca.key"));
    openssl({"req", "-x509", "-new", "-key", stage("ca.key").string(), "-days", days(), "-subj",
             "/O=sensornet/CN=sensornet CA", "-out", stage("ca.pem").string()},
            log_);
    ca_key_ = stage("ca.key");
    ca_pem_ = stage("ca.pem");
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
             signed_document.string(), "-signer", ca_pem_.string(), "-inkey", ca_key_.string()},
            log_);
  }

  void makeRole(const SecurityIdentity& identity) const {
    const std::string name = identity.name();
    const fs::path own = stage(name);
    fs::create_directory(own);
    fs::permissions(own, fs::perms::owner_all);
    newKey(own / "key.pem");
    openssl({"req", "-new", "-key", (own / "key.pem").string(), "-subj",
             "/O=sensornet/CN=" + name, "-out", (own / "identity.csr").string()},
            log_);
    openssl({"x509", "-req", "-in", (own / "identity.csr").string(), "-CA", ca_pem_.string(),
             "-CAkey", ca_key_.string(), "-CAcreateserial", "-CAserial",
             stage("ca.srl").string(), "-days", days(), "-out", (own / "identity.pem").string()},
            log_);
    fs::remove(own / "identity.csr");
    writeText(own / "permissions.xml", permissionsXml(identity, {utcIn(-1), utcIn(options_.days)}));
    sign(own / "permissions.xml", own / "permissions.p7s");
    fs::remove(own / "permissions.xml");
    fs::copy_file(ca_pem_, own / "ca.pem");
    fs::copy_file(stage("governance.p7s"), own / "governance.p7s");
  }

  // Moves what was made from the staging folder into DIR (and the new CA into its folder).
  void place() {
    if (ca_key_ == stage("ca.key")) {
      if (options_.ca_dir.empty()) checkOwnedFolder(ca_dir_);
      moveInto(stage("ca.key"), ca_dir_ / "ca.key");
      fs::copy_file(stage("ca.pem"), ca_dir_ / "ca.pem");
      moveInto(stage("ca.pem"), dir_ / "ca.pem");
    } else {
      fs::copy_file(ca_pem_, dir_ / "ca.pem");
    }
    moveInto(stage("governance.p7s"), dir_ / "governance.p7s");
    for (const SecurityIdentity& identity : identities_) {
      moveInto(stage(identity.name()), dir_ / identity.name());
    }
    std::error_code error;
    fs::remove_all(staging_, error);
  }

  static void moveInto(const fs::path& from, const fs::path& to) {
    if (::rename(from.c_str(), to.c_str()) != 0) {
      throw InputError(to.string(), "", "a place to move " + from.string() + " to: " +
                                            std::strerror(errno));
    }
  }

  [[nodiscard]] fs::path stage(const std::string& name) const { return staging_ / name; }
  [[nodiscard]] std::string days() const { return std::to_string(options_.days); }
  // The roles, then a sensor process's identity per block: those of `sensornet launch
  // SCENARIO` with the same --sensors-per-process and --hosts, or one per sensor.
  static std::vector<SecurityIdentity> identitiesOf(const PkiOptions& options) {
    std::vector<std::vector<int>> blocks;
    if (options.scenario.empty()) {
      for (int j = 0; j < options.sensors; ++j) blocks.push_back({j});
    } else {
      const int sensor_count = loadScenarioFile(options.scenario).sensorCount();
      std::optional<launcher::HostsFile> hosts;
      if (!options.hosts.empty()) hosts = launcher::loadHostsFile(options.hosts, sensor_count);
      blocks = sensorBlocks(hosts ? &*hosts : nullptr, sensor_count,
                            sensorsPerProcess(options.sensors_per_process, sensor_count));
    }
    for (const std::string& spec : options.sensor_blocks) {
      blocks.push_back(emulator::parseSensorIds(spec, "--sensor-block"));
    }
    return securityIdentities(blocks);
  }

  [[nodiscard]] std::string identityNames() const {
    std::string names;
    std::size_t sensors = 0;
    for (const SecurityIdentity& identity : identities_) {
      if (identity.role == SecurityRole::Sensor && ++sensors > 3) continue;
      names += (names.empty() ? "" : ", ") + identity.name();
    }
    if (sensors > 3) names += " and " + std::to_string(sensors - 3) + " more sensor processes";
    return names;
  }

  PkiOptions options_;
  fs::path dir_;
  fs::path ca_dir_;
  std::vector<SecurityIdentity> identities_;
  fs::path staging_;
  fs::path log_;
  fs::path ca_key_;
  fs::path ca_pem_;
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
      "(coordinator, fusion_center, operator for replan/status/watch, launcher) and per sensor "
      "process (sensor-<ids>: the sensors it speaks for), and a signed governance document for "
      "DIR; then run with --security DIR. Each identity gets a folder DIR/<identity> with its "
      "identity.pem, key.pem, permissions.p7s and copies of ca.pem and governance.p7s: all one "
      "process needs, and nothing of another. The CA's private key stays in DIR/ca (or "
      "--ca-dir) and never goes to a process. DIR must be yours and writable only by you; "
      "nothing is written through a symbolic link. Only the coordinator may write Scenario, "
      "Schedule and EpisodeControl; a sensor process only Measurement, EpisodeTally and "
      "SensorStatus, and only for its own sensors; only the fusion center Report and "
      "FusionState; the launcher Command (the sensors' failure notices) and an operator "
      "Command (re-plans), each in its own partition, so the coordinator knows which sent it. "
      "The sensor processes' identities are those `sensornet launch SCENARIO` starts "
      "(--scenario, with the same --sensors-per-process and --hosts), or one per sensor "
      "0..--sensors-1. Example:\n  sensornet pki init run-pki --scenario scenarios/default.yaml "
      "&& sensornet launch scenarios/default.yaml --security run-pki");
  init->add_option("DIR", options->dir, "folder for the files (made if missing)")->required();
  init->add_flag("--force", options->force,
                 "replace the files an earlier `pki init` made in DIR (nothing else: a file it "
                 "did not make, or a symbolic link, is refused)");
  init->add_option("--ca-dir", options->ca_dir,
                   "keep the CA (ca.key, ca.pem) in this folder instead of DIR/ca, for example "
                   "on a medium you keep offline; if it already holds a CA, sign with that one");
  init->add_option("--scenario", options->scenario,
                   "make the identities of the sensor processes `sensornet launch SCENARIO` "
                   "starts (with the same --sensors-per-process and --hosts)")
      ->check(CLI::ExistingFile);
  init->add_option("--sensors-per-process", options->sensors_per_process,
                   "as for `sensornet launch`, with --scenario: auto or N")
      ->capture_default_str()
      ->check(sensorsPerProcessValue());
  init->add_option("--hosts", options->hosts, "as for `sensornet launch`, with --scenario")
      ->check(CLI::ExistingFile);
  init->add_option("--sensors", options->sensors,
                   "without --scenario: one sensor process identity for each of the sensors "
                   "0..N-1")
      ->capture_default_str()
      ->check(CLI::Range(1, 100000));
  init->add_option("--sensor-block", options->sensor_blocks,
                   "also an identity for a sensor process that speaks for these sensors (ids as "
                   "sensor_agent --sensors takes them: 3, 0-9, 0,2,5-7); repeatable");
  init->add_option("--days", options->days, "validity of certificates and permissions (days)")
      ->capture_default_str()
      ->check(CLI::Range(1, 36500));
  wordOption(init->add_option("--key", options->key, "key type: ec (prime256v1) or rsa"),
             {"ec", "rsa"});
  wordOption(init->add_option("--rsa-bits", options->rsa_bits, "RSA key size with --key rsa"),
             {"2048", "3072", "4096"});
  init->add_flag("--json", options->json,
                 "print {\"dir\", \"roles\": {role: folder}, \"ca_key\", \"days\", \"key\"} as "
                 "one JSON line instead of the sentence");
  return {init, [options] { return PkiMaker(*options).make(); }};
}

}  // namespace sensornet::launcher
