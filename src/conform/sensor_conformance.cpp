#include "sensornet/conform/sensor_conformance.hpp"

#include <fmt/format.h>

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>
#include <set>

#include "rules.hpp"
#include "sensornet/core/chi_square.hpp"
#include "sensornet/emulator/sensor_timeline.hpp"
#include "sensornet/report/junit_report.hpp"

namespace sensornet::conform {
namespace detail {

RuleCheck rule(std::string id, std::string statement, std::string section) {
  return {std::move(id), std::move(statement), false, "",
          "docs/wire-protocol.md#" + std::move(section)};
}

double secondsSince(std::int64_t from_ns, std::int64_t ns) {
  return 1e-9 * static_cast<double>(ns - from_ns);
}

std::string plural(std::size_t n, const char* one, const char* many) {
  return std::to_string(n) + " " + (n == 1 ? one : many);
}

std::string programEnding(const RunFacts& facts) {
  if (!facts.program_end.empty()) return facts.program_end;
  return facts.program_exit ? "exited with status " + std::to_string(*facts.program_exit)
                            : std::string("ended by a signal");
}

RuleCheck runCompletes(const RunFacts& facts) {
  RuleCheck r = rule("run", "the run completes with it in the role (status completed, exit 0)",
                     "an-episodes-life");
  if (!facts.report) {
    r.evidence = "no report; the launcher exited " + std::to_string(facts.launcher_exit);
    return r;
  }
  r.pass = facts.launcher_exit == 0 && facts.report->status == emulator::RunStatus::Completed;
  r.evidence =
      fmt::format("status {}, exit {}, {}", wordOf(facts.report->status), facts.launcher_exit,
                  plural(facts.report->faults.size(), "fault", "faults"));
  if (!facts.report->faults.empty()) {
    const report::FaultRecord& f = facts.report->faults.front();
    r.evidence += fmt::format(" (first: {}: {})", wordOf(f.kind), f.detail);
  }
  return r;
}

RuleCheck truth(const RunFacts& facts) {
  RuleCheck r =
      rule("truth", "measures the plant's truth: the run's mean NEES lies in its chi-square band",
           "the-emulated-world");
  const report::SummaryRecord* s = facts.report ? &facts.report->summary : nullptr;
  if (s == nullptr || !s->nees_consistent || !s->nees_mean || !s->nees_band_low ||
      !s->nees_band_high) {
    r.evidence = "no NEES measured (no complete episode)";
    return r;
  }
  r.pass = *s->nees_consistent;
  r.evidence = fmt::format("mean NEES {:.3f} {} the {:g}% band [{:.3f}, {:.3f}]", *s->nees_mean,
                           r.pass ? "in" : "OUTSIDE", 100.0 * s->nees_confidence.value_or(0.0),
                           *s->nees_band_low, *s->nees_band_high);
  return r;
}

std::vector<std::uint32_t> startedEpisodes(const RecordedRun& run) {
  std::vector<std::uint32_t> episodes;
  for (const auto& [k, start] : run.starts_ns) {
    if (!run.shutdown_ns || start < *run.shutdown_ns) episodes.push_back(k);
  }
  return episodes;
}

}  // namespace detail

namespace {

using namespace detail;

using emulator::SensorState;

// A sample's receipt may precede its wall instant by this much (the recorder's clock reading
// and the episode clock's rounding), not more.
constexpr double kEarlyToleranceS = 0.002;
// Below this many expected arrivals the Poisson law is not tested (the tests have no power).
constexpr double kFewestExpected = 10.0;

bool readyLike(SensorState s) {
  return s == SensorState::Ready || s == SensorState::Excluded || s == SensorState::Running;
}

RuleCheck readiness(const RecordedRun& run, const SensorTrace& trace) {
  RuleCheck r = rule("readiness",
                     "says SENSOR_READY (or EXCLUDED) holding a schedule version before the "
                     "first episode starts, and before any measurement",
                     "the-readiness-handshake");
  const auto ready = std::find_if(
      trace.statuses.begin(), trace.statuses.end(),
      [](const SensorTrace::Status& s) { return readyLike(s.state) && s.version >= 1; });
  if (ready == trace.statuses.end()) {
    r.evidence = "no READY status with a schedule version >= 1 (" +
                 plural(trace.statuses.size(), "status", "statuses") + " recorded)";
    return r;
  }
  const double ready_s = secondsSince(run.first_ns, ready->received_ns);
  r.evidence =
      fmt::format("{} (version {}) at +{:.3f} s", wordOf(ready->state), ready->version, ready_s);
  r.pass = true;
  if (!run.starts_ns.empty()) {
    const std::int64_t first_start = run.starts_ns.begin()->second;
    r.evidence += fmt::format("; episode {} starts at +{:.3f} s", run.starts_ns.begin()->first,
                              secondsSince(run.first_ns, first_start));
    r.pass = ready->received_ns <= first_start;
  }
  if (!trace.samples.empty() && trace.samples.front().received_ns < ready->received_ns) {
    r.pass = false;
    r.evidence += fmt::format("; a measurement came first, at +{:.3f} s",
                              secondsSince(run.first_ns, trace.samples.front().received_ns));
  }
  return r;
}

RuleCheck statusPeriod(const RecordedRun& run, const SensorTrace& trace) {
  RuleCheck r = rule(
      "status-period",
      fmt::format("writes a SensorStatus at least every {:g} s until it leaves", kStatusPeriodS),
      "sensorstatus-when-and-what");
  if (trace.statuses.empty()) {
    r.evidence = "no SensorStatus recorded";
    return r;
  }
  double largest = 0.0;
  std::int64_t largest_at = trace.statuses.front().received_ns;
  std::int64_t previous = trace.statuses.front().received_ns;
  bool stopped = false;
  for (const SensorTrace::Status& s : trace.statuses) {
    if (stopped) break;
    const double gap = secondsSince(previous, s.received_ns);
    if (gap > largest) {
      largest = gap;
      largest_at = previous;
    }
    previous = s.received_ns;
    stopped = s.state == SensorState::Stopped;
  }
  // Silent from its last status to the run's end: that gap counts too.
  if (!stopped && run.shutdown_ns && *run.shutdown_ns > previous) {
    const double gap = secondsSince(previous, *run.shutdown_ns);
    if (gap > largest) {
      largest = gap;
      largest_at = previous;
    }
  }
  const double limit = kStatusPeriodS + kStatusSlackS;
  r.pass = largest <= limit;
  r.evidence = fmt::format("{}; the longest silence {:.3f} s from +{:.3f} s (allowed {:g} s)",
                           plural(trace.statuses.size(), "status", "statuses"), largest,
                           secondsSince(run.first_ns, largest_at), limit);
  return r;
}

RuleCheck leaving(const RecordedRun& run, const SensorTrace& trace, const RunFacts& facts) {
  RuleCheck r =
      rule("leaving", "on RUN_SHUTDOWN says SENSOR_STOPPED, then leaves by itself with exit 0",
           "leaving-the-run");
  if (!run.shutdown_ns) {
    r.evidence = "the run recorded no RUN_SHUTDOWN";
    return r;
  }
  // By when each was written: the recorder may get the sensor's answer before the shutdown it
  // answers (two writers, two deliveries).
  const bool said_stopped = !trace.statuses.empty() &&
                            trace.statuses.back().state == SensorState::Stopped &&
                            trace.statuses.back().written_ns >= run.shutdown_written_ns;
  r.evidence = said_stopped ? "SENSOR_STOPPED after RUN_SHUTDOWN"
                            : "no SENSOR_STOPPED after RUN_SHUTDOWN (last status: " +
                                  (trace.statuses.empty()
                                       ? std::string("none")
                                       : std::string(wordOf(trace.statuses.back().state))) +
                                  ")";
  r.evidence += "; it " + programEnding(facts);
  r.pass = said_stopped && facts.program_exit == 0;
  return r;
}

RuleCheck measurementTimes(const RecordedRun& run, const SensorTrace& trace) {
  const double horizon = run.inputs.scenario().horizon_s;
  RuleCheck r = rule("measurement-times",
                     "each Measurement is of an episode that started, at a time in [0, T], "
                     "written no earlier than that instant on the episode's clock",
                     "an-episodes-life");
  std::size_t bad = 0;
  std::string first;
  double lowest = horizon, highest = 0.0;
  for (const SensorTrace::Sample& s : trace.samples) {
    std::string why;
    const auto start = run.starts_ns.find(s.episode);
    if (start == run.starts_ns.end()) {
      why = "names an episode that was not started";
    } else if (!std::isfinite(s.time_s) || s.time_s < 0.0 || s.time_s > horizon) {
      why = fmt::format("time {} s is outside [0, {:g}]", s.time_s, horizon);
    } else {
      const double due_s = secondsSince(start->second, s.received_ns) * run.time_scale;
      if (due_s < s.time_s - kEarlyToleranceS * run.time_scale) {
        why = fmt::format("arrived {:.3f} s (emulated) before its instant {:.6f} s",
                          s.time_s - due_s, s.time_s);
      }
    }
    if (why.empty()) {
      lowest = std::min(lowest, s.time_s);
      highest = std::max(highest, s.time_s);
      continue;
    }
    if (bad++ == 0) first = fmt::format("episode {} seq {}: {}", s.episode, s.seq, why);
  }
  r.pass = bad == 0;
  r.evidence =
      bad == 0
          ? (trace.samples.empty() ? std::string("no measurement to check")
                                   : fmt::format("{} within [{:.4f}, {:.4f}] s of [0, {:g}]",
                                                 plural(trace.samples.size(), "sample", "samples"),
                                                 lowest, highest, horizon))
          : fmt::format("{} of {} wrong; first: {}", bad, trace.samples.size(), first);
  return r;
}

// The tallies by episode (the first of each), and the samples' seqs by episode.
std::map<std::uint32_t, SensorTrace::Tally> talliesByEpisode(const SensorTrace& trace) {
  std::map<std::uint32_t, SensorTrace::Tally> tallies;
  for (const SensorTrace::Tally& t : trace.tallies) tallies.emplace(t.episode, t);
  return tallies;
}

RuleCheck sequenceNumbers(const SensorTrace& trace) {
  RuleCheck r = rule("seq",
                     "numbers each episode's Measurements 0, 1, 2, ... once each, and its "
                     "EpisodeTally's sent counts exactly those",
                     "accounting");
  std::map<std::uint32_t, std::vector<std::uint64_t>> seqs;
  for (const SensorTrace::Sample& s : trace.samples) seqs[s.episode].push_back(s.seq);
  const auto tallies = talliesByEpisode(trace);
  std::string first;
  std::uint64_t total = 0;
  const auto fail = [&](const std::string& why) {
    if (first.empty()) first = why;
  };
  for (auto& [k, list] : seqs) {
    std::sort(list.begin(), list.end());
    if (std::adjacent_find(list.begin(), list.end()) != list.end()) {
      fail(fmt::format("episode {}: a seq written twice", k));
    }
    const auto t = tallies.find(k);
    if (t == tallies.end()) {
      fail(fmt::format("episode {}: {} without a tally", k,
                       plural(list.size(), "sample", "samples")));
      continue;
    }
    if (!list.empty() && list.back() >= t->second.sent) {
      fail(fmt::format("episode {}: seq {} at or past the tally's sent {}", k, list.back(),
                       t->second.sent));
    } else if (list.size() != t->second.sent) {
      fail(fmt::format("episode {}: {} seqs recorded, the tally says {} sent", k, list.size(),
                       t->second.sent));
    }
  }
  for (const auto& [k, t] : tallies) {
    total += t.sent;
    if (!seqs.contains(k) && t.sent > 0) {
      fail(fmt::format("episode {}: the tally says {} sent, none recorded", k, t.sent));
    }
  }
  r.pass = first.empty();
  r.evidence = r.pass ? fmt::format("{} in {}: seq 0 .. sent-1 each once, as the tallies count",
                                    plural(total, "sample", "samples"),
                                    plural(tallies.size(), "episode", "episodes"))
                      : first;
  return r;
}

RuleCheck tallies(const RecordedRun& run, const SensorTrace& trace) {
  RuleCheck r = rule("tally",
                     "writes one EpisodeTally per episode it runs (also at rate zero), finished, "
                     "after the episode's last Measurement",
                     "episodetally-also-at-rate-zero");
  std::map<std::uint32_t, std::int64_t> last_sample;
  for (const SensorTrace::Sample& s : trace.samples) {
    last_sample[s.episode] = std::max(last_sample[s.episode], s.received_ns);
  }
  std::map<std::uint32_t, int> count;
  for (const SensorTrace::Tally& t : trace.tallies) ++count[t.episode];
  const auto first_of = talliesByEpisode(trace);
  std::string first;
  const std::vector<std::uint32_t> episodes = startedEpisodes(run);
  for (const std::uint32_t k : episodes) {
    const auto t = first_of.find(k);
    std::string why;
    if (t == first_of.end()) {
      why = "no tally";
    } else if (count[k] > 1) {
      why = std::to_string(count[k]) + " tallies";
    } else if (!t->second.finished) {
      why = "tally not finished";
    } else if (last_sample.contains(k) && t->second.received_ns < last_sample[k]) {
      why = "tally before the episode's last measurement";
    }
    if (!why.empty() && first.empty()) first = fmt::format("episode {}: {}", k, why);
  }
  r.pass = first.empty() && !episodes.empty();
  r.evidence = !first.empty()     ? first
               : episodes.empty() ? std::string("no episode started")
                                  : fmt::format("{} for {} started",
                                                plural(trace.tallies.size(), "tally", "tallies"),
                                                plural(episodes.size(), "episode", "episodes"));
  return r;
}

RuleCheck versions(const RecordedRun& run, const SensorTrace& trace) {
  RuleCheck r =
      rule("schedule-version", "each Measurement carries the schedule version in force at its time",
           "which-version-is-in-force");
  std::set<std::uint32_t> seen;
  std::size_t bad = 0;
  std::string first;
  for (const SensorTrace::Sample& s : trace.samples) {
    const emulator::ScheduleVersion* v = run.inputs.book().inForce(s.episode, s.time_s);
    const std::uint32_t in_force = v != nullptr ? v->version : 0;
    seen.insert(s.version);
    if (s.version == in_force) continue;
    if (bad++ == 0) {
      first = fmt::format("episode {} seq {} at {:.4f} s says version {}, version {} was in force",
                          s.episode, s.seq, s.time_s, s.version, in_force);
    }
  }
  std::string versions_seen;
  for (const std::uint32_t v : seen)
    versions_seen += (versions_seen.empty() ? "" : ", ") + std::to_string(v);
  r.pass = bad == 0;
  r.evidence = r.pass ? fmt::format("{} under version(s) {} ({} published)",
                                    plural(trace.samples.size(), "sample", "samples"),
                                    versions_seen.empty() ? "-" : versions_seen,
                                    run.inputs.book().versions().size())
                      : fmt::format("{} of {} wrong; first: {}", bad, trace.samples.size(), first);
  return r;
}

// Λ_j(from, t) under one version's rates: the integral of sensor j's rate from `from` to t.
double integratedRate(const RateSchedule& schedule, int j, double from, double t) {
  double total = 0.0;
  const double h = schedule.intervalLength();
  for (int k = std::max(0, schedule.intervalAt(from)); k < schedule.intervals(); ++k) {
    const double start = std::max(from, k * h);
    const double end = k == schedule.intervals() - 1 ? t : std::min(t, (k + 1) * h);
    if (start >= t) break;
    if (end > start) total += schedule.rate(k, j) * (end - start);
  }
  return total;
}

RuleCheck arrivals(const RecordedRun& run, int sensor, const SensorTrace& trace) {
  const Scenario& scenario = run.inputs.scenario();
  const bool timetable = scenario.arrivals == ArrivalMode::Timetable;
  RuleCheck r =
      rule("arrivals",
           timetable ? "transmits at the timetable's instants of the versions in force"
                     : fmt::format("transmits as a Poisson process of the rates in force (time "
                                   "rescaling: Kolmogorov-Smirnov and count, each at alpha {:g})",
                                   kConformAlpha),
           "when-a-sensor-transmits");
  const auto tallies = talliesByEpisode(trace);
  std::map<std::uint32_t, std::vector<double>> times;
  for (const SensorTrace::Sample& s : trace.samples) times[s.episode].push_back(s.time_s);
  std::vector<double> uniforms;
  double expected = 0.0;
  std::size_t counted = 0, episodes = 0, as_ours = 0;
  std::string mismatch;
  for (const auto& [k, tally] : tallies) {
    if (!run.starts_ns.contains(k)) continue;
    std::vector<double>& mine = times[k];
    std::sort(mine.begin(), mine.end());
    ++episodes;
    std::vector<double> ours;
    for (const emulator::TimedArrival& a :
         emulator::sensorTimeline(run.inputs.book(), run.inputs.plant(), run.inputs.run().seed, k,
                                  {sensor}, scenario.horizon_s, scenario.arrivals)) {
      ours.push_back(a.time_s);
    }
    if (ours == mine) ++as_ours;
    if (timetable) {
      if (ours != mine && mismatch.empty()) {
        mismatch = fmt::format("episode {}: {} instants, the timetable has {}", k, mine.size(),
                               ours.size());
      }
      continue;
    }
    for (const emulator::ScheduleSegment& segment :
         run.inputs.book().segments(k, scenario.horizon_s)) {
      const RateSchedule& rates = segment.version->schedule;
      const bool last = segment.to_s >= scenario.horizon_s;
      double previous = segment.from_s;
      for (const double t : mine) {
        if (t < segment.from_s || (last ? t > segment.to_s : t >= segment.to_s)) continue;
        const double gap = integratedRate(rates, sensor, previous, t);
        uniforms.push_back(1.0 - std::exp(-gap));
        previous = t;
        ++counted;
      }
      expected += integratedRate(rates, sensor, segment.from_s, segment.to_s);
    }
  }
  const std::string same =
      as_ours > 0 ? fmt::format("; {} of {} drawn exactly as our agents draw", as_ours, episodes)
                  : "";
  if (timetable) {
    r.pass = mismatch.empty() && episodes > 0;
    r.evidence = !mismatch.empty() ? mismatch
                 : episodes == 0   ? std::string("no tallied episode to check")
                                   : fmt::format("{} equal the timetable",
                                                 plural(episodes, "episode", "episodes"));
    return r;
  }
  if (expected < kFewestExpected) {
    r.pass = true;
    r.evidence =
        fmt::format("not tested: {:.1f} arrivals expected over {} (fewer than {:g}){}", expected,
                    plural(episodes, "episode", "episodes"), kFewestExpected, same);
    return r;
  }
  // The count: Poisson with mean `expected`; normal approximation, two-sided at alpha.
  const double z = (static_cast<double>(counted) - expected) / std::sqrt(expected);
  const double z_limit = std::sqrt(chiSquareQuantile(1.0 - kConformAlpha, 1.0));  // z² ~ χ²(1)
  const KsTest ks = ksUniform(uniforms);
  r.pass = std::abs(z) <= z_limit && ks.p_value >= kConformAlpha;
  r.evidence = fmt::format(
      "{} arrivals for {:.1f} expected (z = {:.2f}, |z| <= {:.2f}); KS D = "
      "{:.4f}, p = {:.3g} over {} rescaled gaps{}",
      counted, expected, z, z_limit, ks.d, ks.p_value, ks.n, same);
  return r;
}

RuleCheck accounted(int sensor, const RunFacts& facts) {
  RuleCheck r = rule("accounted",
                     "every Measurement it sent reached the fusion center well-formed: none "
                     "lost, none refused",
                     "refusals");
  if (!facts.report) {
    r.evidence = "the run wrote no report";
    return r;
  }
  const auto& sensors = facts.report->sensors;
  const auto it = std::find_if(sensors.begin(), sensors.end(), [&](const report::SensorRecord& s) {
    return s.sensor_id == sensor;
  });
  if (it == sensors.end()) {
    r.evidence = "the report has no line for sensor " + std::to_string(sensor);
    return r;
  }
  r.pass = it->lost == 0 && it->refused == 0 && it->received == it->sent;
  r.evidence = fmt::format("sent {}, received {}, lost {}, refused {} (the report)", it->sent,
                           it->received, it->lost, it->refused);
  return r;
}

// The z of each sample against the truth at its tick: Σ e' R^-1 e ~ χ²(p N).
RuleCheck measurementNoise(const RecordedRun& run, int sensor, const SensorTrace& trace) {
  RuleCheck r = rule("measurement-noise",
                     fmt::format("z = H x(t) + v with v ~ N(0, R) at the plant's truth: the sum of "
                                 "e' R^-1 e is chi-square (two-sided, alpha {:g})",
                                 kConformAlpha),
                     "the-emulated-world");
  const Scenario& scenario = run.inputs.scenario();
  const EmulatedPlant& plant = run.inputs.plant();
  const SensorModel& model = scenario.sensors[static_cast<std::size_t>(sensor)];
  const auto p = static_cast<std::size_t>(model.H.rows());
  const Eigen::LLT<Eigen::MatrixXd> r_factor(model.R);
  double sum = 0.0;
  std::size_t used = 0, wrong_size = 0;
  for (const SensorTrace::Sample& s : trace.samples) {
    if (s.z.size() != p || !run.starts_ns.contains(s.episode)) {
      ++wrong_size;
      continue;
    }
    // Instants lie on ticks (t = tick τ); the nearest tick, so that rounding cannot move it.
    const auto tick = std::clamp<std::int64_t>(std::llround(s.time_s / plant.tickSeconds()), 0,
                                               plant.tickCount());
    const Eigen::VectorXd x = plant.stateAt(s.episode, tick);
    const Eigen::VectorXd e =
        Eigen::Map<const Eigen::VectorXd>(s.z.data(), static_cast<Eigen::Index>(p)) - model.H * x;
    sum += e.dot(r_factor.solve(e));
    ++used;
  }
  if (used == 0) {
    r.evidence = "no well-formed measurement to judge";
    return r;
  }
  const double dof = static_cast<double>(p * used);
  const double low = chiSquareQuantile(kConformAlpha / 2.0, dof) / dof;
  const double high = chiSquareQuantile(1.0 - kConformAlpha / 2.0, dof) / dof;
  const double mean = sum / dof;
  r.pass = mean >= low && mean <= high;
  r.evidence = fmt::format("{}: mean e' R^-1 e / p = {:.3f} {} [{:.3f}, {:.3f}]{}",
                           plural(used, "sample", "samples"), mean, r.pass ? "in" : "OUTSIDE", low,
                           high, wrong_size > 0 ? fmt::format(" ({} not judged)", wrong_size) : "");
  return r;
}

}  // namespace

KsTest ksUniform(std::vector<double> values) {
  KsTest test;
  test.n = values.size();
  if (values.empty()) return test;
  std::sort(values.begin(), values.end());
  const auto n = static_cast<double>(values.size());
  for (std::size_t i = 0; i < values.size(); ++i) {
    const double x = std::clamp(values[i], 0.0, 1.0);
    const auto rank = static_cast<double>(i);
    test.d = std::max({test.d, (rank + 1.0) / n - x, x - rank / n});
  }
  // Q_KS(λ) = 2 Σ (-1)^(k-1) exp(-2 k² λ²), with λ = (√n + 0.12 + 0.11/√n) D (Stephens).
  const double root = std::sqrt(n);
  const double lambda = (root + 0.12 + 0.11 / root) * test.d;
  if (lambda < 0.2) return test;  // the series converges slowly there, and Q is 1 to 1e-9
  double q = 0.0, sign = 1.0;
  for (int k = 1; k <= 100; ++k) {
    const double term = std::exp(-2.0 * k * k * lambda * lambda);
    q += sign * term;
    sign = -sign;
    if (term < 1e-16) break;
  }
  test.p_value = std::clamp(2.0 * q, 0.0, 1.0);
  return test;
}

std::vector<RuleCheck> checkSensor(const RecordedRun& run, int sensor, const RunFacts& facts) {
  static const SensorTrace none;
  const auto found = run.sensors.find(sensor);
  const SensorTrace& trace = found != run.sensors.end() ? found->second : none;
  std::vector<RuleCheck> rules = {readiness(run, trace),        statusPeriod(run, trace),
                                  measurementTimes(run, trace), versions(run, trace),
                                  sequenceNumbers(trace),       tallies(run, trace),
                                  arrivals(run, sensor, trace), accounted(sensor, facts),
                                  leaving(run, trace, facts),   runCompletes(facts)};
  if (facts.measures_truth) {
    rules.push_back(measurementNoise(run, sensor, trace));
    rules.push_back(truth(facts));
  }
  return rules;
}

std::string ruleTable(const std::vector<RuleCheck>& rules) {
  std::size_t width = 4;
  for (const RuleCheck& r : rules) width = std::max(width, r.rule.size());
  std::string text = fmt::format("{:<{}}  {:<4}  {}\n", "rule", width, "", "evidence");
  std::size_t failed = 0;
  for (const RuleCheck& r : rules) {
    failed += r.pass ? 0 : 1;
    text += fmt::format("{:<{}}  {:<4}  {}\n{:<{}}        {}; {}\n", r.rule, width,
                        r.pass ? "ok" : "FAIL", r.evidence, "", width, r.statement, r.section);
  }
  text += failed == 0 ? fmt::format("all {} rules hold\n", rules.size())
                      : fmt::format("{} of {} rules FAIL\n", failed, rules.size());
  return text;
}

std::string rulesJunit(const std::string& suite, const std::vector<RuleCheck>& rules,
                       double seconds) {
  std::vector<report::JunitCase> cases;
  for (const RuleCheck& r : rules) {
    cases.push_back(
        {r.rule, r.pass, r.evidence, r.statement + " (" + r.section + "): " + r.evidence});
  }
  return report::junitSuiteXml(suite, suite, cases, seconds);
}

}  // namespace sensornet::conform
