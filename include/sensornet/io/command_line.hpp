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
#include <cstdint>
#include <functional>
#include <limits>
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

// Blocks of at least this size are mapped by themselves and given back to the system when freed:
// below Cyclone's 1 MiB receive buffers, above the planner's N x M matrices at M = 1000 (240 KB
// at N = 30; at glibc's initial 128 KiB each of those was mapped and faulted in afresh, and
// `coordinator plan` at n = 50, M = 1000 took 1.4x as long).
inline constexpr int kMmapThresholdBytes = 512 * 1024;

// Fixes glibc's mmap threshold at kMmapThresholdBytes (runProgram does it first). Cyclone DDS
// receives into 1 MiB buffers, malloc'ed and freed when the last sample in them is gone. glibc
// maps blocks that large by themselves, but after the first is freed it raises its threshold to
// that size (its dynamic threshold) and from then on carves them from a thread's heap, whose
// freed pages stay resident: over 100,000 episodes the fusion center, the coordinator and the
// launcher grew by ~20 bytes/episode (1.13-1.17x; bench/README.md, "Memory over long runs").
// With the threshold fixed they stay mapped and go back when freed (1.04-1.05x).
void keepLargeBlocksMapped();

// Runs `body` (after keepLargeBlocksMapped), turning InputError into
// "program: error: <message>" with kExitBadInput and any other exception into
// "program: error: <message>" with kExitFailure.
int runProgram(const std::string& program, const std::function<int()>& body);

// The project's version (CMakeLists.txt's project version), and what `--version` prints:
// "coordinator (sensornet 0.1.0)".
[[nodiscard]] const char* sensornetVersion();
[[nodiscard]] std::string versionText(const std::string& program);

// The option of `app` (or of a subcommand the user chose) nearest to a mistyped `--word` (or
// `--word=value`), if one is within a small edit distance: "--episdoes" -> "--episodes".
[[nodiscard]] std::optional<std::string> nearestOption(const CLI::App& app,
                                                       const std::string& typed);

// Parses the command line. Returns an exit code when the program must stop now (--help or
// --version printed, or a usage error reported as one line, naming the nearest option for a
// mistyped one), std::nullopt when it should go on. Every program gets --version here.
[[nodiscard]] std::optional<int> parseCommandLine(CLI::App& app, int argc, char** argv);

// A subcommand of a program (`coordinator timetable`, `fusion_center evaluate`, ...): its CLI11
// node and what to run when the user chose it.
struct Subcommand {
  CLI::App* app = nullptr;
  std::function<int()> run;
};

// Runs the subcommand the user chose (parseCommandLine must have succeeded).
int runChosenSubcommand(const std::vector<Subcommand>& subcommands);

// Checks for numeric options. Unlike CLI::Range and CLI::PositiveNumber, they refuse NaN and
// infinities and print numbers readably (CLI11 prints bounds with std::to_string: 300 digits
// for DBL_MAX). CLI11 puts the option's name in front of the message:
//
//   cmd->add_option("--time-scale", scale)->check(numberRange(1e-3, 1e4));
//   // --time-scale 1e308: "--time-scale: expected a number from 0.001 to 10000, got 1e+308"
//
// A finite number from lo to hi (both included).
[[nodiscard]] CLI::Validator numberRange(double lo, double hi);
// A finite number > 0, at most hi.
[[nodiscard]] CLI::Validator positiveNumber(double hi = std::numeric_limits<double>::max());
// A finite number >= 0, at most hi.
[[nodiscard]] CLI::Validator nonNegativeNumber(double hi = std::numeric_limits<double>::max());
// An integer (no fraction, no exponent) from lo to hi (both included).
[[nodiscard]] CLI::Validator integerRange(std::int64_t lo, std::int64_t hi);

// Readable text that reads back as `value`: the shortest digits, in fixed notation unless that
// is much longer ("0.001", "10000", "1e+308", "inf").
[[nodiscard]] std::string formatNumber(double value);

// Prints a JSON document on standard output, one document per line.
void printJson(const nlohmann::json& doc);

}  // namespace sensornet
