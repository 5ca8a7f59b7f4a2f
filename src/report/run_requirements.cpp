#include "sensornet/report/run_requirements.hpp"

#include <charconv>
#include <cmath>
#include <cstdio>
#include <functional>
#include <system_error>

#include "sensornet/core/input_error.hpp"

namespace sensornet::report {
namespace {

using nlohmann::json;

constexpr const char* kSource = "--require";

enum class Kind { YesNo, Count, Number, Duration };

// A value read from a report, or why there is none.
struct Reading {
  std::optional<double> value;
  std::string missing;  // why value is empty
};

Reading present(double value) { return {value, {}}; }
Reading absent(std::string why) { return {std::nullopt, std::move(why)}; }

// A value of the record, or why there is none: `where` names it as the report's keys do.
Reading valueOf(const std::optional<double>& value, const char* where) {
  return value ? present(*value) : absent(std::string(where) + " is null");
}
Reading valueOf(const std::optional<bool>& value, const char* where) {
  return value ? present(*value ? 1.0 : 0.0) : absent(std::string(where) + " is null");
}
Reading count(std::uint64_t value) { return present(static_cast<double>(value)); }

Reading yesNo(bool holds) { return present(holds ? 1.0 : 0.0); }

Reading latency(const RunRecord& r, std::optional<double> LatencyRecord::*member,
                const char* where) {
  if (!r.latency_s) return absent("latency_s missing");
  return valueOf((*r.latency_s).*member, where);
}

Reading episodesComplete(const RunRecord& r) {
  if (!r.episodes_planned) return absent("episodes_planned missing");
  return yesNo(r.summary.episodes_complete == *r.episodes_planned);
}

Reading lossFraction(const RunRecord& r) {
  const SummaryRecord& s = r.summary;
  return present(s.sent > 0 ? static_cast<double>(s.lost) / static_cast<double>(s.sent) : 0.0);
}

Reading fusionAgreement(const RunRecord& r) {
  const auto reference = r.other.find("reference_fusion");
  if (reference == r.other.end() || !reference->is_object()) {
    return absent("reference_fusion missing");
  }
  const auto largest = reference->find("max_relative_difference");
  if (largest == reference->end() || !largest->is_number()) {
    return absent("reference_fusion.max_relative_difference is null");
  }
  return present(largest->get<double>());
}

struct Property {
  const char* name;
  Kind kind;
  const char* meaning;
  std::function<Reading(const RunRecord&)> read;
};

const std::vector<Property>& properties() {
  using R = const RunRecord&;
  static const std::vector<Property> table = {
      {"completed", Kind::YesNo, "the run's status is completed (exit 0 without --require)",
       [](R r) { return yesNo(r.status == RunStatus::Completed); }},
      {"episodes-complete", Kind::YesNo, "every planned episode ran and is complete",
       episodesComplete},
      {"meets-bracket", Kind::YesNo,
       "the 95% interval of the mean realized cost meets the bracket [info, cov]",
       [](R r) { return valueOf(r.summary.meets_bracket, "summary.meets_bracket"); }},
      {"meets-delivered-bracket", Kind::YesNo,
       "the same against the bracket of what the emulated network delivered",
       [](R r) {
         return valueOf(r.summary.meets_delivered_bracket, "summary.meets_delivered_bracket");
       }},
      {"nees-consistent", Kind::YesNo,
       "the mean NEES lies in the 99.9% chi-square band for n x complete episodes (the "
       "filter's covariance is honest about its error)",
       [](R r) { return valueOf(r.summary.nees_consistent, "summary.nees_consistent"); }},
      {"no-loss", Kind::YesNo, "no measurement lost (dropped by the emulated network is not lost)",
       [](R r) { return yesNo(r.summary.lost == 0); }},
      {"no-rejects", Kind::YesNo, "no sample refused on the wire",
       [](R r) { return yesNo(r.summary.rejected == 0); }},
      {"no-faults", Kind::YesNo, "the report lists no fault (its consequences count with it)",
       [](R r) { return yesNo(r.causeCount() == 0); }},
      {"latency-median", Kind::Duration, "median publish-to-fusion latency",
       [](R r) { return latency(r, &LatencyRecord::median, "latency_s.median"); }},
      {"latency-p99", Kind::Duration, "99th percentile of the publish-to-fusion latency",
       [](R r) { return latency(r, &LatencyRecord::p99, "latency_s.p99"); }},
      {"mean", Kind::Number, "mean realized cost over the complete episodes",
       [](R r) { return valueOf(r.summary.mean, "summary.mean"); }},
      {"realtime-mean", Kind::Number, "mean real-time cost (what had arrived by each instant)",
       [](R r) { return valueOf(r.summary.realtime_mean, "summary.realtime_mean"); }},
      {"ci95", Kind::Number, "95% half-width of the mean realized cost",
       [](R r) { return valueOf(r.summary.ci95, "summary.ci95"); }},
      {"episodes", Kind::Count, "episodes that ran", [](R r) { return count(r.summary.episodes); }},
      {"episodes-incomplete", Kind::Count, "episodes closed incomplete",
       [](R r) { return count(r.summary.episodes_incomplete); }},
      {"lost", Kind::Count, "measurements lost", [](R r) { return count(r.summary.lost); }},
      {"loss-fraction", Kind::Number, "lost / sent", lossFraction},
      {"rejected", Kind::Count, "samples refused on the wire",
       [](R r) { return count(r.summary.rejected); }},
      {"late", Kind::Count, "measurements that arrived after a later one (re-fused in order)",
       [](R r) { return count(r.summary.late); }},
      {"fusion-agreement", Kind::Number,
       "largest relative difference of an external fusion center's realized cost from the "
       "reference's, over the episodes both fused (--reference-fusion)",
       fusionAgreement},
  };
  return table;
}

const Property* findProperty(std::string_view name) {
  for (const Property& p : properties()) {
    if (name == p.name) return &p;
  }
  return nullptr;
}

std::string knownNames() {
  std::string names;
  for (const Property& p : properties()) names += (names.empty() ? "" : ", ") + std::string(p.name);
  return names;
}

std::string_view trimmed(std::string_view s) {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) s.remove_prefix(1);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t')) s.remove_suffix(1);
  return s;
}

// The operator at the start of `s` and its length, or Holds and 0.
std::pair<Comparison, std::size_t> operatorAt(std::string_view s) {
  if (s.starts_with("<=")) return {Comparison::AtMost, 2};
  if (s.starts_with(">=")) return {Comparison::AtLeast, 2};
  if (s.starts_with("==")) return {Comparison::Equal, 2};
  if (s.starts_with("<")) return {Comparison::Below, 1};
  if (s.starts_with(">")) return {Comparison::Above, 1};
  if (s.starts_with("=")) return {Comparison::Equal, 1};
  return {Comparison::Holds, 0};
}

// Seconds per unit of a duration suffix, or 0 for an unknown one.
double secondsPer(std::string_view unit) {
  if (unit == "us") return 1e-6;
  if (unit == "ms") return 1e-3;
  if (unit == "s") return 1.0;
  return 0.0;
}

double limitOf(const Property& p, std::string_view criterion, std::string_view text) {
  const auto fail = [&](const std::string& expected) -> double {
    throw InputError(kSource, std::string(criterion), expected);
  };
  double number = 0.0;
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), number);
  if (ec != std::errc() || end == text.data() || !std::isfinite(number)) {
    fail(std::string("a number after the comparison, got '") + std::string(text) + "'");
  }
  const std::string_view unit(end, static_cast<std::size_t>(text.data() + text.size() - end));
  switch (p.kind) {
    case Kind::Duration: {
      const double scale = secondsPer(unit);
      if (scale == 0.0) {
        fail("a duration with its unit us, ms or s (like " + std::string(p.name) + "<=5ms), got '" +
             std::string(text) + "'");
      }
      if (number < 0.0) fail("a duration >= 0, got '" + std::string(text) + "'");
      return number * scale;
    }
    case Kind::Count:
      if (!unit.empty() || number < 0.0 || number != std::floor(number)) {
        fail("a whole number >= 0, got '" + std::string(text) + "'");
      }
      return number;
    case Kind::Number:
      if (!unit.empty()) fail("a plain number, got '" + std::string(text) + "'");
      return number;
    case Kind::YesNo:
      break;
  }
  return number;
}

