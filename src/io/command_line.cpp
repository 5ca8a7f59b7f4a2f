#include "sensornet/io/command_line.hpp"

#include <spdlog/sinks/stdout_sinks.h>
#include <spdlog/spdlog.h>

#include <cstdio>
#include <iostream>

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
