// coordinator: computes sensor schedules and (in `serve` mode) broadcasts them to a run.

#include <vector>

#include "sensornet/io/command_line.hpp"
#include "plan_command.hpp"
#include "serve_command.hpp"
#include "timetable_command.hpp"

int main(int argc, char** argv) {
  return sensornet::runProgram("coordinator", [&] {
    sensornet::configureLogging("coordinator");
    CLI::App app{"sensornet coordinator: offline sensor schedules for CD-KF sensor networks"};
    app.name("coordinator");
    app.require_subcommand(1);
    const std::vector<sensornet::Subcommand> subcommands = {
        sensornet::coordinator::addPlanCommand(app),
        sensornet::coordinator::addServeCommand(app),
        sensornet::coordinator::addTimetableCommand(app)};
    if (auto code = sensornet::parseCommandLine(app, argc, argv)) return *code;
    return sensornet::runChosenSubcommand(subcommands);
  });
}
