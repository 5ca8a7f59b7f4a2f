// sensornet: launches an emulation on this host and talks to a running one.
//   sensornet launch SCENARIO [...]   run coordinator, fusion center and sensors; show progress
//   sensornet replan [...]            change the schedule of the running emulation
//   sensornet status [...]            show its sensors and schedule
//   sensornet watch [...]             follow it live (a terminal view, or lines for a log)
//   sensornet report REPORT [...]     the page (HTML) and CSV tables of a finished run
//   sensornet replay RUN.mcap --info  what a recording of a run (launch --record) holds
//   sensornet pki init DIR            the files of a secured run (--security DIR)
//   sensornet runs [...]              the runs in the scratch folder; remove finished ones
//   sensornet conform sensor -- PROG  whether your participant keeps the protocol, rule by rule

#include <vector>

#include "conform_command.hpp"
#include "launch_command.hpp"
#include "pki_command.hpp"
#include "record_command.hpp"
#include "replan_command.hpp"
#include "replay_command.hpp"
#include "report_command.hpp"
#include "runs_command.hpp"
#include "sensornet/io/command_line.hpp"
#include "status_command.hpp"
#include "sweep_command.hpp"
#include "watch_command.hpp"

int main(int argc, char** argv) {
  return sensornet::runProgram("sensornet", [&] {
    sensornet::configureLogging("sensornet");
    CLI::App app{
        "sensornet: a multi-process emulator of sensor networks for continuous-discrete Kalman "
        "filtering over Cyclone DDS. Start a run with `sensornet launch scenarios/default.yaml`; "
        "while it runs, `sensornet replan` changes its schedule and `sensornet status` shows its "
        "sensors; `sensornet runs` lists the runs kept in the scratch folder."};
    app.name("sensornet");
    app.require_subcommand(1);
    const std::vector<sensornet::Subcommand> subcommands = {
        sensornet::launcher::addLaunchCommand(app), sensornet::launcher::addReplanCommand(app),
        sensornet::launcher::addStatusCommand(app), sensornet::launcher::addWatchCommand(app),
        sensornet::launcher::addReportCommand(app), sensornet::launcher::addPkiCommand(app),
        sensornet::launcher::addRunsCommand(app), sensornet::launcher::addReplayCommand(app),
        sensornet::launcher::addRecordCommand(app), sensornet::launcher::addConformCommand(app),
        sensornet::launcher::addSweepCommand(app)};
    if (auto code = sensornet::parseCommandLine(app, argc, argv)) return *code;
    return sensornet::runChosenSubcommand(subcommands);
  });
}
