#pragma once
// What the pages of src/report share (the run's page, report_page.cpp; a sweep's, sweep_page.cpp):
// the style sheet, the script that counts each plot's drawn marks for the browser test, and a
// plot as a figure with its heading and caption. Private to src/report.

#include <string>

#include "sensornet/core/xml_text.hpp"

namespace sensornet::report {

inline constexpr const char* kPageStyle = R"(
body { font-family: system-ui, "DejaVu Sans", Arial, sans-serif; color: #1a1a1a; margin: 24px auto;
       max-width: 800px; padding: 0 12px; line-height: 1.4; }
h1 { font-size: 22px; margin: 0 0 4px; } h2 { font-size: 16px; margin: 24px 0 6px; }
.meta { color: #444; font-size: 13px; margin-bottom: 12px; }
table { border-collapse: collapse; font-size: 13px; margin: 8px 0; }
th, td { text-align: left; padding: 2px 10px 2px 0; vertical-align: top; }
table.faults td, table.faults th, table.clocks td, table.clocks th { border-bottom: 1px solid #ddd; }
figure { margin: 0 0 12px; break-inside: avoid; page-break-inside: avoid; }
figcaption, .sub, .note p { font-size: 12.5px; color: #333; }
svg.plot { display: block; max-width: 100%; height: auto; }
svg.plot text { font-size: 12px; fill: #1a1a1a; }
svg.plot .tick { font-size: 11px; } svg.plot .rule { font-size: 11px; }
svg.plot .grid { stroke: #e4e4e4; stroke-width: 1; } svg.plot .frame { fill: none; stroke: #555; }
@media print { body { margin: 0; max-width: none; } h2 { break-after: avoid; }
  a { color: inherit; text-decoration: none; } }
)";

// Counts each plot's drawn marks (non-empty boxes) into data-marks, and errors into the body's
// data-errors: what the browser test reads. Inline, fetches nothing.
inline constexpr const char* kPageScript = R"(
(function () {
  var errors = 0;
  window.addEventListener('error', function () { errors += 1; document.body.dataset.errors = errors; });
  document.body.dataset.errors = 0;
  var plots = document.querySelectorAll('svg.plot');
  plots.forEach(function (svg) {
    var drawn = 0;
    svg.querySelectorAll('g.marks > *').forEach(function (mark) {
      var box = mark.getBBox();
      if (box.width > 0 || box.height > 0) drawn += 1;
    });
    svg.dataset.marks = drawn;
  });
  document.body.dataset.plots = plots.length;
})();
)";

inline std::string figure(const std::string& id, const std::string& heading, const std::string& svg,
                          const std::string& caption) {
  return "<figure id=\"fig-" + id + "\">\n<h2>" + escapeXml(heading) + "</h2>\n" + svg +
         "<figcaption>" + caption + "</figcaption>\n</figure>\n";
}

}  // namespace sensornet::report
