#include "sensornet/report/sweep_page.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>
#include <map>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "page_parts.hpp"
#include "sensornet/core/student_t.hpp"
#include "sensornet/core/xml_text.hpp"
#include "sensornet/report/svg_plot.hpp"

namespace sensornet::report {
namespace {

using nlohmann::json;

constexpr double kNan = std::numeric_limits<double>::quiet_NaN();
// Series colours that differ in lightness (the page is printed in grey), then in dash.
const std::vector<std::string> kColours = {"#1b2a49", "#e0891c", "#4a74b4",
                                           "#8a6d3b", "#6b9e3a", "#8c8c8c"};

// The axes a page plots against, with their labels.
const std::vector<std::pair<std::string, std::string>> kAxes = {
    {"budget", "budget b of 1'λ <= b (Hz)"},
    {"energy", "energy budget E_j of each sensor (measurements)"},
    {"sensors", "sensors M"},
    {"states", "states n"},
    {"noise_scale", "noise scale R_scale"},
    {"replan_every", "re-planned every DT (s)"},
    {"time_scale", "emulated runs' time scale (emulated s per wall s)"}};

double numberOf(const json& row, const std::string& key) {
  const auto it = row.find(key);
  return it != row.end() && it->is_number() ? it->get<double>() : kNan;
}

std::string planSeriesOf(const json& row, const std::string& axis);

// A series: the planner, and for the closed loop its surrogate and (unless it is the axis) DT;
// for an emulated cell also the network and faults it ran with, when not the scenario's own.
std::string seriesOf(const json& row, const std::string& axis) {
  std::string name = planSeriesOf(row, axis);
  for (const char* section : {"network", "faults"}) {
    const auto it = row.find(section);
    if (it != row.end() && it->is_string() && *it != "scenario") {
      name += std::string(" · ") + section + " " + it->get<std::string>();
    }
  }
  return name;
}

std::string planSeriesOf(const json& row, const std::string& axis) {
  std::string name = row.value("planner", std::string("?"));
  if (name == "timetable") return name + " (" + row.value("surrogate", std::string("?")) + ")";
  if (name == "schedule") {
    const auto file = row.find("schedule");
    return file != row.end() && file->is_string()
               ? name + " " + std::filesystem::path(file->get<std::string>()).filename().string()
               : name;
  }
  if (name == "closed_loop") {
    name += " (" + row.value("surrogate", std::string("?"));
    if (axis != "replan_every")
      name += ", every " + formatTick(numberOf(row, "replan_every")) + " s";
    name += ")";
  }
  return name;
}

struct Point {
  double x = 0.0, mean = 0.0, low = 0.0, high = 0.0, info = 0.0, cov = 0.0;
  std::size_t cells = 0;
};

// The cells of one series at one value: the mean of their means and its 95% interval.
Point pointOf(double x, const std::vector<const json*>& cells) {
  Point p;
  p.x = x;
  p.cells = cells.size();
  std::vector<double> means;
  double info = 0.0, cov = 0.0;
  for (const json* c : cells) {
    means.push_back(numberOf(*c, "mean"));
    info += numberOf(*c, "bracket_info");
    cov += numberOf(*c, "bracket_cov");
  }
  const double k = static_cast<double>(means.size());
  double sum = 0.0;
  for (const double m : means) sum += m;
  p.mean = sum / k;
  double half = numberOf(*cells.front(), "ci95");  // one cell: its own interval
  if (means.size() > 1) {
    double squares = 0.0;
    for (const double m : means) squares += (m - p.mean) * (m - p.mean);
    half = studentTQuantile(0.975, k - 1.0) * std::sqrt(squares / (k - 1.0)) / std::sqrt(k);
  }
  p.low = p.mean - half;
  p.high = p.mean + half;
  p.info = info / k;
  p.cov = cov / k;
  return p;
}

std::string axisPlot(const std::string& axis, const std::string& label,
                     const std::vector<const json*>& ok) {
  std::set<double> values;
  for (const json* row : ok) {
    const double v = numberOf(*row, axis);
    if (std::isfinite(v)) values.insert(v);
  }
  if (values.size() < 2) return "";
  std::map<std::string, std::map<double, std::vector<const json*>>> groups;
  for (const json* row : ok) {
    const double v = numberOf(*row, axis);
    if (std::isfinite(v) && std::isfinite(numberOf(*row, "mean")))
      groups[seriesOf(*row, axis)][v].push_back(row);
  }
  std::map<std::string, std::vector<Point>> series;
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  for (const auto& [name, by_value] : groups) {
    for (const auto& [x, cells] : by_value) {
      const Point p = pointOf(x, cells);
      series[name].push_back(p);
      for (const double y : {p.low, p.high, p.info, p.cov}) {
        if (std::isfinite(y)) {
          lo = std::min(lo, y);
          hi = std::max(hi, y);
        }
      }
    }
  }
  if (series.empty()) return "";
  const double x_lo = *values.begin(), x_hi = *values.rbegin();
  const bool log_x = x_lo > 0.0 && x_hi / x_lo >= 50.0;
  const bool log_y = lo > 0.0 && hi / lo >= 100.0;
  // A value's interval bar is never on the frame: the range reaches past the first and last.
  const double pad = 0.05 * (x_hi - x_lo);
  Axis x_axis(log_x ? Interval{x_lo / 1.5, x_hi * 1.5} : Interval{x_lo - pad, x_hi + pad}, label,
              log_x);
  x_axis.ticks = values.size() <= 12 ? std::vector<double>(values.begin(), values.end())
                 : log_x             ? logTicks({x_lo, x_hi})
                                     : niceTicks({x_lo, x_hi}, 8);
  Axis y_axis(log_y ? Interval{lo / 1.3, hi * 1.3} : niceRange({std::min(0.0, lo), hi}, 6),
              "realized cost E[J(P)]", log_y);
  SvgPlot plot(SvgPlot::Frame{}, x_axis, y_axis);
  std::vector<LegendEntry> legend;
  std::size_t s = 0;
  for (const auto& [name, points] : series) {
    const std::string& colour = kColours[s++ % kColours.size()];
    std::vector<double> xs, means, infos, covs;
    for (const Point& p : points) {
      xs.push_back(p.x);
      means.push_back(p.mean);
      infos.push_back(p.info);
      covs.push_back(p.cov);
      const std::string tip = name + " at " + formatTick(p.x) + ": " + formatTick(p.mean) + " [" +
                              formatTick(p.low) + ", " + formatTick(p.high) + "] over " +
                              std::to_string(p.cells) + (p.cells == 1 ? " cell" : " cells") +
                              "; bracket [" + formatTick(p.info) + ", " + formatTick(p.cov) + "]";
      plot.polyline({p.x, p.x}, {p.low, p.high}, Style::line(colour, 1.5), tip);
      plot.circle(p.x, p.mean, 3.0, Style::outlined(colour, colour), tip);
    }
    plot.polyline(xs, means, Style::line(colour, 1.8), name);
    plot.polyline(xs, infos, Style::line(colour, 1.0, "5 3"), name + ": J(P_info)");
    plot.polyline(xs, covs, Style::line(colour, 1.0, "2 3"), name + ": J(P_cov)");
    legend.push_back({name, Style::line(colour, 1.8)});
  }
  legend.push_back(
      {"bracket: J(P_info) dashed, J(P_cov) dotted", Style::line(kColours.back(), 1.0, "5 3")});
  plot.legend(legend);
  const std::string heading = "Realized cost against " + label;
  return figure(
      axis, heading, plot.svg("plot-" + axis, heading),
      "Each point: the mean of the cells' means (a Monte Carlo's, or an emulated run's over its "
      "complete episodes) at that value (over the other axes: plants, seeds), with its 95% "
      "Student-t interval over those cells (a single cell: its own interval). Dashed and "
      "dotted: the mean bracket of the "
      "same cells, J(P_info) <= E[J] <= J(P_cov).");
}

// How a cell was measured: "1000 runs" in process, or "5 episodes at x4: degraded (exit 3)".
std::string measuredBy(const json& row) {
  if (std::isfinite(numberOf(row, "runs"))) return formatTick(numberOf(row, "runs")) + " runs";
  std::string text = formatTick(numberOf(row, "episodes")) + " episodes at x" +
                     formatTick(numberOf(row, "time_scale"));
  const auto status = row.find("run_status");
  if (status != row.end() && status->is_string()) {
    text += ": " + status->get<std::string>() + " (exit " + formatTick(numberOf(row, "exit_code")) +
            ")";
  }
  return text;
}

std::string cellTable(const std::vector<json>& rows) {
  std::string t =
      "<h2>Cells</h2>\n<table "
      "class=\"faults\">\n<tr><th>scenario</th><th>budget</th><th>planner</th>"
      "<th>seed</th><th>measured by</th><th>status</th><th>E[J] ± 95%</th><th>bracket</th>"
      "<th>plan</th></tr>\n";
  for (const json& row : rows) {
    std::string scenario = row.value("scenario", std::string("?"));
    if (scenario == "random") {
      scenario += " n=" + formatTick(numberOf(row, "states")) +
                  " M=" + formatTick(numberOf(row, "sensors")) + " seed " +
                  formatTick(numberOf(row, "scenario_seed"));
      if (numberOf(row, "noise_scale") != 1.0)
        scenario += " R×" + formatTick(numberOf(row, "noise_scale"));
    }
    if (std::isfinite(numberOf(row, "energy"))) {
      scenario += " E=" + formatTick(numberOf(row, "energy"));
    }
    const bool ok = row.value("status", std::string()) == "ok";
    const double budget = numberOf(row, "budget");  // none: the file's own constraints
    t += "<tr><td>" + escapeXml(scenario) + "</td><td>" +
         (std::isfinite(budget) ? formatTick(budget) : std::string("file's")) + "</td><td>" +
         escapeXml(seriesOf(row, "")) + "</td><td>" + formatTick(numberOf(row, "seed")) +
         "</td><td>" + escapeXml(measuredBy(row)) + "</td><td>" +
         (ok ? "ok" : "failed: " + escapeXml(row.value("reason", std::string("?")))) + "</td><td>" +
         (ok ? formatTick(numberOf(row, "mean")) + " ± " + formatTick(numberOf(row, "ci95")) : "") +
         "</td><td>" +
         (ok ? "[" + formatTick(numberOf(row, "bracket_info")) + ", " +
                   formatTick(numberOf(row, "bracket_cov")) + "]"
             : "") +
         "</td><td>" + escapeXml(row.value("plan_status", std::string())) + "</td></tr>\n";
  }
  return t + "</table>\n";
}

}  // namespace

std::string sweepPage(const std::string& name, const std::vector<json>& rows) {
  std::vector<const json*> ok;
  for (const json& row : rows) {
    if (row.value("status", std::string()) == "ok") ok.push_back(&row);
  }
  std::string page =
      "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n<title>sensornet "
      "sweep " +
      escapeXml(name) + "</title>\n<style>" + kPageStyle + "</style>\n</head>\n<body>\n";
  page += "<h1>sensornet sweep " + escapeXml(name) + "</h1>\n<div class=\"meta\">" +
          std::to_string(rows.size()) + " cells · " + std::to_string(ok.size()) + " ok · " +
          std::to_string(rows.size() - ok.size()) + " failed</div>\n";
  std::string plots;
  for (const auto& [axis, label] : kAxes) plots += axisPlot(axis, label, ok);
  if (plots.empty()) {
    plots =
        "<section class=\"note\"><h2>No plot</h2><p>No axis of this experiment takes two values or "
        "more "
        "among the cells that are ok: the table below has every cell.</p></section>\n";
  }
  page += plots + cellTable(rows);
  page += std::string("<script>") + kPageScript + "</script>\n</body>\n</html>\n";
  return page;
}

}  // namespace sensornet::report
