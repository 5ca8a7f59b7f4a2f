#pragma once
// What a reader knows of a writer it matched, from the writer's discovery data: the partitions
// it writes in (who wrote a sample, emulator/run_partitions.hpp). Known while the writer is
// matched: look it up when its first sample is taken and keep it. Not from a listener:
// dds_get_matched_publication_data takes the reader's locks, which Cyclone's delivery path may
// hold while it calls the listener.
//
//   const auto names = partitionsOfMatchedWriter(reader, info.publication);

#include <dds/dds.h>

#include <optional>
#include <string>
#include <vector>

#include "sensornet/dds/reader.hpp"

namespace sensornet::dds {

// The partitions of the writer `publication` that `reader` matched ("" for the default
// partition); nullopt when it is not (or no longer) matched.
[[nodiscard]] std::optional<std::vector<std::string>> partitionsOfMatchedWriter(
    const detail::ReaderCore& reader, dds_instance_handle_t publication);

}  // namespace sensornet::dds
