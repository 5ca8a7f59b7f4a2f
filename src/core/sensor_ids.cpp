#include "sensornet/emulator/sensor_ids.hpp"

#include <algorithm>
#include <charconv>

#include "sensornet/core/input_error.hpp"

namespace sensornet::emulator {
namespace {

constexpr int kMaxSensorId = 1'000'000;

int parseId(std::string_view text, std::string_view whole, const std::string& source) {
  int value = -1;
  const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), value);
  if (text.empty() || error != std::errc() || end != text.data() + text.size() || value < 0 ||
      value > kMaxSensorId) {
    throw InputError(source, "sensors",
                     "ids like 3, 0-9 or 0,2,5-7 (non-negative integers), got '" +
                         std::string(whole) + "'");
  }
  return value;
}

}  // namespace

std::vector<int> parseSensorIds(std::string_view text, const std::string& source) {
  std::vector<int> ids;
  std::size_t start = 0;
  while (start <= text.size()) {
    const std::size_t comma = std::min(text.find(',', start), text.size());
    const std::string_view item = text.substr(start, comma - start);
    const std::size_t dash = item.find('-');
    if (dash == std::string_view::npos) {
      ids.push_back(parseId(item, text, source));
    } else {
      const int first = parseId(item.substr(0, dash), text, source);
      const int last = parseId(item.substr(dash + 1), text, source);
      if (last < first) {
        throw InputError(source, "sensors", "ascending ranges, got '" + std::string(item) + "'");
      }
      for (int id = first; id <= last; ++id) ids.push_back(id);
    }
    start = comma + 1;
  }
  std::sort(ids.begin(), ids.end());
  ids.erase(std::unique(ids.begin(), ids.end()), ids.end());
  return ids;
}

std::string formatSensorIds(const std::vector<int>& sorted_ids) {
  std::string spec;
  for (std::size_t i = 0; i < sorted_ids.size();) {
    std::size_t end = i + 1;
    while (end < sorted_ids.size() && sorted_ids[end] == sorted_ids[end - 1] + 1) ++end;
    if (!spec.empty()) spec += ",";
    spec += std::to_string(sorted_ids[i]);
    if (end - i > 1) spec += "-" + std::to_string(sorted_ids[end - 1]);
    i = end;
  }
  return spec;
}

}  // namespace sensornet::emulator
