#include "runs_command.hpp"

#include <fcntl.h>
#include <signal.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <ctime>
#include <fstream>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "sensornet/io/output_file.hpp"
#include "sensornet/launcher/run_files.hpp"
#include "sensornet/core/input_error.hpp"
#include "sensornet/emulator/run_report.hpp"
#include "sensornet/emulator/vocabulary.hpp"

namespace sensornet::launcher {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

// The launch lock of a run folder (run_lock.hpp), taken without waiting and never created: a
// launch of the run cannot start while this is held.
class FolderLock {
 public:
  explicit FolderLock(const fs::path& folder) {
    fd_ = ::open((folder / "launch.lock").c_str(), O_RDONLY | O_NOFOLLOW | O_CLOEXEC | O_NONBLOCK);
    if (fd_ < 0) return;
    struct stat info {};
    if (::fstat(fd_, &info) != 0 || !S_ISREG(info.st_mode)) {
      ::close(fd_);
      fd_ = -1;
      return;
    }
    modified_ = info.st_mtime;
    taken_ = ::flock(fd_, LOCK_EX | LOCK_NB) == 0;
  }
  FolderLock(const FolderLock&) = delete;
  FolderLock& operator=(const FolderLock&) = delete;
  ~FolderLock() {
    if (fd_ >= 0) ::close(fd_);
  }
  [[nodiscard]] bool exists() const { return fd_ >= 0; }
  // Someone else (a running launch) holds it.
  [[nodiscard]] bool heldElsewhere() const { return exists() && !taken_; }
  [[nodiscard]] std::optional<std::time_t> modified() const {
    return exists() ? std::optional<std::time_t>(modified_) : std::nullopt;
  }

 private:
  int fd_ = -1;
  bool taken_ = false;
  std::time_t modified_ = 0;
};

// A JSON object read from a regular file (never through a link), or nullopt.
std::optional<json> readObject(const fs::path& path) {
  struct stat info {};
  if (::lstat(path.c_str(), &info) != 0 || !S_ISREG(info.st_mode)) return std::nullopt;
  std::ifstream in(path);
  json doc = json::parse(in, nullptr, false);
  if (!doc.is_object()) return std::nullopt;
  return doc;
}

std::optional<long long> linesIn(const fs::path& path) {
  struct stat info {};
  if (::lstat(path.c_str(), &info) != 0 || !S_ISREG(info.st_mode)) return std::nullopt;
  std::ifstream in(path);
  long long lines = 0;
  for (std::string line; std::getline(in, line);) lines += line.empty() ? 0 : 1;
  return lines;
}

bool processAlive(pid_t pid) { return pid > 0 && (::kill(pid, 0) == 0 || errno == EPERM); }

// What is in `folder`, read as classifyRun needs it: the report only when the run is not live
// (its per_episode entries skipped: a report of millions of episodes is never held).
RunEntry examine(const fs::path& folder) {
  RunFolderFacts facts;
  facts.folder = folder;
  facts.record = readObject(folder / kLaunchRecordName);
  const FolderLock lock(folder);
  facts.lock = {lock.exists(), lock.heldElsewhere(), lock.modified()};
  facts.launcher_alive = processAlive(launcherPidOf(facts));
  if (isLive(facts)) {
    facts.episodes_logged = linesIn(sensornet::report::episodeLogPath(reportOf(facts)));
  } else {
    facts.report = finishedReportAt(reportOf(facts));
  }
  return classifyRun(facts);
}

// The scratch folder, checked as the launcher checks it (a folder others can change could name
// anyone's runs); nullopt when it does not exist.
std::optional<fs::path> scratchFolder() {
  const fs::path scratch = userScratchDirectory();
  struct stat info {};
  if (::lstat(scratch.c_str(), &info) != 0 && errno == ENOENT) return std::nullopt;
  if (const auto problem = privateDirectoryProblem(scratch)) {
    throw InputError(scratch.string(), "",
                     "a private scratch folder (a real directory owned by you that others cannot "
                     "write to), but " +
                         *problem);
  }
  return scratch;
}

// Every run folder in the scratch folder: real directories only, oldest start first.
std::vector<RunEntry> listRuns(const fs::path& scratch) {
  std::vector<RunEntry> runs;
  std::error_code error;
  for (const fs::directory_entry& entry : fs::directory_iterator(scratch, error)) {
    if (entry.is_symlink() || !entry.is_directory()) continue;
    runs.push_back(examine(entry.path()));
  }
  if (error) throw std::runtime_error("cannot read " + scratch.string() + ": " + error.message());
  sortRuns(runs);
  return runs;
}

// Removes a run's folder while holding its launch lock; why not, or nullopt when removed.
std::optional<std::string> removeRun(const RunEntry& e) {
  const FolderLock lock(e.folder);
  if (lock.heldElsewhere() || (!lock.exists() && processAlive(e.launcher_pid))) {
    return "run " + e.run_id + " is live (a launch holds " + (e.folder / "launch.lock").string() +
           ")";
  }
  std::error_code error;
  fs::remove_all(e.folder, error);
  if (error) return "cannot remove " + e.folder.string() + ": " + error.message();
  return std::nullopt;
}

struct RunsOptions {
  bool json = false;
  bool remove_finished = false;
  std::vector<std::string> remove_ids;
};

int printRemoved(const std::vector<RunEntry>& removed, const std::vector<std::string>& failures,
                 const fs::path& scratch, bool as_json) {
  if (as_json) {
    json doc = {{"scratch", scratch.string()}, {"removed", json::array()}};
    for (const RunEntry& e : removed) doc["removed"].push_back(runEntryJson(e));
    doc["failures"] = failures;
    printJson(doc);
  } else {
    for (const RunEntry& e : removed) {
      std::printf("removed %s (%s)\n", e.run_id.c_str(), e.status.c_str());
    }
    if (removed.empty() && failures.empty())
      std::printf("no finished run in %s\n", scratch.c_str());
  }
  for (const std::string& failure : failures)
    std::fprintf(stderr, "sensornet runs: %s\n", failure.c_str());
  return failures.empty() ? kExitOk : kExitFailure;
}

int removeFinished(const fs::path& scratch, bool as_json) {
  std::vector<RunEntry> removed;
  std::vector<std::string> failures;
  for (const RunEntry& e : listRuns(scratch)) {
    if (e.state != RunState::Finished) continue;
    if (const auto problem = removeRun(e)) {
      failures.push_back(*problem);
    } else {
      removed.push_back(e);
    }
  }
  return printRemoved(removed, failures, scratch, as_json);
}

// `runs rm ID...`: every id must name a run folder that is not live, or nothing is removed.
int removeNamed(const fs::path& scratch, const std::vector<std::string>& ids, bool as_json) {
  std::vector<RunEntry> chosen;
  for (const std::string& id : ids) {
    const fs::path folder = scratch / id;
    struct stat info {};
    const bool plain = !id.empty() && id != "." && id != ".." && id.find('/') == std::string::npos;
    if (!plain || ::lstat(folder.c_str(), &info) != 0 || !S_ISDIR(info.st_mode)) {
      throw InputError(
          "sensornet runs rm", "ID",
          "the id of a run in " + scratch.string() + " (see `sensornet runs`), got '" + id + "'");
    }
    RunEntry e = examine(folder);
    if (e.state == RunState::Live) {
      throw InputError("sensornet runs rm", "ID",
                       "a run that is not live, but " + id +
                           " is (its launch lock is held); nothing was removed");
    }
    chosen.push_back(std::move(e));
  }
  std::vector<RunEntry> removed;
  std::vector<std::string> failures;
  for (const RunEntry& e : chosen) {
    if (const auto problem = removeRun(e)) {
      failures.push_back(*problem);
    } else {
      removed.push_back(e);
    }
  }
  return printRemoved(removed, failures, scratch, as_json);
}

int runRuns(const RunsOptions& options, bool remove_named) {
  const std::optional<fs::path> scratch = scratchFolder();
  if (!scratch) {
    if (remove_named) {
      throw InputError("sensornet runs rm", "ID",
                       "a run in " + userScratchDirectory().string() + ", which does not exist");
    }
    if (options.json) {
      printJson({{"scratch", userScratchDirectory().string()}, {"runs", json::array()}});
    } else {
      std::printf("no runs in %s (it does not exist)\n", userScratchDirectory().c_str());
    }
    return kExitOk;
  }
  if (remove_named) return removeNamed(*scratch, options.remove_ids, options.json);
  if (options.remove_finished) return removeFinished(*scratch, options.json);
  const std::vector<RunEntry> runs = listRuns(*scratch);
  if (options.json) {
    json doc = {{"scratch", scratch->string()}, {"runs", json::array()}};
    for (const RunEntry& e : runs) doc["runs"].push_back(runEntryJson(e));
    printJson(doc);
  } else if (runs.empty()) {
    std::printf("no runs in %s\n", scratch->c_str());
  } else {
    std::printf("%s", runsTable(runs).c_str());
  }
  return kExitOk;
}

}  // namespace

