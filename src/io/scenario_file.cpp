#include "sensornet/io/scenario_file.hpp"

#include <sys/stat.h>
#include <unistd.h>
#include <yaml-cpp/yaml.h>

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <cstdlib>
#include <fstream>
#include <limits>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "sensornet/core/input_error.hpp"
#include "sensornet/io/output_file.hpp"
#include "sensornet/io/yaml_text.hpp"
#include "scenario_network.hpp"
#include "yaml_reader.hpp"

namespace sensornet {

std::string readTextFile(const std::string& path, const std::string& what) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path, "", "a readable " + what + " file (cannot open it)");
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

namespace {

// An energy budget: a number > 0, or .inf for none.
double energyBudget(const YamlReader& in, const YAML::Node& node, const std::string& field) {
  if (node.IsScalar()) {
    const std::string& text = node.Scalar();
    if (text == ".inf" || text == ".Inf" || text == ".INF") {
      return std::numeric_limits<double>::infinity();
    }
  }
  const double value = in.number(node, field);
  if (!(value > 0.0)) {
    in.fail(node, field,
            "a number of expected measurements over the horizon > 0 (.inf for no budget), got " +
                node.Scalar());
  }
  return value;
}

// `energy:` one budget for every sensor, or a list of one per sensor.
Eigen::VectorXd energyBudgets(const YamlReader& in, const YAML::Node& node,
                              const std::string& field, Eigen::Index sensors) {
  if (node.IsSequence()) {
    if (static_cast<Eigen::Index>(node.size()) != sensors) {
      in.fail(node, field,
              std::to_string(sensors) + " budgets (one per sensor) or one for all, got " +
                  std::to_string(node.size()));
    }
    Eigen::VectorXd energy(sensors);
    for (Eigen::Index j = 0; j < sensors; ++j) {
      energy(j) = energyBudget(in, node[static_cast<std::size_t>(j)],
                               field + "[" + std::to_string(j) + "]");
    }
    return energy;
  }
  return Eigen::VectorXd::Constant(sensors, energyBudget(in, node, field));
}

void readRandomForm(const YamlReader& in, const YAML::Node& random, Scenario& s) {
  in.rejectUnknownKeys(random, "random",
                       {"states", "sensors", "rows_per_sensor", "seed", "budget", "noise_scale",
                        "energy"});
  RandomPlantSpec spec;
  spec.horizon_s = s.horizon_s;
  spec.intervals = s.intervals;
  spec.state_dim = static_cast<int>(in.integer(in.required(random, "states", "random.states"),
                                               "random.states"));
  spec.sensor_count = static_cast<int>(
      in.integer(in.required(random, "sensors", "random.sensors"), "random.sensors"));
  if (random["rows_per_sensor"]) {
    spec.rows_per_sensor =
        static_cast<int>(in.integer(random["rows_per_sensor"], "random.rows_per_sensor"));
  }
  const long seed = in.integer(in.required(random, "seed", "random.seed"), "random.seed");
  if (seed < 0) in.fail(random["seed"], "random.seed", "an integer >= 0");
  spec.seed = static_cast<std::uint64_t>(seed);
  if (random["budget"]) spec.budget = in.number(random["budget"], "random.budget");
  if (random["noise_scale"]) {
    spec.noise_scale = in.number(random["noise_scale"], "random.noise_scale");
  }
  if (random["energy"]) {
    if (!random["energy"].IsScalar()) {
      in.fail(random["energy"], "random.energy", "one budget for every sensor");
    }
    spec.energy = energyBudget(in, random["energy"], "random.energy");
  }
  if (spec.state_dim < 1) in.fail(random["states"], "random.states", "an integer >= 1");
  if (spec.sensor_count < 1) in.fail(random["sensors"], "random.sensors", "an integer >= 1");
  if (spec.rows_per_sensor < 1 || spec.rows_per_sensor > spec.state_dim) {
    in.fail(random["rows_per_sensor"], "random.rows_per_sensor",
            "an integer between 1 and random.states");
  }
  if (spec.budget <= 0.0) in.fail(random["budget"], "random.budget", "a number > 0");
  if (spec.noise_scale <= 0.0) {
    in.fail(random["noise_scale"], "random.noise_scale", "a number > 0");
  }
  const double horizon = s.horizon_s;
  const int intervals = s.intervals;
  s = generateRandomScenario(spec);
  s.horizon_s = horizon;
  s.intervals = intervals;
}

void readExplicitForm(const YamlReader& in, const YAML::Node& root, Scenario& s) {
  const YAML::Node plant = in.required(root, "plant", "plant");
  in.rejectUnknownKeys(plant, "plant", {"A", "Q", "P0", "m0"});
  s.plant.A = in.matrix(in.required(plant, "A", "plant.A"), "plant.A");
  const Eigen::Index n = s.plant.A.rows();
  s.plant.Q = in.matrix(in.required(plant, "Q", "plant.Q"), "plant.Q");
  s.plant.P0 = in.matrix(in.required(plant, "P0", "plant.P0"), "plant.P0");
  s.plant.m0 = plant["m0"] ? Eigen::VectorXd(in.vector(plant["m0"], "plant.m0"))
                           : Eigen::VectorXd::Zero(n);

  const YAML::Node sensors = in.required(root, "sensors", "sensors");
  if (!sensors.IsSequence() || sensors.size() == 0) {
    in.fail(sensors, "sensors", "a non-empty list of sensors, each with H and R");
  }
  for (std::size_t j = 0; j < sensors.size(); ++j) {
    const std::string field = "sensors[" + std::to_string(j) + "]";
    in.rejectUnknownKeys(sensors[j], field, {"H", "R", "name"});
    SensorModel sensor;
    sensor.H = in.matrix(in.required(sensors[j], "H", field + ".H"), field + ".H");
    sensor.R = in.matrix(in.required(sensors[j], "R", field + ".R"), field + ".R");
    s.sensors.push_back(std::move(sensor));
  }
  const auto m = static_cast<Eigen::Index>(s.sensors.size());

  s.cost.W = Eigen::MatrixXd::Zero(n, n);
  s.cost.WT = Eigen::MatrixXd::Identity(n, n);
  if (const YAML::Node cost = root["cost"]) {
    in.rejectUnknownKeys(cost, "cost", {"W", "WT"});
    if (cost["W"]) s.cost.W = in.matrix(cost["W"], "cost.W");
    if (cost["WT"]) s.cost.WT = in.matrix(cost["WT"], "cost.WT");
  }
  const YAML::Node constraints = in.required(root, "constraints", "constraints");
  in.rejectUnknownKeys(constraints, "constraints", {"C", "b", "energy"});
  s.constraints.C = constraints["C"] ? in.matrix(constraints["C"], "constraints.C")
                                     : Eigen::MatrixXd::Ones(1, m);
  s.constraints.b = in.vector(in.required(constraints, "b", "constraints.b"), "constraints.b");
  if (constraints["energy"]) {
    s.constraints.energy = energyBudgets(in, constraints["energy"], "constraints.energy", m);
  }
}

// The node a validation field path such as "sensors[1].R" or "constraints.b[0]" points at,
// or the deepest existing ancestor, so that semantic errors can name a line too.
YAML::Node locate(const YAML::Node& root, const std::string& field) {
  YAML::Node node = root;
  std::size_t at = 0;
  while (at < field.size()) {
    const std::size_t end = field.find_first_of(".[", at);
    const std::string key = field.substr(at, end == std::string::npos ? end : end - at);
    YAML::Node child;
    if (!key.empty()) {
      child = node[key];
    } else if (field[at] == '[') {
      const std::size_t close = field.find(']', at);
      if (close == std::string::npos) break;
      const auto index = std::stoul(field.substr(at + 1, close - at - 1));
      if (!node.IsSequence() || index >= node.size()) break;
      child = node[index];
      at = close + 1;
      if (at < field.size() && field[at] == '.') ++at;
      node.reset(child);
      continue;
    }
    if (!child.IsDefined()) break;
    node.reset(child);
    if (end == std::string::npos) break;
    at = field[end] == '.' ? end + 1 : end;
  }
  return node;
}

// `arrivals: poisson|timetable` (optional, Poisson when absent).
void readArrivalMode(const YamlReader& in, const YAML::Node& node, Scenario& s) {
  if (!node) return;
  if (!node.IsScalar()) in.fail(node, "arrivals", wordChoices<ArrivalMode>());
  try {
    s.arrivals = parseWord<ArrivalMode>(node.Scalar(), "", "arrivals");
  } catch (const InputError& e) {
    in.fail(node, "arrivals", e.expected());
  }
}

}  // namespace

