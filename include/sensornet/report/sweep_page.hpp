#pragma once
// The page of a sweep (`sensornet sweep`, results.html): one self-contained HTML file in the
// style of a run's page, from the sweep's result rows (evaluation/sweep.hpp).
//
//   writeTextFile("sweeps/fig1/results.html", sweepPage("fig1", rows));
//
// For each axis whose cells take two values or more (budget, sensors, states, noise_scale,
// replan_every), the realized cost against it, one series per planner: at each value, the mean
// of the cells' Monte Carlo means over the other axes (plants, seeds), with its 95% Student-t
// interval over those cells (one cell: its own Monte Carlo interval), and the planner's mean
// bracket [J(P_info), J(P_cov)] as two dashed lines. Then the table of every cell, failed ones
// with their reason.

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace sensornet::report {

[[nodiscard]] std::string sweepPage(const std::string& name,
                                    const std::vector<nlohmann::json>& rows);

}  // namespace sensornet::report
