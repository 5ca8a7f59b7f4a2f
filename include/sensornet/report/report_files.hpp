#pragma once
// A run's report on disk and the logs beside it: the report file as every reader takes it
// (readReport), the episode log the fusion center appends each episode's entry to as it closes
// and the fault log beside it, and writing a report whose per_episode is streamed from a log
// instead of held. No DDS, no processes: the fusion center's core, the launcher, the page, the
// replay and users' tools read and write through these.
//
//   const ReportFile file = readReport(path);           // or the one reason it is no report
//   EpisodeLog log(episodeLogPath(path));               // report.json -> report.jsonl
//   log.append(entry);                                  // one line, one write(2)
//   writeReportWithLog(out, doc, episodeLogPath(path), 2);

#include <cstddef>
#include <filesystem>
#include <functional>
#include <iosfwd>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace sensornet::report {

// The report's key whose entries may be streamed (every other member is held).
inline constexpr const char* kPerEpisode = "per_episode";

// The episode log beside a report: report.json -> report.jsonl (any other name gets ".jsonl"
// appended).
[[nodiscard]] std::filesystem::path episodeLogPath(const std::filesystem::path& report_path);
// Beside it, the faults the fusion center recorded, one JSON line each as they happen
// ("report.json" -> "report.faults.jsonl"): a restarted fusion center starts from them, so that
// what an earlier life of it saw stays in the report.
[[nodiscard]] std::filesystem::path faultLogPath(const std::filesystem::path& report_path);
// Where a report goes when its own path refuses it (a full disk there), so that nothing the run
// measured is lost, in the order to try: `fallback_dir`/<run id>-<its name> (unless that is
// the report's own folder), then the same in the system's temporary folder. The fusion center
// and the launcher agree on them.
[[nodiscard]] std::vector<std::filesystem::path> fallbackReportPaths(
    const std::filesystem::path& report_path, const std::string& run_id,
    const std::filesystem::path& fallback_dir);

// Appends one JSON document per line, each line in one write(2) to the file itself, so that a
// crash of the process loses no line it appended and tears none. A line the file cannot take
// whole (a full disk, a file size limit) is cut off again, so the log never ends in half an
// entry. Throws std::runtime_error naming the file and the system's reason when it cannot be
// opened or a line cannot be written.
class EpisodeLog {
 public:
  enum class Mode {
    Truncate,  // a new run
    Append     // a restarted fusion center: after what is there (a torn last line stays alone)
  };
  explicit EpisodeLog(const std::filesystem::path& path, Mode mode = Mode::Truncate);
  ~EpisodeLog();
  EpisodeLog(const EpisodeLog&) = delete;
  EpisodeLog& operator=(const EpisodeLog&) = delete;
  void append(const nlohmann::json& entry);

 private:
  void writeWhole(const std::string& line);

  std::filesystem::path path_;
  int fd_ = -1;
};

// The entries of an episode log, in order; a torn last line (a crash mid-write) is skipped.
[[nodiscard]] std::vector<nlohmann::json> readEpisodeLog(const std::filesystem::path& path);
// The faults of a fault log (faultLogPath), in order; none when there is no such file.
[[nodiscard]] std::vector<nlohmann::json> readFaultLog(const std::filesystem::path& path);
// The same, one at a time, without holding them; returns how many there were.
std::size_t forEachLoggedEpisode(const std::filesystem::path& path,
                                 const std::function<void(nlohmann::json)>& each);
// The entries of a report's per_episode from its episode log: each episode once (the first of
// repeated lines), in episode order (the log holds them in the order they closed).
void forEachReportedEpisode(const std::filesystem::path& episode_log,
                            const std::function<void(const nlohmann::json&)>& each);
// Writes `doc` (a report without per_episode) with per_episode streamed in from `episode_log`,
// as RunReport::write does.
void writeReportWithLog(std::ostream& out, const nlohmann::json& doc,
                        const std::filesystem::path& episode_log, int indent);
// A report file parsed without its per_episode entries (each dropped once parsed, so a report of
// millions of episodes is never held); `listed`, if given, receives how many there were. A
// discarded (not a JSON document) value when the text is not JSON.
[[nodiscard]] nlohmann::json parseReportWithoutEpisodes(std::istream& in,
                                                        std::size_t* listed = nullptr);

// A report file as every reader takes it (the launcher's outcome, `sensornet report` and `runs`,
// the testing fixture, the benchmarks): the document, or the one reason it is not a report.
// A report is a JSON object with a string run_id, an object summary and (unless skipped) an
// array per_episode; what each reader needs beyond that it checks itself (the page:
// checkReport).
struct ReportFile {
  enum class Problem { None, Unreadable, NotJson, NotAReport };
  nlohmann::json report;  // the document when problem is None
  Problem problem = Problem::None;
  std::string field;     // NotAReport: the key that is missing or of the wrong type
  std::string expected;  // NotAReport: what it should be
  [[nodiscard]] bool ok() const { return problem == Problem::None; }
};
enum class EpisodeEntries {
  Read,
  Skipped,  // per_episode is dropped while parsed (a report with an episode log beside it)
};
[[nodiscard]] ReportFile readReport(const std::filesystem::path& path,
                                    EpisodeEntries entries = EpisodeEntries::Read);

// Writes `doc` (a report without per_episode) with per_episode holding the entries `for_each`
// hands out, in their order, as doc.dump(indent) would print the whole.
using EpisodeSource = std::function<void(const std::function<void(const nlohmann::json&)>&)>;
void writeReportWith(std::ostream& out, const nlohmann::json& doc, const EpisodeSource& for_each,
                     int indent);

// A run whose fusion center died: the episode log beside `report_path` exists and the final
// report does not (what `fusion_center serve --resume-unfinished` resumes).
[[nodiscard]] bool unfinishedRunAt(const std::filesystem::path& report_path);

}  // namespace sensornet::report