Scenario parseScenarioYaml(const std::string& text, const std::string& source) {
  const YAML::Node root = parseYamlText(text, source);
  const YamlReader in(source);
  if (!root.IsMap()) in.fail(root, "(top level)", "a mapping with horizon, intervals, ...");
  in.rejectUnknownKeys(root, "", {"horizon", "intervals", "plant", "sensors", "cost",
                                  "constraints", "random", "name", "description", "network",
                                  "faults", "arrivals"});
  Scenario s;
  s.horizon_s = in.number(in.required(root, "horizon", "horizon"), "horizon");
  if (s.horizon_s <= 0.0) in.fail(root["horizon"], "horizon", "a number > 0");
  const long intervals = in.integer(in.required(root, "intervals", "intervals"), "intervals");
  if (intervals < 1 || intervals > 1000000) {
    in.fail(root["intervals"], "intervals", "an integer between 1 and 1000000");
  }
  s.intervals = static_cast<int>(intervals);

  if (const YAML::Node random = root["random"]) {
    for (const char* key : {"plant", "sensors", "cost", "constraints"}) {
      if (root[key]) {
        in.fail(root[key], key, "either the random form or the explicit form, not both");
      }
    }
    readRandomForm(in, random, s);
  } else {
    readExplicitForm(in, root, s);
  }
  readNetworkSection(in, root["network"], s);
  readFaults(in, root["faults"], s);
  readArrivalMode(in, root["arrivals"], s);
  try {
    validateScenario(s, source);
  } catch (const InputError& e) {
    const YAML::Node node = root["random"] ? root["random"] : locate(root, e.field());
    throw e.relocated(source + ":" + std::to_string(node.Mark().line + 1));
  }
  return s;
}

