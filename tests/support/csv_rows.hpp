#pragma once
// The rows of a CSV text as written by `sensornet report --csv` (no quoting: cells hold numbers
// and plain names), each split at its commas; a line that ends in a comma ends in an empty cell.
//
//   const auto rows = sensornet::testing::csvRows(readText("tables/sensors.csv"));
//   rows[0]  // the header

#include <sstream>
#include <string>
#include <vector>

namespace sensornet::testing {

inline std::vector<std::vector<std::string>> csvRows(const std::string& text) {
  std::vector<std::vector<std::string>> rows;
  std::istringstream in(text);
  std::string line;
  while (std::getline(in, line)) {
    std::vector<std::string> cells;
    std::istringstream fields(line);
    std::string cell;
    while (std::getline(fields, cell, ',')) cells.push_back(cell);
    if (!line.empty() && line.back() == ',') cells.emplace_back();
    rows.push_back(cells);
  }
  return rows;
}

}  // namespace sensornet::testing
