#include "sensornet/dds/matched_writers.hpp"

namespace sensornet::dds {

std::optional<std::vector<std::string>> partitionsOfMatchedWriter(
    const detail::ReaderCore& reader, dds_instance_handle_t publication) {
  dds_builtintopic_endpoint_t* endpoint =
      dds_get_matched_publication_data(reader.handle(), publication);
  if (endpoint == nullptr) return std::nullopt;
  std::vector<std::string> names;
  std::uint32_t count = 0;
  char** partitions = nullptr;
  if (endpoint->qos != nullptr && dds_qget_partition(endpoint->qos, &count, &partitions)) {
    for (std::uint32_t i = 0; i < count; ++i) {
      names.emplace_back(partitions[i]);
      dds_free(partitions[i]);
    }
    dds_free(partitions);
  }
  dds_builtintopic_free_endpoint(endpoint);
  if (names.empty()) names.emplace_back();  // no partition QoS: the default partition ""
  return names;
}

}  // namespace sensornet::dds