Scenario loadScenarioFile(const std::string& path) {
  return parseScenarioYaml(readTextFile(path, "scenario"), path);
}

namespace {

// A number in JSON text that does not fit a double ("1e309").
struct OverflowingNumber {
  std::size_t offset = 0;
  int line = 1;  // 1-based
  std::string text;
};

// Every number in JSON `text` that overflows a double. Meant for text the JSON parser refused
// for such a number (its exception carries no position), so the text is valid JSON up to
// there: strings are skipped, and a number is the longest run of number characters.
std::vector<OverflowingNumber> overflowingNumbers(const std::string& text) {
  std::vector<OverflowingNumber> found;
  int line = 1;
  for (std::size_t at = 0; at < text.size(); ++at) {
    const char c = text[at];
    if (c == '\n') {
      ++line;
    } else if (c == '"') {
      for (++at; at < text.size() && text[at] != '"'; ++at) {
        if (text[at] == '\\') ++at;
      }
    } else if (c == '-' || (c >= '0' && c <= '9')) {
      const std::size_t end = text.find_first_not_of("+-.0123456789eE", at);
      std::string number = text.substr(at, end == std::string::npos ? end : end - at);
      const std::size_t length = number.size();
      if (!std::isfinite(std::strtod(number.c_str(), nullptr))) {
        found.push_back({at, line, std::move(number)});
      }
      at += length - 1;
    }
  }
  return found;
}

// The field path ("rates[2][1]") of the first string value equal to `marker` in `doc`.
std::optional<std::string> fieldHolding(const nlohmann::json& doc, const std::string& marker,
                                        const std::string& path = "") {
  if (doc.is_string() && doc.get<std::string>() == marker) return path;
  if (doc.is_object()) {
    for (const auto& [key, value] : doc.items()) {
      if (auto field = fieldHolding(value, marker, path.empty() ? key : path + "." + key)) {
        return field;
      }
    }
  } else if (doc.is_array()) {
    for (std::size_t i = 0; i < doc.size(); ++i) {
      if (auto field = fieldHolding(doc[i], marker, path + "[" + std::to_string(i) + "]")) {
        return field;
      }
    }
  }
  return std::nullopt;
}

// The InputError for JSON text the parser refused for an overflowing number: the line and the
// field of the first one. The field is found by parsing again with that number replaced by a
// marker string (and any later one by 0).
InputError overflowError(const std::string& text, const std::string& source,
                         const std::string& library_message) {
  const std::vector<OverflowingNumber> numbers = overflowingNumbers(text);
  if (numbers.empty()) {
    return InputError(source, "", "a finite number (" + library_message + ")");
  }
  const std::string marker = "@sensornet: the overflowing number@";
  std::string patched = text;
  for (std::size_t i = numbers.size(); i-- > 0;) {  // from the back: offsets stay valid
    patched.replace(numbers[i].offset, numbers[i].text.size(), i == 0 ? "\"" + marker + "\"" : "0");
  }
  const nlohmann::json doc = nlohmann::json::parse(patched, nullptr, /*allow_exceptions=*/false);
  const std::string field = doc.is_discarded() ? "" : fieldHolding(doc, marker).value_or("");
  return InputError(source + ":" + std::to_string(numbers.front().line), field,
                    "a finite number, got " + shortened(numbers.front().text) +
                        " (the number overflows a double)");
}

nlohmann::json parseJsonDocument(const std::string& text, const std::string& source) {
  try {
    return nlohmann::json::parse(text);
  } catch (const nlohmann::json::parse_error& e) {
    throw InputError(source, "", std::string("valid JSON (") + e.what() + ")");
  } catch (const nlohmann::json::out_of_range& e) {
    throw overflowError(text, source, e.what());  // 406: "number overflow parsing '1e309'"
  } catch (const nlohmann::json::exception& e) {
    throw InputError(source, "", std::string("valid JSON (") + e.what() + ")");
  }
}

}  // namespace

