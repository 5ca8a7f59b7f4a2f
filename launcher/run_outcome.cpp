#include "run_outcome.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <optional>
#include <set>

#include "output_file.hpp"
#include "sensornet/core/bracket_differs.hpp"
#include "sensornet/emulator/fault_causes.hpp"
#include "sensornet/emulator/run_report.hpp"
#include "sensornet/io/command_line.hpp"
#include "sensornet/launcher/supervisor.hpp"
#include "sensornet/report/run_status.hpp"

namespace sensornet::launcher {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

// The fusion center's report of this run, or nullopt with what is wrong ("wrote no report at
// ...", completing "fusion_center ..."). With an episode log (`logged`) the report is read
// without its per_episode entries, which a rewrite streams back in from the log: a report of
// millions of episodes is never held.
std::optional<json> readRunReport(const fs::path& path, const std::string& run_id, bool logged,
                                  std::string& problem) {
  emulator::ReportFile file = emulator::readReport(
      path, logged ? emulator::EpisodeEntries::Skipped : emulator::EpisodeEntries::Read);
  if (file.problem == emulator::ReportFile::Problem::Unreadable) {
    problem = "wrote no report at " + path.string();
    return std::nullopt;
  }
  if (!file.ok()) {
    problem = "wrote " + path.string() + ", which is not a sensornet report";
    return std::nullopt;
  }
  if (file.report["run_id"].get<std::string>() != run_id) {
    problem = "wrote a report of another run in " + path.string();
    return std::nullopt;
  }
  return std::move(file.report);
}

// The report rebuilt from the episode log beside `report_path` (no log: no episode); with a log,
// without per_episode (a rewrite streams it in from the log).
json rebuildReport(const RunEnd& end, bool logged) {
  const fs::path log = emulator::episodeLogPath(end.report_path);
  // What our fusion center recorded before it died: its fault log (the launch removed an
  // earlier run's; an external fusion center keeps none).
  json faults = json::array();
  if (!end.external_fusion_center) {
    for (json& fault : emulator::readFaultLog(emulator::faultLogPath(end.report_path))) {
      faults.push_back(std::move(fault));
    }
  }
  json report;
  if (logged) {
    emulator::RunReport rebuilt(end.run_id, "", end.sensor_count, 0, log);
    emulator::forEachReportedEpisode(log, [&rebuilt](const json& entry) { rebuilt.add(entry); });
    report = rebuilt.toJsonWithoutEpisodes("failed", faults, json::array());
  } else {
    report = emulator::reportFromEpisodes(end.run_id, end.sensor_count, {}, "failed", faults);
  }
  report["rebuilt_from"] = log.string();
  if (!report.contains("episodes_planned")) report["episodes_planned"] = end.episodes_planned;
  return report;
}

json field(const json& object, const char* key) {
  return object.is_object() && object.contains(key) ? object[key] : json();
}

// The report of a run whose fusion center was external: built from the Reports the launcher
// recorded in the episode log, with the status our fusion center would give the same results
// (completed: every episode complete, nothing lost, no Report refused; else degraded, its
// cause in `faults`).
json externalReport(const RunEnd& end, bool logged) {
  json report = rebuildReport(end, logged);
  report.erase("rebuilt_from");
  const fs::path log = emulator::episodeLogPath(end.report_path);
  report["built_from"] = "the Reports of the external fusion center, recorded in " + log.string();
  json faults = json::array();
  const json summary = field(report, "summary");
  const std::uint64_t lost = field(summary, "lost").is_number_unsigned()
                                 ? field(summary, "lost").get<std::uint64_t>()
                                 : 0;
  if (lost > 0) {
    faults.push_back(emulator::faultEntry(
        emulator::FaultKind::Lost, kFusionCenter, std::nullopt, std::nullopt, std::nullopt,
        "the external fusion center reported " + std::to_string(lost) + " measurements lost"));
  }
  if (end.reports_refused > 0) {
    faults.push_back(emulator::faultEntry(
        emulator::FaultKind::Rejected, kFusionCenter, std::nullopt, std::nullopt, std::nullopt,
        std::to_string(end.reports_refused) +
            " Reports of the external fusion center did not fit the scenario (the launcher's "
            "log says why)"));
  }
  // The latencies the external fusion center measured, as its last Report gave them (ours
  // sends the run's so far); none when it left them at zero.
  double median = 0.0;
  double p99 = 0.0;
  if (logged) {
    emulator::forEachReportedEpisode(log, [&](const json& entry) {
      median = field(entry, "latency_median_s").is_number() ? entry["latency_median_s"].get<double>() : 0.0;
      p99 = field(entry, "latency_p99_s").is_number() ? entry["latency_p99_s"].get<double>() : 0.0;
    });
  }
  if (median > 0.0) {
    report["latency_s"]["median"] = median;
    report["latency_s"]["p99"] = p99;
  }
  const auto count = [&summary](const char* key) {
    const json value = field(summary, key);
    return value.is_number_unsigned() ? value.get<std::uint64_t>() : std::uint64_t{0};
  };
  sensornet::report::StatusEvidence seen;
  seen.faults = faults.size();
  seen.lost = lost;
  seen.episodes = count("episodes");
  seen.episodes_complete = count("episodes_complete");
  report["status"] = std::string(wordOf(sensornet::report::decideRunStatus(seen)));
  report["faults"] = std::move(faults);
  return report;
}

// The realized cost of each episode an episode log holds with one (null: not fused).
std::map<std::uint32_t, double> realizedCosts(const fs::path& log) {
  std::map<std::uint32_t, double> costs;
  std::error_code missing;
  if (!fs::is_regular_file(log, missing)) return costs;
  emulator::forEachReportedEpisode(log, [&costs](const json& entry) {
    const json cost = field(entry, "realized_cost");
    if (field(entry, "episode").is_number_unsigned() && cost.is_number()) {
      costs.emplace(entry["episode"].get<std::uint32_t>(), cost.get<double>());
    }
  });
  return costs;
}

// --reference-fusion: per episode the external realized cost beside the reference's and their
// relative difference |external - reference| / |reference|, and the largest over the episodes
// both fused (null when there is none).
json referenceComparison(const RunEnd& end) {
  const fs::path reference_log = emulator::episodeLogPath(end.reference_report);
  const std::map<std::uint32_t, double> external =
      realizedCosts(emulator::episodeLogPath(end.report_path));
  const std::map<std::uint32_t, double> reference = realizedCosts(reference_log);
  std::set<std::uint32_t> episodes;
  for (const auto& [k, cost] : external) episodes.insert(k);
  for (const auto& [k, cost] : reference) episodes.insert(k);
  json per_episode = json::array();
  std::optional<double> largest;
  std::size_t compared = 0;
  for (const std::uint32_t k : episodes) {
    const auto e = external.find(k);
    const auto r = reference.find(k);
    json row = {{"episode", k},
                {"external", e != external.end() ? json(e->second) : json(nullptr)},
                {"reference", r != reference.end() ? json(r->second) : json(nullptr)},
                {"relative_difference", nullptr}};
    if (e != external.end() && r != reference.end()) {
      const double scale = std::abs(r->second) > 0.0 ? std::abs(r->second) : 1.0;
      const double difference = std::abs(e->second - r->second) / scale;
      row["relative_difference"] = difference;
      largest = std::max(largest.value_or(0.0), difference);
      ++compared;
    }
    per_episode.push_back(std::move(row));
  }
  return {{"report", end.reference_report.string()},
          {"episodes_compared", compared},
          {"max_relative_difference", largest ? json(*largest) : json(nullptr)},
          {"per_episode", std::move(per_episode)}};
}

std::uint64_t finishedEpisodes(const json& report) {
  if (report.contains("episodes") && report["episodes"].is_number_unsigned()) {
    return report["episodes"].get<std::uint64_t>();
  }
  if (report.contains("per_episode") && report["per_episode"].is_array()) {
    return report["per_episode"].size();
  }
  return 0;
}

// A number as text ("12", "0.0123"); "n/a" when missing or not a number.
std::string shown(const json& value) {
  if (value.is_number_integer()) return std::to_string(value.get<std::int64_t>());
  if (value.is_number()) {
    char text[32];
    std::snprintf(text, sizeof text, "%.6g", value.get<double>());
    return text;
  }
  return "n/a";
}

// A count that may be given by reason ({"malformed": 2, ...}): its total.
json total(const json& value) {
  if (!value.is_object()) return value;
  std::uint64_t sum = 0;
  for (const auto& [reason, count] : value.items()) {
    if (count.is_number_unsigned()) sum += count.get<std::uint64_t>();
  }
  return sum;
}

std::string sensorsText(const json& fault) {
  const json sensors = field(fault, "sensors");
  if (sensors.is_array() && !sensors.empty()) {
    std::string text = sensors.size() == 1 ? "sensor " : "sensors ";
    for (std::size_t i = 0; i < sensors.size(); ++i) {
      text += (i == 0 ? "" : ", ") + shown(sensors[i]);
    }
    return text;
  }
  const json sensor = field(fault, "sensor");
  return sensor.is_number() ? "sensor " + shown(sensor) : "";
}

// "process_killed in sensor_agent-0-2 (sensors 0, 1, 2), episode 1 at t = 1.25 s: killed by ..."
std::string faultLine(const json& fault) {
  std::string line = field(fault, "kind").is_string() ? field(fault, "kind").get<std::string>()
                                                      : std::string("fault");
  if (const json process = field(fault, "process"); process.is_string()) {
    line += " in " + process.get<std::string>();
  }
  if (const std::string sensors = sensorsText(fault); !sensors.empty()) {
    line += " (" + sensors + ")";
  }
  if (const json episode = field(fault, "episode"); episode.is_number()) {
    line += ", episode " + shown(episode);
  }
  if (const json t = field(fault, "emulated_time_s"); t.is_number()) {
    line += " at t = " + shown(t) + " s";
  }
  if (const json detail = field(fault, "detail"); detail.is_string()) {
    line += ": " + detail.get<std::string>();
  }
  return line;
}

// " (and 12 consequences: 11 stall, 1 run_aborted)" after the line of a cause, else "".
std::string consequencesOf(const json& cause, const json& faults) {
  std::map<std::string, int> kinds;
  int total = 0;
  for (const json& f : faults) {
    const json by = field(f, emulator::kCausedByField);
    if (by.is_object() && by.value("kind", json()) == field(cause, "kind") &&
        by.value("process", json()) == field(cause, "process")) {
      ++kinds[f.value("kind", std::string("fault"))];
      ++total;
    }
  }
  if (total == 0) return "";
  std::string text = " (and " + std::to_string(total) + " consequence" + (total == 1 ? "" : "s");
  std::string sep = ": ";
  for (const auto& [kind, n] : kinds) {
    text += sep + std::to_string(n) + " " + kind;
    sep = ", ";
  }
  return text + ")";
}

std::uint64_t incompleteEpisodes(const json& report, const json& summary) {
  if (const json n = field(summary, "episodes_incomplete"); n.is_number_unsigned()) {
    return n.get<std::uint64_t>();
  }
  std::uint64_t count = 0;
  for (const json& entry : field(report, "per_episode")) {
    if (field(entry, "complete") == json(false)) ++count;
  }
  return count;
}

std::string meetsText(const json& meets) {
  if (meets.is_boolean()) return meets.get<bool>() ? "true" : "false";
  return "undetermined";
}

// The arrival mode of the run (the report's "arrivals"), and under timetables what the realized
// cost line printed before it does not say: its bracket is about Poisson arrivals. A report
// without the key (a rebuilt one, an older fusion center) says nothing of the mode.
std::string arrivalsLine(const json& arrivals) {
  const std::string mode =
      arrivals.is_object() ? arrivals.value("mode", std::string("unknown")) : "not reported";
  if (mode != "timetable") return "arrivals: " + mode;
  return "arrivals: timetable (deterministic instants, the same every episode): the bracket "
         "[info, cov] bounds the Poisson mean of the schedule, not this cost; meets_bracket only "
         "says whether the cost lies in it";
}

// Two brackets of the report differ beyond their rounding (false when one is not there).
bool differs(const json& a, const json& b) {
  const json ia = field(a, "info"), ca = field(a, "cov"), ib = field(b, "info"),
             cb = field(b, "cov");
  if (!ia.is_number() || !ca.is_number() || !ib.is_number() || !cb.is_number()) return false;
  return bracketsDiffer(ia.get<double>(), ca.get<double>(), ib.get<double>(), cb.get<double>());
}

// What the schedule could deliver, when that is not what it planned (an emulated network's
// losses and outages, a dead sensor under --on-sensor-failure continue), else "".
std::string deliveredLine(const json& summary) {
  const json delivered = field(summary, "delivered_bracket");
  if (!differs(delivered, field(summary, "bracket"))) return "";
  return "  against what the schedule delivered (network losses and outages, dead sensors): [" +
         shown(field(delivered, "info")) + ", " + shown(field(delivered, "cov")) +
         "]: meets_delivered_bracket " + meetsText(field(summary, "meets_delivered_bracket"));
}

// The real-time cost, when it differs from the realized one (measurements arrived late).
std::string realtimeLine(const json& summary) {
  const json realtime = field(summary, "realtime_mean"), mean = field(summary, "mean");
  if (!realtime.is_number() || !mean.is_number() || realtime == mean) return "";
  return "  real-time cost (the covariance of what had arrived by each instant): mean " +
         shown(realtime);
}

std::string measurementsLine(const json& summary) {
  std::string line = "measurements: " + shown(field(summary, "sent")) + " sent, " +
                     shown(field(summary, "received")) + " received, ";
  if (const json dropped = field(summary, "dropped_by_network");
      dropped.is_number() && dropped.get<double>() > 0) {
    line += shown(dropped) + " dropped by the emulated network, ";
  }
  return line + shown(field(summary, "lost")) + " lost, " +
         shown(total(field(summary, "rejected"))) + " rejected";
}

}  // namespace

