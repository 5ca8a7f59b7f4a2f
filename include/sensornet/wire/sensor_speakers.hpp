#pragma once
// Whom a writer of the sensor topics speaks for: the sensors its partition names
// (run_partitions.hpp), read from its discovery data when its first sample is taken and kept,
// so that the question costs a map look-up per sample. In a secured run the partition is the
// writer's authenticated identity. Used by the fusion center and the coordinator, in their main
// loops only (not thread-safe; never from a listener, see dds/matched_endpoints.hpp).
//
//   SensorSpeakers speakers(participant.partition());
//   if (!speakers.speaksFor(reader, info.publication, sample.sensor_id)) { refuse; }

#include <dds/dds.h>

#include <map>
#include <string>
#include <vector>

#include "sensornet/dds/reader.hpp"

namespace sensornet::wire {

class SensorSpeakers {
 public:
  explicit SensorSpeakers(std::string run_partition) : run_partition_(std::move(run_partition)) {}

  // The sensors the writer `publication` of `reader` speaks for, sorted; empty when its
  // partition names none, or when it is gone before it was first asked about (then it is asked
  // again next time: a writer that comes back is looked up).
  [[nodiscard]] const std::vector<int>& of(const dds::detail::ReaderCore& reader,
                                           dds_instance_handle_t publication);
  [[nodiscard]] bool speaksFor(const dds::detail::ReaderCore& reader,
                               dds_instance_handle_t publication, int sensor);

 private:
  std::string run_partition_;
  std::map<dds_instance_handle_t, std::vector<int>> known_;  // handles are never reused
};

}  // namespace sensornet::wire
