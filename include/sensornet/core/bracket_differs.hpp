#pragma once
// Whether two cost brackets [J(P_info), J(P_cov)] differ beyond rounding: the planned bracket
// and the one the schedule can deliver (a dead sensor's share, an emulated network's losses)
// are the same numbers up to the last bits when nothing is lost. One rule for every place that
// shows the delivered bracket only when it differs (the launcher's progress and closing lines,
// the report page).
//
//   if (bracketsDiffer(planned_info, planned_cov, delivered_info, delivered_cov)) show both;

#include <algorithm>
#include <cmath>

namespace sensornet {

[[nodiscard]] inline bool bracketsDiffer(double info_a, double cov_a, double info_b,
                                         double cov_b) {
  const auto apart = [](double u, double v) {
    return std::abs(u - v) > 1e-9 * std::max({std::abs(u), std::abs(v), 1.0});
  };
  return apart(info_a, info_b) || apart(cov_a, cov_b);
}

}  // namespace sensornet
