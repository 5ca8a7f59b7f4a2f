#include "sensornet/io/command_line.hpp"

#include <spdlog/sinks/stdout_sinks.h>
#include <spdlog/spdlog.h>

#include <cstdio>
#include <iostream>
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

int runProgram(const std::string& program, const std::function<int()>& body) {
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

void printJson(const nlohmann::json& doc) {
  std::cout << doc.dump() << std::endl;
}

}  // namespace sensornet
