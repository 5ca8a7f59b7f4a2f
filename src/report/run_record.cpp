#include "sensornet/report/run_record.hpp"

#include <limits>
#include <set>
#include <type_traits>
#include <utility>

namespace sensornet::report {
namespace {

using nlohmann::json;

// What a value of type T must be, for the error message.
template <class T>
std::string expectedText() {
  if constexpr (std::is_same_v<T, bool>) {
    return "true or false";
  } else if constexpr (std::is_same_v<T, std::string>) {
    return "a string";
  } else if constexpr (std::is_same_v<T, double>) {
    return "a number";
  } else if constexpr (std::is_same_v<T, int>) {
    return "a whole number";
  } else if constexpr (std::is_unsigned_v<T>) {
    return "a whole number >= 0";
  } else {
    return "a value";
  }
}

template <class T>
void decodeValue(const json& value, const std::string& path, T& out);

template <class T>
void decodeScalar(const json& value, const std::string& path, T& out) {
  if constexpr (std::is_same_v<T, bool>) {
    if (!value.is_boolean()) throw RecordError(path, expectedText<T>());
    out = value.get<bool>();
  } else if constexpr (std::is_same_v<T, std::string>) {
    if (!value.is_string()) throw RecordError(path, expectedText<T>());
    out = value.get<std::string>();
  } else if constexpr (std::is_same_v<T, double>) {
    if (!value.is_number()) throw RecordError(path, expectedText<T>());
    out = value.get<double>();
  } else if constexpr (std::is_same_v<T, int>) {
    if (!value.is_number_integer() || value.get<std::int64_t>() < std::numeric_limits<int>::min() ||
        value.get<std::int64_t>() > std::numeric_limits<int>::max()) {
      throw RecordError(path, expectedText<T>());
    }
    out = value.get<int>();
  } else {
    static_assert(std::is_unsigned_v<T>);
    // Parsed text gives a count as unsigned; a document built in code (json{{"episodes", 4}})
    // gives it as a signed integer: both are the same count when it is not negative.
    const bool count = value.is_number_unsigned() ||
                       (value.is_number_integer() && value.get<std::int64_t>() >= 0);
    if (!count || value.get<std::uint64_t>() > std::numeric_limits<T>::max()) {
      throw RecordError(path, expectedText<T>());
    }
    out = value.get<T>();
  }
}

template <class T>
void decodeValue(const json& value, const std::string& path, std::vector<T>& out) {
  if (!value.is_array()) throw RecordError(path, "a list");
  out.clear();
  out.reserve(value.size());
  for (std::size_t i = 0; i < value.size(); ++i) {
    T item{};
    decodeValue(value[i], path + "[" + std::to_string(i) + "]", item);
    out.push_back(std::move(item));
  }
}

template <class E>
void decodeWord(const json& value, const std::string& path, E& out) {
  const std::optional<E> word =
      value.is_string() ? lookUpWord<E>(value.get<std::string>()) : std::nullopt;
  if (!word) throw RecordError(path, wordChoices<E>());
  out = *word;
}

void decodeValue(const json& value, const std::string& path, RunStatus& out) {
  decodeWord(value, path, out);
}
void decodeValue(const json& value, const std::string& path, FaultKind& out) {
  decodeWord(value, path, out);
}

void decodeValue(const json& value, const std::string& path, RejectionTally& out) {
  if (!value.is_object()) throw RecordError(path, "an object of counts by reason");
  out.clear();
  for (const auto& [word, count] : value.items()) {
    const std::string at = path + "." + word;
    const std::optional<RejectionReason> reason = lookUpWord<RejectionReason>(word);
    if (!reason) throw RecordError(at, "a rejection reason: " + wordChoices<RejectionReason>());
    decodeScalar(count, at, out[*reason]);
  }
}

void decodeValue(const json& value, const std::string& path, BracketRecord& out);
void decodeValue(const json& value, const std::string& path, FaultCause& out);

template <class T>
void decodeValue(const json& value, const std::string& path, T& out) {
  decodeScalar(value, path, out);
}

// The keys of one object, read one by one; what is not read is kept in `other`.
class Fields {
 public:
  Fields(const json& object, std::string path) : object_(object), path_(std::move(path)) {
    if (!object.is_object()) throw RecordError(path_.empty() ? "(report)" : path_, "an object");
  }

