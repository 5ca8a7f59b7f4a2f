#pragma once
// Plumbing shared by every sensornet program: logs go to standard error through spdlog, results
// to standard output (JSON with --json), and any bad input ends the program with one line on
// standard error and a non-zero exit code.
//
//   int main(int argc, char** argv) {
//     return sensornet::runProgram("coordinator", [&] {
//       CLI::App app{"..."};
//       ...
//       return sensornet::parseCommandLine(app, argc, argv).value_or(...);
//     });
//   }

#include <CLI/CLI.hpp>
#include <functional>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

namespace sensornet {

// Exit codes of every sensornet program.
inline constexpr int kExitOk = 0;
inline constexpr int kExitFailure = 1;    // the work failed (a run did not complete, ...)
inline constexpr int kExitBadInput = 2;   // bad input: a file, a flag, a value

// Sets up the stderr logger ("[program] level: message") at the given level
// (trace, debug, info, warn, error, off).
void configureLogging(const std::string& program, const std::string& level = "info");

// Runs `body`, turning InputError into "program: error: <message>" with kExitBadInput and any
// other exception into "program: error: <message>" with kExitFailure.
int runProgram(const std::string& program, const std::function<int()>& body);

// Parses the command line. Returns an exit code when the program must stop now (--help printed,
// or a usage error reported as one line), std::nullopt when it should go on.
[[nodiscard]] std::optional<int> parseCommandLine(CLI::App& app, int argc, char** argv);

// A subcommand of a program (`coordinator timetable`, `fusion_center evaluate`, ...): its CLI11
// node and what to run when the user chose it.
struct Subcommand {
  CLI::App* app = nullptr;
  std::function<int()> run;
};

// Runs the subcommand the user chose (parseCommandLine must have succeeded).
int runChosenSubcommand(const std::vector<Subcommand>& subcommands);

// Prints a JSON document on standard output, one document per line.
void printJson(const nlohmann::json& doc);

}  // namespace sensornet
