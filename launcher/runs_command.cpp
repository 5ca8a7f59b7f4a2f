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

#include "output_file.hpp"
#include "run_files.hpp"
#include "sensornet/core/input_error.hpp"
#include "sensornet/core/words.hpp"
#include "sensornet/emulator/run_report.hpp"
#include "sensornet/emulator/vocabulary.hpp"

namespace sensornet::launcher {

enum class RunState { Live, Finished, Unknown };

}  // namespace sensornet::launcher

namespace sensornet {
template <>
struct Words<launcher::RunState> {
  using S = launcher::RunState;
  static constexpr std::array<WordOf<S>, 3> kTable{
      {{S::Live, "live"}, {S::Finished, "finished"}, {S::Unknown, "unknown"}}};
};
}  // namespace sensornet

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

std::string utcText(std::time_t t) {
  std::tm parts{};
  ::gmtime_r(&t, &parts);
  char text[32];
  std::strftime(text, sizeof text, "%Y-%m-%dT%H:%M:%SZ", &parts);
  return text;
}

// A JSON object read from a regular file (never through a link), or nullopt.
std::optional<json> readObject(const fs::path& path) {
  struct stat info {};
  if (::lstat(path.c_str(), &info) != 0 || !S_ISREG(info.st_mode)) return std::nullopt;
  std::ifstream in(path);
  json doc = json::parse(in, nullptr, false);
  if (!doc.is_object()) return std::nullopt;
  return doc;
}

std::string stringIn(const json& doc, const char* key) {
  const auto it = doc.find(key);
  return it != doc.end() && it->is_string() ? it->get<std::string>() : std::string();
}

std::optional<long long> countIn(const json& doc, const char* key) {
  const auto it = doc.find(key);
  if (it == doc.end() || !it->is_number_integer()) return std::nullopt;
  return it->get<long long>();
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

// One run folder as `sensornet runs` shows it.
struct RunEntry {
  std::string run_id;
  fs::path folder;
  RunState state = RunState::Unknown;
  std::string status;      // the report's status word (finished runs), "live" or "unknown"
  std::string started_at;  // "" when unknown
  std::string scenario;    // "" when unknown
  std::optional<long long> episodes;
  std::optional<long long> episodes_planned;
  fs::path report;
  pid_t launcher_pid = 0;
};

RunEntry examine(const fs::path& folder) {
  RunEntry e;
  e.run_id = folder.filename().string();
  e.folder = folder;
  e.report = folder / "report.json";
  const std::optional<json> record = readObject(folder / kRunRecordName);
  if (record) {
    e.scenario = stringIn(*record, "scenario");
    e.started_at = stringIn(*record, "started_at");
    e.episodes_planned = countIn(*record, "episodes");
    if (const std::string report = stringIn(*record, "report"); !report.empty()) e.report = report;
    if (const auto pid = countIn(*record, "launcher_pid"))
      e.launcher_pid = static_cast<pid_t>(*pid);
  }
  const FolderLock lock(folder);
  if (e.started_at.empty() && lock.modified()) e.started_at = utcText(*lock.modified());
  const bool live = lock.heldElsewhere() || (!lock.exists() && processAlive(e.launcher_pid));
  if (live) {
    e.state = RunState::Live;
    e.status = "live";
    e.episodes = linesIn(emulator::episodeLogPath(e.report));
    return e;
  }
  // Its per_episode entries are not needed here (a report of millions of episodes is never held).
  const emulator::ReportFile file =
      emulator::readReport(e.report, emulator::EpisodeEntries::Skipped);
  if (file.ok()) {
    const std::string status = stringIn(file.report, "status");
    if (lookUpWord<emulator::RunStatus>(status)) {
      e.state = RunState::Finished;
      e.status = status;
      e.episodes = countIn(file.report, "episodes");
      if (const auto planned = countIn(file.report, "episodes_planned")) {
        e.episodes_planned = planned;
      }
      return e;
    }
  }
  e.status = "unknown";
  return e;
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
  std::sort(runs.begin(), runs.end(), [](const RunEntry& a, const RunEntry& b) {
    if (a.started_at.empty() != b.started_at.empty()) return b.started_at.empty();
    if (a.started_at != b.started_at) return a.started_at < b.started_at;
    return a.run_id < b.run_id;
  });
  return runs;
}

std::string episodesText(const RunEntry& e) {
  if (!e.episodes && !e.episodes_planned) return "-";
  return (e.episodes ? std::to_string(*e.episodes) : std::string("?")) + "/" +
         (e.episodes_planned ? std::to_string(*e.episodes_planned) : std::string("?"));
}

json toJson(const RunEntry& e) {
  const auto orNull = [](const std::string& text) {
    return text.empty() ? json(nullptr) : json(text);
  };
  const auto countOrNull = [](const std::optional<long long>& n) {
    return n ? json(*n) : json(nullptr);
  };
  return {{"run_id", e.run_id},
          {"folder", e.folder.string()},
          {"state", std::string(wordOf(e.state))},
          {"status", e.state == RunState::Finished ? json(e.status) : json(nullptr)},
          {"started_at", orNull(e.started_at)},
          {"scenario", orNull(e.scenario)},
          {"episodes", countOrNull(e.episodes)},
          {"episodes_planned", countOrNull(e.episodes_planned)},
          {"report", e.report.string()}};
}

void printTable(const std::vector<RunEntry>& runs) {
  std::vector<std::vector<std::string>> rows = {
      {"RUN", "STATUS", "STARTED", "EPISODES", "SCENARIO"}};
  for (const RunEntry& e : runs) {
    rows.push_back({e.run_id, e.status, e.started_at.empty() ? "-" : e.started_at, episodesText(e),
                    e.scenario.empty() ? "-" : e.scenario});
  }
  std::vector<std::size_t> width(rows[0].size(), 0);
  for (const auto& row : rows) {
    for (std::size_t c = 0; c < row.size(); ++c) width[c] = std::max(width[c], row[c].size());
  }
  for (const auto& row : rows) {
    std::string line;
    for (std::size_t c = 0; c < row.size(); ++c) {
      line += row[c];
      if (c + 1 < row.size()) line += std::string(width[c] - row[c].size() + 2, ' ');
    }
    std::printf("%s\n", line.c_str());
  }
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
    for (const RunEntry& e : removed) doc["removed"].push_back(toJson(e));
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
    for (const RunEntry& e : runs) doc["runs"].push_back(toJson(e));
    printJson(doc);
  } else if (runs.empty()) {
    std::printf("no runs in %s\n", scratch->c_str());
  } else {
    printTable(runs);
  }
  return kExitOk;
}

}  // namespace

std::string utcNow() { return utcText(std::time(nullptr)); }

void writeRunRecord(const fs::path& log_dir, const RunRecord& record) {
  const json doc = {{"run_id", record.run_id},
                    {"scenario", record.scenario.string()},
                    {"episodes", record.episodes},
                    {"report", record.report.string()},
                    {"launcher_pid", record.launcher_pid},
                    {"started_at", record.started_at}};
  replaceFileAtomically(log_dir / kRunRecordName, doc.dump(2) + "\n");
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