  // A key that must be there (not null).
  template <class T>
  void required(const char* key, T& out) {
    const json* value = find(key);
    if (value == nullptr || value->is_null()) throw RecordError(pathOf(key), expectedText<T>());
    decodeValue(*value, pathOf(key), out);
  }
  // A key that may be missing (left as is) or null.
  template <class T>
  void optional(const char* key, T& out) {
    const json* value = find(key);
    if (value == nullptr || value->is_null()) return;
    decodeValue(*value, pathOf(key), out);
  }
  template <class T>
  void optional(const char* key, std::optional<T>& out) {
    const json* value = find(key);
    if (value == nullptr || value->is_null()) return;
    T decoded{};
    decodeValue(*value, pathOf(key), decoded);
    out = std::move(decoded);
  }
  // A key kept as its JSON value.
  void raw(const char* key, json& out) {
    if (const json* value = find(key)) out = *value;
  }
  // A key decoded by the caller: not part of rest().
  void taken(const char* key) { read_.insert(key); }
  [[nodiscard]] json rest() const {
    json other = json::object();
    for (const auto& [key, value] : object_.items()) {
      if (read_.count(key) == 0) other[key] = value;
    }
    return other;
  }
  [[nodiscard]] std::string pathOf(const char* key) const {
    return path_.empty() ? std::string(key) : path_ + "." + key;
  }