RunOutcome settleRun(const RunEnd& end) {
  RunOutcome outcome;
  ReportSeen seen;
  const fs::path log = emulator::episodeLogPath(end.report_path);
  std::error_code missing;
  const bool logged = fs::is_regular_file(log, missing);
  std::optional<json> report;
  if (end.external_fusion_center) {  // no process of ours wrote one: the Reports make it
    report = externalReport(end, logged);
    seen.readable = true;
    outcome.amended = true;
  } else {
    report = readRunReport(end.report_path, end.run_id, logged, seen.problem);
    seen.readable = report.has_value();
    if (!report) {
      report = rebuildReport(end, logged);
      outcome.rebuilt = true;
    }
  }
  seen.status = report->value("status", std::string());
  seen.finished_episodes = finishedEpisodes(*report);
  if (const json summary = field(*report, "summary"); summary.is_object()) {
    if (const json n = field(summary, "episodes_complete"); n.is_number_unsigned()) {
      seen.complete_episodes = n.get<std::uint64_t>();
    }
    if (const json n = field(summary, "lost"); n.is_number_unsigned()) {
      seen.lost = n.get<std::uint64_t>();
    }
  }
  const Verdict verdict = decideVerdict(end.faults, end.interrupted, seen, end.episodes_planned);
  outcome.status = verdict.status;
  outcome.exit_code = exitCodeOf(verdict.status);
  const std::string status(wordOf(verdict.status));
  outcome.amended =
      outcome.amended || outcome.rebuilt || status != seen.status || !verdict.faults.empty();
  if (outcome.amended) {
    (*report)["status"] = status;
    // The launcher's causes first: what the other processes saw of them follows, marked.
    (*report)["faults"] = faultList(verdict.faults, field(*report, "faults"));
  }
  // The fusion center learns the planned count from the first episode's start: a run that
  // ended before one says 0. What the launch asked for is the plan.
  if (const json planned = field(*report, "episodes_planned");
      !planned.is_number() || planned.get<double>() < 1.0) {
    (*report)["episodes_planned"] = end.episodes_planned;
    outcome.amended = true;
  }
  if (!end.external_sensors.empty() || end.external_fusion_center) {
    json external = json::object();  // the roles a participant of the user's played
    if (!end.external_sensors.empty()) external["sensors"] = end.external_sensors;
    if (end.external_fusion_center) external["fusion_center"] = true;
    (*report)["external"] = std::move(external);
    outcome.amended = true;
  }
  if (!end.reference_report.empty()) {
    (*report)["reference_fusion"] = referenceComparison(end);
    outcome.amended = true;
  }
  if (!end.requirements.empty()) {  // against the settled report: its status and faults
    outcome.checks = emulator::checkRequirements(end.requirements, *report);
    (*report)["requirements"] = emulator::toJson(outcome.checks);
    outcome.exit_code = emulator::gatedExitCode(outcome.exit_code, outcome.checks);
    outcome.amended = true;
  }
  if (outcome.amended) {
    try {
      if (logged) {
        replaceFileAtomically(end.report_path, [&](std::ostream& out) {
          emulator::writeReportWithLog(out, *report, log, 2);
          out << '\n';
        });
      } else {
        replaceFileAtomically(end.report_path, report->dump(2) + "\n");
      }
    } catch (const std::exception& e) {
      outcome.write_problem = e.what();
    }
  }
  outcome.report = std::move(*report);
  return outcome;
}

