#include "sensornet/io/command_line.hpp"

#include <spdlog/sinks/stdout_sinks.h>
#include <spdlog/spdlog.h>

#include <algorithm>
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

namespace {

// Edit distance (insertions, deletions, substitutions, adjacent swaps) between two words.
std::size_t editDistance(const std::string& a, const std::string& b) {
  std::vector<std::vector<std::size_t>> d(a.size() + 1, std::vector<std::size_t>(b.size() + 1));
  for (std::size_t i = 0; i <= a.size(); ++i) d[i][0] = i;
  for (std::size_t j = 0; j <= b.size(); ++j) d[0][j] = j;
  for (std::size_t i = 1; i <= a.size(); ++i) {
    for (std::size_t j = 1; j <= b.size(); ++j) {
      const std::size_t change = a[i - 1] == b[j - 1] ? 0 : 1;
      d[i][j] = std::min({d[i - 1][j] + 1, d[i][j - 1] + 1, d[i - 1][j - 1] + change});
      if (i > 1 && j > 1 && a[i - 1] == b[j - 2] && a[i - 2] == b[j - 1]) {
        d[i][j] = std::min(d[i][j], d[i - 2][j - 2] + 1);
      }
    }
  }
  return d[a.size()][b.size()];
}

// The long option names of `app`, of its option groups and of the subcommands the user chose.
std::vector<std::string> optionNames(const CLI::App& app) {
  std::vector<std::string> names;
  for (const CLI::Option* option : app.get_options()) {
    for (const std::string& name : option->get_lnames()) names.push_back("--" + name);
  }
  const auto chosen = [](const CLI::App* sub) {
    return sub->parsed() || dynamic_cast<const CLI::Option_group*>(sub) != nullptr;
  };
  for (const CLI::App* sub : app.get_subcommands(chosen)) {
    const std::vector<std::string> more = optionNames(*sub);
    names.insert(names.end(), more.begin(), more.end());
  }
  return names;
}

}  // namespace

std::optional<std::string> nearestOption(const CLI::App& app, const std::string& typed) {
  const std::string word = typed.substr(0, typed.find('='));
  if (word.rfind("--", 0) != 0) return std::nullopt;
  std::optional<std::string> best;
  const std::vector<std::string> names = optionNames(app);
  std::size_t best_distance = std::max<std::size_t>(1, (word.size() - 2) / 4) + 1;
  for (const std::string& name : names) {
    const std::size_t distance = editDistance(word, name);
    if (distance < best_distance) {
      best = name;
      best_distance = distance;
    }
  }
  if (best) return best;
  // Else an option that holds the typed word or is held in it (--html: --no-html; --report-file:
  // --report), the one of nearest length; only for words long enough to mean something.
  const std::string body = word.substr(2);
  if (body.size() < 4) return std::nullopt;
  std::size_t best_gap = std::numeric_limits<std::size_t>::max();
  for (const std::string& name : names) {
    const std::string other = name.substr(2);
    const bool related = other.size() >= 4 && (other.find(body) != std::string::npos ||
                                               body.find(other) != std::string::npos);
    const std::size_t gap = other.size() > body.size() ? other.size() - body.size()
                                                       : body.size() - other.size();
    if (related && gap < best_gap) {
      best = name;
      best_gap = gap;
    }
  }
  return best;
}

namespace {

// What CLI11 could not place, as one clause: the first unknown option and the option nearest
// to it ("unknown option --html (did you mean --no-html?)"), else the stray arguments. The
// words after an unknown option are its value, not worth naming.
std::string unexpectedText(const CLI::App& app) {
  const std::vector<std::string> extras = app.remaining(true);
  for (const std::string& extra : extras) {
    if (extra.size() < 2 || extra[0] != '-') continue;
    const std::string option = extra.substr(0, extra.find('='));
    std::string text = "unknown option " + option;
    if (const auto nearest = nearestOption(app, extra)) text += " (did you mean " + *nearest + "?)";
    return text;
  }
  std::string words;
  for (const std::string& extra : extras) words += (words.empty() ? "'" : " '") + extra + "'";
  return (extras.size() > 1 ? "unexpected arguments " : "unexpected argument ") + words;
}

}  // namespace

const char* sensornetVersion() { return SENSORNET_VERSION; }

std::string versionText(const std::string& program) {
  return program + " (sensornet " + sensornetVersion() + ")";
}

std::optional<int> parseCommandLine(CLI::App& app, int argc, char** argv) {
  if (app.get_option_no_throw("--version") == nullptr) {
    app.set_version_flag("--version", versionText(app.get_name()), "print the version and exit");
  }
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
  } catch (const CLI::CallForVersion& e) {
    return app.exit(e);
  } catch (const CLI::ExtrasError&) {
    // A mistyped option: name it and the nearest one the program knows.
    std::fprintf(stderr, "%s: error: %s (see --help)\n", app.get_name().c_str(),
                 unexpectedText(app).c_str());
    return kExitBadInput;
  } catch (const CLI::ParseError& e) {
    // A mistyped option also leaves its right spelling missing ("--scenaro x": --scenario is
    // required): the typo is the news.
    const std::vector<std::string> extras = app.remaining(true);
    const bool typo = std::any_of(extras.begin(), extras.end(), [](const std::string& extra) {
      return extra.size() > 2 && extra.rfind("--", 0) == 0;
    });
    std::fprintf(stderr, "%s: error: %s (see --help)\n", app.get_name().c_str(),
                 typo ? unexpectedText(app).c_str() : e.what());
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