RateSchedule parseScheduleJson(const std::string& text, const std::string& source) {
  const nlohmann::json doc = parseJsonDocument(text, source);
  if (!doc.is_object()) throw InputError(source, "(top level)", "a JSON object");
  auto requireNumber = [&](const char* key) {
    if (!doc.contains(key)) throw InputError(source, key, "a value (the field is missing)");
    if (!doc[key].is_number()) throw InputError(source, key, "a number");
    return doc[key].get<double>();
  };
  const double horizon = requireNumber("horizon");
  if (!std::isfinite(horizon) || horizon <= 0.0) {
    throw InputError(source, "horizon", "a finite number > 0");
  }
  const double intervals_value = requireNumber("intervals");
  if (intervals_value < 1 || intervals_value != std::floor(intervals_value)) {
    throw InputError(source, "intervals", "an integer >= 1");
  }
  const auto intervals = static_cast<Eigen::Index>(intervals_value);
  if (!doc.contains("rates")) throw InputError(source, "rates", "a value (the field is missing)");
  const auto& rows = doc["rates"];
  if (!rows.is_array() || static_cast<Eigen::Index>(rows.size()) != intervals) {
    throw InputError(source, "rates",
                     "a list of " + std::to_string(intervals) + " rows (one per interval)");
  }
  Eigen::MatrixXd rates;
  for (Eigen::Index k = 0; k < intervals; ++k) {
    const auto& row = rows[static_cast<std::size_t>(k)];
    const std::string field = "rates[" + std::to_string(k) + "]";
    if (!row.is_array() || row.empty()) throw InputError(source, field, "a non-empty list of rates");
    if (k == 0) rates.resize(intervals, static_cast<Eigen::Index>(row.size()));
    if (static_cast<Eigen::Index>(row.size()) != rates.cols()) {
      throw InputError(source, field, std::to_string(rates.cols()) + " rates like rates[0]");
    }
    for (Eigen::Index j = 0; j < rates.cols(); ++j) {
      const auto& value = row[static_cast<std::size_t>(j)];
      const std::string entry = field + "[" + std::to_string(j) + "]";
      if (!value.is_number()) throw InputError(source, entry, "a number");
      const double rate = value.get<double>();
      if (!std::isfinite(rate) || rate < 0.0) {
        throw InputError(source, entry, "a finite rate >= 0 (Hz)");
      }
      rates(k, j) = rate;
    }
  }
  return RateSchedule(horizon, std::move(rates));
}

