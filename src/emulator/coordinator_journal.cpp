#include "sensornet/emulator/coordinator_journal.hpp"

#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <system_error>

#include "sensornet/core/input_error.hpp"
#include "sensornet/io/scenario_file.hpp"

namespace sensornet::emulator {
namespace {

using nlohmann::json;

constexpr const char* kFormat = "sensornet coordinator journal 1";

// ---- writing

json ratesJson(const RateSchedule& schedule) {
  json rows = json::array();
  for (int k = 0; k < schedule.intervals(); ++k) {
    json row = json::array();
    for (int j = 0; j < schedule.sensorCount(); ++j) row.push_back(schedule.rate(k, j));
    rows.push_back(std::move(row));
  }
  return rows;
}

json versionJson(const ScheduleVersion& v) {
  return {{"version", v.version},
          {"effective_episode", v.effective_episode},
          {"effective_time_s", v.effective_time_s},
          {"surrogate", v.surrogate},
          {"bracket", {{"info", v.bracket.info}, {"cov", v.bracket.cov}}},
          {"command_id", v.command_id},
          {"horizon_s", v.schedule.horizon()},
          {"rates", ratesJson(v.schedule)}};
}

json settingsJson(const ReplanSettings& s) {
  json budget = json::array();
  for (Eigen::Index i = 0; i < s.budget.size(); ++i) budget.push_back(s.budget(i));
  return {{"surrogate", std::string(describe(s.surrogate))},
          {"excluded", s.excluded},
          {"failed", s.failed},
          {"budget", budget}};
}

// Consecutive episodes as [first, last] ranges.
json episodeRanges(const EpisodeSet& episodes) {
  json ranges = json::array();
  for (const auto& [first, last] : episodes.ranges()) ranges.push_back({first, last});
  return ranges;
}

// ---- reading, every field checked

class Fields {
 public:
  explicit Fields(std::string source) : source_(std::move(source)) {}

  [[noreturn]] void fail(const std::string& field, const std::string& expected) const {
    throw InputError(source_, field, expected);
  }
  const json& member(const json& object, const std::string& path, const char* key) const {
    if (!object.is_object() || !object.contains(key)) fail(path + key, "present");
    return object.at(key);
  }
  const json& array(const json& object, const std::string& path, const char* key) const {
    const json& value = member(object, path, key);
    if (!value.is_array()) fail(path + key, "an array");
    return value;
  }
  template <typename Unsigned>
  Unsigned unsignedAt(const json& value, const std::string& field) const {
    if (!value.is_number_unsigned() &&
        !(value.is_number_integer() && value.get<std::int64_t>() >= 0)) {
      fail(field, "a non-negative integer");
    }
    const auto number = value.get<std::uint64_t>();
    if (number > std::numeric_limits<Unsigned>::max()) fail(field, "a smaller integer");
    return static_cast<Unsigned>(number);
  }
  template <typename Unsigned>
  Unsigned unsignedOf(const json& object, const std::string& path, const char* key) const {
    return unsignedAt<Unsigned>(member(object, path, key), path + key);
  }
  double numberAt(const json& value, const std::string& field) const {
    if (!value.is_number()) fail(field, "a number");
    const double number = value.get<double>();
    if (!std::isfinite(number)) fail(field, "a finite number");
    return number;
  }
  double numberOf(const json& object, const std::string& path, const char* key) const {
    return numberAt(member(object, path, key), path + key);
  }
  std::string stringOf(const json& object, const std::string& path, const char* key) const {
    const json& value = member(object, path, key);
    if (!value.is_string()) fail(path + key, "a string");
    return value.get<std::string>();
  }
  bool boolOf(const json& object, const std::string& path, const char* key) const {
    const json& value = member(object, path, key);
    if (!value.is_boolean()) fail(path + key, "true or false");
    return value.get<bool>();
  }

