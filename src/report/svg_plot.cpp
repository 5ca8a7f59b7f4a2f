#include "sensornet/report/svg_plot.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>

namespace sensornet::report {
namespace {

// The tick step niceTicks uses: 1, 2 or 5 times a power of ten, about span / count.
double niceStep(double span, int count) {
  const double raw = span / std::max(count, 1);
  const double power = std::pow(10.0, std::floor(std::log10(raw)));
  const double mantissa = raw / power;
  const double nice = mantissa < 1.5 ? 1.0 : mantissa < 3.5 ? 2.0 : mantissa < 7.5 ? 5.0 : 10.0;
  return nice * power;
}

std::string styleAttributes(const Style& s) {
  std::string a = " stroke=\"" + s.stroke + "\" fill=\"" + s.fill + "\"";
  if (s.stroke != "none") a += " stroke-width=\"" + formatTick(s.stroke_width) + "\"";
  if (!s.dash.empty()) a += " stroke-dasharray=\"" + s.dash + "\"";
  if (s.fill_opacity < 1.0) a += " fill-opacity=\"" + formatTick(s.fill_opacity) + "\"";
  return a;
}

std::string titled(const std::string& element, const std::string& attributes,
                   const std::string& title) {
  if (title.empty()) return "<" + element + attributes + "/>\n";
  return "<" + element + attributes + "><title>" + escapeXml(title) + "</title></" + element +
         ">\n";
}

std::string point(double x, double y) { return formatPixels(x) + "," + formatPixels(y); }

bool finite(double a, double b) { return std::isfinite(a) && std::isfinite(b); }

}  // namespace

std::string formatPixels(double pixels) {
  char text[32];
  std::snprintf(text, sizeof text, "%.2f", pixels);
  return text;
}

std::string formatTick(double value) {
  if (std::abs(value) < 1e-300) return "0";
  char text[32];
  std::snprintf(text, sizeof text, "%.6g", value);
  return text;
}

Scale::Scale(Interval data, Interval pixels, bool log) : data_(data), pixels_(pixels), log_(log) {
  if (log_ && !(data_.lo > 0.0 && data_.hi > 0.0)) {
    throw std::invalid_argument("a log scale needs a positive range");
  }
}

double Scale::operator()(double value) const {
  const double lo = log_ ? std::log10(data_.lo) : data_.lo;
  const double hi = log_ ? std::log10(data_.hi) : data_.hi;
  const double v = log_ ? std::log10(value) : value;
  if (hi == lo) return 0.5 * (pixels_.lo + pixels_.hi);
  return pixels_.lo + (v - lo) / (hi - lo) * (pixels_.hi - pixels_.lo);
}

std::vector<double> niceTicks(Interval range, int count) {
  if (!(range.hi > range.lo)) return {range.lo};
  const double step = niceStep(range.hi - range.lo, count);
  std::vector<double> ticks;
  const double first = std::ceil(range.lo / step - 1e-9);
  for (double k = first; k * step <= range.hi + 1e-9 * step; k += 1.0) {
    const double tick = k * step;
    ticks.push_back(std::abs(tick) < 1e-12 * step ? 0.0 : tick);
  }
  return ticks;
}

Interval niceRange(Interval range, int count) {
  if (!(range.hi > range.lo)) {
    const double half = range.lo == 0.0 ? 1.0 : 0.5 * std::abs(range.lo);
    range = {range.lo - half, range.hi + half};
  }
  const double step = niceStep(range.hi - range.lo, count);
  return {std::floor(range.lo / step + 1e-9) * step, std::ceil(range.hi / step - 1e-9) * step};
}

std::vector<double> decadeTicks(Interval range) {
  std::vector<double> ticks;
  for (double e = std::ceil(std::log10(range.lo) - 1e-9); e <= std::log10(range.hi) + 1e-9; e += 1) {
    ticks.push_back(std::pow(10.0, e));
  }
  return ticks;
}

std::vector<double> logTicks(Interval range) {
  std::vector<double> ticks = decadeTicks(range);
  if (ticks.size() >= 3) return ticks;
  ticks.clear();
  for (double e = std::floor(std::log10(range.lo)); e <= std::ceil(std::log10(range.hi)); e += 1) {
    for (const double m : {1.0, 2.0, 5.0}) {
      const double tick = m * std::pow(10.0, e);
      if (tick >= range.lo * (1 - 1e-9) && tick <= range.hi * (1 + 1e-9)) ticks.push_back(tick);
    }
  }
  return ticks;
}

std::vector<PlacedLabel> layOutRuleLabels(const std::vector<double>& at,
                                          const std::vector<std::string>& labels, double left,
                                          double right, double top, double row_height) {
  constexpr double kGap = 3.0;  // between a rule and its label, and between labels
  std::vector<std::size_t> order(std::min(at.size(), labels.size()));
  for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return at[a] < at[b]; });
  std::vector<PlacedLabel> placed(order.size());
  std::vector<std::vector<Interval>> rows;  // the pixel spans taken in each row
  for (const std::size_t i : order) {
    const double width = kRuleLabelCharPx * static_cast<double>(labels[i].size());
    PlacedLabel p;
    p.anchor_end = at[i] + kGap + width > right && at[i] - kGap - width >= left;
    const double from = p.anchor_end ? at[i] - kGap - width : at[i] + kGap;
    p.x = p.anchor_end ? at[i] - kGap : at[i] + kGap;
    const Interval span{from - kGap, from + width + kGap};
    std::size_t row = 0;
    for (; row < rows.size(); ++row) {
      const bool clear = std::none_of(rows[row].begin(), rows[row].end(), [&](const Interval& t) {
        return span.lo < t.hi && t.lo < span.hi;
      });
      if (clear) break;
    }
    if (row == rows.size()) rows.emplace_back();
    rows[row].push_back(span);
    p.y = top + row_height * static_cast<double>(row + 1);
    placed[i] = p;
  }
  return placed;
}

