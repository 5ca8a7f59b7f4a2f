#include "sensornet/report/report_page.hpp"


#include <algorithm>
#include <cmath>
#include <fstream>
#include <limits>
#include <map>
#include <optional>
#include <utility>
#include <sstream>
#include <vector>

#include "sensornet/core/bracket_differs.hpp"
#include "sensornet/core/input_error.hpp"
#include "sensornet/core/student_t.hpp"
#include "sensornet/report/svg_plot.hpp"
#include "sensornet/io/command_line.hpp"
#include "sensornet/io/scenario_file.hpp"
#include "sensornet/report/report_files.hpp"
#include "page_parts.hpp"

namespace sensornet::report {
namespace {


using nlohmann::json;

const double kNan = std::numeric_limits<double>::quiet_NaN();
const json kNone;  // what a part the record keeps as json reads as when it is absent

// A palette that survives grey-scale printing: its colours differ in lightness, and the lines
// that share a plot differ in dash pattern too.
constexpr const char* kInk = "#1b2a49";      // darkest: the main series
constexpr const char* kMid = "#4a74b4";      // middle
constexpr const char* kAccent = "#e0891c";   // light-middle orange: what went wrong, p99
constexpr const char* kPale = "#cfdbee";     // pale: expected counts
constexpr const char* kSand = "#e9e1cf";     // pale and warm: the bracket, apart from the interval
constexpr const char* kGrey = "#8c8c8c";
// The bracket a schedule delivered, beside the planned one; the real-time cost beside the
// realized one.
const Style kDelivered = Style::line("#8a6d3b", 1.3, "4 3");
const Style kRealtime = Style::outlined(kGrey, kGrey);

// A value the record may not have, as the plots take it: NaN where there is none (a plot skips
// a NaN mark, a table prints it as "nan", a CSV cell stays empty).
double orNan(const std::optional<double>& value) { return value.value_or(kNan); }
template <class T>
double orNan(const std::optional<T>& value) {
  return value ? static_cast<double>(*value) : kNan;
}

// The plots' axes are doubles: counts, ids and episode numbers as the double they are.
template <class T>
double asDouble(T value) {
  return static_cast<double>(value);
}

// The json reads below are of what the record keeps as written (RunRecord::other's
// covariance_traces, LatencyRecord::histogram): numbers where they are numbers, NaN elsewhere.
double number(const json& j, const char* key) {
  const auto it = j.find(key);
  return it != j.end() && it->is_number() ? it->get<double>() : kNan;
}

double number(const json& j) { return j.is_number() ? j.get<double>() : kNan; }

std::vector<double> numbers(const json& values) {
  std::vector<double> out;
  if (values.is_array()) {
    for (const json& v : values) out.push_back(number(v));
  }
  return out;
}

// The sum of an episode's per-sensor counts, in sensor order (as the CSV has always summed them).
template <class T>
double sumOf(const std::vector<T>& values) {
  double total = 0.0;
  for (const T v : values) {
    const auto x = static_cast<double>(v);
    total += std::isfinite(x) ? x : 0.0;
  }
  return total;
}

// The finite extremes of some values; nullopt-like (lo > hi) when there are none.
struct Extent {
  double lo = std::numeric_limits<double>::infinity();
  double hi = -std::numeric_limits<double>::infinity();
  void add(double v) {
    if (!std::isfinite(v)) return;
    lo = std::min(lo, v);
    hi = std::max(hi, v);
  }
  void add(const std::vector<double>& vs) {
    for (const double v : vs) add(v);
  }
  [[nodiscard]] bool empty() const { return lo > hi; }
};

// An axis over episodes first..last (each a unit wide, centred on its number): a tick on every
// episode up to 20 of them, else 1-2-5 steps (whole numbers then).
Axis episodeAxis(double first, double last, const std::string& label) {
  Axis axis({first - 0.5, last + 0.5}, label);
  if (last - first <= 20.0) {
    for (double k = first; k <= last; k += 1.0) axis.ticks.push_back(k);
  } else {
    axis.ticks = niceTicks({first, last}, 10);
  }
  return axis;
}

std::string note(const std::string& heading, const std::string& text) {
  return "<section class=\"note\"><h2>" + escapeXml(heading) + "</h2><p>" + escapeXml(text) +
         "</p></section>\n";
}

// ---- 1. cost per episode ----------------------------------------------------------------------

struct RunningMean {
  std::vector<double> episodes, mean, low, high;
};

// The running mean of the complete episodes' costs and its 95% Student-t interval (from the
// second complete episode on), as the report's summary computes it at the end.
RunningMean runningMean(const std::vector<EpisodeRecord>& per_episode) {
  RunningMean r;
  double sum = 0.0, squares = 0.0;
  double k = 0.0;
  for (const EpisodeRecord& e : per_episode) {
    const double cost = orNan(e.realized_cost);
    if (!e.complete || !std::isfinite(cost)) continue;
    k += 1.0;
    sum += cost;
    squares += cost * cost;
    const double mean = sum / k;
    r.episodes.push_back(asDouble(e.episode));
    r.mean.push_back(mean);
    if (k < 2.0) {
      r.low.push_back(kNan);
      r.high.push_back(kNan);
      continue;
    }
    const double variance = std::max(0.0, (squares - k * mean * mean) / (k - 1.0));
    const double half = studentTQuantile(0.975, k - 1.0) * std::sqrt(variance / k);
    r.low.push_back(std::max(0.0, mean - half));
    r.high.push_back(mean + half);
  }
  return r;
}

// The bracket the schedule delivered, when it is not the planned one (a dead sensor's share, an
// emulated network's losses and outages); nullopt otherwise. A side that is missing is NaN, and
// NaN never differs (bracketsDiffer): no planned bracket, no delivered one shown.
std::optional<std::pair<double, double>> deliveredBracketOf(const EpisodeRecord& e) {
  const double info = orNan(e.bracket.info), cov = orNan(e.bracket.cov);
  const double d_info = orNan(e.delivered_bracket.info);
  const double d_cov = orNan(e.delivered_bracket.cov);
  if (!std::isfinite(d_info) || !std::isfinite(d_cov) ||
      !bracketsDiffer(info, cov, d_info, d_cov)) {
    return std::nullopt;
  }
  return std::make_pair(d_info, d_cov);
}

// The real-time cost of a complete episode, when measurements arrived late enough to make it
// differ from the realized one.
std::optional<double> realtimeCostOf(const EpisodeRecord& e) {
  const double realized = orNan(e.realized_cost), realtime = orNan(e.realtime_cost);
  if (!e.complete || !std::isfinite(realtime) || realtime == realized) return std::nullopt;
  return realtime;
}

// The cost axis: what the complete episodes, the brackets and the interval span (the interval
// from the third complete episode on: with two, Student's t stretches it tenfold). An incomplete
// episode's cost (cut short, aborted) joins only if it does not stretch the axis past half as
// much again: one aborted episode must not flatten the rest (it is drawn at the top edge).
Interval costRange(const std::vector<EpisodeRecord>& per_episode, const RunningMean& running) {
  Extent y;
  for (const EpisodeRecord& e : per_episode) {
    if (e.complete) y.add(orNan(e.realized_cost));
    y.add(orNan(e.bracket.info));  // Extent skips a missing side
    y.add(orNan(e.bracket.cov));
    if (const auto delivered = deliveredBracketOf(e)) {
      y.add(delivered->first);
      y.add(delivered->second);
    }
    if (const auto realtime = realtimeCostOf(e)) y.add(*realtime);
  }
  for (std::size_t i = 2; i < running.low.size(); ++i) {
    y.add(running.low[i]);
    y.add(running.high[i]);
  }
  for (const EpisodeRecord& e : per_episode) {
    const double cost = orNan(e.realized_cost);
    if (y.empty() || (!e.complete && cost <= 1.5 * y.hi)) y.add(cost);
  }
  if (y.empty()) return {kNan, kNan};
  return niceRange({std::min(0.0, y.lo), y.hi}, 5);
}

std::string costPlot(const std::vector<EpisodeRecord>& per_episode,
                     const std::vector<ScheduleVersionRecord>& versions) {
  if (per_episode.empty()) return note("Realized cost per episode", "The run fused no episode.");
  const RunningMean running = runningMean(per_episode);
  Extent x;
  for (const EpisodeRecord& e : per_episode) x.add(asDouble(e.episode));
  const Interval y_range = costRange(per_episode, running);
  if (!std::isfinite(y_range.lo)) {
    return note("Realized cost per episode", "No episode has a finite cost.");
  }
  const bool any_delivered =
      std::any_of(per_episode.begin(), per_episode.end(),
                  [](const EpisodeRecord& e) { return deliveredBracketOf(e).has_value(); });
  const bool any_realtime =
      std::any_of(per_episode.begin(), per_episode.end(),
                  [](const EpisodeRecord& e) { return realtimeCostOf(e).has_value(); });
  SvgPlot::Frame frame;
  if (any_delivered || any_realtime) frame.top += kLegendRow;  // the legend takes two rows
  SvgPlot plot(frame, episodeAxis(x.lo, x.hi, "episode"), Axis{y_range, "cost J (state units²)"});
  for (const EpisodeRecord& e : per_episode) {
    // A missing side is NaN, and rect() draws no box with a NaN edge: no bracket, no box.
    const double k = asDouble(e.episode);
    const double info = orNan(e.bracket.info);
    const double cov = orNan(e.bracket.cov);
    plot.rect(k - 0.5, k + 0.5, info, cov, Style::area(kSand),
              "episode " + formatTick(k) + ": bracket [" + formatTick(info) + ", " +
                  formatTick(cov) + "]");
  }
  // What the schedule delivered, beside what it planned: a dashed box.
  for (const EpisodeRecord& e : per_episode) {
    const auto delivered = deliveredBracketOf(e);
    if (!delivered) continue;
    const double k = asDouble(e.episode);
    plot.rect(k - 0.4, k + 0.4, std::min(delivered->first, y_range.hi),
              std::min(delivered->second, y_range.hi), kDelivered,
              "episode " + formatTick(k) + ": delivered bracket [" +
                  formatTick(delivered->first) + ", " + formatTick(delivered->second) + "]");
  }
  Style interval = Style::area(kMid, 0.45);
  plot.band(running.episodes, running.low, running.high, interval, "95% interval of the mean");
  plot.polyline(running.episodes, running.mean, Style::line(kInk, 2.0), "running mean");
  for (const ScheduleVersionRecord& v : versions) {
    const double effective = asDouble(v.effective_episode);
    if (v.version == 0 || effective <= x.lo) continue;
    plot.vline(effective - 0.5, Style::line(kGrey, 1.2, "5 3"),
               "v" + formatTick(asDouble(v.version)));
  }
  bool off_scale = false;
  for (const EpisodeRecord& e : per_episode) {
    const double k = asDouble(e.episode);
    const double cost = orNan(e.realized_cost);
    const bool above = cost > y_range.hi;
    off_scale = off_scale || above;
    plot.circle(k, above ? y_range.hi : cost, 3.5,
                e.complete ? Style::outlined(kInk, kInk) : Style::outlined("white", kAccent),
                "episode " + formatTick(k) + ": " + formatTick(cost) +
                    (e.complete ? "" : " (incomplete)") + (above ? ", off the scale" : ""));
  }
  for (const EpisodeRecord& e : per_episode) {
    const auto realtime = realtimeCostOf(e);
    if (!realtime) continue;
    const double k = asDouble(e.episode);
    plot.circle(k, std::min(*realtime, y_range.hi), 2.5, kRealtime,
                "episode " + formatTick(k) + ": real-time cost " + formatTick(*realtime));
  }
  std::vector<LegendEntry> legend = {{"bracket in force", Style::area(kSand)}};
  if (any_delivered) legend.push_back({"bracket delivered", kDelivered});
  legend.push_back({"realized cost", Style::outlined(kInk, kInk)});
  if (any_realtime) legend.push_back({"real-time cost", kRealtime});
  legend.push_back({"incomplete", Style::outlined("white", kAccent)});
  legend.push_back({"running mean", Style::line(kInk, 2.0)});
  legend.push_back({"95% interval", interval});
  plot.legend(legend);
  return figure("cost", "Realized cost per episode", plot.svg("plot-cost", "Realized cost per episode"),
                "Each dot is one episode's realized cost J(P); the shaded box behind it is the "
                "bracket [J(P<sub>info</sub>), J(P<sub>cov</sub>)] of the schedule in force. The "
                "line is the running mean over complete episodes with its 95% Student-t interval; "
                "dashed rules mark the episodes where a new schedule version took effect." +
                    std::string(any_delivered
                                    ? " A dashed box is the bracket of what the schedule could "
                                      "still deliver (dead sensors deliver nothing; the emulated "
                                      "network's losses and outages thin the rates), where it "
                                      "differs from the planned one."
                                    : "") +
                    std::string(any_realtime
                                    ? " A small grey dot is the episode's real-time cost: the "
                                      "covariance of what had arrived by each instant, with the "
                                      "emulated network's delay."
                                    : "") +
                    std::string(off_scale ? " An incomplete episode whose cost lies far above "
                                            "the rest sits on the top edge (its value is in "
                                            "its tooltip)."
                                          : ""));
}

// ---- 2. schedule heat maps --------------------------------------------------------------------

// Pale (rate 0) to dark (the largest rate of any version): lightness carries the value.
std::string rampColour(double fraction) {
  fraction = std::clamp(fraction, 0.0, 1.0);
  const int from[3] = {0xf4, 0xf6, 0xfa};
  const int to[3] = {0x0b, 0x1f, 0x44};
  char text[8];
  int c[3];
  for (int i = 0; i < 3; ++i) {
    c[i] = static_cast<int>(std::lround(from[i] + fraction * (to[i] - from[i])));
  }
  std::snprintf(text, sizeof text, "#%02x%02x%02x", c[0], c[1], c[2]);
  return text;
}

// The schedule versions as the page reads them, in the order they were published.
struct PageVersion {
  double version = 0.0;
  double episode = 0.0;  // effective from this episode ...
  double time_s = 0.0;   // ... at this emulated time within it
  std::vector<std::vector<double>> rates;  // [interval][sensor]
};

std::vector<PageVersion> pageVersions(const std::vector<ScheduleVersionRecord>& versions) {
  std::vector<PageVersion> out;
  for (const ScheduleVersionRecord& v : versions) {
    if (v.rates.empty()) continue;  // a version without rates is in the table, not the map
    out.push_back({asDouble(v.version), asDouble(v.effective_episode), v.effective_time_s,
                   v.rates});
  }
  return out;
}

// The version in force at time t of an episode: the latest published whose effective point is
// at or before (episode, t), as the schedule book decides it.
const PageVersion* versionInForce(const std::vector<PageVersion>& versions, double episode,
                                  double t) {
  for (auto it = versions.rbegin(); it != versions.rend(); ++it) {
    if (it->episode < episode || (it->episode == episode && it->time_s <= t)) return &*it;
  }
  return nullptr;
}

// An episode's pieces [from, to) of emulated time, each under one version.
struct Piece {
  double from = 0.0;
  double to = 0.0;
  const PageVersion* version = nullptr;
};

std::vector<Piece> piecesOf(const std::vector<PageVersion>& versions, double episode,
                            double horizon) {
  std::vector<double> breaks = {0.0};
  for (const PageVersion& v : versions) {
    if (v.episode == episode && v.time_s > 0.0 && v.time_s < horizon) breaks.push_back(v.time_s);
  }
  std::sort(breaks.begin(), breaks.end());
  std::vector<Piece> pieces;
  for (std::size_t i = 0; i < breaks.size(); ++i) {
    const double to = i + 1 < breaks.size() ? breaks[i + 1] : horizon;
    if (to <= breaks[i]) continue;
    if (const PageVersion* v = versionInForce(versions, episode, breaks[i])) {
      pieces.push_back({breaks[i], to, v});
    }
  }
  return pieces;
}

// The rate of `sensor` in interval k of version v (0 where the version lacks it).
double rateOf(const PageVersion& v, std::size_t k, std::size_t sensor) {
  if (k >= v.rates.size() || sensor >= v.rates[k].size()) return 0.0;
  return std::isfinite(v.rates[k][sensor]) ? v.rates[k][sensor] : 0.0;
}

// At most this many columns and cells in the map: past them, a column is the mean rate over a
// block of episodes instead of one interval of one episode.
constexpr double kMaxMapColumns = 600.0;
constexpr double kMaxMapCells = 40000.0;

struct MapShape {
  double first = 0.0, last = 0.0;  // episodes shown
  std::size_t intervals = 0, sensors = 0;
  double horizon = 1.0;
};

// One cell per interval of every episode, split where a version switches within it.
void drawDetailedMap(SvgPlot& plot, const std::vector<PageVersion>& versions, const MapShape& m,
                     double largest) {
  const double step = m.horizon / static_cast<double>(m.intervals);
  for (double e = m.first; e <= m.last; e += 1.0) {
    for (const Piece& piece : piecesOf(versions, e, m.horizon)) {
      for (std::size_t k = 0; k < m.intervals; ++k) {
        const double t0 = std::max(piece.from, step * static_cast<double>(k));
        const double t1 = std::min(piece.to, step * static_cast<double>(k + 1));
        if (t1 <= t0) continue;
        for (std::size_t j = 0; j < m.sensors; ++j) {
          const double rate = rateOf(*piece.version, k, j);
          const auto s = static_cast<double>(j);
          plot.rect(e + t0 / m.horizon, e + t1 / m.horizon, s - 0.5, s + 0.5,
                    Style::area(rampColour(largest > 0.0 ? rate / largest : 0.0)),
                    "sensor " + std::to_string(j) + ", episode " + formatTick(e) + ", t in [" +
                        formatTick(t0) + ", " + formatTick(t1) + ") s: " + formatTick(rate) +
                        " Hz (v" + formatTick(piece.version->version) + ")");
        }
      }
    }
  }
}

// Per sensor, ∫ λ_j dt over one episode: its expected count.
std::vector<double> expectedCounts(const std::vector<PageVersion>& versions, const MapShape& m,
                                   double episode) {
  const double step = m.horizon / static_cast<double>(m.intervals);
  std::vector<double> counts(m.sensors, 0.0);
  for (const Piece& piece : piecesOf(versions, episode, m.horizon)) {
    for (std::size_t k = 0; k < m.intervals; ++k) {
      const double t0 = std::max(piece.from, step * static_cast<double>(k));
      const double t1 = std::min(piece.to, step * static_cast<double>(k + 1));
      if (t1 <= t0) continue;
      for (std::size_t j = 0; j < m.sensors; ++j) counts[j] += (t1 - t0) * rateOf(*piece.version, k, j);
    }
  }
  return counts;
}

// One column per block of episodes: each sensor's mean rate over the block.
void drawBlockMap(SvgPlot& plot, const std::vector<PageVersion>& versions, const MapShape& m,
                  double largest, double per_column) {
  std::map<const PageVersion*, std::vector<double>> whole;  // episodes without a switch
  for (double from = m.first; from <= m.last; from += per_column) {
    const double to = std::min(m.last, from + per_column - 1.0);
    std::vector<double> total(m.sensors, 0.0);
    for (double e = from; e <= to; e += 1.0) {
      const std::vector<Piece> pieces = piecesOf(versions, e, m.horizon);
      std::vector<double> counts;
      if (pieces.size() == 1) {
        auto [it, fresh] = whole.try_emplace(pieces.front().version);
        if (fresh) it->second = expectedCounts(versions, m, e);
        counts = it->second;
      } else {
        counts = expectedCounts(versions, m, e);
      }
      for (std::size_t j = 0; j < m.sensors; ++j) total[j] += counts[j];
    }
    const double span = (to - from + 1.0) * m.horizon;
    for (std::size_t j = 0; j < m.sensors; ++j) {
      const double rate = total[j] / span;
      const auto s = static_cast<double>(j);
      plot.rect(from, to + 1.0, s - 0.5, s + 0.5,
                Style::area(rampColour(largest > 0.0 ? rate / largest : 0.0)),
                "sensor " + std::to_string(j) + ", episodes " + formatTick(from) + "-" +
                    formatTick(to) + ": mean " + formatTick(rate) + " Hz");
    }
  }
}

std::string versionTable(const std::vector<ScheduleVersionRecord>& versions) {
  std::string t = "<table class=\"versions\"><tr><th>version</th><th>surrogate</th>"
                  "<th>in force from</th><th>bracket [info, cov]</th></tr>\n";
  for (const ScheduleVersionRecord& v : versions) {
    // No surrogate recorded: "?" (every writer records one).
    t += "<tr><td>v" + formatTick(asDouble(v.version)) + "</td><td>" +
         escapeXml(v.surrogate.empty() ? std::string("?") : v.surrogate) + "</td><td>episode " +
         formatTick(asDouble(v.effective_episode)) + ", t = " + formatTick(v.effective_time_s) +
         " s</td><td>[" + formatTick(orNan(v.bracket.info)) + ", " +
         formatTick(orNan(v.bracket.cov)) + "]</td></tr>\n";
  }
  return t + "</table>\n";
}

std::string schedulePlots(const std::vector<ScheduleVersionRecord>& published,
                          const std::vector<EpisodeRecord>& per_episode) {
  const std::string heading = "Schedule in force (rates per sensor over the run)";
  const std::vector<PageVersion> versions = pageVersions(published);
  if (versions.empty()) return note(heading, "The report carries no schedule rates.");
  MapShape m;
  m.intervals = versions.front().rates.size();
  for (const PageVersion& v : versions) {
    for (const auto& row : v.rates) m.sensors = std::max(m.sensors, row.size());
  }
  for (const ScheduleVersionRecord& v : published) {
    if (v.horizon_s > 0.0) m.horizon = v.horizon_s;
  }
  Extent episodes;
  for (const EpisodeRecord& e : per_episode) episodes.add(asDouble(e.episode));
  for (const PageVersion& v : versions) episodes.add(v.episode);
  m.first = std::max(0.0, episodes.lo);
  m.last = std::max(m.first, episodes.hi);
  double largest = 0.0;
  for (const PageVersion& v : versions) {
    for (const auto& row : v.rates) {
      for (const double r : row) largest = std::max(largest, std::isfinite(r) ? r : 0.0);
    }
  }
  const double count = m.last - m.first + 1.0;
  const auto sensors = static_cast<double>(m.sensors);
  SvgPlot::Frame frame;
  frame.height = frame.top + frame.bottom + std::clamp(16.0 * sensors, 64.0, 420.0);
  Axis x({m.first, m.last + 1.0}, "episode (each spans its horizon, " + formatTick(m.horizon) +
                                      " s of emulated time)");
  if (count <= 20.0) {
    for (double k = m.first; k <= m.last + 1.0; k += 1.0) x.ticks.push_back(k);
  }
  Axis y{{-0.5, sensors - 0.5}, "sensor"};
  const double every = std::max(1.0, std::ceil(sensors / 20.0));
  for (double j = 0; j < sensors; j += every) y.ticks.push_back(j);
  SvgPlot plot(frame, x, y);
  const double cells = count * static_cast<double>(m.intervals) * sensors;
  const bool detailed = count * static_cast<double>(m.intervals) <= kMaxMapColumns &&
                        cells <= kMaxMapCells;
  if (detailed) {
    drawDetailedMap(plot, versions, m, largest);
  } else {
    const double columns = std::max(1.0, std::min(kMaxMapColumns, std::floor(kMaxMapCells / sensors)));
    drawBlockMap(plot, versions, m, largest, std::ceil(count / columns));
  }
  for (std::size_t i = 1; i < versions.size(); ++i) {
    plot.vline(versions[i].episode + versions[i].time_s / m.horizon,
               Style::line(kAccent, 1.6, "6 3"), "v" + formatTick(versions[i].version));
  }
  plot.legend({{"0 Hz", Style::outlined(rampColour(0.0), kGrey)},
               {formatTick(0.5 * largest) + " Hz", Style::area(rampColour(0.5))},
               {formatTick(largest) + " Hz", Style::area(rampColour(1.0))},
               {"a new version takes effect", Style::line(kAccent, 1.6, "6 3")}});
  return figure("schedule", heading, plot.svg("plot-schedule", heading) + versionTable(published),
                std::string("Rows are sensors, time runs left to right through the episodes; "
                            "darker is a higher rate λ<sub>j</sub>(t) of the version in force. ") +
                    (detailed ? "Each cell is one interval of the schedule in one episode."
                              : "Each column is the mean rate over a block of episodes (too many "
                                "episodes to draw every interval).") +
                    " Dashed rules mark where a new version took effect.");
}

// ---- 3. per-sensor counts ---------------------------------------------------------------------

std::string sensorPlot(const std::vector<SensorRecord>& sensors) {
  if (sensors.empty()) return note("Measurements per sensor", "The report lists no sensor.");
  struct Series {
    double (*value)(const SensorRecord&);
    const char* label;
    Style style;
  };
  const auto dropped_by_network = [](const SensorRecord& s) {
    return asDouble(s.dropped_by_network);
  };
  std::vector<Series> series = {
      {[](const SensorRecord& s) { return s.expected; }, "expected",
       Style::outlined(kPale, kGrey)},
      {[](const SensorRecord& s) { return asDouble(s.sent); }, "sent", Style::area(kInk)},
      {[](const SensorRecord& s) { return asDouble(s.received); }, "received", Style::area(kMid)},
      {[](const SensorRecord& s) { return asDouble(s.lost); }, "lost", Style::area(kAccent)}};
  Extent y;
  bool dropped = false;
  for (const SensorRecord& s : sensors) {
    for (const Series& one : series) y.add(one.value(s));
    dropped = dropped || s.dropped_by_network > 0;
  }
  if (dropped) {
    series.push_back({dropped_by_network, "dropped by the network",
                      Style::outlined("#ffffff", kInk)});
    series.back().style.dash = "3 2";
    for (const SensorRecord& s : sensors) y.add(dropped_by_network(s));
  }
  const auto count = static_cast<double>(sensors.size());
  Axis x{{-0.5, count - 0.5}, "sensor"};
  const double every = std::max(1.0, std::ceil(count / 25.0));
  for (double j = 0; j < count; j += every) x.ticks.push_back(j);
  SvgPlot plot(SvgPlot::Frame{}, x, Axis{niceRange({0.0, std::max(1.0, y.hi)}, 5), "measurements"});
  const double width = 0.84 / static_cast<double>(series.size());
  std::vector<LegendEntry> legend;
  for (std::size_t i = 0; i < series.size(); ++i) {
    legend.push_back({series[i].label, series[i].style});
    for (std::size_t j = 0; j < sensors.size(); ++j) {
      const double left = static_cast<double>(j) - 0.42 + width * static_cast<double>(i);
      const double value = series[i].value(sensors[j]);
      plot.rect(left, left + width, 0.0, value, series[i].style,
                "sensor " + std::to_string(j) + ": " + formatTick(value) + " " + series[i].label);
    }
  }
  plot.legend(legend);
  return figure("sensors", "Measurements per sensor",
                plot.svg("plot-sensors", "Measurements per sensor"),
                "Over every episode: expected = ∫λ<sub>j</sub> dt under the versions in force; "
                "sent = received + lost (+ dropped by the emulated network, when it drops).");
}

// ---- 4. latency histogram ---------------------------------------------------------------------

std::string formatDuration(double seconds) {
  if (seconds <= 0.0) return "0";
  if (seconds >= 1.0) return formatTick(seconds) + " s";
  if (seconds >= 1e-3) return formatTick(seconds * 1e3) + " ms";
  if (seconds >= 1e-6) return formatTick(seconds * 1e6) + " µs";
  return formatTick(seconds * 1e9) + " ns";
}

std::string latencyPlot(const std::optional<LatencyRecord>& latency) {
  const std::string heading = "Publish-to-fusion latency";
  if (latency && latency->unknown_because) {
    return note(heading, "Not known: " + *latency->unknown_because + ".");
  }
  const double median = latency ? orNan(latency->median) : kNan;
  const double p99 = latency ? orNan(latency->p99) : kNan;
  // The record keeps the histogram as written (LatencyRecord::histogram): read here as json.
  const json& histogram = latency ? latency->histogram : kNone;
  if (!histogram.is_object()) {
    return note(heading, "The report carries no latency histogram (median " +
                             formatDuration(median) + ", p99 " + formatDuration(p99) + ").");
  }
  const std::vector<double> edges = numbers(histogram.value("edges_s", json::array()));
  const std::vector<double> counts = numbers(histogram.value("counts", json::array()));
  if (edges.size() != counts.size() + 1 || counts.empty() || !(edges.front() > 0.0)) {
    return note(heading, "The report's latency histogram is malformed.");
  }
  Extent y;
  y.add(counts);
  Axis x{{edges.front(), edges.back()}, "latency (log scale)", true};
  x.format = formatDuration;
  SvgPlot plot(SvgPlot::Frame{}, x, Axis{niceRange({0.0, std::max(1.0, y.hi)}, 5), "measurements"});
  for (std::size_t i = 0; i < counts.size(); ++i) {
    plot.rect(edges[i], edges[i + 1], 0.0, counts[i], Style::outlined(kMid, "#ffffff"),
              formatDuration(edges[i]) + " to " + formatDuration(edges[i + 1]) + ": " +
                  formatTick(counts[i]));
  }
  if (median > 0.0) plot.vline(median, Style::line(kInk, 2.0), "median " + formatDuration(median));
  if (p99 > 0.0) plot.vline(p99, Style::line(kAccent, 2.0, "6 3"), "p99 " + formatDuration(p99));
  plot.legend({{"measurements per bin", Style::outlined(kMid, "#ffffff")},
               {"median", Style::line(kInk, 2.0)},
               {"p99", Style::line(kAccent, 2.0, "6 3")}});
  return figure("latency", heading, plot.svg("plot-latency", heading),
                "Wall time from a sensor's publication to the fusion center's receipt, every "
                "measurement of the run, in log-spaced bins (5 a decade).");
}

// The sensor processes' clocks against the fusion center's (the report's `clocks`): a table,
// since a handful of offsets with their uncertainties read best as numbers.
std::string clocksTable(const std::optional<report::ClocksRecord>& clocks) {
  if (!clocks || clocks->processes.empty()) return "";
  const auto signedDuration = [](double seconds) {
    return (seconds < 0.0 ? "−" : seconds > 0.0 ? "+" : "") + formatDuration(std::abs(seconds));
  };
  std::string t = "<table class=\"clocks\"><tr><th>process</th><th>sensors</th>"
                  "<th>offset</th><th>±</th><th>exchanges</th><th></th></tr>\n";
  for (const report::ClockProcessRecord& p : clocks->processes) {
    std::string sensors;
    for (const int j : p.sensors) sensors += (sensors.empty() ? "" : ", ") + std::to_string(j);
    const bool beyond = std::abs(p.offset_s) - p.uncertainty_s > clocks->bound_s;
    t += "<tr><td>" + escapeXml(p.process) + "</td><td>" + escapeXml(sensors) + "</td><td>" +
         escapeXml(signedDuration(p.offset_s)) + "</td><td>" + escapeXml(formatDuration(p.uncertainty_s)) +
         "</td><td>" + std::to_string(p.exchanges) + "</td><td>" +
         (beyond ? "beyond the bound" : "") + "</td></tr>\n";
  }
  return "<section class=\"note\"><h2>Clocks</h2><p>" +
         escapeXml("Each sensor process's wall clock minus the fusion center's (+ ahead), measured "
                   "both ways as NTP does, from the fastest of its latest exchanges; the true "
                   "offset lies within ± of it. Beyond " + formatDuration(clocks->bound_s) +
                   " for certain, latencies across it are not known.") +
         "</p>" + t + "</table></section>\n";
}

// ---- 5. covariance traces ---------------------------------------------------------------------

std::string tracePlot(const RunRecord& run) {
  const std::string heading = "Weighted covariance over time";
  // The record keeps covariance_traces as written (RunRecord::other): read here as json.
  const auto found = run.other.find("covariance_traces");
  const json& traces = found != run.other.end() ? *found : kNone;
  if (!traces.is_object() || traces.value("episodes", json::array()).empty()) {
    return note(heading, "The report carries no covariance traces.");
  }
  const std::string weight = traces.value("weight", std::string("W"));
  Extent x, y;
  const auto extentOf = [&](const json& curve) {
    x.add(numbers(curve.value("times_s", json::array())));
    y.add(numbers(curve.value("values", json::array())));
  };
  for (const json& e : traces.at("episodes")) extentOf(e);
  for (const json& s : traces.value("surrogates", json::array())) {
    extentOf(s.value("info", json::object()));
    extentOf(s.value("cov", json::object()));
  }
  if (x.empty() || y.empty()) return note(heading, "The covariance traces are empty.");
  // A log axis: the covariance falls by orders of magnitude within the first measurements, and
  // on a linear axis everything after them is flat. Linear only if a value is not positive.
  const bool log = y.lo > 0.0;
  const Interval y_range = log ? Interval{y.lo / 1.25, y.hi * 1.25}
                               : niceRange({std::min(0.0, y.lo), y.hi}, 5);
  SvgPlot plot(SvgPlot::Frame{}, Axis{{x.lo, x.hi}, "emulated time t (s)"},
               Axis{y_range, "⟨" + weight + ", P(t)⟩ (state units², " +
                                 (log ? "log scale)" : "linear)"), log});
  std::vector<LegendEntry> legend;
  const char* shades[] = {kInk, kMid, "#9db3d6"};
  std::size_t i = 0;
  for (const json& e : traces.at("episodes")) {
    const Style style = Style::line(shades[std::min<std::size_t>(i++, 2)], 1.4);
    const std::string label = "episode " + formatTick(number(e, "episode"));
    plot.polyline(numbers(e.at("times_s")), numbers(e.at("values")), style, label);
    legend.push_back({label, style});
  }
  for (const json& s : traces.value("surrogates", json::array())) {
    const std::string v = " (v" + formatTick(number(s, "version")) + ")";
    const Style info = Style::line(kAccent, 2.0, "8 4");
    const Style cov = Style::line(kInk, 2.0, "2 3");
    plot.polyline(numbers(s.at("info").at("times_s")), numbers(s.at("info").at("values")), info,
                  "information-form surrogate" + v);
    plot.polyline(numbers(s.at("cov").at("times_s")), numbers(s.at("cov").at("values")), cov,
                  "covariance-form surrogate" + v);
    legend.push_back({"info surrogate" + v, info});
    legend.push_back({"cov surrogate" + v, cov});
  }
  plot.legend(legend);
  return figure("trace", heading, plot.svg("plot-trace", heading),
                "⟨" + escapeXml(weight) + ", P(t)⟩ of the fusion center's exact filter in the "
                "first episodes (sampled on 200 times; it drops at each fused measurement), and "
                "the same of the information-form (eq. 11) and covariance-form (eq. 15) "
                "surrogates of the schedule in force at their start, from P0.");
}

// ---- 6. faults --------------------------------------------------------------------------------

// "consequence of interrupted in sensornet: " for an entry that followed from another.
std::string consequenceNote(const FaultRecord& fault) {
  if (!fault.caused_by) return "";
  return escapeXml("consequence of " + std::string(wordOf(fault.caused_by->kind)) + " in " +
                   fault.caused_by->process + ": ");
}

// A cell of the faults table: "–" for what the fault does not say.
template <class T>
std::string faultCell(const std::optional<T>& value) {
  return value ? escapeXml(formatTick(asDouble(*value))) : std::string("–");
}

// The sensors a fault names: its list ("3, 4, 5") or its one sensor.
std::string sensorsCell(const FaultRecord& f) {
  if (!f.sensors || f.sensors->empty()) return faultCell(f.sensor);
  std::string names;
  for (const int j : *f.sensors) names += (names.empty() ? "" : ", ") + std::to_string(j);
  return escapeXml(names);
}

std::string faultPlot(const RunRecord& run) {
  if (run.faults.empty()) return "";
  // The report's `episodes` (not finishedEpisodes()): the axis the page has always drawn.
  const double episodes = std::max(1.0, orNan(run.episodes));
  double horizon = 1.0;
  for (const ScheduleVersionRecord& v : run.schedule_versions) {
    if (v.horizon_s > 0.0) horizon = v.horizon_s;
  }
  std::map<std::string, double> rows;
  for (const FaultRecord& f : run.faults) rows.emplace(wordOf(f.kind), 0.0);
  double row = 0.0;
  for (auto& [kind, at] : rows) at = row++;
  SvgPlot::Frame frame;
  frame.left = 130.0;
  frame.height = frame.top + frame.bottom + std::max(60.0, 26.0 * row);
  Axis y{{-0.5, row - 0.5}, "fault"};
  for (const auto& [kind, at] : rows) y.ticks.push_back(at);
  y.format = [rows](double v) {
    for (const auto& [kind, at] : rows) {
      if (at == v) return kind;
    }
    return std::string();
  };
  SvgPlot plot(frame, episodeAxis(0.0, episodes - 1.0, "episode (and emulated time within it)"), y);
  std::string table = "<table class=\"faults\"><tr><th>kind</th><th>process</th><th>sensor</th>"
                      "<th>episode</th><th>t (s)</th><th>detail</th></tr>\n";
  for (const FaultRecord& f : run.faults) {
    const double episode = orNan(f.episode);
    const double t = orNan(f.emulated_time_s);
    const double within = std::isfinite(t) ? std::clamp(t / horizon, 0.0, 1.0) : 0.5;
    const double at = std::isfinite(episode) ? episode - 0.5 + within : episodes - 0.5;
    const std::string kind(wordOf(f.kind));
    plot.circle(at, rows[kind], 5.0, Style::outlined(kAccent, kInk), kind + ": " + f.detail);
    table += "<tr><td>" + escapeXml(kind) + "</td><td>" + escapeXml(f.process) + "</td><td>" +
             sensorsCell(f) + "</td><td>" + faultCell(f.episode) + "</td><td>" +
             faultCell(f.emulated_time_s) + "</td><td>" + consequenceNote(f) +
             escapeXml(f.detail) + "</td></tr>\n";
  }
  plot.legend({{"fault (a fault of no episode sits at the run's end)",
                Style::outlined(kAccent, kInk)}});
  return figure("faults", "Faults", plot.svg("plot-faults", "Faults") + table + "</table>\n",
                "Each mark is one entry of the report's faults list, at its episode and, when "
                "known, its emulated time within the episode.");
}

// ---- the page ---------------------------------------------------------------------------------

std::string summaryTable(const RunRecord& run) {
  const SummaryRecord& s = run.summary;
  const auto row = [](const std::string& name, const std::string& value) {
    return "<tr><th>" + escapeXml(name) + "</th><td>" + escapeXml(value) + "</td></tr>\n";
  };
  const auto yesNo = [](const std::optional<bool>& meets) {
    return meets ? (*meets ? "yes" : "no") : "undetermined (fewer than 2 complete episodes)";
  };
  std::string t = "<table class=\"summary\">\n";
  t += row("status", std::string(wordOf(run.status)));
  t += row("episodes (complete)", formatTick(asDouble(s.episodes)) + " (" +
                                      formatTick(asDouble(s.episodes_complete)) + ")");
  // Nothing that was not measured is printed as a number: no mean without a complete episode,
  // no interval without two.
  const double complete = asDouble(s.episodes_complete);
  const double mean = orNan(s.mean);
  std::string cost = "not measured (no complete episode)";
  if (complete >= 1.0 && std::isfinite(mean)) {
    cost = formatTick(mean);
    const double low = orNan(s.ci95_low);
    const double high = orNan(s.ci95_high);
    cost += complete >= 2.0 && std::isfinite(low) && std::isfinite(high)
                ? ", 95% interval [" + formatTick(low) + ", " + formatTick(high) + "]"
                : ", no 95% interval (one complete episode)";
  }
  t += row("mean realized cost", cost);
  const BracketRecord bracket = s.bracket.value_or(BracketRecord{});
  const double info = orNan(bracket.info);
  const double cov = orNan(bracket.cov);
  t += row("mean bracket", complete >= 1.0 && std::isfinite(info) && std::isfinite(cov)
                               ? "[" + formatTick(info) + ", " + formatTick(cov) + "]"
                               : "not measured (no complete episode)");
  t += row("meets the bracket", yesNo(s.meets_bracket));
  if (s.nees_band_low && s.nees_band_high && s.nees_mean) {
    t += row("mean NEES in the chi-square band of a consistent filter",
             formatTick(*s.nees_mean) + " in [" + formatTick(*s.nees_band_low) + ", " +
                 formatTick(*s.nees_band_high) + "]: " + yesNo(s.nees_consistent));
  }
  // What the schedule delivered and the real-time cost, where they are not the planned bracket
  // and the realized cost (as the launcher's closing lines say).
  const BracketRecord delivered = s.delivered_bracket.value_or(BracketRecord{});
  const double d_info = orNan(delivered.info), d_cov = orNan(delivered.cov);
  if (complete >= 1.0 && std::isfinite(d_info) && std::isfinite(d_cov) && std::isfinite(info) &&
      std::isfinite(cov) && bracketsDiffer(info, cov, d_info, d_cov)) {
    t += row("mean bracket delivered (dead sensors, network losses)",
             "[" + formatTick(d_info) + ", " + formatTick(d_cov) + "]");
    t += row("meets the delivered bracket", yesNo(s.meets_delivered_bracket));
  }
  const double realtime = orNan(s.realtime_mean);
  if (complete >= 1.0 && std::isfinite(realtime) && std::isfinite(mean) && realtime != mean) {
    t += row("mean real-time cost (what had arrived by each instant)", formatTick(realtime));
  }
  const std::string sent = formatTick(asDouble(s.sent));
  const std::string received = formatTick(asDouble(s.received));
  const std::string lost = formatTick(asDouble(s.lost));
  // sent = received + dropped by the emulated network + refused + lost, the parts that occur.
  std::string names = "sent / received";
  std::string counts = sent + " / " + received;
  const auto part = [&](std::uint64_t count, const std::string& name) {
    if (count == 0) return;
    names += " / " + name;
    counts += " / " + formatTick(asDouble(count));
  };
  part(s.dropped_by_network, "dropped by the emulated network");
  part(s.refused, "refused (malformed)");
  t += row(names + " / lost", counts + " / " + lost);
  // Causes: an entry that followed from another (caused_by) is counted with it.
  const std::size_t causes = run.causeCount();
  const std::size_t listed = run.faults.size();
  t += row("faults", std::to_string(causes) +
                         (listed > causes ? " (and " + std::to_string(listed - causes) +
                                                " consequences)"
                                          : std::string()));
  return t + "</table>\n";
}

std::string formatCsv(double value) { return std::isfinite(value) ? formatNumber(value) : ""; }

}  // namespace

RunRecord decodeReport(const json& report, const std::string& source) {
  // What every report has, checked first to name it in the reader's words (the codec's are
  // terser: "a string"); the rest is the codec's, its field and expectation as the error's.
  if (!report.is_object()) throw InputError(source, "", "a JSON object (a run report)");
  const auto require = [&](const char* key, json::value_t type, const std::string& what) {
    const auto it = report.find(key);
    if (it == report.end() || it->type() != type) throw InputError(source, key, what);
  };
  require("run_id", json::value_t::string, "a string (the run id)");
  require("status", json::value_t::string, "the run's status: " + wordChoices<RunStatus>());
  require("per_episode", json::value_t::array, "an array of episode entries");
  require("sensors", json::value_t::array, "an array of per-sensor counts");
  require("summary", json::value_t::object, "an object (the run's summary)");
  try {
    return decodeRunRecord(report);
  } catch (const RecordError& e) {
    throw InputError(source, e.field(), e.expected());
  }
}

void checkReport(const json& report, const std::string& source) {
  (void)decodeReport(report, source);
}

namespace {

// The report file's document, or the InputError saying why it is none.
json readReportDocument(const std::filesystem::path& path) {
  ReportFile file = readReport(path);
  switch (file.problem) {
    case ReportFile::Problem::None: break;
    case ReportFile::Problem::Unreadable:
      throw InputError(path.string(), "", "a readable run report (cannot open it)");
    case ReportFile::Problem::NotJson:
      throw InputError(path.string(), "", "JSON (a run report)");
    case ReportFile::Problem::NotAReport:
      throw InputError(path.string(), file.field, file.expected);
  }
  return std::move(file.report);
}

}  // namespace

json readReportFile(const std::filesystem::path& path) {
  json report = readReportDocument(path);
  checkReport(report, path.string());
  return report;
}

namespace {

// The episode entries the page and the tables draw: a record read without them
// (EpisodeEntries::Skipped) has none to draw, which is not a run that fused no episode.
const std::vector<EpisodeRecord>& episodeEntries(const RunRecord& run, const std::string& source) {
  if (!run.per_episode) throw InputError(source, "per_episode", "an array of episode entries");
  return *run.per_episode;
}

}  // namespace

std::string reportPage(const RunRecord& run, const std::string& source) {
  const std::vector<EpisodeRecord>& per_episode = episodeEntries(run, source);
  const std::string digest = run.scenario ? run.scenario->digest : std::string();
  const std::string written = run.written_at.value_or("unknown date");
  std::string page = "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n"
                     "<title>sensornet run " + escapeXml(run.run_id) + "</title>\n<style>" +
                     kPageStyle + "</style>\n</head>\n<body>\n";
  page += "<h1>sensornet run " + escapeXml(run.run_id) + "</h1>\n<div class=\"meta\">scenario " +
          escapeXml(digest.empty() ? "(digest unknown)" : digest) + " · " +
          formatTick(run.scenario ? asDouble(run.scenario->sensors) : kNan) + " sensors, " +
          formatTick(run.scenario ? asDouble(run.scenario->states) : kNan) + " states · written " +
          escapeXml(written) + "</div>\n";
  page += summaryTable(run);
  page += costPlot(per_episode, run.schedule_versions);
  page += schedulePlots(run.schedule_versions, per_episode);
  page += sensorPlot(run.sensors);
  page += latencyPlot(run.latency_s);
  page += clocksTable(run.clocks);
  page += tracePlot(run);
  page += faultPlot(run);
  page += std::string("<script>") + kPageScript + "</script>\n</body>\n</html>\n";
  return page;
}

std::string reportPage(const json& report, const std::string& source) {
  return reportPage(decodeReport(report, source), source);
}

ReportTables reportTables(const RunRecord& run, const std::string& source) {
  ReportTables tables;
  std::ostringstream e;
  e << "episode,complete,realized_cost,realtime_cost,bracket_info,bracket_cov,"
       "delivered_bracket_info,delivered_bracket_cov,nees,schedule_version,switch_time_s,sent,"
       "received,lost,dropped_by_network,late,expected,latency_median_s,latency_p99_s\n";
  for (const EpisodeRecord& r : episodeEntries(run, source)) {
    e << formatCsv(asDouble(r.episode)) << ',' << (r.complete ? 1 : 0) << ','
      << formatCsv(orNan(r.realized_cost)) << ',' << formatCsv(orNan(r.realtime_cost)) << ','
      << formatCsv(orNan(r.bracket.info)) << ',' << formatCsv(orNan(r.bracket.cov)) << ','
      << formatCsv(orNan(r.delivered_bracket.info)) << ','
      << formatCsv(orNan(r.delivered_bracket.cov)) << ',' << formatCsv(orNan(r.nees)) << ','
      << (r.schedule_versions.empty() ? "" : formatCsv(asDouble(r.schedule_versions.back())))
      << ',' << formatCsv(r.switch_time_s);
    for (const double sum : {sumOf(r.sent), sumOf(r.received), sumOf(r.lost),
                             sumOf(r.dropped_by_network), sumOf(r.late), sumOf(r.expected)}) {
      e << ',' << formatCsv(sum);
    }
    e << ',' << formatCsv(orNan(r.latency_median_s)) << ',' << formatCsv(orNan(r.latency_p99_s)) << '\n';
  }
  tables.episodes = e.str();
  std::ostringstream s;
  s << "sensor_id,sent,received,lost,dropped_by_network,late,expected,wrong_version\n";
  for (const SensorRecord& row : run.sensors) {
    s << formatCsv(asDouble(row.sensor_id)) << ',' << formatCsv(asDouble(row.sent)) << ','
      << formatCsv(asDouble(row.received)) << ',' << formatCsv(asDouble(row.lost)) << ','
      << formatCsv(asDouble(row.dropped_by_network)) << ',' << formatCsv(asDouble(row.late))
      << ',' << formatCsv(row.expected) << ',' << formatCsv(asDouble(row.wrong_version)) << '\n';
  }
  tables.sensors = s.str();
  return tables;
}

ReportTables reportTables(const json& report, const std::string& source) {
  return reportTables(decodeReport(report, source), source);
}

std::filesystem::path pagePathBeside(const std::filesystem::path& report_path) {
  std::filesystem::path page = report_path;
  if (page.extension() == ".json") return page.replace_extension(".html");
  return page += ".html";
}

std::optional<std::string> writePageBeside(const std::filesystem::path& report_path) {
  const std::filesystem::path page = pagePathBeside(report_path);
  try {
    // Decoded once: the page of the record, not readReportFile's check and then the page's.
    const std::string source = report_path.string();
    const std::string html = reportPage(decodeReport(readReportDocument(report_path), source),
                                        source);
    writeJsonFile(page.string(), "report page", [&](std::ostream& out) { out << html; });
    return std::nullopt;
  } catch (const std::exception& e) {
    return "no report page " + page.string() + ": " + e.what();
  }
}

}  // namespace sensornet::report