void printOutcome(const RunOutcome& outcome, const fs::path& report_path) {
  const json& report = outcome.report;
  const json summary = field(report, "summary");
  const json faults = field(report, "faults").is_array() ? report["faults"] : json::array();
  const std::size_t causes = emulator::causeCount(faults);
  std::printf("run %s: %s (%zu fault%s)\n", report.value("run_id", std::string()).c_str(),
              std::string(wordOf(outcome.status)).c_str(), causes, causes == 1 ? "" : "s");
  for (const json& fault : faults) {
    if (emulator::isConsequence(fault)) continue;
    std::printf("  fault: %s%s\n", faultLine(fault).c_str(), consequencesOf(fault, faults).c_str());
  }

  json complete = field(summary, "episodes_complete");
  if (!complete.is_number()) complete = field(summary, "episodes");
  std::printf("episodes: %s complete, %llu incomplete, of %s planned\n", shown(complete).c_str(),
              static_cast<unsigned long long>(incompleteEpisodes(report, summary)),
              shown(field(report, "episodes_planned")).c_str());
  const json bracket = field(summary, "bracket");
  std::string interval = "(one complete episode: no 95% interval)";  // ci95 needs two
  if (const json ci95 = field(summary, "ci95"); ci95.is_number()) {
    interval = "\u00b1 " + shown(ci95) + " (95%: [" + shown(field(summary, "ci95_low")) + ", " +
               shown(field(summary, "ci95_high")) + "])";
  }
  if (field(summary, "mean").is_number()) {
    std::printf(
        "realized cost over complete episodes: mean %s %s against the bracket [%s, %s]: "
        "meets_bracket %s\n",
        shown(field(summary, "mean")).c_str(), interval.c_str(),
        shown(field(bracket, "info")).c_str(), shown(field(bracket, "cov")).c_str(),
        meetsText(field(summary, "meets_bracket")).c_str());
    if (const std::string line = deliveredLine(summary); !line.empty()) {
      std::printf("%s\n", line.c_str());
    }
    if (const std::string line = realtimeLine(summary); !line.empty()) {
      std::printf("%s\n", line.c_str());
    }
  } else {
    std::printf("realized cost: not measured (no complete episode)\n");
  }
  std::printf("%s\n", arrivalsLine(field(report, "arrivals")).c_str());
  std::printf("%s\n", measurementsLine(summary).c_str());
  const json latency = field(report, "latency_s");
  const auto ms = [](const json& seconds) {
    return seconds.is_number() ? json(1e3 * seconds.get<double>()) : seconds;
  };
  const json delay = field(report, "network_delay_s");
  const bool delayed = field(delay, "max").is_number() && field(delay, "max").get<double>() > 0.0;
  const char* which = delayed ? " (the middleware's, without the emulated network's delay)" : "";
  if (field(latency, "median").is_number()) {
    std::printf("latency publish-to-fusion%s: median %s ms, p99 %s ms\n", which,
                shown(ms(field(latency, "median"))).c_str(),
                shown(ms(field(latency, "p99"))).c_str());
  } else {
    std::printf("latency publish-to-fusion: %s\n",
                field(field(report, "external"), "fusion_center") == true
                    ? "not reported by the external fusion center"
                    : "not measured (no measurement arrived)");
  }
  if (delayed) {
    std::printf("emulated network delay: mean %s ms, largest %s ms (emulated time)\n",
                shown(ms(field(delay, "mean"))).c_str(), shown(ms(field(delay, "max"))).c_str());
  }
  for (const emulator::RequirementCheck& check : outcome.checks) {
    std::printf("%s\n", emulator::describe(check).c_str());
  }
  if (outcome.write_problem) {
    std::printf("report: NOT WRITTEN: %s\n", outcome.write_problem->c_str());
  } else {
    std::printf("report: %s%s\n", report_path.c_str(),
                outcome.rebuilt ? " (rebuilt from the episode log)" : "");
  }
  std::printf("exit code %d\n", outcome.exit_code);
  std::fflush(stdout);
}

void printOutcomeJson(const RunOutcome& outcome, const fs::path& report_path) {
  json line = field(outcome.report, "summary");
  if (!line.is_object()) line = json::object();
  line["run_id"] = field(outcome.report, "run_id");
  line["status"] = std::string(wordOf(outcome.status));
  line["faults"] =
      field(outcome.report, "faults").is_array() ? outcome.report["faults"] : json::array();
  line["episodes"] = field(outcome.report, "episodes");
  line["episodes_planned"] = field(outcome.report, "episodes_planned");
  line["arrivals"] = field(outcome.report, "arrivals");
  line["report"] = report_path.string();
  if (outcome.rebuilt) line["rebuilt_from"] = field(outcome.report, "rebuilt_from");
  if (outcome.write_problem) line["report_error"] = *outcome.write_problem;
  if (!outcome.checks.empty()) line["requirements"] = emulator::toJson(outcome.checks);
  line["exit_code"] = outcome.exit_code;
  printJson(line);
}

}  // namespace sensornet::launcher