void writeLaunchRecord(const fs::path& log_dir, const LaunchRecord& record) {
  replaceFileAtomically(log_dir / kLaunchRecordName, launchRecordJson(record).dump(2) + "\n");
}

Subcommand addRunsCommand(CLI::App& app) {
  auto options = std::make_shared<RunsOptions>();
  CLI::App* cmd = app.add_subcommand(
      "runs",
      "List the runs in the scratch folder (/tmp/sensornet-<uid>, or $SENSORNET_SCRATCH_DIR), "
      "where `sensornet launch` keeps each run's logs and report by default: one line per run "
      "with its id, status (live: a launch holds its lock; else the status its report gives: "
      "completed, degraded, failed or interrupted; unknown: neither), start time (UTC), episodes "
      "(finished/planned) and scenario. Runs launched with --log-dir elsewhere are not listed. "
      "Examples:\n  sensornet runs\n  sensornet runs --remove-finished\n"
      "  sensornet runs rm run-42-1a2b");
  cmd->add_flag("--json", options->json,
                "print {\"scratch\", \"runs\": [{\"run_id\", \"state\" (live, finished, unknown), "
                "\"status\", \"started_at\", \"scenario\", \"episodes\", \"episodes_planned\", "
                "\"report\", \"folder\"}]} as one JSON line");
  cmd->add_flag("--remove-finished", options->remove_finished,
                "remove the folders of the finished runs (never a live one, nor one whose state "
                "is unknown) and say which");
  CLI::App* rm = cmd->add_subcommand(
      "rm",
      "Remove the folders of these runs: finished or unknown ones; a live one is refused and "
      "then nothing is removed.");
  rm->add_option("ID", options->remove_ids, "run ids (as `sensornet runs` lists them)")->required();
  rm->add_flag("--json", options->json,
               "print {\"scratch\", \"removed\": [...], \"failures\": [...]} as one JSON line");
  return {cmd, [options, rm] { return runRuns(*options, rm->parsed()); }};
}

}  // namespace sensornet::launcher
