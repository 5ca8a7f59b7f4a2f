#pragma once
// `fusion_center evaluate`: the offline evaluation of a schedule on a scenario: the surrogate
// bracket [J(P_info), J(P_cov)] (Corollary 1) and an in-process Monte Carlo of the exact CD-KF.

#include "sensornet/io/command_line.hpp"

namespace sensornet::fusion_center {

Subcommand addEvaluateCommand(CLI::App& app);

}  // namespace sensornet::fusion_center
