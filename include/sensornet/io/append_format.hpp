#pragma once
// printf into a string, for the summaries a program prints (they are built, and unit tested, as
// text before a program writes them):
//
//   std::string out;
//   appendf(out, "bracket    J(P_info) = %.9g <= E[J]\n", bracket.info);

#include <string>

namespace sensornet {

[[gnu::format(printf, 2, 3)]] void appendf(std::string& out, const char* format, ...);

}  // namespace sensornet
