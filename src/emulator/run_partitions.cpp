#include "sensornet/emulator/run_partitions.hpp"

#include "sensornet/core/input_error.hpp"
#include "sensornet/emulator/sensor_ids.hpp"

namespace sensornet::emulator {
namespace {

constexpr std::string_view kSensors = "/sensors/";

std::string under(std::string_view run_partition, std::string_view rest) {
  return std::string(run_partition) + std::string(rest);
}

}  // namespace

std::string sensorPartition(std::string_view run_partition, const std::vector<int>& sensors) {
  return under(run_partition, std::string(kSensors) + formatSensorIds(sensors));
}

std::string sensorPartitionPattern(std::string_view run_partition) {
  return under(run_partition, std::string(kSensors) + "*");
}

std::optional<std::vector<int>> sensorsOfPartition(std::string_view run_partition,
                                                   std::string_view partition) {
  const std::string prefix = under(run_partition, kSensors);
  if (partition.size() <= prefix.size() || partition.substr(0, prefix.size()) != prefix) {
    return std::nullopt;
  }
  const std::string_view ids = partition.substr(prefix.size());
  try {
    std::vector<int> sensors = parseSensorIds(ids, "partition");
    if (formatSensorIds(sensors) != ids) return std::nullopt;
    return sensors;
  } catch (const InputError&) {
    return std::nullopt;
  }
}

std::optional<std::vector<int>> sensorsOfPartitions(std::string_view run_partition,
                                                    const std::vector<std::string>& partitions) {
  std::optional<std::vector<int>> found;
  for (const std::string& partition : partitions) {
    std::optional<std::vector<int>> sensors = sensorsOfPartition(run_partition, partition);
    if (!sensors) continue;
    if (found) return std::nullopt;
    found = std::move(sensors);
  }
  return found;
}

std::string commandPartition(std::string_view run_partition, CommandSender sender) {
  return under(run_partition, "/" + std::string(commandSenderName(sender)));
}

std::string referencePartition(std::string_view run_partition) {
  return under(run_partition, "/reference");
}

std::string_view commandSenderName(CommandSender sender) noexcept {
  switch (sender) {
    case CommandSender::Launcher: return "launcher";
    case CommandSender::Operator: return "operator";
  }
  return "?";
}

}  // namespace sensornet::emulator