Style Style::line(const std::string& colour, double width, const std::string& dash) {
  Style s;
  s.stroke = colour;
  s.stroke_width = width;
  s.dash = dash;
  return s;
}

Style Style::area(const std::string& colour, double opacity) {
  Style s;
  s.fill = colour;
  s.fill_opacity = opacity;
  return s;
}

Style Style::outlined(const std::string& fill, const std::string& stroke) {
  Style s;
  s.fill = fill;
  s.stroke = stroke;
  s.stroke_width = 1.0;
  return s;
}

SvgPlot::SvgPlot(Frame frame, Axis x, Axis y)
    : frame_(frame),
      x_(std::move(x)),
      y_(std::move(y)),
      x_scale_(x_.range, {frame_.left, frame_.width - frame_.right}, x_.log),
      y_scale_(y_.range, {frame_.height - frame_.bottom, frame_.top}, y_.log) {
  if (x_.ticks.empty()) x_.ticks = x_.log ? logTicks(x_.range) : niceTicks(x_.range, 8);
  if (y_.ticks.empty()) y_.ticks = y_.log ? logTicks(y_.range) : niceTicks(y_.range, 5);
}

void SvgPlot::polyline(const std::vector<double>& xs, const std::vector<double>& ys,
                       const Style& style, const std::string& title) {
  std::string points;
  const auto flush = [&] {
    if (points.find(' ') != std::string::npos) {
      marks_ += titled("polyline", " points=\"" + points + "\"" + styleAttributes(style), title);
    }
    points.clear();
  };
  for (std::size_t i = 0; i < std::min(xs.size(), ys.size()); ++i) {
    if (!finite(xs[i], ys[i])) {
      flush();
      continue;
    }
    points += (points.empty() ? "" : " ") + point(px(xs[i]), py(ys[i]));
  }
  flush();
}