Requirement parseCriterion(std::string_view criterion) {
  if (criterion.empty()) {
    throw InputError(kSource, "", "criteria separated by single commas, got an empty one");
  }
  std::size_t at = 0;
  while (at < criterion.size() && operatorAt(criterion.substr(at)).second == 0) ++at;
  const std::string_view name = trimmed(criterion.substr(0, at));
  const Property* property = findProperty(name);
  if (property == nullptr) {
    throw InputError(kSource, std::string(criterion),
                     "one of the known criteria (" + knownNames() + ")");
  }
  Requirement r{std::string(criterion), std::string(name), Comparison::Holds, 0.0};
  if (at == criterion.size()) {
    if (property->kind != Kind::YesNo) {
      throw InputError(kSource, std::string(criterion),
                       std::string("a comparison, like ") + property->name +
                           (property->kind == Kind::Duration ? "<=5ms" : "<=0"));
    }
    return r;
  }
  if (property->kind == Kind::YesNo) {
    throw InputError(kSource, std::string(criterion),
                     std::string(property->name) + " alone: it holds or not, there is nothing to compare");
  }
  const auto [comparison, length] = operatorAt(criterion.substr(at));
  r.comparison = comparison;
  r.limit = limitOf(*property, criterion, trimmed(criterion.substr(at + length)));
  return r;
}