RateSchedule loadScheduleFile(const std::string& path) {
  return parseScheduleJson(readTextFile(path, "schedule"), path);
}

RateSchedule loadScheduleFile(const std::string& path, const Scenario& scenario) {
  RateSchedule schedule = loadScheduleFile(path);
  const Feasibility feasibility = checkFeasibility(schedule, scenario);
  if (!feasibility.feasible) {
    throw InputError(path, "rates", "a schedule feasible for the scenario: " + feasibility.reason);
  }
  return schedule;
}

nlohmann::json scheduleToJson(const RateSchedule& schedule) {
  nlohmann::json rows = nlohmann::json::array();
  for (int k = 0; k < schedule.intervals(); ++k) {
    nlohmann::json row = nlohmann::json::array();
    for (int j = 0; j < schedule.sensorCount(); ++j) row.push_back(schedule.rate(k, j));
    rows.push_back(std::move(row));
  }
  return {{"horizon", schedule.horizon()}, {"intervals", schedule.intervals()},
          {"rates", std::move(rows)}};
}

void writeJsonFile(const std::string& path, const nlohmann::json& doc, const std::string& what) {
  writeJsonFile(path, what, [&doc](std::ostream& out) { out << doc.dump(2) << '\n'; });
}

void writeJsonFile(const std::string& path, const std::string& what,
                   const std::function<void(std::ostream&)>& write) {
  // Only a regular file is ever replaced: renaming over a device, a FIFO or a directory would
  // turn it into a JSON file (or fail after all the work is done).
  struct stat existing {};
  if (::lstat(path.c_str(), &existing) == 0 && !S_ISREG(existing.st_mode)) {
    throw InputError(
        path, "",
        "a regular file for the " + what + " (it exists and is a device, FIFO, directory or link)");
  }
  // Beside the target, then renamed over it: a reader never sees half a file. When that fails,
  // a path where no file can be made is bad input; a disk that refuses the bytes (full, a size
  // limit) is not, and the error says the disk's own cause.
  try {
    replaceFileAtomically(path, write, what);
  } catch (const std::runtime_error&) {
    if (const auto problem = outputFileProblem(path)) {
      const bool full = problem->find(std::strerror(ENOSPC)) != std::string::npos ||
                        problem->find(std::strerror(EDQUOT)) != std::string::npos;
      if (!full) {
        throw InputError(path, "", "a writable path for the " + what + "; it " + *problem);
      }
    }
    throw;
  }
}

void writeScheduleFile(const std::string& path, const RateSchedule& schedule,
                       const nlohmann::json& extra) {
  nlohmann::json doc = scheduleToJson(schedule);
  for (const auto& [key, value] : extra.items()) doc[key] = value;
  writeJsonFile(path, doc, "schedule file");
}

}  // namespace sensornet
