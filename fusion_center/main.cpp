// fusion_center: runs the CD-KF on what arrives and reports realized cost against the bracket;
// `evaluate` does the same offline, in process.

#include <vector>

#include "evaluate_command.hpp"
#include "serve_command.hpp"
#include "sensornet/io/command_line.hpp"

int main(int argc, char** argv) {
  return sensornet::runProgram("fusion_center", [&] {
    sensornet::configureLogging("fusion_center");
    CLI::App app{"sensornet fusion center: CD-KF fusion and realized-versus-bracketed cost"};
    app.name("fusion_center");
    app.require_subcommand(1);
    const std::vector<sensornet::Subcommand> subcommands = {
        sensornet::fusion_center::addEvaluateCommand(app),
        sensornet::fusion_center::addServeCommand(app)};
    if (auto code = sensornet::parseCommandLine(app, argc, argv)) return *code;
    return sensornet::runChosenSubcommand(subcommands);
  });
}