bool compare(double value, Comparison c, double limit) {
  switch (c) {
    case Comparison::AtMost:
      return value <= limit;
    case Comparison::Below:
      return value < limit;
    case Comparison::AtLeast:
      return value >= limit;
    case Comparison::Above:
      return value > limit;
    case Comparison::Equal:
      return value == limit;
    case Comparison::Holds:
      return value != 0.0;
  }
  return false;
}

std::string formatted(double value, Kind kind) {
  char text[64];
  switch (kind) {
    case Kind::YesNo:
      return value != 0.0 ? "yes" : "no";
    case Kind::Count:
      std::snprintf(text, sizeof text, "%.0f", value);
      break;
    case Kind::Duration:
      if (value < 1e-3) {
        std::snprintf(text, sizeof text, "%.3g us", value * 1e6);
      } else if (value < 1.0) {
        std::snprintf(text, sizeof text, "%.3g ms", value * 1e3);
      } else {
        std::snprintf(text, sizeof text, "%.3g s", value);
      }
      break;
    case Kind::Number:
      std::snprintf(text, sizeof text, "%.6g", value);
      break;
  }
  return text;
}

}  // namespace

std::vector<Requirement> parseRequirements(std::string_view spec) {
  std::vector<Requirement> requirements;
  if (trimmed(spec).empty()) {
    throw InputError(kSource, "", "at least one criterion (" + knownNames() + ")");
  }
  while (true) {
    const std::size_t comma = spec.find(',');
    requirements.push_back(parseCriterion(trimmed(spec.substr(0, comma))));
    if (comma == std::string_view::npos) break;
    spec.remove_prefix(comma + 1);
  }
  return requirements;
}

std::vector<RequirementCheck> checkRequirements(const std::vector<Requirement>& requirements,
                                                const RunRecord& report) {
  std::vector<RequirementCheck> checks;
  for (const Requirement& r : requirements) {
    const Property* property = findProperty(r.name);
    RequirementCheck check{r, false, ""};
    if (property == nullptr) {
      check.measured = "not a known criterion";
    } else if (const Reading reading = property->read(report); !reading.value) {
      check.measured = "not in the report (" + reading.missing + ")";
    } else {
      check.pass = compare(*reading.value, r.comparison, r.limit);
      check.measured = formatted(*reading.value, property->kind);
    }
    checks.push_back(std::move(check));
  }
  return checks;
}

std::vector<RequirementCheck> checkRequirements(const std::vector<Requirement>& requirements,
                                                const nlohmann::json& report) {
  try {
    return checkRequirements(requirements, decodeRunRecord(report));
  } catch (const RecordError& e) {
    // Not a report this version reads: every criterion fails, saying where.
    std::vector<RequirementCheck> checks;
    for (const Requirement& r : requirements) {
      checks.push_back({r, false, "not in the report (" + e.field() + ": expected " +
                                      e.expected() + ")"});
    }
    return checks;
  }
}

std::string describe(const RequirementCheck& check) {
  return "require " + check.requirement.text + ": " + (check.pass ? "pass" : "FAIL") +
         " (measured " + check.measured + ")";
}

nlohmann::json toJson(const std::vector<RequirementCheck>& checks) {
  json out = json::array();
  for (const RequirementCheck& c : checks) {
    out.push_back(
        {{"criterion", c.requirement.text}, {"pass", c.pass}, {"measured", c.measured}});
  }
  return out;
}

int gatedExitCode(int run_exit_code, const std::vector<RequirementCheck>& checks) {
  if (run_exit_code == 1) return run_exit_code;
  for (const RequirementCheck& c : checks) {
    if (!c.pass) return kExitRequirementFailed;
  }
  return run_exit_code;
}

std::string requirementsHelp() {
  std::string help;
  for (const Property& p : properties()) {
    std::string usage = p.name;
    if (p.kind == Kind::Duration) usage += "<=DURATION";
    if (p.kind == Kind::Count) usage += "<=COUNT";
    if (p.kind == Kind::Number) usage += "<=NUMBER";
    help += "  " + usage + std::string(usage.size() < 28 ? 28 - usage.size() : 1, ' ') +
            p.meaning + "\n";
  }
  help.pop_back();  // the caller ends the last line
  return help;
}

}  // namespace sensornet::report
