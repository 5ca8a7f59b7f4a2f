#include "sensornet/launcher/run_folder.hpp"

#include "sensornet/report/report_files.hpp"

#include <algorithm>
#include <chrono>

#include "sensornet/emulator/vocabulary.hpp"
#include "sensornet/io/utc_time.hpp"

namespace sensornet::launcher {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

std::string stringIn(const json& doc, const char* key) {
  const auto it = doc.find(key);
  return it != doc.end() && it->is_string() ? it->get<std::string>() : std::string();
}

std::optional<long long> countIn(const json& doc, const char* key) {
  const auto it = doc.find(key);
  if (it == doc.end() || !it->is_number_integer()) return std::nullopt;
  return it->get<long long>();
}

}  // namespace

json launchRecordJson(const LaunchRecord& record) {
  return {{"run_id", record.run_id},
          {"scenario", record.scenario.string()},
          {"episodes", record.episodes},
          {"report", record.report.string()},
          {"launcher_pid", record.launcher_pid},
          {"started_at", record.started_at}};
}

fs::path reportOf(const RunFolderFacts& facts) {
  if (facts.record) {
    if (std::string report = stringIn(*facts.record, "report"); !report.empty()) return report;
  }
  return facts.folder / "report.json";
}

pid_t launcherPidOf(const RunFolderFacts& facts) {
  if (!facts.record) return 0;
  const auto pid = countIn(*facts.record, "launcher_pid");
  return pid ? static_cast<pid_t>(*pid) : 0;
}

bool isLive(const RunFolderFacts& facts) {
  return facts.lock.held_elsewhere || (!facts.lock.exists && facts.launcher_alive);
}

RunEntry classifyRun(const RunFolderFacts& facts) {
  RunEntry e;
  e.run_id = facts.folder.filename().string();
  e.folder = facts.folder;
  e.report = reportOf(facts);
  e.launcher_pid = launcherPidOf(facts);
  if (facts.record) {
    e.scenario = stringIn(*facts.record, "scenario");
    e.started_at = stringIn(*facts.record, "started_at");
    e.episodes_planned = countIn(*facts.record, "episodes");
  }
  if (e.started_at.empty() && facts.lock.modified) {
    e.started_at = utcText(std::chrono::system_clock::from_time_t(*facts.lock.modified));
  }
  if (isLive(facts)) {
    e.state = RunState::Live;
    e.status = "live";
    e.episodes = facts.episodes_logged;
    return e;
  }
  if (facts.report) {
    e.state = RunState::Finished;
    e.status = std::string(wordOf(facts.report->status));
    if (facts.report->episodes) e.episodes = static_cast<long long>(*facts.report->episodes);
    if (const auto planned = facts.report->episodes_planned) {
      e.episodes_planned = static_cast<long long>(*planned);
    }
    return e;
  }
  e.status = "unknown";
  return e;
}

std::optional<report::RunRecord> finishedReportAt(const fs::path& path) {
  const report::ReportFile file = report::readReport(path, report::EpisodeEntries::Skipped);
  if (!file.ok()) return std::nullopt;
  try {
    return report::decodeRunRecord(file.report);
  } catch (const report::RecordError&) {
    return std::nullopt;  // an unknown status, a count that is no number: not a report we read
  }
}

void sortRuns(std::vector<RunEntry>& runs) {
  std::sort(runs.begin(), runs.end(), [](const RunEntry& a, const RunEntry& b) {
    if (a.started_at.empty() != b.started_at.empty()) return b.started_at.empty();
    if (a.started_at != b.started_at) return a.started_at < b.started_at;
    return a.run_id < b.run_id;
  });
}

std::string episodesText(const RunEntry& e) {
  if (!e.episodes && !e.episodes_planned) return "-";
  return (e.episodes ? std::to_string(*e.episodes) : std::string("?")) + "/" +
         (e.episodes_planned ? std::to_string(*e.episodes_planned) : std::string("?"));
}

json runEntryJson(const RunEntry& e) {
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

std::string runsTable(const std::vector<RunEntry>& runs) {
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
  std::string table;
  for (const auto& row : rows) {
    for (std::size_t c = 0; c < row.size(); ++c) {
      table += row[c];
      if (c + 1 < row.size()) table += std::string(width[c] - row[c].size() + 2, ' ');
    }
    table += "\n";
  }
  return table;
}

}  // namespace sensornet::launcher