 private:
  const json* find(const char* key) {
    read_.insert(key);
    const auto it = object_.find(key);
    return it == object_.end() ? nullptr : &*it;
  }
  const json& object_;
  std::string path_;
  std::set<std::string> read_;
};

void decodeValue(const json& value, const std::string& path, BracketRecord& out) {
  Fields f(value, path);
  f.optional("info", out.info);
  f.optional("cov", out.cov);
}

void decodeValue(const json& value, const std::string& path, FaultCause& out) {
  Fields f(value, path);
  f.required("kind", out.kind);
  f.required("process", out.process);
}

FaultRecord decodeFaultAt(const json& entry, const std::string& path) {
  FaultRecord r;
  Fields f(entry, path);
  f.required("kind", r.kind);
  f.optional("process", r.process);
  f.optional("sensor", r.sensor);
  f.optional("sensors", r.sensors);
  f.optional("episode", r.episode);
  f.optional("episodes", r.episodes);
  f.optional("emulated_time_s", r.emulated_time_s);
  f.optional("detail", r.detail);
  f.optional("survived", r.survived);
  f.optional("schedule_version", r.schedule_version);
  f.optional("caused_by", r.caused_by);
  if (const auto it = entry.find("ended_by"); it != entry.end() && !it->is_null()) {
    FaultKind kind{};
    decodeWord(*it, f.pathOf("ended_by"), kind);
    r.ended_by = kind;
  }
  f.taken("ended_by");
  r.other = f.rest();
  return r;
}

EpisodeRecord decodeEpisodeAt(const json& entry, const std::string& path) {
  EpisodeRecord r;
  Fields f(entry, path);
  f.required("episode", r.episode);
  f.optional("realized_cost", r.realized_cost);
  f.optional("realtime_cost", r.realtime_cost);
  f.optional("received_realtime_cost", r.received_realtime_cost);
  f.optional("bracket", r.bracket);
  f.optional("delivered_bracket", r.delivered_bracket);
  f.optional("schedule_versions", r.schedule_versions);
  f.optional("switch_time_s", r.switch_time_s);
  f.optional("nees", r.nees);
  f.required("complete", r.complete);
  f.optional("incomplete_reason", r.incomplete_reason);
  f.optional("failed_sensors", r.failed_sensors);
  f.required("sent", r.sent);
  f.required("received", r.received);
  f.required("lost", r.lost);
  f.optional("dropped_by_network", r.dropped_by_network);
  f.optional("late", r.late);
  f.optional("refused", r.refused);
  f.optional("expected", r.expected);
  f.optional("wrong_version", r.wrong_version);
  f.optional("rejected", r.rejected);
  f.optional("drain_s", r.drain_s);
  f.optional("backlog", r.backlog);
  f.optional("latency_median_s", r.latency_median_s);
  f.optional("latency_p99_s", r.latency_p99_s);
  f.optional("network_delay_mean_s", r.network_delay_mean_s);
  f.optional("network_delay_max_s", r.network_delay_max_s);
  r.other = f.rest();
  return r;
}

SummaryRecord decodeSummaryAt(const json& summary, const std::string& path) {
  SummaryRecord s;
  Fields f(summary, path);
  f.optional("episodes", s.episodes);
  f.optional("episodes_complete", s.episodes_complete);
  f.optional("episodes_incomplete", s.episodes_incomplete);
  f.optional("mean", s.mean);
  f.optional("std", s.std_dev);
  f.optional("ci95", s.ci95);
  f.optional("ci95_low", s.ci95_low);
  f.optional("ci95_high", s.ci95_high);
  f.optional("realtime_mean", s.realtime_mean);
  f.optional("received_realtime_mean", s.received_realtime_mean);
  f.optional("nees_mean", s.nees_mean);
  f.optional("nees_band_low", s.nees_band_low);
  f.optional("nees_band_high", s.nees_band_high);
  f.optional("nees_confidence", s.nees_confidence);
  f.optional("nees_consistent", s.nees_consistent);
  f.optional("bracket", s.bracket);
  f.optional("meets_bracket", s.meets_bracket);
  f.optional("delivered_bracket", s.delivered_bracket);
  f.optional("meets_delivered_bracket", s.meets_delivered_bracket);
  f.optional("sent", s.sent);
  f.optional("received", s.received);
  f.optional("lost", s.lost);
  f.optional("dropped_by_network", s.dropped_by_network);
  f.optional("late", s.late);
  f.optional("refused", s.refused);
  f.optional("expected", s.expected);
  f.optional("rejected", s.rejected);
  f.optional("rejected_by_reason", s.rejected_by_reason);
  s.other = f.rest();
  return s;
}

SensorRecord decodeSensor(const json& entry, const std::string& path) {
  SensorRecord r;
  Fields f(entry, path);
  f.required("sensor_id", r.sensor_id);
  f.optional("sent", r.sent);
  f.optional("received", r.received);
  f.optional("lost", r.lost);
  f.optional("dropped_by_network", r.dropped_by_network);
  f.optional("late", r.late);
  f.optional("wrong_version", r.wrong_version);
  f.optional("refused", r.refused);
  f.optional("expected", r.expected);
  return r;
}

ClockProcessRecord decodeClockProcess(const json& entry, const std::string& path) {
  ClockProcessRecord p;
  Fields f(entry, path);
  f.required("process", p.process);
  f.required("sensors", p.sensors);
  f.required("offset_s", p.offset_s);
  f.required("uncertainty_s", p.uncertainty_s);
  f.optional("farthest_offset_s", p.farthest_offset_s);
  f.optional("farthest_uncertainty_s", p.farthest_uncertainty_s);
  f.optional("exchanges", p.exchanges);
  return p;
}

ScheduleVersionRecord decodeVersion(const json& entry, const std::string& path) {
  ScheduleVersionRecord v;
  Fields f(entry, path);
  f.required("version", v.version);
  f.optional("effective_episode", v.effective_episode);
  f.optional("effective_time_s", v.effective_time_s);
  f.optional("surrogate", v.surrogate);
  f.optional("bracket", v.bracket);
  f.optional("command_id", v.command_id);
  f.optional("horizon_s", v.horizon_s);
  f.optional("rates", v.rates);
  v.other = f.rest();
  return v;
}

template <class T, class Decode>
std::vector<T> decodeList(const json& list, const std::string& path, Decode decode) {
  if (!list.is_array()) throw RecordError(path, "a list");
  std::vector<T> out;
  out.reserve(list.size());
  for (std::size_t i = 0; i < list.size(); ++i) {
    out.push_back(decode(list[i], path + "[" + std::to_string(i) + "]"));
  }
  return out;
}

json orNull(const std::optional<double>& value) { return value ? json(*value) : json(nullptr); }
json orNull(const std::optional<bool>& value) { return value ? json(*value) : json(nullptr); }

template <class T>
void putIf(json& doc, const char* key, const std::optional<T>& value) {
  if (value) doc[key] = *value;
}

// `other`'s keys (those a later version wrote) back into `doc`.
void merge(json& doc, const json& other) {
  for (const auto& [key, value] : other.items()) doc[key] = value;
}

json encodeSensor(const SensorRecord& r) {
  return {{"sensor_id", r.sensor_id},
          {"sent", r.sent},
          {"received", r.received},
          {"lost", r.lost},
          {"dropped_by_network", r.dropped_by_network},
          {"late", r.late},
          {"refused", r.refused},
          {"expected", r.expected},
          {"wrong_version", r.wrong_version}};
}

}  // namespace

RecordError::RecordError(std::string field, std::string expected)
    : std::runtime_error("report field " + field + ": expected " + expected),
      field_(std::move(field)),
      expected_(std::move(expected)) {}

std::vector<int> FaultRecord::namedSensors() const {
  if (sensors && !sensors->empty()) return *sensors;
  if (sensor) return {*sensor};
  return {};
}

std::size_t RunRecord::causeCount() const {
  std::size_t causes = 0;
  for (const FaultRecord& f : faults) causes += f.isConsequence() ? 0 : 1;
  return causes;
}

std::uint64_t RunRecord::finishedEpisodes() const {
  if (episodes) return *episodes;
  return per_episode ? per_episode->size() : 0;
}

FaultRecord decodeFault(const json& entry) { return decodeFaultAt(entry, "fault"); }
EpisodeRecord decodeEpisode(const json& entry) { return decodeEpisodeAt(entry, "episode entry"); }
SummaryRecord decodeSummary(const json& summary) { return decodeSummaryAt(summary, "summary"); }

RunRecord decodeRunRecord(const json& doc) {
  RunRecord run;
  Fields f(doc, "");
  f.optional("schema_version", run.schema_version);
  f.required("run_id", run.run_id);
  f.required("status", run.status);
  if (const auto it = doc.find("faults"); it != doc.end() && !it->is_null()) {
    run.faults = decodeList<FaultRecord>(*it, "faults", decodeFaultAt);
  }
  f.taken("faults");
  if (const auto it = doc.find("scenario"); it != doc.end() && !it->is_null()) {
    ScenarioRecord s;
    Fields sf(*it, "scenario");
    sf.optional("digest", s.digest);
    sf.optional("sensors", s.sensors);
    sf.optional("states", s.states);
    run.scenario = s;
  }
  f.taken("scenario");
  f.optional("episodes", run.episodes);
  f.optional("episodes_planned", run.episodes_planned);
  if (const auto it = doc.find("schedule_versions"); it != doc.end() && !it->is_null()) {
    run.schedule_versions =
        decodeList<ScheduleVersionRecord>(*it, "schedule_versions", decodeVersion);
  }
  f.taken("schedule_versions");
  const auto summary = doc.find("summary");
  if (summary == doc.end()) throw RecordError("summary", "an object");
  run.summary = decodeSummaryAt(*summary, "summary");
  f.taken("summary");
  if (const auto it = doc.find("sensors"); it != doc.end() && !it->is_null()) {
    run.sensors = decodeList<SensorRecord>(*it, "sensors", decodeSensor);
  }
  f.taken("sensors");
  if (const auto it = doc.find("latency_s"); it != doc.end() && !it->is_null()) {
    LatencyRecord l;
    Fields lf(*it, "latency_s");
    lf.optional("median", l.median);
    lf.optional("p99", l.p99);
    lf.optional("quantile_relative_error", l.quantile_relative_error);
    lf.optional("unknown_because", l.unknown_because);
    lf.raw("histogram", l.histogram);
    run.latency_s = std::move(l);
  }
  f.taken("latency_s");
  if (const auto it = doc.find("network_delay_s"); it != doc.end() && !it->is_null()) {
    NetworkDelayRecord d;
    Fields df(*it, "network_delay_s");
    df.optional("mean", d.mean);
    df.optional("max", d.max);
    run.network_delay_s = d;
  }
  f.taken("network_delay_s");
  if (const auto it = doc.find("clocks"); it != doc.end() && !it->is_null()) {
    ClocksRecord c;
    Fields cf(*it, "clocks");
    cf.required("bound_s", c.bound_s);
    if (const auto list = it->find("processes"); list != it->end() && !list->is_null()) {
      c.processes = decodeList<ClockProcessRecord>(*list, "clocks.processes", decodeClockProcess);
    }
    cf.taken("processes");
    cf.optional("echoes_refused", c.echoes_refused);
    run.clocks = std::move(c);
  }
  f.taken("clocks");
  if (const auto it = doc.find("arrivals"); it != doc.end() && !it->is_null()) {
    ArrivalsRecord a;
    Fields af(*it, "arrivals");
    af.required("mode", a.mode);
    af.optional("bracket_note", a.bracket_note);
    run.arrivals = a;
  }
  f.taken("arrivals");
  if (const auto it = doc.find("external"); it != doc.end() && !it->is_null()) {
    ExternalRoles e;
    Fields ef(*it, "external");
    ef.optional("sensors", e.sensors);
    ef.optional("fusion_center", e.fusion_center);
    run.external = e;
  }
  f.taken("external");
  f.optional("seed", run.seed);
  f.optional("written_at", run.written_at);
  f.optional("rebuilt_from", run.rebuilt_from);
  f.optional("built_from", run.built_from);
  if (const auto it = doc.find("per_episode"); it != doc.end() && !it->is_null()) {
    run.per_episode = decodeList<EpisodeRecord>(*it, "per_episode", decodeEpisodeAt);
  }
  f.taken("per_episode");
  run.other = f.rest();
  return run;
}

json encode(const BracketRecord& b) { return {{"info", orNull(b.info)}, {"cov", orNull(b.cov)}}; }

json encode(const RejectionTally& tally) {
  json counts = json::object();
  for (const auto& [reason, count] : tally) counts[std::string(wordOf(reason))] = count;
  return counts;
}

json encode(const FaultRecord& r) {
  json doc = {{"kind", std::string(wordOf(r.kind))},
              {"process", r.process},
              {"sensor", r.sensor ? json(*r.sensor) : json(nullptr)},
              {"episode", r.episode ? json(*r.episode) : json(nullptr)},
              {"emulated_time_s", orNull(r.emulated_time_s)},
              {"detail", r.detail}};
  putIf(doc, "sensors", r.sensors);
  putIf(doc, "episodes", r.episodes);
  putIf(doc, "survived", r.survived);
  putIf(doc, "schedule_version", r.schedule_version);
  if (r.caused_by) {
    doc["caused_by"] = {{"kind", std::string(wordOf(r.caused_by->kind))},
                        {"process", r.caused_by->process}};
  }
  if (r.ended_by) doc["ended_by"] = std::string(wordOf(*r.ended_by));
  merge(doc, r.other);
  return doc;
}

json encode(const std::vector<FaultRecord>& faults) {
  json list = json::array();
  for (const FaultRecord& f : faults) list.push_back(encode(f));
  return list;
}

json encode(const EpisodeRecord& r) {
  json doc = {{"episode", r.episode},
              {"realized_cost", orNull(r.realized_cost)},
              {"realtime_cost", orNull(r.realtime_cost)},
              {"received_realtime_cost", orNull(r.received_realtime_cost)},
              {"bracket", encode(r.bracket)},
              {"delivered_bracket", encode(r.delivered_bracket)},
              {"schedule_versions", r.schedule_versions},
              {"switch_time_s", r.switch_time_s},
              {"nees", orNull(r.nees)},
              {"complete", r.complete},
              {"incomplete_reason", r.incomplete_reason ? json(*r.incomplete_reason) : json()},
              {"failed_sensors", r.failed_sensors},
              {"sent", r.sent},
              {"received", r.received},
              {"lost", r.lost},
              {"dropped_by_network", r.dropped_by_network},
              {"late", r.late},
              {"expected", r.expected},
              {"wrong_version", r.wrong_version},
              {"rejected", encode(r.rejected)},
              {"drain_s", r.drain_s},
              {"backlog", r.backlog},
              {"latency_median_s", orNull(r.latency_median_s)},
              {"latency_p99_s", orNull(r.latency_p99_s)},
              {"network_delay_mean_s", r.network_delay_mean_s},
              {"network_delay_max_s", r.network_delay_max_s}};
  if (!r.refused.empty()) doc["refused"] = r.refused;  // absent from records older than it
  merge(doc, r.other);
  return doc;
}

json encode(const SummaryRecord& s) {
  const auto bracketOrNull = [](const std::optional<BracketRecord>& b) {
    return b ? encode(*b) : json(nullptr);
  };
  json doc = {{"episodes", s.episodes},
              {"episodes_complete", s.episodes_complete},
              {"episodes_incomplete", s.episodes_incomplete},
              {"mean", orNull(s.mean)},
              {"std", orNull(s.std_dev)},
              {"ci95", orNull(s.ci95)},
              {"ci95_low", orNull(s.ci95_low)},
              {"ci95_high", orNull(s.ci95_high)},
              {"realtime_mean", orNull(s.realtime_mean)},
              {"received_realtime_mean", orNull(s.received_realtime_mean)},
              {"bracket", bracketOrNull(s.bracket)},
              {"meets_bracket", orNull(s.meets_bracket)},
              {"delivered_bracket", bracketOrNull(s.delivered_bracket)},
              {"meets_delivered_bracket", orNull(s.meets_delivered_bracket)},
              {"nees_mean", orNull(s.nees_mean)},
              {"nees_band_low", orNull(s.nees_band_low)},
              {"nees_band_high", orNull(s.nees_band_high)},
              {"nees_consistent", orNull(s.nees_consistent)},
              {"sent", s.sent},
              {"received", s.received},
              {"expected", s.expected},
              {"lost", s.lost},
              {"dropped_by_network", s.dropped_by_network},
              {"late", s.late},
              {"refused", s.refused},
              {"rejected", s.rejected},
              {"rejected_by_reason", encode(s.rejected_by_reason)}};
  if (s.nees_confidence) doc["nees_confidence"] = *s.nees_confidence;
  merge(doc, s.other);
  return doc;
}

json encode(const ScheduleVersionRecord& v) {
  json doc = {{"version", v.version},
              {"effective_episode", v.effective_episode},
              {"effective_time_s", v.effective_time_s},
              {"surrogate", v.surrogate},
              {"bracket", encode(v.bracket)},
              {"command_id", v.command_id},
              {"horizon_s", v.horizon_s},
              {"rates", v.rates}};
  merge(doc, v.other);
  return doc;
}

json encode(const RunRecord& run) {
  json doc = json::object();
  putIf(doc, "schema_version", run.schema_version);
  doc["run_id"] = run.run_id;
  doc["status"] = std::string(wordOf(run.status));
  doc["faults"] = encode(run.faults);
  if (run.scenario) {
    doc["scenario"] = {{"digest", run.scenario->digest},
                       {"sensors", run.scenario->sensors},
                       {"states", run.scenario->states}};
  }
  putIf(doc, "episodes", run.episodes);
  putIf(doc, "episodes_planned", run.episodes_planned);
  json versions = json::array();
  for (const ScheduleVersionRecord& v : run.schedule_versions) versions.push_back(encode(v));
  doc["schedule_versions"] = std::move(versions);
  doc["summary"] = encode(run.summary);
  json sensors = json::array();
  for (const SensorRecord& s : run.sensors) sensors.push_back(encodeSensor(s));
  doc["sensors"] = std::move(sensors);
  if (run.latency_s) {
    doc["latency_s"] = {{"median", orNull(run.latency_s->median)},
                        {"p99", orNull(run.latency_s->p99)},
                        {"quantile_relative_error", orNull(run.latency_s->quantile_relative_error)},
                        {"histogram", run.latency_s->histogram}};
    if (run.latency_s->unknown_because) doc["latency_s"]["unknown_because"] = *run.latency_s->unknown_because;
  }
  if (run.network_delay_s) {
    doc["network_delay_s"] = {{"mean", orNull(run.network_delay_s->mean)},
                              {"max", orNull(run.network_delay_s->max)}};
  }
  if (run.clocks) {
    json processes = json::array();
    for (const ClockProcessRecord& p : run.clocks->processes) {
      json entry = {{"process", p.process},
                    {"sensors", p.sensors},
                    {"offset_s", p.offset_s},
                    {"uncertainty_s", p.uncertainty_s},
                    {"exchanges", p.exchanges}};
      if (p.farthest_offset_s) entry["farthest_offset_s"] = *p.farthest_offset_s;
      if (p.farthest_uncertainty_s) entry["farthest_uncertainty_s"] = *p.farthest_uncertainty_s;
      processes.push_back(std::move(entry));
    }
    doc["clocks"] = {{"bound_s", run.clocks->bound_s},
                     {"processes", std::move(processes)},
                     {"echoes_refused", run.clocks->echoes_refused}};
  }
  if (run.arrivals) {
    doc["arrivals"] = {{"mode", run.arrivals->mode}, {"bracket_note", run.arrivals->bracket_note}};
  }
  if (run.external) {
    json external = json::object();
    if (!run.external->sensors.empty()) external["sensors"] = run.external->sensors;
    if (run.external->fusion_center) external["fusion_center"] = true;
    doc["external"] = std::move(external);
  }
  putIf(doc, "seed", run.seed);
  putIf(doc, "written_at", run.written_at);
  putIf(doc, "rebuilt_from", run.rebuilt_from);
  putIf(doc, "built_from", run.built_from);
  if (run.per_episode) {
    json entries = json::array();
    for (const EpisodeRecord& e : *run.per_episode) entries.push_back(encode(e));
    doc["per_episode"] = std::move(entries);
  }
  merge(doc, run.other);
  return doc;
}

}  // namespace sensornet::report
