#include "invariants.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <set>
#include <sstream>

#include "sensornet/report/fault_causes.hpp"

namespace sensornet::chaos {
namespace {

using nlohmann::json;

constexpr double kCostRelTolerance = 1e-9;
// A stop longer than this may exceed the stall limits (10 s absorbed, 12 s stall limit): what
// follows it is not held to "nothing lost".
constexpr double kAbsorbedStopS = 9.0;
// Two run-ending faults this close together may each be the one the launcher saw first.
constexpr double kTerminalRaceS = 3.0;

std::string num(double x) {
  char text[32];
  std::snprintf(text, sizeof text, "%.17g", x);
  return text;
}

bool near(double a, double b, double rel) {
  return std::abs(a - b) <= rel * std::max({std::abs(a), std::abs(b), 1e-12});
}

enum class Terminal { None, Interrupted, LauncherKilled, Failed };

Terminal terminalOf(const InjectedFault& f, const std::string& policy) {
  if (!f.injected) return Terminal::None;
  const PlannedFault& p = f.planned;
  if (p.target == Target::Launcher) {
    if (p.action == Action::Interrupt || p.action == Action::Terminate) return Terminal::Interrupted;
    if (p.action == Action::Kill) return Terminal::LauncherKilled;
  }
  if (p.target == Target::SensorAgent && p.action == Action::Kill && policy == "stop") {
    return Terminal::Failed;
  }
  return Terminal::None;
}

// Injected faults in the order they struck.
std::vector<const InjectedFault*> struck(const TrialRecord& r) {
  std::vector<const InjectedFault*> out;
  for (const InjectedFault& f : r.faults) {
    if (f.injected) out.push_back(&f);
  }
  std::stable_sort(out.begin(), out.end(),
                   [](const InjectedFault* a, const InjectedFault* b) { return a->at_s < b->at_s; });
  return out;
}

// When the first run-ending fault struck (infinity: none did).
double firstTerminalAt(const TrialRecord& r) {
  for (const InjectedFault* f : struck(r)) {
    if (terminalOf(*f, r.trial.policy) != Terminal::None) return f->at_s;
  }
  return std::numeric_limits<double>::infinity();
}

bool injectedAny(const TrialRecord& r, Target target, Action action) {
  return std::any_of(r.faults.begin(), r.faults.end(), [&](const InjectedFault& f) {
    return f.injected && f.planned.target == target && f.planned.action == action;
  });
}

std::set<int> killedSensors(const TrialRecord& r) {
  std::set<int> sensors;
  for (const InjectedFault& f : r.faults) {
    if (f.injected && f.planned.target == Target::SensorAgent && f.planned.action == Action::Kill) {
      sensors.insert(f.agent);
    }
  }
  return sensors;
}

// A process stopped, or a sensor host cut off from the fusion center, for longer than the
// stall limits absorb.
bool silences(const PlannedFault& p) {
  return p.action == Action::Stop || p.action == Action::CutLink || p.action == Action::FusionDeaf ||
         p.action == Action::HostDeaf;
}

// Silences that overlap or follow within a second count as one, whatever they struck: a cut of
// 8 s lengthened by another of 8 s is a silence of up to 16 s.
bool longSilence(const TrialRecord& r) {
  std::vector<std::pair<double, double>> spans;
  for (const InjectedFault& f : r.faults) {
    if (f.injected && silences(f.planned)) spans.emplace_back(f.at_s, f.at_s + f.planned.length_s);
  }
  std::sort(spans.begin(), spans.end());
  for (std::size_t i = 0; i < spans.size();) {
    double end = spans[i].second;
    std::size_t k = i + 1;
    while (k < spans.size() && spans[k].first <= end + 1.0) end = std::max(end, spans[k++].second);
    if (end - spans[i].first > kAbsorbedStopS) return true;
    i = k;
  }
  return false;
}

// The whole lines of the episode log; a line that is not a JSON object is a violation.
std::vector<json> logLines(const std::string& text, std::vector<std::string>& violations) {
  std::vector<json> lines;
  std::size_t start = 0;
  std::size_t number = 0;
  while (start < text.size()) {
    std::size_t end = text.find('\n', start);
    const bool torn = end == std::string::npos;
    if (torn) end = text.size();
    ++number;
    const std::string line = text.substr(start, end - start);
    json parsed = json::parse(line, nullptr, false);
    if (torn || !parsed.is_object()) {
      violations.push_back("episode log: line " + std::to_string(number) + " is not a whole JSON " +
                           "object (" + std::to_string(line.size()) + " bytes" +
                           (torn ? ", no newline" : "") + ")");
    } else {
      lines.push_back(std::move(parsed));
    }
    start = end + 1;
  }
  return lines;
}

std::uint64_t at(const json& list, std::size_t j) {
  return list.is_array() && j < list.size() && list[j].is_number_unsigned() ? list[j].get<std::uint64_t>()
                                                                             : 0;
}

void checkAccounting(const json& per_episode, std::vector<std::string>& v) {
  for (const json& e : per_episode) {
    const json& sent = e.value("sent", json());
    for (std::size_t j = 0; sent.is_array() && j < sent.size(); ++j) {
      const std::uint64_t s = at(sent, j), rec = at(field(e, "received"), j), lost = at(field(e, "lost"), j),
                          dropped = at(field(e, "dropped_by_network"), j),
                          refused = at(e.value("refused", json()), j);
      if (s != rec + lost + dropped + refused) {
        v.push_back("accounting: episode " + field(e, "episode").dump() + " sensor " + std::to_string(j) +
                    ": sent " + std::to_string(s) + " != received " + std::to_string(rec) +
                    " + lost " + std::to_string(lost) + " + dropped " + std::to_string(dropped) +
                    " + refused " + std::to_string(refused));
      }
    }
  }
}

void checkSummary(const json& report, std::vector<std::string>& v) {
  const json& per_episode = field(report, "per_episode");
  const json& s = field(report, "summary");
  std::vector<double> costs;
  std::uint64_t sent = 0, received = 0, lost = 0;
  std::size_t incomplete = 0;
  for (const json& e : per_episode) {
    if (e.value("complete", false) && field(e, "realized_cost").is_number()) {
      costs.push_back(field(e, "realized_cost").get<double>());
    } else {
      ++incomplete;
    }
    for (std::size_t j = 0; field(e, "sent").is_array() && j < field(e, "sent").size(); ++j) {
      sent += at(field(e, "sent"), j);
      received += at(field(e, "received"), j);
      lost += at(field(e, "lost"), j);
    }
  }
  const auto expectCount = [&](const char* key, std::uint64_t want) {
    if (!s.contains(key) || !s[key].is_number_unsigned() || s[key].get<std::uint64_t>() != want) {
      v.push_back(std::string("summary: ") + key + " " + (s.contains(key) ? s[key].dump() : "missing") +
                  ", recomputed " + std::to_string(want));
    }
  };
  expectCount("episodes_complete", costs.size());
  expectCount("episodes_incomplete", incomplete);
  expectCount("sent", sent);
  expectCount("received", received);
  expectCount("lost", lost);
  if (costs.empty()) {
    if (!field(s, "mean").is_null()) v.push_back("summary: mean " + field(s, "mean").dump() + " without a complete episode");
    return;
  }
  double mean = 0.0;
  for (const double c : costs) mean += c;
  mean /= static_cast<double>(costs.size());
  if (!field(s, "mean").is_number() || !near(field(s, "mean").get<double>(), mean, kCostRelTolerance)) {
    v.push_back("summary: mean " + field(s, "mean").dump() + ", recomputed " + num(mean));
  }
  if (costs.size() >= 2) {
    double ss = 0.0;
    for (const double c : costs) ss += (c - mean) * (c - mean);
    const double sd = std::sqrt(ss / static_cast<double>(costs.size() - 1));
    if (!field(s, "std").is_number() || !near(field(s, "std").get<double>(), sd, 1e-7)) {
      v.push_back("summary: std " + field(s, "std").dump() + ", recomputed " + num(sd));
    }
  }
}

void checkLogAgainstReport(const std::vector<json>& lines, const json& per_episode,
                           std::vector<std::string>& v) {
  std::map<std::int64_t, const json*> logged;
  for (const json& line : lines) {
    const std::int64_t k = line.value("episode", std::int64_t{-1});
    if (!logged.emplace(k, &line).second) {
      v.push_back("episode log: episode " + std::to_string(k) + " logged twice");
    }
  }
  std::set<std::int64_t> reported;
  for (const json& e : per_episode) {
    const std::int64_t k = e.value("episode", std::int64_t{-1});
    if (!reported.insert(k).second) {
      v.push_back("report: episode " + std::to_string(k) + " twice in per_episode");
    }
    const auto it = logged.find(k);
    if (it == logged.end()) {
      v.push_back("episode log: episode " + std::to_string(k) + " of per_episode not logged");
    } else if (*it->second != e) {
      v.push_back("episode log: episode " + std::to_string(k) + " differs from per_episode");
    }
  }
  for (const auto& [k, line] : logged) {
    if (reported.count(k) == 0) {
      v.push_back("episode log: episode " + std::to_string(k) + " logged but not in per_episode");
    }
  }
}

// The complete episodes the faults cannot change equal the clean run's (docs/guide/first-run.md: the same seed
// gives the same realized costs; stalls and restarts change nothing; a death changes what
// follows it).
void checkCosts(const TrialRecord& r, const json& per_episode, std::vector<std::string>& v) {
  std::size_t limit = std::numeric_limits<std::size_t>::max();
  for (const InjectedFault& f : r.faults) {
    if (f.injected && f.planned.target == Target::SensorAgent && f.planned.action == Action::Kill) {
      limit = std::min(limit, f.logged_before);
    }
  }
  for (const json& e : per_episode) {
    if (!e.value("complete", false) || !field(e, "realized_cost").is_number()) continue;
    const auto k = e.value("episode", std::size_t{0});
    if (k >= limit || k >= r.clean_costs.size() || !r.clean_costs[k]) continue;
    const double cost = field(e, "realized_cost").get<double>();
    if (!near(cost, *r.clean_costs[k], kCostRelTolerance)) {
      v.push_back("cost: episode " + std::to_string(k) + " realized " + num(cost) +
                  ", clean run " + num(*r.clean_costs[k]));
    }
  }
  // One version without a death; none only when no episode ran (a run stopped before the
  // coordinator's schedule reached the fusion center).
  const auto ran = [&r] {
    const json& episodes = field((*r.report), "per_episode");
    return episodes.is_array() && !episodes.empty();
  };
  const auto versions = [&r] { return field((*r.report), "schedule_versions").size(); };
  if (limit == std::numeric_limits<std::size_t>::max() && r.report &&
      field((*r.report), "schedule_versions").is_array() &&
      (versions() > 1 || (versions() == 0 && ran()))) {
    v.push_back("schedule: " + std::to_string(field((*r.report), "schedule_versions").size()) +
                " versions without a sensor death");
  }
}

// Each part of an incomplete reason names what made the episode incomplete; each must follow
// from something injected.
bool explained(const TrialRecord& r, const std::string& reason, double first_terminal_at) {
  if (reason == "fusion_center_restarted") {
    return injectedAny(r, Target::FusionCenter, Action::Kill);
  }
  if (reason.rfind("cut short", 0) == 0) return first_terminal_at < 1e300;
  if (longSilence(r)) return true;
  const std::set<int> killed = killedSensors(r);
  // A sensor whose host's clock is ahead begins each episode that much early (by the fusion
  // center's clock): after a restart of the fusion center it may publish the first samples of
  // an episode before the new one matched its writer, and those are lost (seed 435: a host
  // 1.02 s ahead). The report names the loss, the restart and the clock.
  std::set<int> ahead;
  if (injectedAny(r, Target::FusionCenter, Action::Kill)) {
    for (const InjectedFault& f : r.faults) {
      if (!f.injected || !isClockFault(f.planned.action) || f.planned.clock_s <= 0.0) continue;
      for (int j = 0; j < r.trial.sensors; ++j) {
        if (hostOf(r.trial, j) == f.planned.host) ahead.insert(j);
      }
    }
  }
  std::istringstream parts(reason);
  std::string part;
  while (std::getline(parts, part, ';')) {
    while (!part.empty() && part.front() == ' ') part.erase(part.begin());
    int sensor = -1;
    if (std::sscanf(part.c_str(), "sensor %d", &sensor) != 1) return false;
    if (killed.count(sensor) == 0 && ahead.count(sensor) == 0) return false;
  }
  return true;
}

void checkIncomplete(const TrialRecord& r, const json& per_episode, std::vector<std::string>& v) {
  const double first_terminal_at = firstTerminalAt(r);
  if (first_terminal_at < 1e300 && r.exit_code == 128 + 9) return;  // everything cut
  for (const json& e : per_episode) {
    if (e.value("complete", false)) continue;
    const std::string reason = field(e, "incomplete_reason").is_string() ? field(e, "incomplete_reason").get<std::string>() : "";
    if (!explained(r, reason, first_terminal_at)) {
      v.push_back("incomplete: episode " + field(e, "episode").dump() + " (" + reason +
                  ") follows from no injected fault");
    }
  }
}

void checkDeathsListed(const TrialRecord& r, const json& report, std::vector<std::string>& v) {
  const double first_terminal_at = firstTerminalAt(r);
  std::map<std::string, int> killed;  // process name prefix -> injected kills before the end
  for (const InjectedFault& f : r.faults) {
    if (!f.injected || f.planned.action != Action::Kill || f.planned.target == Target::Launcher ||
        f.at_s >= first_terminal_at) {
      continue;
    }
    const std::string name = f.planned.target == Target::SensorAgent
                                 ? "sensor_agent-" + std::to_string(f.agent)
                                 : nameOf(f.planned.target);
    ++killed[name];
  }
  for (const auto& [name, count] : killed) {
    int listed = 0;
    for (const json& fault : field(report, "faults")) {
      if (fault.value("kind", "") == "process_killed" && fault.value("process", "") == name) ++listed;
    }
    if (listed < count) {
      v.push_back("faults: " + std::to_string(count) + " kill(s) of " + name + ", " +
                  std::to_string(listed) + " process_killed entries");
    }
  }
}

bool networkOnly(const TrialRecord& r) {
  const std::vector<const InjectedFault*> order = struck(r);
  return !order.empty() && std::all_of(order.begin(), order.end(), [](const InjectedFault* f) {
           return isNetworkFault(f->planned.action);
         });
}

// Only the network was faulted: what the report blames is the network (a network_partition),
// never a consequence of it standing as a cause (a stall of the sensors it cut off, an overload).
// Only when each silence healed while the run went on (2 s before the launcher ended, and
// before the fusion center wrote its report: the launcher may wait on after it for agents the
// cut keeps from hearing the end, seed 4035): a partition the run ends in leaves nothing that
// tells it from silent sensors.
void checkNetworkNamed(const TrialRecord& r, const json& report, std::vector<std::string>& v) {
  if (!networkOnly(r) || !field(report, "faults").is_array()) return;
  double run_went_on_until_s = r.ended_at_s - 2.0;
  if (r.report_written_at_s >= 0.0) run_went_on_until_s = std::min(run_went_on_until_s, r.report_written_at_s - 2.0);
  for (const InjectedFault& f : r.faults) {
    if (f.injected && silences(f.planned) && (f.healed_at_s < 0.0 || f.healed_at_s > run_went_on_until_s)) {
      return;
    }
  }
  for (const json& fault : field(report, "faults")) {
    if (sensornet::report::isConsequence(fault) || fault.value("kind", "") == "network_partition") continue;
    v.push_back("cause: only the network was faulted, and the report blames " + fault.value("kind", "?") +
                " in " + fault.value("process", "?") + ": " + fault.value("detail", "").substr(0, 160));
  }
}

// Clocks (a sensor host's under libfaketime, off from the start or stepped mid-run). Measured
// both ways (the report's `clocks`): every process's offset is one its host's clock had (0
// before a step, the step's after it) within the uncertainty it states (+5 ms: faketime re-reads
// its file each second, and a step between t2 and t3 shows as half a step); a host off from the
// start by more than the bound plus what a process's measurement can tell is named by a
// clock_offset fault, however the fusion center lived (a restarted one measures afresh), unless
// the report was rebuilt without its faults or the launcher was killed. A clock_offset fault
// names only sensors of hosts whose clock was put off; by the one-way test (a process that never
// answered), by no more than the host was put ahead. With a fault, the latency figures are not
// given.
void checkClocks(const TrialRecord& r, const json& report, std::vector<std::string>& v) {
  constexpr double kSlackS = 0.005;
  std::map<int, std::set<double>> had;  // sensor host -> the offsets its clock had
  std::map<int, double> from_start;
  for (const InjectedFault& f : r.faults) {
    if (!f.injected || !isClockFault(f.planned.action)) continue;
    had[f.planned.host].insert(f.planned.clock_s);
    if (f.planned.action == Action::ClockOffset) {
      from_start[f.planned.host] = f.planned.clock_s;
    } else if (from_start.count(f.planned.host) == 0) {
      had[f.planned.host].insert(0.0);
    }
  }
  const auto offsetsOf = [&had](int host) { return had.count(host) > 0 ? had.at(host) : std::set<double>{0.0}; };
  const auto near = [&](int host, double offset, double uncertainty) {
    for (const double put : offsetsOf(host)) {
      if (std::abs(offset - put) <= uncertainty + kSlackS) return true;
    }
    return false;
  };
  const json& clocks = field(report, "clocks");
  const double bound = clocks.is_object() ? clocks.value("bound_s", 1e-3) : 1e-3;
  std::set<int> measured_hosts;
  std::map<int, double> best_uncertainty;  // host -> the least uncertainty of its processes
  for (const json& p : clocks.is_object() ? field(clocks, "processes") : json::array()) {
    if (!field(p, "sensors").is_array() || field(p, "sensors").empty()) continue;
    const int host = hostOf(r.trial, field(p, "sensors")[0].get<int>());
    measured_hosts.insert(host);
    const double u = p.value("uncertainty_s", 0.0);
    best_uncertainty[host] = best_uncertainty.count(host) > 0 ? std::min(best_uncertainty[host], u) : u;
    for (const char* which : {"offset_s", "farthest_offset_s"}) {
      const double offset = p.value(which, 0.0);
      const double uncertainty = p.value(std::string(which) == "offset_s" ? "uncertainty_s" : "farthest_uncertainty_s", 0.0);
      if (!near(host, offset, uncertainty)) {
        v.push_back("clock: " + p.value("process", "?") + " measured " + num(offset) + " +/- " + num(uncertainty) +
                    " s off (" + which + "), its host's clock was not");
      }
    }
  }
  bool named_any = false;
  std::set<int> named_hosts;
  for (const json& fault : field(report, "faults")) {
    if (fault.value("kind", "") != "clock_offset") continue;
    named_any = true;
    const std::string detail = fault.value("detail", "");
    double least = 0.0;  // the one-way figure, when there is one: a lower bound of the offset
    const std::size_t at = detail.find("by at least ");
    if (at != std::string::npos && std::sscanf(detail.c_str() + at + 12, "%lf", &least) != 1) least = 0.0;
    for (const json& j : fault.value("sensors", json::array())) {
      const int host = hostOf(r.trial, j.get<int>());
      const std::set<double> put = offsetsOf(host);
      const double most_ahead = *put.rbegin();
      if (put == std::set<double>{0.0}) {
        v.push_back("clock: clock_offset names sensor " + j.dump() + ", whose host's clock was not put off");
      } else if (measured_hosts.count(host) == 0 && least > most_ahead + kSlackS) {
        v.push_back("clock: clock_offset says at least " + num(least) + " s ahead, the clock was put " +
                    num(most_ahead) + " s ahead at most");
      } else {
        named_hosts.insert(host);
      }
    }
  }
  const json& latency = field(report, "latency_s");
  if (named_any && latency.is_object() && !field(latency, "median").is_null()) {
    v.push_back("clock: a clock_offset fault, and the latency median " + field(latency, "median").dump() + " is given");
  }
  const bool rebuilt = std::any_of(field(report, "faults").begin(), field(report, "faults").end(), [](const json& f) {
    return f.value("kind", "") == "report_missing" || f.value("kind", "") == "report_invalid";
  });
  if (rebuilt || r.exit_code == 128 + 9) return;
  for (const auto& [host, clock_s] : from_start) {
    if (named_hosts.count(host) > 0 || measured_hosts.count(host) == 0) continue;
    if (std::abs(clock_s) - best_uncertainty[host] - kSlackS <= bound) continue;
    v.push_back("clock: edge-" + std::to_string(host + 1) + "'s clock was " + num(clock_s) +
                " s off from the start and measured so, but no clock_offset fault names it");
  }
}

}  // namespace

const json& field(const json& object, std::string_view key) {
  static const json kNull;
  if (!object.is_object()) return kNull;
  const auto it = object.find(key);
  return it == object.end() ? kNull : *it;
}

ExpectedOutcome expectedOutcome(const TrialRecord& r) {
  ExpectedOutcome out;
  const std::vector<const InjectedFault*> order = struck(r);
  double first = std::numeric_limits<double>::infinity();
  std::set<Terminal> terminals;
  for (const InjectedFault* f : order) {
    const Terminal t = terminalOf(*f, r.trial.policy);
    if (t == Terminal::None) continue;
    if (first == std::numeric_limits<double>::infinity()) first = f->at_s;
    if (f->at_s <= first + kTerminalRaceS) terminals.insert(t);
  }
  if (!terminals.empty()) {
    if (terminals.count(Terminal::LauncherKilled) > 0) {
      out.exit_codes.push_back(128 + 9);
      out.why = "the launcher was killed";
      if (terminals.size() == 1) return out;
    }
    out.exit_codes.push_back(1);
    if (terminals.count(Terminal::Interrupted) > 0) out.statuses.push_back("interrupted");
    if (terminals.count(Terminal::Failed) > 0) out.statuses.push_back("failed");
    out.why += out.why.empty() ? "" : " or ";
    out.why += terminals.count(Terminal::Failed) > 0 ? "a sensor died under stop" : "a signal";
    if (terminals.count(Terminal::LauncherKilled) > 0) out.statuses.clear();
    return out;
  }
  const bool death = std::any_of(order.begin(), order.end(), [](const InjectedFault* f) {
    return f->planned.action == Action::Kill;
  });
  const bool network_only = networkOnly(r);
  if (death) {
    out.exit_codes = {3};
    out.statuses = {"degraded"};
    out.why = "a death the run survives";
  } else if (network_only && !longSilence(r)) {
    // A partition, loss or reordering within the stall limit loses nothing: a stall, not an
    // overload nor a death (docs/ARCHITECTURE.md, "Stalls and deaths").
    out.exit_codes = {0};
    out.statuses = {"completed"};
    out.why = "network faults within the stall limit";
  } else {
    out.exit_codes = {0, 3};
    out.statuses = {"completed", "degraded"};
    out.why = "stalls only";
  }
  return out;
}

std::vector<std::string> checkInvariants(const TrialRecord& r) {
  std::vector<std::string> v;
  if (!r.ended) v.push_back("the launcher did not end within the trial's limit");
  const ExpectedOutcome want = expectedOutcome(r);
  const bool launcher_killed = r.exit_code == 128 + 9;
  if (std::find(want.exit_codes.begin(), want.exit_codes.end(), r.exit_code) == want.exit_codes.end()) {
    std::string codes;
    for (const int c : want.exit_codes) codes += (codes.empty() ? "" : " or ") + std::to_string(c);
    v.push_back("exit code " + std::to_string(r.exit_code) + ", expected " + codes + " (" + want.why + ")");
  }
  for (const std::string& leftover : r.leftovers) v.push_back("left running: " + leftover);

  std::vector<json> lines = logLines(r.episode_log, v);
  if (!r.report) {
    if (!launcher_killed || r.report_exists) {
      v.push_back(r.report_exists ? "report: not a JSON object" : "report: missing");
    }
    return v;
  }
  const json& report = *r.report;
  const std::string status = report.value("status", "");
  if (!launcher_killed) {
    if (!want.statuses.empty() &&
        std::find(want.statuses.begin(), want.statuses.end(), status) == want.statuses.end()) {
      v.push_back("status " + status + " (" + want.why + ")");
    }
    const int table = status == "completed" ? 0 : status == "degraded" ? 3 : 1;
    if (r.exit_code != table) {
      v.push_back("exit code " + std::to_string(r.exit_code) + " with status " + status);
    }
    if (status != "completed" && sensornet::report::causeCount(field(report, "faults")) == 0) {
      v.push_back("cause: status " + status + " with no fault that is not a consequence");
    }
    checkDeathsListed(r, report, v);
    checkNetworkNamed(r, report, v);
    checkClocks(r, report, v);
  }
  const json& per_episode = field(report, "per_episode");
  if (!per_episode.is_array()) {
    v.push_back("report: no per_episode");
    return v;
  }
  checkAccounting(per_episode, v);
  checkSummary(report, v);
  checkLogAgainstReport(lines, per_episode, v);
  checkCosts(r, per_episode, v);
  checkIncomplete(r, per_episode, v);
  return v;
}

}  // namespace sensornet::chaos
