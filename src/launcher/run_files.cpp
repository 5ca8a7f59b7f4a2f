#include "sensornet/launcher/run_files.hpp"

#include <fcntl.h>
#include <signal.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <nlohmann/json.hpp>
#include <random>
#include <stdexcept>

#include "sensornet/io/output_file.hpp"
#include "sensornet/core/input_error.hpp"

namespace sensornet::launcher {
namespace {

namespace fs = std::filesystem;

bool isExecutableFile(const fs::path& path) {
  std::error_code error;
  return fs::is_regular_file(path, error) && ::access(path.c_str(), X_OK) == 0;
}

// Looks for all three programs in one layout; the first missing one, or none.
std::optional<fs::path> firstMissing(const EmulatorPrograms& programs) {
  for (const fs::path& path :
       {programs.coordinator, programs.fusion_center, programs.sensor_agent}) {
    if (!isExecutableFile(path)) return path;
  }
  return std::nullopt;
}

EmulatorPrograms inDirectory(const fs::path& dir) {
  return {dir / "coordinator", dir / "fusion_center", dir / "sensor_agent"};
}

EmulatorPrograms inBuildTree(const fs::path& launcher_dir) {
  const fs::path top = launcher_dir.parent_path();
  return {top / "coordinator" / "coordinator", top / "fusion_center" / "fusion_center",
          top / "sensor_agent" / "sensor_agent"};
}

}  // namespace

fs::path userScratchDirectory() {
  if (const char* dir = std::getenv(kScratchDirVariable); dir != nullptr && *dir != '\0') {
    return fs::absolute(dir);
  }
  return fs::path("/tmp") / ("sensornet-" + std::to_string(::getuid()));
}

fs::path currentRunFile() {
  const char* runtime = std::getenv("XDG_RUNTIME_DIR");
  const fs::path dir = (runtime != nullptr && *runtime != '\0') ? fs::path(runtime) / "sensornet"
                                                                : userScratchDirectory();
  return dir / "current-run";
}

fs::path defaultLogDirectory(const std::string& run_id) { return userScratchDirectory() / run_id; }

void ensurePrivateDirectory(const fs::path& dir) {
  if (::mkdir(dir.c_str(), 0700) != 0 && errno != EEXIST) {
    throw InputError(dir.string(), "",
                     std::string("a folder that can be created: ") + std::strerror(errno));
  }
  if (const auto problem = privateDirectoryProblem(dir)) {
    throw InputError(dir.string(), "",
                     "a private folder (a real directory owned by you that others cannot write "
                     "to), but " +
                         *problem);
  }
}

void recordCurrentRun(const CurrentRun& run) {
  const fs::path file = currentRunFile();
  ensurePrivateDirectory(file.parent_path());
  nlohmann::json doc = {{"run_id", run.run_id}, {"launcher_pid", run.launcher_pid}};
  if (run.domain_id) doc["domain_id"] = *run.domain_id;
  replaceFileAtomically(file, doc.dump() + "\n");
}

std::optional<CurrentRun> readCurrentRun() {
  const fs::path file = currentRunFile();
  // A record in a folder others can change, or behind a link, could name anyone's run.
  if (privateDirectoryProblem(file.parent_path())) return std::nullopt;
  struct stat info {};
  if (::lstat(file.c_str(), &info) != 0 || !S_ISREG(info.st_mode)) return std::nullopt;
  std::ifstream in(file);
  if (!in) return std::nullopt;
  const nlohmann::json doc = nlohmann::json::parse(in, nullptr, false);
  if (!doc.is_object() || !doc.contains("run_id") || !doc["run_id"].is_string()) {
    return std::nullopt;
  }
  CurrentRun run;
  run.run_id = doc["run_id"].get<std::string>();
  if (doc.contains("domain_id") && doc["domain_id"].is_number_integer()) {
    run.domain_id = doc["domain_id"].get<int>();
  }
  if (doc.contains("launcher_pid") && doc["launcher_pid"].is_number_integer()) {
    run.launcher_pid = doc["launcher_pid"].get<pid_t>();
  }
  return run;
}

void forgetCurrentRun(const std::string& run_id) {
  const std::optional<CurrentRun> current = readCurrentRun();
  if (current && current->run_id == run_id) removeRegularFile(currentRunFile());
}

std::string chooseRunId(const std::string& given, std::optional<int>& domain_id) {
  if (!given.empty()) return given;
  const std::optional<CurrentRun> current = readCurrentRun();
  if (!current) {
    throw InputError("command line", "--run-id",
                     "a run id: no run launched by `sensornet launch` is going on here (no " +
                         currentRunFile().string() + ")");
  }
  if (current->launcher_pid > 0 && ::kill(current->launcher_pid, 0) != 0 && errno == ESRCH) {
    throw InputError("command line", "--run-id",
                     "a run id: the last launched run, " + current->run_id +
                         ", is over (its launcher, pid " + std::to_string(current->launcher_pid) +
                         ", is gone)");
  }
  if (!domain_id) domain_id = current->domain_id;
  return current->run_id;
}

std::string generateRunId() {
  std::random_device entropy;
  char suffix[5];
  std::snprintf(suffix, sizeof suffix, "%04x", static_cast<unsigned>(entropy() & 0xffffu));
  return "run-" + std::to_string(::getpid()) + "-" + suffix;
}

EmulatorPrograms findEmulatorPrograms() {
  if (const char* bin_dir = std::getenv("SENSORNET_BIN_DIR"); bin_dir != nullptr && *bin_dir) {
    const EmulatorPrograms programs = inDirectory(bin_dir);
    if (const auto missing = firstMissing(programs)) {
      throw std::runtime_error("no executable " + missing->string() +
                               " (SENSORNET_BIN_DIR is set to " + bin_dir + ")");
    }
    return programs;
  }
  std::error_code error;
  const fs::path self_dir = fs::read_symlink("/proc/self/exe", error).parent_path();
  if (error) throw std::runtime_error("cannot find the launcher's own path (/proc/self/exe)");
  const EmulatorPrograms installed = inDirectory(self_dir);
  if (!firstMissing(installed)) return installed;
  const EmulatorPrograms build_tree = inBuildTree(self_dir);
  if (const auto missing = firstMissing(build_tree)) {
    throw std::runtime_error("cannot find the emulator programs: no executable " +
                             firstMissing(installed)->string() + " nor " + missing->string() +
                             " (set SENSORNET_BIN_DIR to their directory)");
  }
  return build_tree;
}

}  // namespace sensornet::launcher
