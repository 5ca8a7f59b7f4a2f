#include "sensornet/io/command_line.hpp"

#include <spdlog/sinks/stdout_sinks.h>
#include <spdlog/spdlog.h>

#include <array>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <malloc.h>
#include <string>
#include <vector>

#include "sensornet/core/input_error.hpp"

namespace sensornet {

void configureLogging(const std::string& program, const std::string& level) {
  auto logger = spdlog::stderr_logger_mt(program + "-log");
  logger->set_pattern("[" + program + "] %l: %v");
  logger->set_level(spdlog::level::from_str(level));
  spdlog::set_default_logger(std::move(logger));
}

void keepLargeBlocksMapped() { (void)::mallopt(M_MMAP_THRESHOLD, kMmapThresholdBytes); }

int runProgram(const std::string& program, const std::function<int()>& body) {
  keepLargeBlocksMapped();
  try {
    return body();
  } catch (const InputError& e) {
    std::fprintf(stderr, "%s: error: %s\n", program.c_str(), e.what());
    return kExitBadInput;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "%s: error: %s\n", program.c_str(), e.what());
    return kExitFailure;
  }
}

std::optional<int> parseCommandLine(CLI::App& app, int argc, char** argv) {
  // CLI11 reports an unknown first word as a missing subcommand; name it instead.
  const std::vector<CLI::App*> subcommands = app.get_subcommands([](CLI::App*) { return true; });
  if (!subcommands.empty() && argc > 1 && argv[1][0] != '-') {
    std::string names;
    bool known = false;
    for (const CLI::App* sub : subcommands) {
      known = known || sub->check_name(argv[1]);
      names += (names.empty() ? "" : ", ") + sub->get_name();
    }
    if (!known) {
      std::fprintf(stderr, "%s: error: unknown subcommand '%s' (expected one of: %s; see --help)\n",
                   app.get_name().c_str(), argv[1], names.c_str());
      return kExitBadInput;
    }
  }
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForAllHelp& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    std::fprintf(stderr, "%s: error: %s (see --help)\n", app.get_name().c_str(), e.what());
    return kExitBadInput;
  }
  return std::nullopt;
}

int runChosenSubcommand(const std::vector<Subcommand>& subcommands) {
  for (const auto& subcommand : subcommands) {
    if (subcommand.app->parsed()) return subcommand.run();
  }
  std::fprintf(stderr, "error: no subcommand given (see --help)\n");
  return kExitBadInput;
}

std::string formatNumber(double value) {
  // The shortest round-trip digits in fixed and in scientific notation; fixed unless it is
  // much longer (1e+308, 1e-12), so that 10000 and 0.0009 do not become 1e+04 and 9e-04.
  const auto shortest = [value](std::chars_format format) {
    std::array<char, 400> text{};  // fixed notation of 1e308 takes 309 characters
    const auto [end, error] = std::to_chars(text.data(), text.data() + text.size(), value, format);
    return error == std::errc() ? std::string(text.data(), end) : std::string();
  };
  const std::string fixed = shortest(std::chars_format::fixed);
  const std::string scientific = shortest(std::chars_format::scientific);
  if (scientific.empty()) return std::to_string(value);
  return !fixed.empty() && fixed.size() <= scientific.size() + 4 ? fixed : scientific;
}

namespace {

// What the user typed, quoted and cut short: a 400-digit argument is not repeated in full.
std::string shownInput(const std::string& input) {
  constexpr std::size_t kShown = 40;
  if (input.size() <= kShown) return "'" + input + "'";
  return "'" + input.substr(0, kShown) + "...' (" + std::to_string(input.size()) + " characters)";
}

// The whole of `input` as a number (leading and trailing blanks allowed, as CLI11 allows), or
// nullopt. Overflow gives an infinity, which the callers refuse.
std::optional<double> parseNumber(const std::string& input) {
  const char* begin = input.c_str();
  char* end = nullptr;
  const double value = std::strtod(begin, &end);
  if (end == begin) return std::nullopt;
  while (*end == ' ' || *end == '\t') ++end;
  if (*end != '\0') return std::nullopt;
  return value;
}

// Checks a number against [lo, hi] (exclusive_lo: (lo, hi]), describing the range as `range`.
CLI::Validator numberCheck(double lo, double hi, bool exclusive_lo, const std::string& range) {
  return CLI::Validator(
      [lo, hi, exclusive_lo, range](std::string& input) -> std::string {
        const std::optional<double> value = parseNumber(input);
        if (!value) return "expected " + range + ", got " + shownInput(input);
        if (!std::isfinite(*value)) {
          // An infinity the user did not spell ("inf", "Infinity") is an overflow (1e309).
          const bool overflow =
              !std::isnan(*value) && input.find_first_of("iI") == std::string::npos;
          return "expected " + range + ", got " + shownInput(input) +
                 (overflow ? " (the number overflows a double)" : " (not a finite number)");
        }
        const bool below = exclusive_lo ? !(*value > lo) : *value < lo;
        if (below || *value > hi) return "expected " + range + ", got " + formatNumber(*value);
        return {};
      },
      range);
}

}  // namespace

CLI::Validator numberRange(double lo, double hi) {
  return numberCheck(lo, hi, false,
                     "a number from " + formatNumber(lo) + " to " + formatNumber(hi));
}

CLI::Validator positiveNumber(double hi) {
  const bool bounded = hi < std::numeric_limits<double>::max();
  return numberCheck(0.0, hi, true,
                     bounded ? "a number > 0 and at most " + formatNumber(hi)
                             : std::string("a finite number > 0"));
}

CLI::Validator nonNegativeNumber(double hi) {
  const bool bounded = hi < std::numeric_limits<double>::max();
  return numberCheck(
      0.0, hi, false,
      bounded ? "a number from 0 to " + formatNumber(hi) : std::string("a finite number >= 0"));
}

CLI::Validator integerRange(std::int64_t lo, std::int64_t hi) {
  const std::string range = "an integer from " + std::to_string(lo) + " to " + std::to_string(hi);
  return CLI::Validator(
      [lo, hi, range](std::string& input) -> std::string {
        std::size_t first = input.find_first_not_of(" \t");
        std::size_t last = input.find_last_not_of(" \t");
        if (first == std::string::npos) return "expected " + range + ", got " + shownInput(input);
        if (input[first] == '+') ++first;
        std::int64_t value = 0;
        const char* begin = input.data() + first;
        const char* end = input.data() + last + 1;
        const auto [stop, error] = std::from_chars(begin, end, value);
        if (error == std::errc() && stop == end) {
          if (value >= lo && value <= hi) return {};
          return "expected " + range + ", got " + std::to_string(value);
        }
        // Not an int64: say what the number was if it is one (1e308, 2.5, 99999999999999999999).
        const std::optional<double> number = parseNumber(input);
        if (number && std::isfinite(*number)) {
          return "expected " + range + ", got " + formatNumber(*number);
        }
        return "expected " + range + ", got " + shownInput(input);
      },
      range);
}

void printJson(const nlohmann::json& doc) { std::cout << doc.dump() << std::endl; }

}  // namespace sensornet
