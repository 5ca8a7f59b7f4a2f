#pragma once
// `coordinator plan`: the optimal offline rate schedule of a scenario for the information-form
// or covariance-form surrogate (or the uniform baseline), written as a schedule file.

#include "sensornet/io/command_line.hpp"

namespace sensornet::coordinator {

Subcommand addPlanCommand(CLI::App& app);

}  // namespace sensornet::coordinator
