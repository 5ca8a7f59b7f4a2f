#include "sensornet/wire/sensor_speakers.hpp"

#include <algorithm>

#include "sensornet/dds/matched_endpoints.hpp"
#include "sensornet/emulator/run_partitions.hpp"

namespace sensornet::wire {

using emulator::sensorsOfPartitions;

const std::vector<int>& SensorSpeakers::of(const dds::detail::ReaderCore& reader,
                                           dds_instance_handle_t publication) {
  static const std::vector<int> kNobody;
  if (const auto it = known_.find(publication); it != known_.end()) return it->second;
  const auto names = dds::partitionsOfMatchedWriter(reader, publication);
  if (!names) return kNobody;
  return known_[publication] = sensorsOfPartitions(run_partition_, *names).value_or(std::vector<int>{});
}

bool SensorSpeakers::speaksFor(const dds::detail::ReaderCore& reader,
                               dds_instance_handle_t publication, int sensor) {
  const std::vector<int>& sensors = of(reader, publication);
  return std::binary_search(sensors.begin(), sensors.end(), sensor);
}

}  // namespace sensornet::wire
