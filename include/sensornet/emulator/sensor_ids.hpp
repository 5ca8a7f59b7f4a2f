#pragma once
// Which sensors a sensor_agent process hosts, from its --sensors flag: "3", "0-9", "0,2,5-7".
//
//   std::vector<int> ids = parseSensorIds("0-2,7", "--sensors");   // {0, 1, 2, 7}
//   formatSensorIds(ids)                                          // "0-2,7"

#include <string>
#include <string_view>
#include <vector>

namespace sensornet::emulator {

// Sorted, without repeats; throws InputError(source, ...) for anything else than non-negative
// integers and ascending ranges separated by commas.
[[nodiscard]] std::vector<int> parseSensorIds(std::string_view text, const std::string& source);

// The canonical text of sorted ids without repeats: consecutive runs as ranges ("0-2,7"); what
// parseSensorIds reads back. It names a sensor process's block in `--sensors`, in the process's
// log name, in its partition and in its security identity, so these always agree.
[[nodiscard]] std::string formatSensorIds(const std::vector<int>& sorted_ids);

}  // namespace sensornet::emulator