void SvgPlot::band(const std::vector<double>& xs, const std::vector<double>& lo,
                   const std::vector<double>& hi, const Style& style, const std::string& title) {
  std::string path;
  const std::size_t n = std::min({xs.size(), lo.size(), hi.size()});
  for (std::size_t i = 0; i < n; ++i) {
    if (!finite(xs[i], hi[i])) continue;
    path += (path.empty() ? "M" : " L") + point(px(xs[i]), py(hi[i]));
  }
  for (std::size_t i = n; i-- > 0;) {
    if (!finite(xs[i], lo[i])) continue;
    path += " L" + point(px(xs[i]), py(lo[i]));
  }
  if (path.empty()) return;
  marks_ += titled("path", " d=\"" + path + " Z\"" + styleAttributes(style), title);
}

void SvgPlot::rect(double x0, double x1, double y0, double y1, const Style& style,
                   const std::string& title) {
  if (!finite(x0, x1) || !finite(y0, y1)) return;
  const double left = std::min(px(x0), px(x1));
  const double top = std::min(py(y0), py(y1));
  const double width = std::abs(px(x1) - px(x0));
  const double height = std::abs(py(y1) - py(y0));
  marks_ += titled("rect",
                   " x=\"" + formatPixels(left) + "\" y=\"" + formatPixels(top) + "\" width=\"" +
                       formatPixels(width) + "\" height=\"" + formatPixels(height) + "\"" +
                       styleAttributes(style),
                   title);
}

void SvgPlot::circle(double x, double y, double radius_px, const Style& style,
                     const std::string& title) {
  if (!finite(x, y)) return;
  marks_ += titled("circle",
                   " cx=\"" + formatPixels(px(x)) + "\" cy=\"" + formatPixels(py(y)) + "\" r=\"" +
                       formatPixels(radius_px) + "\"" + styleAttributes(style),
                   title);
}

void SvgPlot::vline(double x, const Style& style, const std::string& label) {
  if (!std::isfinite(x)) return;
  const std::string at = formatPixels(px(x));
  marks_ += "<line x1=\"" + at + "\" x2=\"" + at + "\" y1=\"" + formatPixels(frame_.top) +
            "\" y2=\"" + formatPixels(frame_.height - frame_.bottom) + "\"" +
            styleAttributes(style) + "/>\n";
  if (!label.empty()) {
    rule_at_.push_back(px(x));
    rule_text_.push_back(label);
  }
}

std::string SvgPlot::ruleLabelsSvg() const {
  const std::vector<PlacedLabel> placed =
      layOutRuleLabels(rule_at_, rule_text_, 2.0, frame_.width - 2.0, frame_.top);
  std::string s;
  for (std::size_t i = 0; i < placed.size(); ++i) {
    s += "<text x=\"" + formatPixels(placed[i].x) + "\" y=\"" + formatPixels(placed[i].y) +
         "\" class=\"rule\"" + (placed[i].anchor_end ? " text-anchor=\"end\"" : "") + ">" +
         escapeXml(rule_text_[i]) + "</text>\n";
  }
  return s;
}

void SvgPlot::legend(const std::vector<LegendEntry>& entries) {
  legend_.insert(legend_.end(), entries.begin(), entries.end());
}

