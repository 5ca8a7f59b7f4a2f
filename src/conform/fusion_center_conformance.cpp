// The rules of a fusion center's role, judged against our fusion center run beside it on the
// same measurements (`--reference-fusion`: its Reports in P/reference), which is the exact
// CD-KF: an outside fusion center's costs, brackets and counts must be the reference's.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <map>

#include "rules.hpp"
#include "sensornet/conform/sensor_conformance.hpp"

namespace sensornet::conform {
namespace {

using namespace detail;

constexpr const char* kSection = "fusion-center-ours-or-your-estimator";

// The first Report of each episode, and how many came.
struct ByEpisode {
  std::map<std::uint32_t, const RecordedReport*> first;
  std::map<std::uint32_t, int> count;
};

ByEpisode byEpisode(const std::vector<RecordedReport>& reports) {
  ByEpisode out;
  for (const RecordedReport& r : reports) {
    out.first.emplace(r.episode, &r);
    ++out.count[r.episode];
  }
  return out;
}

double relativeDifference(double value, double reference) {
  if (value == reference) return 0.0;  // also both infinite
  if (!std::isfinite(value) || !std::isfinite(reference)) return HUGE_VAL;
  return std::abs(value - reference) / std::max(std::abs(reference), 1e-300);
}

RuleCheck presence(const RecordedRun& run) {
  RuleCheck r = rule("presence",
                     "is present for the coordinator (its EpisodeControl reader and Report and "
                     "FusionState writers matched), so that the first episode starts",
                     "the-readiness-handshake");
  r.pass = !run.starts_ns.empty();
  r.evidence = r.pass ? fmt::format("episode {} started at +{:.3f} s", run.starts_ns.begin()->first,
                                    secondsSince(run.first_ns, run.starts_ns.begin()->second))
                      : "no episode started";
  return r;
}

RuleCheck reportPerEpisode(const RecordedRun& run) {
  RuleCheck r = rule("report-per-episode",
                     "publishes one Report per episode, after the episode's end", kSection);
  const ByEpisode mine = byEpisode(run.reports);
  const double horizon = run.inputs.scenario().horizon_s;
  std::string first;
  const std::vector<std::uint32_t> started = startedEpisodes(run);
  for (const std::uint32_t k : started) {
    const std::int64_t start_ns = run.starts_ns.at(k);
    const auto report = mine.first.find(k);
    std::string why;
    if (report == mine.first.end()) {
      why = "no Report";
    } else if (mine.count.at(k) > 1) {
      why = std::to_string(mine.count.at(k)) + " Reports";
    } else {
      const double after_end_s =
          secondsSince(start_ns, report->second->received_ns) - horizon / run.time_scale;
      if (after_end_s < 0.0) why = fmt::format("Report {:.3f} s before the end", -after_end_s);
    }
    if (!why.empty() && first.empty()) first = fmt::format("episode {}: {}", k, why);
  }
  r.pass = first.empty() && !started.empty();
  r.evidence = !first.empty()    ? first
               : started.empty() ? std::string("no episode started")
                                 : fmt::format("{} for {} started",
                                               plural(run.reports.size(), "Report", "Reports"),
                                               plural(started.size(), "episode", "episodes"));
  return r;
}

// One Report field against the reference's, episode by episode.
template <class Compare>
RuleCheck againstReference(const RecordedRun& run, RuleCheck r, const Compare& compare) {
  const ByEpisode mine = byEpisode(run.reports);
  const ByEpisode reference = byEpisode(run.reference_reports);
  if (reference.first.empty()) {
    r.evidence = "no Report of the reference fusion center was recorded";
    return r;
  }
  std::size_t compared = 0;
  std::string first, worst;
  for (const auto& [k, theirs] : reference.first) {
    const auto ours = mine.first.find(k);
    if (ours == mine.first.end()) continue;  // report-per-episode says it
    ++compared;
    std::string why = compare(*ours->second, *theirs, worst);
    if (!why.empty() && first.empty()) first = fmt::format("episode {}: {}", k, why);
  }
  r.pass = first.empty() && compared > 0;
  r.evidence = !first.empty()  ? first
               : compared == 0 ? std::string("no episode to compare")
                               : fmt::format("{} equal the reference's{}",
                                             plural(compared, "episode", "episodes"), worst);
  return r;
}

RuleCheck costs(const RecordedRun& run, double tolerance) {
  RuleCheck r = rule("costs",
                     fmt::format("each episode's realized cost is the exact CD-KF's on the same "
                                 "measurements (ours beside it), to a relative {:g}",
                                 tolerance),
                     kSection);
  double largest = 0.0;
  return againstReference(
      run, std::move(r),
      [&](const RecordedReport& mine, const RecordedReport& reference, std::string& note) {
        const double d = relativeDifference(mine.realized_cost, reference.realized_cost);
        largest = std::max(largest, d);
        note = fmt::format(" (largest relative difference {:.3g})", largest);
        return d <= tolerance ? std::string()
                              : fmt::format(
                                    "cost {} against the reference's {} "
                                    "(relative difference {:.3g})",
                                    mine.realized_cost, reference.realized_cost, d);
      });
}

RuleCheck brackets(const RecordedRun& run, double tolerance) {
  RuleCheck r = rule("bracket",
                     "each Report carries the bracket [J(P_info), J(P_cov)] of the schedule in "
                     "force, as the reference's",
                     kSection);
  return againstReference(
      run, std::move(r),
      [&](const RecordedReport& mine, const RecordedReport& reference, std::string&) {
        const bool same =
            relativeDifference(mine.bracket_lower, reference.bracket_lower) <= tolerance &&
            relativeDifference(mine.bracket_upper, reference.bracket_upper) <= tolerance;
        return same ? std::string()
                    : fmt::format("[{}, {}] against the reference's [{}, {}]", mine.bracket_lower,
                                  mine.bracket_upper, reference.bracket_lower,
                                  reference.bracket_upper);
      });
}

RuleCheck counts(const RecordedRun& run) {
  RuleCheck r = rule("counts",
                     "each Report's per-sensor counts (sent, received, lost) and completeness "
                     "are the reference's",
                     "accounting");
  return againstReference(
      run, std::move(r),
      [](const RecordedReport& mine, const RecordedReport& reference, std::string&) {
        if (mine.complete != reference.complete) {
          return fmt::format("complete {} against the reference's {}", mine.complete,
                             reference.complete);
        }
        for (std::size_t j = 0; j < std::max(mine.counts.size(), reference.counts.size()); ++j) {
          const RecordedReport::Counts none;
          const auto& a = j < mine.counts.size() ? mine.counts[j] : none;
          const auto& b = j < reference.counts.size() ? reference.counts[j] : none;
          if (a == b) continue;
          return fmt::format(
              "sensor {}: sent/received/lost {}/{}/{} against the reference's "
              "{}/{}/{}",
              j, a.sent, a.received, a.lost, b.sent, b.received, b.lost);
        }
        return std::string();
      });
}

RuleCheck leaves(const RecordedRun& run, const RunFacts& facts) {
  RuleCheck r = rule("leaving", "on RUN_SHUTDOWN leaves by itself with exit 0", "leaving-the-run");
  r.pass = run.shutdown_ns.has_value() && facts.program_exit == 0;
  r.evidence =
      (run.shutdown_ns ? std::string("RUN_SHUTDOWN came") : std::string("no RUN_SHUTDOWN")) +
      "; it " + programEnding(facts);
  return r;
}

}  // namespace

std::vector<RuleCheck> checkFusionCenter(const RecordedRun& run, const RunFacts& facts,
                                         double tolerance) {
  std::vector<RuleCheck> rules = {
      presence(run), reportPerEpisode(run), costs(run, tolerance), brackets(run, tolerance),
      counts(run),   leaves(run, facts),    runCompletes(facts)};
  if (facts.measures_truth) rules.push_back(truth(facts));
  return rules;
}

}  // namespace sensornet::conform
