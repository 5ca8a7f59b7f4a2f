#include "sensornet/launcher/run_outcome.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <optional>
#include <set>

#include "sensornet/io/output_file.hpp"
#include "sensornet/core/bracket_differs.hpp"
#include "sensornet/emulator/run_report.hpp"
#include "sensornet/io/command_line.hpp"
#include "sensornet/launcher/supervisor.hpp"
#include "sensornet/report/run_status.hpp"

namespace sensornet::launcher {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using report::BracketRecord;
using report::FaultRecord;
using report::RunRecord;
using report::SummaryRecord;

// The fusion center's report of this run, or nullopt with what is wrong ("wrote no report at
// ...", completing "fusion_center ..."). With an episode log (`logged`) the report is read
// without its per_episode entries, which a rewrite streams back in from the log: a report of
// millions of episodes is never held.
std::optional<RunRecord> readRunReport(const fs::path& path, const std::string& run_id,
                                       bool logged, std::string& problem) {
  sensornet::report::ReportFile file = sensornet::report::readReport(
      path, logged ? sensornet::report::EpisodeEntries::Skipped : sensornet::report::EpisodeEntries::Read);
  if (file.problem == sensornet::report::ReportFile::Problem::Unreadable) {
    problem = "wrote no report at " + path.string();
    return std::nullopt;
  }
  if (!file.ok()) {
    problem = "wrote " + path.string() + ", which is not a sensornet report";
    return std::nullopt;
  }
  RunRecord run;
  try {
    run = report::decodeRunRecord(file.report);
  } catch (const report::RecordError& e) {
    problem = "wrote " + path.string() + ", which is not a sensornet report (" + e.what() + ")";
    return std::nullopt;
  }
  if (run.run_id != run_id) {
    problem = "wrote a report of another run in " + path.string();
    return std::nullopt;
  }
  return run;
}

// The report rebuilt from the episode log beside `report_path` (no log: no episode); with a log,
// without per_episode (a rewrite streams it in from the log).
RunRecord rebuildReport(const RunEnd& end, bool logged) {
  const fs::path log = sensornet::report::episodeLogPath(end.report_path);
  // What our fusion center recorded before it died: its fault log (the launch removed an
  // earlier run's; an external fusion center keeps none).
  json faults = json::array();
  if (!end.external_fusion_center) {
    for (json& fault : sensornet::report::readFaultLog(sensornet::report::faultLogPath(end.report_path))) {
      faults.push_back(std::move(fault));
    }
  }
  json doc;
  if (logged) {
    emulator::RunReport rebuilt(end.run_id, "", end.sensor_count, end.state_dim, log);
    sensornet::report::forEachReportedEpisode(log, [&rebuilt](const json& entry) { rebuilt.add(entry); });
    doc = rebuilt.toJsonWithoutEpisodes("failed", faults, json::array());
  } else {
    doc = emulator::reportFromEpisodes(end.run_id, end.sensor_count, end.state_dim, {}, "failed",
                                       faults);
  }
  RunRecord run = report::decodeRunRecord(doc);
  run.rebuilt_from = log.string();
  if (!run.episodes_planned) run.episodes_planned = static_cast<std::uint64_t>(end.episodes_planned);
  return run;
}

FaultRecord fusionCenterFault(emulator::FaultKind kind, const std::string& detail) {
  FaultRecord fault;
  fault.kind = kind;
  fault.process = kFusionCenter;
  fault.detail = detail;
  return fault;
}

// The report of a run whose fusion center was external: built from the Reports the launcher
// recorded in the episode log, with the status the one rule gives the same results
// (completed: every episode complete, nothing lost, no Report refused; else degraded, its
// cause in `faults`).
RunRecord externalReport(const RunEnd& end, bool logged) {
  RunRecord run = rebuildReport(end, logged);
  run.rebuilt_from.reset();
  const fs::path log = sensornet::report::episodeLogPath(end.report_path);
  run.built_from = "the Reports of the external fusion center, recorded in " + log.string();
  run.faults.clear();
  if (run.summary.lost > 0) {
    run.faults.push_back(fusionCenterFault(
        emulator::FaultKind::Lost, "the external fusion center reported " +
                                       std::to_string(run.summary.lost) + " measurements lost"));
  }
  if (end.reports_refused > 0) {
    run.faults.push_back(fusionCenterFault(
        emulator::FaultKind::Rejected,
        std::to_string(end.reports_refused) +
            " Reports of the external fusion center did not fit the scenario (the launcher's "
            "log says why)"));
  }
  // The latencies the external fusion center measured, as its last Report gave them (ours
  // sends the run's so far); none when it left them at zero.
  double median = 0.0;
  double p99 = 0.0;
  if (logged) {
    sensornet::report::forEachReportedEpisode(log, [&](const json& entry) {
      const report::EpisodeRecord episode = report::decodeEpisode(entry);
      median = episode.latency_median_s.value_or(0.0);
      p99 = episode.latency_p99_s.value_or(0.0);
    });
  }
  if (median > 0.0) {
    if (!run.latency_s) run.latency_s = report::LatencyRecord{};
    run.latency_s->median = median;
    run.latency_s->p99 = p99;
  }
  sensornet::report::StatusEvidence seen;
  seen.faults = run.faults.size();
  seen.lost = run.summary.lost;
  seen.episodes = run.summary.episodes;
  seen.episodes_complete = run.summary.episodes_complete;
  run.status = sensornet::report::decideRunStatus(seen);
  return run;
}

// The realized cost of each episode an episode log holds with one (null: not fused).
std::map<std::uint32_t, double> realizedCosts(const fs::path& log) {
  std::map<std::uint32_t, double> costs;
  std::error_code missing;
  if (!fs::is_regular_file(log, missing)) return costs;
  sensornet::report::forEachReportedEpisode(log, [&costs](const json& entry) {
    const report::EpisodeRecord episode = report::decodeEpisode(entry);
    if (episode.realized_cost) costs.emplace(episode.episode, *episode.realized_cost);
  });
  return costs;
}

// --reference-fusion: per episode the external realized cost beside the reference's and their
// relative difference |external - reference| / |reference|, and the largest over the episodes
// both fused (null when there is none).
json referenceComparison(const RunEnd& end) {
  const fs::path reference_log = sensornet::report::episodeLogPath(end.reference_report);
  const std::map<std::uint32_t, double> external =
      realizedCosts(sensornet::report::episodeLogPath(end.report_path));
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

// A number as text ("12", "0.0123"); "n/a" when there is none.
std::string shown(std::optional<double> value) {
  if (!value) return "n/a";
  char text[32];
  std::snprintf(text, sizeof text, "%.6g", *value);
  return text;
}
std::string shown(std::uint64_t value) { return std::to_string(value); }

std::string sensorsText(const FaultRecord& fault) {
  const std::vector<int> sensors = fault.namedSensors();
  if (sensors.empty()) return "";
  std::string text = sensors.size() == 1 ? "sensor " : "sensors ";
  for (std::size_t i = 0; i < sensors.size(); ++i) {
    text += (i == 0 ? "" : ", ") + std::to_string(sensors[i]);
  }
  return text;
}

// "process_killed in sensor_agent-0-2 (sensors 0, 1, 2), episode 1 at t = 1.25 s: killed by ..."
std::string faultLine(const FaultRecord& fault) {
  std::string line(wordOf(fault.kind));
  if (!fault.process.empty()) line += " in " + fault.process;
  if (const std::string sensors = sensorsText(fault); !sensors.empty()) {
    line += " (" + sensors + ")";
  }
  if (fault.episode) line += ", episode " + std::to_string(*fault.episode);
  if (fault.emulated_time_s) line += " at t = " + shown(fault.emulated_time_s) + " s";
  if (!fault.detail.empty()) line += ": " + fault.detail;
  return line;
}

// " (and 12 consequences: 11 stall, 1 run_aborted)" after the line of a cause, else "".
std::string consequencesOf(const FaultRecord& cause, const std::vector<FaultRecord>& faults) {
  std::map<std::string, int> kinds;
  int total = 0;
  for (const FaultRecord& f : faults) {
    if (f.caused_by && f.caused_by->kind == cause.kind && f.caused_by->process == cause.process) {
      ++kinds[std::string(wordOf(f.kind))];
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

std::string meetsText(std::optional<bool> meets) {
  if (meets) return *meets ? "true" : "false";
  return "undetermined";
}

// The arrival mode of the run (the report's "arrivals"), and under timetables what the realized
// cost line printed before it does not say: its bracket is about Poisson arrivals. A report
// without the key (a rebuilt one, an older fusion center) says nothing of the mode.
std::string arrivalsLine(const std::optional<report::ArrivalsRecord>& arrivals, bool rebuilt) {
  const std::string mode = arrivals ? arrivals->mode
                           : rebuilt ? "not known (the episode log keeps no arrival mode)"
                                     : "not reported";
  if (mode != "timetable") return "arrivals: " + mode;
  return "arrivals: timetable (deterministic instants, the same every episode): the bracket "
         "[info, cov] bounds the Poisson mean of the schedule, not this cost; meets_bracket only "
         "says whether the cost lies in it";
}

// The sensor processes' clocks as the fusion center measured them (the report's "clocks"): how
// far the farthest may be off, which bounds what the clocks can do to the latency figures; none
// when the report has no measurement (an older one, an outside fusion center's, a rebuilt one).
std::string clocksLine(const std::optional<report::ClocksRecord>& clocks) {
  if (!clocks || clocks->processes.empty()) return "";
  double within_s = 0.0;
  std::size_t beyond = 0;
  for (const report::ClockProcessRecord& p : clocks->processes) {
    within_s = std::max(within_s, std::abs(p.offset_s) + p.uncertainty_s);
    if (std::abs(p.offset_s) - p.uncertainty_s > clocks->bound_s) ++beyond;
  }
  char text[200];
  const std::size_t n = clocks->processes.size();
  if (beyond > 0) {
    std::snprintf(text, sizeof text,
                  "clocks: %zu of %zu sensor processes off the fusion center's by more than %g ms "
                  "(the clock_offset fault above)",
                  beyond, n, 1e3 * clocks->bound_s);
  } else {
    std::snprintf(text, sizeof text,
                  "clocks: %zu sensor process%s measured against the fusion center's, all within "
                  "%.2g ms of it (the bound is %g ms)",
                  n, n == 1 ? "" : "es", 1e3 * within_s, 1e3 * clocks->bound_s);
  }
  return text;
}

// Two brackets of the report differ beyond their rounding (false when one is not there).
bool differs(const std::optional<BracketRecord>& a, const std::optional<BracketRecord>& b) {
  if (!a || !b || !a->info || !a->cov || !b->info || !b->cov) return false;
  return bracketsDiffer(*a->info, *a->cov, *b->info, *b->cov);
}

// What the schedule could deliver, when that is not what it planned (an emulated network's
// losses and outages, a dead sensor under --on-sensor-failure continue), else "".
std::string deliveredLine(const SummaryRecord& summary) {
  if (!differs(summary.delivered_bracket, summary.bracket)) return "";
  return "  against what the schedule delivered (network losses and outages, dead sensors): [" +
         shown(summary.delivered_bracket->info) + ", " + shown(summary.delivered_bracket->cov) +
         "]: meets_delivered_bracket " + meetsText(summary.meets_delivered_bracket);
}

// The real-time cost, when it differs from the realized one (measurements arrived late).
std::string realtimeLine(const SummaryRecord& summary) {
  if (!summary.realtime_mean || !summary.mean || *summary.realtime_mean == *summary.mean) return "";
  return "  real-time cost (the covariance of what had arrived by each instant): mean " +
         shown(summary.realtime_mean);
}

// "NEES: mean 4.1 in the 99.9% band [2.9, 5.3] of a consistent filter (n = 4, K = 20)", or
// its failure, which says what it means; "" when no NEES was measured.
std::string neesLine(const SummaryRecord& summary) {
  if (!summary.nees_consistent || !summary.nees_band_low || !summary.nees_band_high) return "";
  const std::string band = "[" + shown(summary.nees_band_low) + ", " +
                           shown(summary.nees_band_high) + "]";
  const double confidence = 100.0 * summary.nees_confidence.value_or(0.999);
  char percent[16];
  std::snprintf(percent, sizeof percent, "%.4g%%", confidence);
  if (*summary.nees_consistent) {
    return "NEES: mean " + shown(summary.nees_mean) + " in the " + percent + " band " + band +
           " of a consistent filter";
  }
  return "NEES: mean " + shown(summary.nees_mean) + " OUTSIDE the " + percent + " band " + band +
         " of a consistent filter: the estimates' errors do not match their covariance (are "
         "the measurements of the emulated plant? is R right?)";
}

std::string measurementsLine(const SummaryRecord& summary) {
  std::string line = "measurements: " + shown(summary.sent) + " sent, " +
                     shown(summary.received) + " received, ";
  if (summary.dropped_by_network > 0) {
    line += shown(summary.dropped_by_network) + " dropped by the emulated network, ";
  }
  if (summary.refused > 0) line += shown(summary.refused) + " refused (malformed), ";
  return line + shown(summary.lost) + " lost, " + shown(summary.rejected) + " rejected";
}

// The report as the launcher writes it: over the fusion center's file, atomically, with
// per_episode streamed in from the episode log when there is one.
void writeSettled(const RunEnd& end, const RunRecord& run, bool logged, const fs::path& path) {
  const json doc = report::encode(run);
  if (logged) {
    replaceFileAtomically(path, [&](std::ostream& out) {
      sensornet::report::writeReportWithLog(out, doc, sensornet::report::episodeLogPath(end.report_path), 2);
      out << '\n';
    });
  } else {
    replaceFileAtomically(path, doc.dump(2) + "\n");
  }
}

std::vector<fs::path> fallbackPaths(const RunEnd& end) {
  return report::fallbackReportPaths(end.report_path, end.run_id, end.fallback_dir);
}

// A file of the run was refused (write_failed): the episode log may lack episodes the report
// holds, so per_episode comes from the report itself.
bool someWriteFailed(const RunRecord& run) {
  return std::any_of(run.faults.begin(), run.faults.end(),
                     [](const FaultRecord& f) { return f.kind == emulator::FaultKind::WriteFailed; });
}

}  // namespace

RunOutcome settleRun(const RunEnd& end) {
  RunOutcome outcome;
  ReportSeen seen;
  const fs::path log = sensornet::report::episodeLogPath(end.report_path);
  std::error_code missing;
  bool logged = fs::is_regular_file(log, missing);
  std::optional<RunRecord> read;
  if (end.external_fusion_center) {  // no process of ours wrote one: the Reports make it
    read = externalReport(end, logged);
    seen.readable = true;
    outcome.amended = true;
  } else {
    read = readRunReport(end.report_path, end.run_id, logged, seen.problem);
    fs::path read_from = end.report_path;
    for (const fs::path& elsewhere : fallbackPaths(end)) {  // where a full disk made it go
      std::string ignored;
      if (read || !fs::is_regular_file(elsewhere, missing)) continue;
      read = readRunReport(elsewhere, end.run_id, false, ignored);
      if (read) {
        read_from = elsewhere;
        outcome.written_to = elsewhere;
        outcome.write_problem = "the fusion center's write_failed fault says why";
      }
    }
    if (read && logged && someWriteFailed(*read)) {
      std::string ignored;
      if (auto whole = readRunReport(read_from, end.run_id, false, ignored)) {
        read = std::move(whole);
        logged = false;
      }
    }
    seen.readable = read.has_value();
    if (!read) {
      read = rebuildReport(end, logged);
      outcome.rebuilt = true;
    }
  }
  RunRecord& run = *read;
  seen.status = std::string(wordOf(run.status));
  seen.finished_episodes = run.finishedEpisodes();
  seen.complete_episodes = run.summary.episodes_complete;
  seen.lost = run.summary.lost;
  const Verdict verdict = decideVerdict(end.faults, end.interrupted, seen, end.episodes_planned);
  outcome.status = verdict.status;
  outcome.exit_code = exitCodeOf(verdict.status);
  outcome.amended = outcome.amended || outcome.rebuilt || verdict.status != run.status ||
                    !verdict.faults.empty();
  if (outcome.amended) {
    run.status = verdict.status;
    // The launcher's causes first: what the other processes saw of them follows, marked.
    run.faults = faultList(verdict.faults, run.faults);
  }
  // The fusion center learns the planned count from the first episode's start: a run that
  // ended before one says 0. What the launch asked for is the plan.
  if (!run.episodes_planned || *run.episodes_planned < 1) {
    run.episodes_planned = static_cast<std::uint64_t>(end.episodes_planned);
    outcome.amended = true;
  }
  if (!end.external_sensors.empty() || end.external_fusion_center) {
    run.external = report::ExternalRoles{end.external_sensors, end.external_fusion_center};
    outcome.amended = true;
  }
  if (!end.reference_report.empty()) {
    run.other["reference_fusion"] = referenceComparison(end);
    outcome.amended = true;
  }
  if (!end.requirements.empty()) {  // against the settled report: its status and faults
    outcome.checks = sensornet::report::checkRequirements(end.requirements, run);
    run.other["requirements"] = sensornet::report::toJson(outcome.checks);
    outcome.exit_code = sensornet::report::gatedExitCode(outcome.exit_code, outcome.checks);
    outcome.amended = true;
  }
  if (outcome.amended) {
    try {
      writeSettled(end, run, logged, end.report_path);
    } catch (const std::exception& e) {
      // Nothing the run measured is lost for a full disk there: the report goes elsewhere.
      outcome.write_problem = e.what();
      outcome.written_to.reset();
      for (const fs::path& elsewhere : fallbackPaths(end)) {
        try {
          writeSettled(end, run, logged, elsewhere);
          outcome.written_to = elsewhere;
          break;
        } catch (const std::exception& again) {
          *outcome.write_problem += std::string("; nor ") + again.what();
        }
      }
    }
  }
  outcome.report = std::move(run);
  return outcome;
}

void printOutcome(const RunOutcome& outcome, const fs::path& report_path) {
  const RunRecord& run = outcome.report;
  const SummaryRecord& summary = run.summary;
  const std::size_t causes = run.causeCount();
  std::printf("run %s: %s (%zu fault%s)\n", run.run_id.c_str(),
              std::string(wordOf(outcome.status)).c_str(), causes, causes == 1 ? "" : "s");
  for (const FaultRecord& fault : run.faults) {
    if (fault.isConsequence()) continue;
    std::printf("  fault: %s%s\n", faultLine(fault).c_str(),
                consequencesOf(fault, run.faults).c_str());
  }
  std::printf("episodes: %llu complete, %llu incomplete, of %s planned\n",
              static_cast<unsigned long long>(summary.episodes_complete),
              static_cast<unsigned long long>(summary.episodes_incomplete),
              run.episodes_planned ? std::to_string(*run.episodes_planned).c_str() : "n/a");
  std::string interval = "(one complete episode: no 95% interval)";  // ci95 needs two
  if (summary.ci95) {
    interval = "\u00b1 " + shown(summary.ci95) + " (95%: [" + shown(summary.ci95_low) + ", " +
               shown(summary.ci95_high) + "])";
  }
  if (summary.mean) {
    const std::optional<BracketRecord>& bracket = summary.bracket;
    std::printf(
        "realized cost over complete episodes: mean %s %s against the bracket [%s, %s]: "
        "meets_bracket %s\n",
        shown(summary.mean).c_str(), interval.c_str(),
        shown(bracket ? bracket->info : std::nullopt).c_str(),
        shown(bracket ? bracket->cov : std::nullopt).c_str(),
        meetsText(summary.meets_bracket).c_str());
    if (const std::string line = deliveredLine(summary); !line.empty()) {
      std::printf("%s\n", line.c_str());
    }
    if (const std::string line = realtimeLine(summary); !line.empty()) {
      std::printf("%s\n", line.c_str());
    }
  } else {
    std::printf("realized cost: not measured (no complete episode)\n");
  }
  if (const std::string line = neesLine(summary); !line.empty()) std::printf("%s\n", line.c_str());
  std::printf("%s\n", arrivalsLine(run.arrivals, outcome.rebuilt).c_str());
  std::printf("%s\n", measurementsLine(summary).c_str());
  const auto ms = [](std::optional<double> seconds) {
    return seconds ? std::optional<double>(1e3 * *seconds) : std::nullopt;
  };
  const std::optional<double> delay_max = run.network_delay_s ? run.network_delay_s->max : std::nullopt;
  const bool delayed = delay_max && *delay_max > 0.0;
  const char* which = delayed ? " (the middleware's, without the emulated network's delay)" : "";
  if (run.latency_s && run.latency_s->unknown_because) {
    std::printf("latency publish-to-fusion: not known (%s)\n", run.latency_s->unknown_because->c_str());
  } else if (run.latency_s && run.latency_s->median) {
    std::printf("latency publish-to-fusion%s: median %s ms, p99 %s ms\n", which,
                shown(ms(run.latency_s->median)).c_str(), shown(ms(run.latency_s->p99)).c_str());
  } else {
    // Only a report of the fusion center's own keeps latencies: say why there are none.
    const char* why = run.external && run.external->fusion_center
                          ? "not reported by the external fusion center"
                      : outcome.rebuilt
                          ? "not known (the fusion center wrote no report, and the episode log "
                            "it was rebuilt from keeps no latencies)"
                      : summary.received > 0 ? "not reported"
                                             : "not measured (no measurement arrived)";
    std::printf("latency publish-to-fusion: %s\n", why);
  }
  if (const std::string line = clocksLine(run.clocks); !line.empty()) std::printf("%s\n", line.c_str());
  if (delayed) {
    std::printf("emulated network delay: mean %s ms, largest %s ms (emulated time)\n",
                shown(ms(run.network_delay_s->mean)).c_str(), shown(ms(delay_max)).c_str());
  }
  for (const sensornet::report::RequirementCheck& check : outcome.checks) {
    std::printf("%s\n", sensornet::report::describe(check).c_str());
  }
  if (outcome.written_to) {
    std::printf("report: %s%s, not at its path (%s)\n", outcome.written_to->c_str(),
                outcome.rebuilt ? " (rebuilt from the episode log)" : "",
                outcome.write_problem->c_str());
  } else if (outcome.write_problem) {
    std::printf("report: NOT WRITTEN: %s\n", outcome.write_problem->c_str());
  } else {
    std::printf("report: %s%s\n", report_path.c_str(),
                outcome.rebuilt ? " (rebuilt from the episode log)" : "");
  }
  std::printf("exit code %d\n", outcome.exit_code);
  std::fflush(stdout);
}

void printOutcomeJson(const RunOutcome& outcome, const fs::path& report_path) {
  const RunRecord& run = outcome.report;
  json line = report::encode(run.summary);
  line["run_id"] = run.run_id;
  line["status"] = std::string(wordOf(outcome.status));
  line["faults"] = report::encode(run.faults);
  line["episodes"] = run.episodes ? json(*run.episodes) : json();
  line["episodes_planned"] = run.episodes_planned ? json(*run.episodes_planned) : json();
  line["arrivals"] = run.arrivals ? json({{"mode", run.arrivals->mode},
                                          {"bracket_note", run.arrivals->bracket_note}})
                                  : json();
  line["report"] = outcome.written_to.value_or(report_path).string();
  if (outcome.rebuilt && run.rebuilt_from) line["rebuilt_from"] = *run.rebuilt_from;
  if (outcome.write_problem) line["report_error"] = *outcome.write_problem;
  if (!outcome.checks.empty()) line["requirements"] = sensornet::report::toJson(outcome.checks);
  line["exit_code"] = outcome.exit_code;
  printJson(line);
}

}  // namespace sensornet::launcher
