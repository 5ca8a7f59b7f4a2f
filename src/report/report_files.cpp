#include "sensornet/report/report_files.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <stdexcept>

namespace sensornet::report {

using nlohmann::json;

void forEachReportedEpisode(const std::filesystem::path& episode_log,
                            const std::function<void(const json&)>& each) {
  // Entries are appended as episodes close, which is not always in order (an episode that
  // closed late follows the next one): first where each episode's first line starts, then
  // those lines in episode order. Only the offsets are held, never the entries.
  std::map<std::uint32_t, std::streamoff> first_line;
  std::ifstream in(episode_log, std::ios::binary);
  std::string line;
  std::streamoff at = 0;
  while (std::getline(in, line)) {
    const std::streamoff start = at;
    at += static_cast<std::streamoff>(line.size()) + 1;
    const json entry = json::parse(line, nullptr, false);
    if (!entry.is_object()) continue;
    const auto number = entry.find("episode");
    if (number == entry.end() || !number->is_number_unsigned()) continue;
    const auto episode = number->get<std::uint32_t>();
    if (first_line.count(episode) != 0) continue;
    first_line.emplace(episode, start);
  }
  in.clear();
  for (const auto& [episode, start] : first_line) {
    in.seekg(start);
    std::getline(in, line);
    each(json::parse(line));
  }
}


void writeReportWith(std::ostream& out, const json& doc, const EpisodeSource& for_each,
                     int indent) {
  const bool pretty = indent >= 0;
  const std::string pad = pretty ? std::string(static_cast<std::size_t>(indent), ' ') : "";
  const char* separator = pretty ? ",\n" : ",";
  // A member's value as doc.dump(indent) prints it `depth` levels down.
  const auto nested = [&](const json& value, int depth) {
    std::string text = value.dump(indent);
    if (!pretty) return text;
    const std::string shift(static_cast<std::size_t>(depth * indent), ' ');
    for (std::size_t at = text.find('\n'); at != std::string::npos; at = text.find('\n', at + 1)) {
      text.insert(at + 1, shift);
    }
    return text;
  };
  const auto member = [&](const std::string& key) {
    out << pad << json(key).dump() << (pretty ? ": " : ":");
  };
  const auto perEpisode = [&] {
    member(kPerEpisode);
    out << '[';
    bool first = true;
    for_each([&](const json& entry) {
      out << (first ? (pretty ? "\n" : "") : separator) << pad << pad << nested(entry, 2);
      first = false;
    });
    if (!first && pretty) out << '\n' << pad;
    out << ']';
  };
  out << '{' << (pretty ? "\n" : "");
  bool episodes_written = false;
  bool first = true;
  for (const auto& [key, value] : doc.items()) {
    if (key == kPerEpisode) continue;
    if (!first) out << separator;
    first = false;
    if (!episodes_written && key > kPerEpisode) {  // the members are in key order
      perEpisode();
      out << separator;
      episodes_written = true;
    }
    member(key);
    out << nested(value, 1);
  }
  if (!episodes_written) {
    if (!first) out << separator;
    perEpisode();
  }
  out << (pretty ? "\n" : "") << '}';
}


void writeReportWithLog(std::ostream& out, const json& doc,
                        const std::filesystem::path& episode_log, int indent) {
  writeReportWith(
      out, doc,
      [&episode_log](const std::function<void(const json&)>& each) {
        forEachReportedEpisode(episode_log, each);
      },
      indent);
}

json parseReportWithoutEpisodes(std::istream& in, std::size_t* listed) {
  std::size_t count = 0;
  bool in_episodes = false;
  const json::parser_callback_t skip = [&](int depth, json::parse_event_t event, json& parsed) {
    if (depth == 1 && event == json::parse_event_t::key) {
      in_episodes = parsed == kPerEpisode;
    } else if (in_episodes && depth == 2 &&
               (event == json::parse_event_t::object_end ||
                event == json::parse_event_t::array_end ||
                event == json::parse_event_t::value)) {
      ++count;  // an entry of per_episode, dropped once parsed
      return false;
    }
    return true;
  };
  json report = json::parse(in, skip, false);
  if (report.is_object()) report.erase(kPerEpisode);
  if (listed != nullptr) *listed = count;
  return report;
}

ReportFile readReport(const std::filesystem::path& path, EpisodeEntries entries) {
  ReportFile file;
  // Only a regular file is a report: a folder opens as a stream, and then throws on reading.
  std::error_code error;
  std::ifstream in;
  if (std::filesystem::is_regular_file(path, error)) in.open(path);
  if (!in.is_open()) {
    file.problem = ReportFile::Problem::Unreadable;
    return file;
  }
  try {
    file.report = entries == EpisodeEntries::Skipped ? parseReportWithoutEpisodes(in)
                                                     : json::parse(in, nullptr, false);
  } catch (const std::ios_base::failure&) {  // a read error (EIO) mid-file
    file.problem = ReportFile::Problem::Unreadable;
    return file;
  }
  if (file.report.is_discarded()) {
    file.problem = ReportFile::Problem::NotJson;
    return file;
  }
  const auto lacks = [&](const char* key, json::value_t type, const char* what) {
    const auto it = file.report.find(key);
    if (it != file.report.end() && it->type() == type) return false;
    file.problem = ReportFile::Problem::NotAReport;
    file.field = key;
    file.expected = what;
    return true;
  };
  if (!file.report.is_object()) {
    file.problem = ReportFile::Problem::NotAReport;
    file.expected = "a JSON object (a run report)";
    return file;
  }
  if (lacks("run_id", json::value_t::string, "a string (the run id)") ||
      lacks("summary", json::value_t::object, "an object (the run's summary)") ||
      (entries == EpisodeEntries::Read &&
       lacks(kPerEpisode, json::value_t::array, "an array of episode entries"))) {
    file.report = json();
  }
  return file;
}


std::vector<std::filesystem::path> fallbackReportPaths(const std::filesystem::path& report_path,
                                                       const std::string& run_id,
                                                       const std::filesystem::path& fallback_dir) {
  namespace fs = std::filesystem;
  const fs::path folder =
      report_path.parent_path().empty() ? fs::path(".") : report_path.parent_path();
  const std::string name = run_id + "-" + report_path.filename().string();
  std::vector<fs::path> paths;
  for (const fs::path& dir : {fallback_dir, fs::temp_directory_path()}) {
    std::error_code ignored;
    if (dir.empty() || fs::equivalent(dir, folder, ignored)) continue;
    if (!paths.empty() && fs::equivalent(dir, paths.front().parent_path(), ignored)) continue;
    paths.push_back(dir / name);
  }
  return paths;
}

std::filesystem::path episodeLogPath(const std::filesystem::path& report_path) {
  std::filesystem::path log = report_path;
  if (log.extension() == ".json") return log.replace_extension(".jsonl");
  return log += ".jsonl";
}

std::filesystem::path faultLogPath(const std::filesystem::path& report_path) {
  std::filesystem::path log = report_path;
  if (log.extension() == ".json") log.replace_extension();
  return log += ".faults.jsonl";
}

namespace {

// The file is not empty and its last byte is not a newline: a line torn by a crash.
bool endsInTornLine(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary | std::ios::ate);
  if (!in || in.tellg() <= 0) return false;
  in.seekg(-1, std::ios::end);
  char last = '\n';
  in.get(last);
  return last != '\n';
}

}  // namespace

