#pragma once
// A small builder of self-contained SVG plots for the run's report page (report_page.hpp): axes
// with ticks, labels and a light grid, a legend row above the plot area, and marks (polylines,
// bands, rects, circles, vertical rules) given in data coordinates. No scripts, no fonts or
// styles fetched from anywhere: the page can be read offline and printed.
//
//   SvgPlot plot(SvgPlot::Frame{}, Axis{{0, 20}, "episode"}, Axis{{0, 5}, "cost J (m^2)"});
//   plot.band({0, 1, 2}, {1, 1, 1}, {3, 3, 3}, Style::area("#c6d4e8"), "bracket");
//   plot.polyline({0, 1, 2}, {2, 2.5, 2.2}, Style::line("#1f3b73"), "running mean");
//   plot.legend({{"bracket", Style::area("#c6d4e8")}, {"running mean", Style::line("#1f3b73")}});
//   const std::string svg = plot.svg("cost", "Realized cost per episode");
//
// Geometry: the plot area spans [left, width - right] x [top, height - bottom] pixels; a data x
// maps linearly (or by log10 on a log axis) from the axis range onto it, y the same with the
// range's low end at the bottom. Pixel coordinates are written with two decimals. Marks are
// clipped to the plot area and live in one <g class="marks"> (what the page's browser test
// counts); a value that is not finite breaks a polyline and skips a rect or circle.

#include <functional>
#include <string>
#include <utility>
#include <vector>

#include "sensornet/core/xml_text.hpp"

namespace sensornet::report {

struct Interval {
  double lo = 0.0;
  double hi = 1.0;
};

// A map from data values to pixels: linear, or linear in log10 (data > 0).
class Scale {
 public:
  Scale(Interval data, Interval pixels, bool log = false);
  [[nodiscard]] double operator()(double value) const;
  [[nodiscard]] Interval data() const { return data_; }
  [[nodiscard]] bool log() const { return log_; }

 private:
  Interval data_;
  Interval pixels_;
  bool log_;
};

// About `count` ticks at multiples of 1, 2 or 5 times a power of ten within [lo, hi] (both
// included when they fall on one); for lo == hi, that value alone.
[[nodiscard]] std::vector<double> niceTicks(Interval range, int count);
// The range widened outwards to the nearest multiples of the step niceTicks would use, and
// made non-empty (a single value v becomes [v - 1, v + 1], or [v - |v|/2, v + |v|/2]).
[[nodiscard]] Interval niceRange(Interval range, int count);
// Powers of ten within [lo, hi] (lo > 0), for a log axis.
[[nodiscard]] std::vector<double> decadeTicks(Interval range);
// The ticks of a log axis: the powers of ten within [lo, hi], and where fewer than three of
// them fall inside, also 2 and 5 times a power of ten.
[[nodiscard]] std::vector<double> logTicks(Interval range);
// A tick label: up to 6 significant digits, no trailing zeros ("0.2", "1500", "1e-05").
[[nodiscard]] std::string formatTick(double value);

struct Axis {
  Axis(Interval range_, std::string label_, bool log_ = false)
      : range(range_), label(std::move(label_)), log(log_) {}
  Interval range;
  std::string label;  // with its unit: "emulated time t (s)"
  bool log = false;
  std::vector<double> ticks;                 // empty: niceTicks (decadeTicks on a log axis)
  std::function<std::string(double)> format;  // empty: formatTick
};

// How a mark is drawn. Colours and dash patterns are chosen so that marks differ in lightness
// and pattern, not only in hue (the page is printed in grey).
struct Style {
  std::string stroke = "none";
  std::string fill = "none";
  double stroke_width = 1.5;
  std::string dash;          // stroke-dasharray, empty: solid
  double fill_opacity = 1.0;
  static Style line(const std::string& colour, double width = 1.5, const std::string& dash = "");
  static Style area(const std::string& colour, double opacity = 1.0);
  static Style outlined(const std::string& fill, const std::string& stroke);
};

struct LegendEntry {
  std::string label;
  Style style;
};

// The height of a legend row: the legend wraps where a row would pass the frame's right edge.
inline constexpr double kLegendRow = 16.0;

class SvgPlot {
 public:
  struct Frame {
    double width = 760.0;
    double height = 300.0;
    double left = 72.0;
    double right = 20.0;
    double top = 34.0;  // room for the legend row (kLegendRow more for each further row)
    double bottom = 50.0;
  };

  SvgPlot(Frame frame, Axis x, Axis y);

  [[nodiscard]] double px(double x) const { return x_scale_(x); }
  [[nodiscard]] double py(double y) const { return y_scale_(y); }
  [[nodiscard]] const Frame& frame() const { return frame_; }

  // Each mark may carry a tooltip (`title`, shown on hover, ignored in print).
  void polyline(const std::vector<double>& xs, const std::vector<double>& ys, const Style& style,
                const std::string& title = "");
  // The area between lo(x) and hi(x) (xs increasing), as one closed path.
  void band(const std::vector<double>& xs, const std::vector<double>& lo,
            const std::vector<double>& hi, const Style& style, const std::string& title = "");
  // The rectangle [x0, x1] x [y0, y1] in data coordinates (either order).
  void rect(double x0, double x1, double y0, double y1, const Style& style,
            const std::string& title = "");
  void circle(double x, double y, double radius_px, const Style& style,
              const std::string& title = "");
  // A vertical rule across the plot area at x, labelled at its top.
  void vline(double x, const Style& style, const std::string& label = "");
  void legend(const std::vector<LegendEntry>& entries);

  // The <svg> element; `id` must be unique within the page (it names the clip path).
  [[nodiscard]] std::string svg(const std::string& id, const std::string& title) const;

 private:
  [[nodiscard]] std::string axesSvg() const;
  [[nodiscard]] std::string legendSvg() const;

  Frame frame_;
  Axis x_;
  Axis y_;
  Scale x_scale_;
  Scale y_scale_;
  [[nodiscard]] std::string ruleLabelsSvg() const;

  std::string marks_;
  std::vector<double> rule_at_;         // pixel x of each labelled rule
  std::vector<std::string> rule_text_;  // ... and its label (laid out when the svg is written)
  std::vector<LegendEntry> legend_;
};

// Where the label of a vertical rule goes: its text starts at x (anchor start) or ends there
// (anchor end), on the baseline y.
struct PlacedLabel {
  double x = 0.0;
  double y = 0.0;
  bool anchor_end = false;
};

// Lays out the labels of vertical rules at pixel positions `at` (any order) so that none
// overlaps another and none leaves [left, right]: each goes right of its rule if it fits there,
// else left of it, on the first row below `top` where it clears every label already placed
// (rows `row_height` apart). Widths are estimated from the text (kRuleLabelCharPx a character).
inline constexpr double kRuleLabelCharPx = 6.6;  // 11 px sans-serif, with room to spare
[[nodiscard]] std::vector<PlacedLabel> layOutRuleLabels(const std::vector<double>& at,
                                                        const std::vector<std::string>& labels,
                                                        double left, double right, double top,
                                                        double row_height = 12.0);

// Writes a number of pixels as the builder does (two decimals).
[[nodiscard]] std::string formatPixels(double pixels);

}  // namespace sensornet::report
