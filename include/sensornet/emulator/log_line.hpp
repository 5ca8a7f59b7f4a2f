#pragma once
// A line a process core asks its executable to log: the cores decide what is said, the
// executables own the logger.

#include <string>

#include <spdlog/common.h>

namespace sensornet::emulator {

struct LogLine {
  spdlog::level::level_enum level = spdlog::level::info;
  std::string text;
};

}  // namespace sensornet::emulator
