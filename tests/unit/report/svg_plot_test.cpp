// The SVG builder of the report page: data -> pixel geometry computed here by hand from the
// frame, ticks, and what a mark's element carries.

#include "sensornet/report/svg_plot.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>
#include <vector>

namespace sensornet::report {
namespace {

// The default frame: the plot area is x in [72, 740] and y in [34, 250] pixels.
constexpr double kLeft = 72.0, kRight = 760.0 - 20.0, kTop = 34.0, kBottom = 300.0 - 50.0;

double expectedX(double x, double lo, double hi) { return kLeft + (x - lo) / (hi - lo) * (kRight - kLeft); }
double expectedY(double y, double lo, double hi) { return kBottom - (y - lo) / (hi - lo) * (kBottom - kTop); }

std::string twoDecimals(double v) {
  char text[32];
  std::snprintf(text, sizeof text, "%.2f", v);
  return text;
}

int occurrences(const std::string& text, const std::string& part) {
  int count = 0;
  for (std::size_t at = text.find(part); at != std::string::npos; at = text.find(part, at + 1)) ++count;
  return count;
}

TEST(SvgPlot, MapsDataToPixelsLinearlyWithTheLowYAtTheBottom) {
  const SvgPlot plot(SvgPlot::Frame{}, Axis{{0.0, 10.0}, "x"}, Axis{{0.0, 5.0}, "y"});
  EXPECT_NEAR(plot.px(0.0), 72.0, 1e-12);
  EXPECT_NEAR(plot.px(10.0), 740.0, 1e-12);
  EXPECT_NEAR(plot.px(2.5), 239.0, 1e-12);  // 72 + 0.25 * 668
  EXPECT_NEAR(plot.py(0.0), 250.0, 1e-12);
  EXPECT_NEAR(plot.py(5.0), 34.0, 1e-12);
  EXPECT_NEAR(plot.py(1.0), 206.8, 1e-12);  // 250 - 0.2 * 216
}

TEST(SvgPlot, MapsALogAxisByDecades) {
  const Scale scale({1e-6, 1e-2}, {0.0, 400.0}, true);
  EXPECT_NEAR(scale(1e-6), 0.0, 1e-9);
  EXPECT_NEAR(scale(1e-4), 200.0, 1e-9);
  EXPECT_NEAR(scale(1e-3), 300.0, 1e-9);
  EXPECT_NEAR(scale(std::sqrt(10.0) * 1e-6), 50.0, 1e-9);
  EXPECT_THROW(Scale({0.0, 1.0}, {0.0, 1.0}, true), std::invalid_argument);
}

TEST(SvgPlot, DrawsARectFromItsDataCornersInEitherOrder) {
  SvgPlot plot(SvgPlot::Frame{}, Axis{{0.0, 10.0}, "x"}, Axis{{0.0, 5.0}, "y"});
  plot.rect(3.0, 1.0, 2.0, 0.0, Style::area("#000000"));
  const std::string svg = plot.svg("t", "test");
  const double x = expectedX(1.0, 0, 10), w = expectedX(3.0, 0, 10) - x;
  const double y = expectedY(2.0, 0, 5), h = expectedY(0.0, 0, 5) - y;
  EXPECT_EQ(twoDecimals(x), "138.80");
  EXPECT_EQ(twoDecimals(h), "86.40");
  EXPECT_NE(svg.find("<rect x=\"" + twoDecimals(x) + "\" y=\"" + twoDecimals(y) + "\" width=\"" +
                     twoDecimals(w) + "\" height=\"" + twoDecimals(h) + "\""),
            std::string::npos)
      << svg;
}

TEST(SvgPlot, DrawsAPolylineThroughEveryPointAndBreaksItAtAMissingValue) {
  SvgPlot plot(SvgPlot::Frame{}, Axis{{-1.0, 1.0}, "x"}, Axis{{10.0, 20.0}, "y"});
  const std::vector<double> xs = {-1.0, -0.3, 0.2, 0.7, 1.0};
  const std::vector<double> ys = {10.0, 13.0, std::numeric_limits<double>::quiet_NaN(), 17.5, 20.0};
  plot.polyline(xs, ys, Style::line("#123456"));
  const std::string svg = plot.svg("t", "test");
  const auto at = [&](std::size_t i) {
    return twoDecimals(expectedX(xs[i], -1, 1)) + "," + twoDecimals(expectedY(ys[i], 10, 20));
  };
  EXPECT_NE(svg.find("points=\"" + at(0) + " " + at(1) + "\""), std::string::npos) << svg;
  EXPECT_NE(svg.find("points=\"" + at(3) + " " + at(4) + "\""), std::string::npos) << svg;
  EXPECT_EQ(occurrences(svg, "<polyline"), 2);
}

TEST(SvgPlot, ABandIsOneClosedPathAlongTheTopAndBackAlongTheBottom) {
  SvgPlot plot(SvgPlot::Frame{}, Axis{{0.0, 2.0}, "x"}, Axis{{0.0, 4.0}, "y"});
  plot.band({0.0, 2.0}, {1.0, 2.0}, {3.0, 4.0}, Style::area("#cccccc"));
  const std::string svg = plot.svg("t", "test");
  const auto p = [](double x, double y) {
    return twoDecimals(expectedX(x, 0, 2)) + "," + twoDecimals(expectedY(y, 0, 4));
  };
  EXPECT_NE(svg.find("d=\"M" + p(0, 3) + " L" + p(2, 4) + " L" + p(2, 2) + " L" + p(0, 1) + " Z\""),
            std::string::npos)
      << svg;
}

TEST(SvgPlot, PutsTicksAtOneTwoOrFiveTimesAPowerOfTen) {
  EXPECT_EQ(niceTicks({0.0, 10.0}, 5), (std::vector<double>{0, 2, 4, 6, 8, 10}));
  const std::vector<double> ticks = niceTicks({0.13, 0.91}, 4);
  ASSERT_EQ(ticks.size(), 4u);
  for (std::size_t i = 0; i < ticks.size(); ++i) EXPECT_NEAR(ticks[i], 0.2 * static_cast<double>(i + 1), 1e-12);
  const Interval nice = niceRange({0.13, 0.91}, 4);
  EXPECT_NEAR(nice.lo, 0.0, 1e-12);
  EXPECT_NEAR(nice.hi, 1.0, 1e-12);
  const Interval single = niceRange({3.0, 3.0}, 5);
  EXPECT_LT(single.lo, 3.0);
  EXPECT_GT(single.hi, 3.0);
  const std::vector<double> decades = decadeTicks({2e-6, 3e-3});
  ASSERT_EQ(decades.size(), 3u);
  EXPECT_NEAR(decades[0], 1e-5, 1e-20);
  EXPECT_NEAR(decades[2], 1e-3, 1e-18);
}

TEST(SvgPlot, WritesTickLabelsAtTheirPixelsAndTheAxisLabels) {
  const SvgPlot plot(SvgPlot::Frame{}, Axis{{0.0, 10.0}, "time t (s)"}, Axis{{0.0, 1.0}, "P & Q <1>"});
  const std::string svg = plot.svg("t", "test");
  // x tick 4 at 72 + 0.4 * 668 = 339.2, below the area; y tick 0.6 at 250 - 0.6 * 216 = 120.4.
  EXPECT_NE(svg.find("x=\"339.20\" y=\"266.00\" text-anchor=\"middle\">4</text>"), std::string::npos) << svg;
  EXPECT_NE(svg.find("y=\"120.40\" dy=\"0.35em\" text-anchor=\"end\">0.6</text>"), std::string::npos) << svg;
  EXPECT_NE(svg.find(">time t (s)</text>"), std::string::npos);
  EXPECT_NE(svg.find(">P &amp; Q &lt;1&gt;</text>"), std::string::npos);
}

TEST(SvgPlot, KeepsMarksInOneClippedGroupAndDrawsTheLegend) {
  SvgPlot plot(SvgPlot::Frame{}, Axis{{0.0, 1.0}, "x"}, Axis{{0.0, 1.0}, "y"});
  plot.circle(0.5, 0.5, 3.0, Style::outlined("#000000", "#000000"), "a <dot>");
  plot.vline(0.25, Style::line("#000000", 1.0, "4 2"), "switch");
  plot.legend({{"dots", Style::outlined("#000000", "#000000")}, {"rule", Style::line("#000000")}});
  const std::string svg = plot.svg("p1", "test");
  EXPECT_NE(svg.find("<clipPath id=\"p1-area\">"), std::string::npos);
  EXPECT_NE(svg.find("<g class=\"marks\" clip-path=\"url(#p1-area)\">\n<circle cx=\"406.00\" cy=\"142.00\" r=\"3.00\""),
            std::string::npos)
      << svg;
  EXPECT_NE(svg.find("<title>a &lt;dot&gt;</title>"), std::string::npos);
  EXPECT_NE(svg.find("stroke-dasharray=\"4 2\""), std::string::npos);
  EXPECT_NE(svg.find(">switch</text>"), std::string::npos);
  EXPECT_NE(svg.find(">dots</text>"), std::string::npos);
  EXPECT_NE(svg.find(">rule</text>"), std::string::npos);
}

TEST(SvgPlot, RuleLabelsNeverOverlapAndStayInsideTheFrame) {
  // Ten rules, some 4 px apart (v2/v4 and v9/v10 collided before), one at the right edge.
  const std::vector<double> at = {100, 104, 108, 300, 304, 500, 640, 700, 744, 755};
  std::vector<std::string> labels;
  for (std::size_t i = 0; i < at.size(); ++i) labels.push_back("v" + std::to_string(i + 2));
  labels.back() = "switch: episode 12, t = 2.5 s";  // long, at the right edge
  const double left = 2.0, right = 758.0;
  const auto placed = layOutRuleLabels(at, labels, left, right, 34.0);
  ASSERT_EQ(placed.size(), at.size());
  struct Span { double lo, hi, y; };
  std::vector<Span> spans;
  for (std::size_t i = 0; i < at.size(); ++i) {
    const double width = kRuleLabelCharPx * static_cast<double>(labels[i].size());
    const double lo = placed[i].anchor_end ? placed[i].x - width : placed[i].x;
    spans.push_back({lo, lo + width, placed[i].y});
    EXPECT_GE(lo, left) << labels[i];
    EXPECT_LE(lo + width, right) << labels[i];
    // Beside its own rule, on one side or the other.
    EXPECT_LE(std::abs(placed[i].x - at[i]), 3.0 + 1e-9) << labels[i];
  }
  for (std::size_t i = 0; i < spans.size(); ++i) {
    for (std::size_t k = i + 1; k < spans.size(); ++k) {
      if (spans[i].y != spans[k].y) continue;
      EXPECT_TRUE(spans[i].hi <= spans[k].lo || spans[k].hi <= spans[i].lo)
          << labels[i] << " overlaps " << labels[k];
    }
  }
  EXPECT_TRUE(placed.back().anchor_end) << "the right-edge label goes left of its rule";
}

TEST(SvgPlot, ALogAxisWithinADecadeGetsOneTwoFiveTicks) {
  EXPECT_EQ(logTicks({1.5, 40.0}), (std::vector<double>{2.0, 5.0, 10.0, 20.0}));
  EXPECT_EQ(logTicks({1e-6, 1.0}).size(), 7u);  // the decades alone
}

TEST(SvgPlot, FormatsTicksWithoutTrailingZeros) {
  EXPECT_EQ(formatTick(0.2), "0.2");
  EXPECT_EQ(formatTick(1500.0), "1500");
  EXPECT_EQ(formatTick(1e-5), "1e-05");
  EXPECT_EQ(formatTick(1e-320), "0");
}

}  // namespace
}  // namespace sensornet::report
