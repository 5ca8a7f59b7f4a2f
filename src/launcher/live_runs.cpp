#include "sensornet/launcher/live_runs.hpp"

#include <signal.h>
#include <sys/stat.h>
#include <sys/sysmacros.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <tuple>

#include "sensornet/launcher/run_files.hpp"
#include "sensornet/core/input_error.hpp"

namespace sensornet::launcher {
namespace {

namespace fs = std::filesystem;
using FileId = std::tuple<unsigned, unsigned, unsigned long long>;  // major, minor, inode

// flock()s held on this host by file, with the holder's pid: lines of /proc/locks such as
// "1: FLOCK  ADVISORY  WRITE 23855 fe:00:10952719 0 EOF".
std::map<FileId, pid_t> heldFlocks() {
  std::map<FileId, pid_t> held;
  std::ifstream in("/proc/locks");
  std::string line;
  while (std::getline(in, line)) {
    std::istringstream fields(line);
    std::string number, kind, mode, access, file;
    long pid = 0;
    if (!(fields >> number >> kind >> mode >> access >> pid >> file) || kind != "FLOCK") continue;
    unsigned major = 0, minor = 0;
    unsigned long long inode = 0;
    if (std::sscanf(file.c_str(), "%x:%x:%llu", &major, &minor, &inode) != 3) continue;
    held[{major, minor, inode}] = static_cast<pid_t>(pid);
  }
  return held;
}

std::string clockTime(std::time_t when) {
  std::tm local{};
  char text[16] = "";
  if (::localtime_r(&when, &local) != nullptr) std::strftime(text, sizeof text, "%H:%M:%S", &local);
  return text;
}

bool launcherAlive(pid_t pid) { return pid <= 0 || ::kill(pid, 0) == 0 || errno != ESRCH; }

}  // namespace

std::vector<LiveRun> liveRunsInScratch() {
  std::vector<LiveRun> live;
  const fs::path scratch = userScratchDirectory();
  if (privateDirectoryProblem(scratch)) return live;  // nobody's runs, or not to be trusted
  const std::map<FileId, pid_t> held = heldFlocks();
  std::error_code error;
  for (const fs::directory_entry& entry : fs::directory_iterator(scratch, error)) {
    const fs::path lock = entry.path() / "launch.lock";
    struct stat info {};
    if (::lstat(lock.c_str(), &info) != 0 || !S_ISREG(info.st_mode)) continue;
    const auto holder = held.find({major(info.st_dev), minor(info.st_dev), info.st_ino});
    if (holder == held.end()) continue;
    live.push_back({entry.path().filename().string(), holder->second, std::nullopt,
                    entry.path().string(), clockTime(info.st_mtime)});
  }
  std::sort(live.begin(), live.end(),
            [](const LiveRun& a, const LiveRun& b) { return a.run_id < b.run_id; });
  return live;
}

LiveRun chooseLiveRun(const std::string& given, std::optional<int>& domain_id) {
  std::optional<RecordedRun> record;
  if (const std::optional<CurrentRun> current = readCurrentRun()) {
    record = RecordedRun{{current->run_id, current->launcher_pid, current->domain_id, "", ""},
                         launcherAlive(current->launcher_pid)};
  }
  const std::vector<LiveRun> found = liveRunsInScratch();
  if (!given.empty()) {
    LiveRun run{given, 0, std::nullopt, "", ""};
    for (const LiveRun& r : found) {
      if (r.run_id == given) run = r;
    }
    if (record && record->launcher_alive && record->run.run_id == given) {
      run.launcher_pid = record->run.launcher_pid;
    }
    return run;
  }
  const RunChoice choice = chooseRun(given, record, found, currentRunFile().string());
  if (!choice.run) throw InputError("command line", "--run-id", choice.expected);
  if (!domain_id) domain_id = choice.run->domain_id;
  return *choice.run;
}

std::optional<std::string> securityOfLauncher(pid_t launcher_pid) {
  if (launcher_pid <= 0) return std::nullopt;
  std::ifstream in("/proc/" + std::to_string(launcher_pid) + "/cmdline");
  std::vector<std::string> argv;
  for (std::string arg; std::getline(in, arg, '\0');) argv.push_back(arg);
  constexpr std::string_view kFlag = "--security";
  for (std::size_t i = 0; i < argv.size(); ++i) {
    if (argv[i] == kFlag && i + 1 < argv.size()) return argv[i + 1];
    if (argv[i].starts_with("--security=")) return argv[i].substr(kFlag.size() + 1);
  }
  return std::nullopt;
}

}  // namespace sensornet::launcher
