#pragma once
// Text made safe inside XML and HTML: & < > " ' become entity references. One function for
// every XML the project writes (the report page's SVG and HTML, Cyclone's security
// configuration).
//
//   "<title>" + escapeXml(run_id) + "</title>"

#include <string>

namespace sensornet {

[[nodiscard]] inline std::string escapeXml(const std::string& text) {
  std::string out;
  out.reserve(text.size());
  for (const char c : text) {
    switch (c) {
      case '&': out += "&amp;"; break;
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '"': out += "&quot;"; break;
      case '\'': out += "&#39;"; break;
      default: out += c;
    }
  }
  return out;
}

}  // namespace sensornet