 private:
  std::string source_;
};

std::set<int> sensorSet(const Fields& f, const json& object, const std::string& path,
                        const char* key, int sensor_count) {
  std::set<int> sensors;
  const json& values = f.array(object, path, key);
  for (std::size_t i = 0; i < values.size(); ++i) {
    const std::string field = path + key + "[" + std::to_string(i) + "]";
    const auto id = f.unsignedAt<std::uint32_t>(values[i], field);
    if (id >= static_cast<std::uint32_t>(sensor_count)) {
      f.fail(field, "a sensor id below M = " + std::to_string(sensor_count));
    }
    sensors.insert(static_cast<int>(id));
  }
  return sensors;
}

template <class E>
E wordFrom(const Fields& f, const std::string& name, const std::string& field) {
  if (const auto value = lookUpWord<E>(name)) return *value;
  f.fail(field, wordChoices<E>() + ", got '" + name + "'");
}

ReplanSettings settingsFrom(const Fields& f, const json& s, const Scenario& scenario) {
  const std::string path = "settings.";
  ReplanSettings settings;
  settings.surrogate =
      wordFrom<PlanSurrogate>(f, f.stringOf(s, path, "surrogate"), path + "surrogate");
  settings.excluded = sensorSet(f, s, path, "excluded", scenario.sensorCount());
  settings.failed = sensorSet(f, s, path, "failed", scenario.sensorCount());
  const json& budget = f.array(s, path, "budget");
  if (static_cast<Eigen::Index>(budget.size()) != scenario.constraints.b.size()) {
    f.fail(path + "budget",
           std::to_string(scenario.constraints.b.size()) + " values (one per row of C)");
  }
  settings.budget.resize(static_cast<Eigen::Index>(budget.size()));
  for (std::size_t i = 0; i < budget.size(); ++i) {
    const std::string field = path + "budget[" + std::to_string(i) + "]";
    const double b = f.numberAt(budget[i], field);
    if (!(b > 0.0)) f.fail(field, "a value > 0");
    settings.budget(static_cast<Eigen::Index>(i)) = b;
  }
  return settings;
}

RateSchedule ratesFrom(const Fields& f, const json& v, const std::string& path,
                       const Scenario& scenario) {
  if (f.numberOf(v, path, "horizon_s") != scenario.horizon_s) {
    f.fail(path + "horizon_s", "the scenario's T");
  }
  const json& rows = f.array(v, path, "rates");
  const auto n = static_cast<std::size_t>(scenario.intervals);
  const auto m = static_cast<std::size_t>(scenario.sensorCount());
  Eigen::MatrixXd rates(scenario.intervals, scenario.sensorCount());
  if (rows.size() != n) f.fail(path + "rates", std::to_string(n) + " rows (N)");
  for (std::size_t k = 0; k < n; ++k) {
    const std::string row_field = path + "rates[" + std::to_string(k) + "]";
    if (!rows[k].is_array() || rows[k].size() != m) {
      f.fail(row_field, "an array of " + std::to_string(m) + " rates (M)");
    }
    for (std::size_t j = 0; j < m; ++j) {
      const double rate = f.numberAt(rows[k][j], row_field + "[" + std::to_string(j) + "]");
      if (rate < 0.0) f.fail(row_field + "[" + std::to_string(j) + "]", "a rate >= 0");
      rates(static_cast<Eigen::Index>(k), static_cast<Eigen::Index>(j)) = rate;
    }
  }
  return RateSchedule(scenario.horizon_s, std::move(rates));
}

ScheduleVersion versionFrom(const Fields& f, const json& v, const std::string& path,
                            const Scenario& scenario) {
  ScheduleVersion version;
  version.version = f.unsignedOf<std::uint32_t>(v, path, "version");
  version.effective_episode = f.unsignedOf<std::uint32_t>(v, path, "effective_episode");
  version.effective_time_s = f.numberOf(v, path, "effective_time_s");
  if (version.effective_time_s < 0.0 || version.effective_time_s > scenario.horizon_s) {
    f.fail(path + "effective_time_s", "a time in [0, T]");
  }
  version.surrogate =
      wordFrom<SurrogateKind>(f, f.stringOf(v, path, "surrogate"), path + "surrogate");
  const json& bracket = f.member(v, path, "bracket");
  version.bracket.info = f.numberOf(bracket, path + "bracket.", "info");
  version.bracket.cov = f.numberOf(bracket, path + "bracket.", "cov");
  version.command_id = f.unsignedOf<std::uint64_t>(v, path, "command_id");
  version.schedule = ratesFrom(f, v, path, scenario);
  return version;
}

std::vector<ScheduleVersion> versionsFrom(const Fields& f, const json& root,
                                          const Scenario& scenario) {
  std::vector<ScheduleVersion> versions;
  const json& values = f.array(root, "", "versions");
  if (values.empty()) f.fail("versions", "at least version 1");
  for (std::size_t i = 0; i < values.size(); ++i) {
    const std::string path = "versions[" + std::to_string(i) + "].";
    versions.push_back(versionFrom(f, values[i], path, scenario));
    const std::uint32_t number = versions.back().version;
    if (i == 0 ? number != 1 : number <= versions[i - 1].version) {
      f.fail(path + "version", i == 0 ? "1 first" : "numbers that increase");
    }
  }
  return versions;
}

EpisodeSet episodesFrom(const Fields& f, const json& root, std::uint32_t episodes_planned) {
  EpisodeSet episodes;
  const json& ranges = f.array(root, "", "episodes_reported");
  for (std::size_t i = 0; i < ranges.size(); ++i) {
    const std::string field = "episodes_reported[" + std::to_string(i) + "]";
    if (!ranges[i].is_array() || ranges[i].size() != 2) f.fail(field, "a range [first, last]");
    const auto first = f.unsignedAt<std::uint32_t>(ranges[i][0], field + "[0]");
    const auto last = f.unsignedAt<std::uint32_t>(ranges[i][1], field + "[1]");
    if (last < first || last >= episodes_planned) {
      f.fail(field, "first <= last < episodes_planned = " + std::to_string(episodes_planned));
    }
    episodes.insertRange(first, last);
  }
  return episodes;
}

std::map<std::uint64_t, AnsweredCommand> answeredFrom(const Fields& f, const json& root) {
  std::map<std::uint64_t, AnsweredCommand> answered;
  const json& values = f.array(root, "", "answered");
  for (std::size_t i = 0; i < values.size(); ++i) {
    const std::string path = "answered[" + std::to_string(i) + "].";
    AnsweredCommand a;
    a.accepted = f.boolOf(values[i], path, "accepted");
    a.schedule_version = f.unsignedOf<std::uint32_t>(values[i], path, "schedule_version");
    a.reason = f.stringOf(values[i], path, "reason");
    answered[f.unsignedOf<std::uint64_t>(values[i], path, "command_id")] = std::move(a);
  }
  return answered;
}

std::optional<AnnouncedEpisode> announcedFrom(const Fields& f, const json& root) {
  const json& value = f.member(root, "", "announced");
  if (value.is_null()) return std::nullopt;
  AnnouncedEpisode announced;
  announced.episode = f.unsignedOf<std::uint32_t>(value, "announced.", "episode");
  const json& start = f.member(value, "announced.", "start_wall_ns");
  if (!start.is_number_integer()) f.fail("announced.start_wall_ns", "an integer");
  announced.start_wall_ns = start.get<std::int64_t>();
  return announced;
}

}  // namespace

std::string journalToJson(const CoordinatorJournal& journal) {
  json answered = json::array();
  for (const auto& [id, a] : journal.answered) {
    answered.push_back({{"command_id", id},
                        {"accepted", a.accepted},
                        {"schedule_version", a.schedule_version},
                        {"reason", a.reason}});
  }
  json versions = json::array();
  for (const ScheduleVersion& v : journal.versions) versions.push_back(versionJson(v));
  json announced = nullptr;
  if (journal.announced) {
    announced = {{"episode", journal.announced->episode},
                 {"start_wall_ns", journal.announced->start_wall_ns}};
  }
  const json root = {{"format", kFormat},
                     {"run_id", journal.run_id},
                     {"scenario_digest", journal.scenario_digest},
                     {"seed", journal.seed},
                     {"episodes_planned", journal.episodes_planned},
                     {"time_scale", journal.time_scale},
                     {"settings", settingsJson(journal.settings)},
                     {"versions", std::move(versions)},
                     {"episodes_reported", episodeRanges(journal.episodes_reported)},
                     {"announced", std::move(announced)},
                     {"answered", std::move(answered)},
                     {"shutdown_requested", journal.shutdown_requested},
                     {"abort_detail", journal.abort_detail}};
  return root.dump(1) + "\n";
}

CoordinatorJournal journalFromJson(const std::string& text, const std::string& source,
                                   const Scenario& scenario) {
  const Fields f(source);
  json root;
  try {
    root = json::parse(text);
  } catch (const json::exception& e) {
    f.fail("", std::string("JSON (") + e.what() + ")");
  }
  if (!root.is_object()) f.fail("", "a JSON object");
  if (f.stringOf(root, "", "format") != kFormat) f.fail("format", std::string("'") + kFormat + "'");
  CoordinatorJournal journal;
  journal.run_id = f.stringOf(root, "", "run_id");
  journal.scenario_digest = f.stringOf(root, "", "scenario_digest");
  journal.seed = f.unsignedOf<std::uint64_t>(root, "", "seed");
  journal.episodes_planned = f.unsignedOf<std::uint32_t>(root, "", "episodes_planned");
  journal.time_scale = f.numberOf(root, "", "time_scale");
  if (!(journal.time_scale > 0.0)) f.fail("time_scale", "a number > 0");
  journal.settings = settingsFrom(f, f.member(root, "", "settings"), scenario);
  journal.versions = versionsFrom(f, root, scenario);
  journal.episodes_reported = episodesFrom(f, root, journal.episodes_planned);
  journal.announced = announcedFrom(f, root);
  journal.answered = answeredFrom(f, root);
  journal.shutdown_requested = f.boolOf(root, "", "shutdown_requested");
  journal.abort_detail = f.stringOf(root, "", "abort_detail");
  return journal;
}

void saveJournal(const std::string& path, const CoordinatorJournal& journal) {
  // Atomic, and on a full disk the system's reason with no temporary left behind.
  writeJsonFile(path, "coordinator journal",
                [&journal](std::ostream& out) { out << journalToJson(journal); });
}

CoordinatorJournal loadJournal(const std::string& path, const Scenario& scenario) {
  return journalFromJson(readTextFile(path, "coordinator state"), path, scenario);
}

}  // namespace sensornet::emulator
