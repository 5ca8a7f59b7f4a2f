#pragma once
// How many times `what` occurs in `text` (overlapping occurrences counted), for the tests that
// count marks in a page or cases in a JUnit file.
//
//   EXPECT_EQ(sensornet::testing::occurrences(xml, "<testcase "), 5u);

#include <cstddef>
#include <string>

namespace sensornet::testing {

[[nodiscard]] inline std::size_t occurrences(const std::string& text, const std::string& what) {
  std::size_t n = 0;
  for (std::size_t at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++n;
  return n;
}

}  // namespace sensornet::testing