EpisodeLog::EpisodeLog(const std::filesystem::path& path, Mode mode) : path_(path) {
  const bool torn = mode == Mode::Append && endsInTornLine(path);
  fd_ = ::open(path.c_str(),
               O_WRONLY | O_CREAT | O_CLOEXEC | (mode == Mode::Append ? O_APPEND : O_TRUNC), 0644);
  if (fd_ < 0) {
    throw std::runtime_error("cannot write the episode log " + path.string() + ": " +
                             std::strerror(errno));
  }
  if (torn) writeWhole("\n");  // the torn line stays a line of its own, which readEpisodeLog skips
}

EpisodeLog::~EpisodeLog() {
  if (fd_ >= 0) ::close(fd_);
}

void EpisodeLog::append(const json& entry) { writeWhole(entry.dump() + '\n'); }

void EpisodeLog::writeWhole(const std::string& line) {
  struct stat before {};
  const bool sized = ::fstat(fd_, &before) == 0;
  std::size_t done = 0;
  while (done < line.size()) {
    const ssize_t n = ::write(fd_, line.data() + done, line.size() - done);
    if (n > 0) {
      done += static_cast<std::size_t>(n);
      continue;
    }
    if (n < 0 && errno == EINTR) continue;
    const int error = n < 0 ? errno : ENOSPC;
    // What went in of the line is cut off again: a reader never sees half an entry.
    if (sized && done > 0) (void)::ftruncate(fd_, before.st_size);
    throw std::runtime_error("cannot append to the episode log " + path_.string() + ": " +
                             std::strerror(error));
  }
}

std::size_t forEachLoggedEpisode(const std::filesystem::path& path,
                                 const std::function<void(json)>& each) {
  std::size_t count = 0;
  std::ifstream in(path);
  std::string line;
  while (std::getline(in, line)) {
    json entry = json::parse(line, nullptr, false);
    if (entry.is_object() && entry.contains("episode")) {
      each(std::move(entry));
      ++count;
    }
  }
  return count;
}

std::vector<json> readEpisodeLog(const std::filesystem::path& path) {
  std::vector<json> entries;
  (void)forEachLoggedEpisode(path, [&entries](json entry) { entries.push_back(std::move(entry)); });
  return entries;
}

std::vector<json> readFaultLog(const std::filesystem::path& path) {
  std::vector<json> faults;
  std::ifstream in(path);
  std::string line;
  while (std::getline(in, line)) {  // a torn last line is no object, and skipped
    json fault = json::parse(line, nullptr, false);
    if (fault.is_object() && fault.contains("kind") && fault["kind"].is_string()) {
      faults.push_back(std::move(fault));
    }
  }
  return faults;
}


bool unfinishedRunAt(const std::filesystem::path& report_path) {
  std::error_code error;
  return std::filesystem::exists(episodeLogPath(report_path), error) &&
         !std::filesystem::exists(report_path, error);
}

}  // namespace sensornet::report
