#include "sensornet/dds/dds_error.hpp"

#include <filesystem>
#include <utility>

namespace sensornet::dds {
namespace {

std::string describe(const std::string& call, dds_return_t code,
                     const std::source_location& where) {
  const std::string file = std::filesystem::path(where.file_name()).filename().string();
  return call + " failed: " + returnCodeText(code) + " (" + std::to_string(code) + ") at " + file +
         ":" + std::to_string(where.line());
}

}  // namespace

DdsError::DdsError(std::string call, dds_return_t code, std::source_location where)
    : std::runtime_error(describe(call, code, where)),
      call_(std::move(call)),
      code_(code),
      where_(where) {}

dds_return_t check(dds_return_t result, const char* call, std::source_location where) {
  if (result < 0) throw DdsError(call, result, where);
  return result;
}

std::string returnCodeText(dds_return_t code) {
  const char* text = dds_strretcode(code);
  return text != nullptr ? text : "unknown return code";
}

}  // namespace sensornet::dds