std::string SvgPlot::axesSvg() const {
  const double left = frame_.left;
  const double right = frame_.width - frame_.right;
  const double top = frame_.top;
  const double bottom = frame_.height - frame_.bottom;
  const auto label = [](const Axis& axis, double v) {
    return escapeXml(axis.format ? axis.format(v) : formatTick(v));
  };
  std::string s = "<g class=\"axes\">\n";
  for (const double t : x_.ticks) {
    const std::string at = formatPixels(px(t));
    s += "<line class=\"grid\" x1=\"" + at + "\" x2=\"" + at + "\" y1=\"" + formatPixels(top) +
         "\" y2=\"" + formatPixels(bottom) + "\"/>\n";
    s += "<text class=\"tick\" x=\"" + at + "\" y=\"" + formatPixels(bottom + 16.0) +
         "\" text-anchor=\"middle\">" + label(x_, t) + "</text>\n";
  }
  for (const double t : y_.ticks) {
    const std::string at = formatPixels(py(t));
    s += "<line class=\"grid\" x1=\"" + formatPixels(left) + "\" x2=\"" + formatPixels(right) +
         "\" y1=\"" + at + "\" y2=\"" + at + "\"/>\n";
    s += "<text class=\"tick\" x=\"" + formatPixels(left - 6.0) + "\" y=\"" + at +
         "\" dy=\"0.35em\" text-anchor=\"end\">" + label(y_, t) + "</text>\n";
  }
  s += "<rect class=\"frame\" x=\"" + formatPixels(left) + "\" y=\"" + formatPixels(top) +
       "\" width=\"" + formatPixels(right - left) + "\" height=\"" + formatPixels(bottom - top) +
       "\"/>\n";
  s += "<text class=\"label\" x=\"" + formatPixels(0.5 * (left + right)) + "\" y=\"" +
       formatPixels(frame_.height - 10.0) + "\" text-anchor=\"middle\">" + escapeXml(x_.label) +
       "</text>\n";
  const std::string mid = formatPixels(0.5 * (top + bottom));
  s += "<text class=\"label\" x=\"16\" y=\"" + mid + "\" text-anchor=\"middle\" transform=\"rotate(-90 16 " +
       mid + ")\">" + escapeXml(y_.label) + "</text>\n";
  return s + "</g>\n";
}

std::string SvgPlot::legendSvg() const {
  std::string s = "<g class=\"legend\">\n";
  double x = frame_.left;
  double y = 14.0;
  for (const LegendEntry& e : legend_) {
    // About 6.5 px a character; an entry that would pass the frame's right edge starts a new
    // row (Frame::top leaves room for kLegendRow px a row).
    const double width = 27.0 + 6.5 * static_cast<double>(e.label.size());
    if (x > frame_.left && x + width > frame_.width - frame_.right) {
      x = frame_.left;
      y += kLegendRow;
    }
    if (e.style.fill != "none") {
      Style swatch = e.style;
      s += "<rect x=\"" + formatPixels(x) + "\" y=\"" + formatPixels(y - 8.0) +
           "\" width=\"22\" height=\"10\"" + styleAttributes(swatch) + "/>\n";
    } else {
      s += "<line x1=\"" + formatPixels(x) + "\" x2=\"" + formatPixels(x + 22.0) + "\" y1=\"" +
           formatPixels(y - 3.0) + "\" y2=\"" + formatPixels(y - 3.0) + "\"" +
           styleAttributes(e.style) + "/>\n";
    }
    s += "<text x=\"" + formatPixels(x + 27.0) + "\" y=\"" + formatPixels(y) + "\">" +
         escapeXml(e.label) + "</text>\n";
    x += width + 18.0;
  }
  return s + "</g>\n";
}

std::string SvgPlot::svg(const std::string& id, const std::string& title) const {
  const std::string w = formatTick(frame_.width);
  const std::string h = formatTick(frame_.height);
  std::string s = "<svg xmlns=\"http://www.w3.org/2000/svg\" class=\"plot\" id=\"" +
                  escapeXml(id) + "\" viewBox=\"0 0 " + w + " " + h + "\" width=\"" + w +
                  "\" height=\"" + h + "\" role=\"img\" aria-label=\"" + escapeXml(title) +
                  "\">\n<title>" + escapeXml(title) + "</title>\n";
  const double plot_w = frame_.width - frame_.right - frame_.left;
  const double plot_h = frame_.height - frame_.bottom - frame_.top;
  s += "<defs><clipPath id=\"" + escapeXml(id) + "-area\"><rect x=\"" +
       formatPixels(frame_.left) + "\" y=\"" + formatPixels(frame_.top) + "\" width=\"" +
       formatPixels(plot_w) + "\" height=\"" + formatPixels(plot_h) + "\"/></clipPath></defs>\n";
  s += axesSvg();
  s += "<g class=\"marks\" clip-path=\"url(#" + escapeXml(id) + "-area)\">\n" + marks_ + "</g>\n";
  s += ruleLabelsSvg();
  s += legendSvg();
  return s + "</svg>\n";
}

}  // namespace sensornet::report
