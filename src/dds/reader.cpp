#include "sensornet/dds/reader.hpp"

#include <limits>

#include "sensornet/core/input_error.hpp"
#include "sensornet/dds/waitset.hpp"

namespace sensornet::dds {

SampleInfo toSampleInfo(const dds_sample_info_t& info) noexcept {
  SampleInfo out;
  switch (info.instance_state) {
    case DDS_IST_ALIVE:
      out.instance_state = InstanceState::Alive;
      break;
    case DDS_IST_NOT_ALIVE_DISPOSED:
      out.instance_state = InstanceState::Disposed;
      break;
    case DDS_IST_NOT_ALIVE_NO_WRITERS:
      out.instance_state = InstanceState::NoWriters;
      break;
  }
  out.source_time_ns = info.source_timestamp;
  out.instance = info.instance_handle;
  out.publication = info.publication_handle;
  return out;
}

namespace detail {

ReaderCore::ReaderCore(const Participant& participant, dds_entity_t topic, const Qos& qos)
    : Entity(participant.api(),
             check(participant.api().create_reader(participant.handle(), topic,
                                                   participant.endpointQos(qos).get(), nullptr),
                   "dds_create_reader")),
      participant_(participant.handle()) {}

std::int32_t ReaderCore::fetch(Access access, void** samples, dds_sample_info_t* infos,
                               std::size_t max) {
  if (max == 0 || max > static_cast<std::size_t>(std::numeric_limits<std::int32_t>::max())) {
    throw InputError("reader", "max_samples", "an integer in [1, 2^31 - 1]");
  }
  const auto max32 = static_cast<std::uint32_t>(max);
  if (access == Access::Take)
    return check(api().take(handle(), samples, infos, max, max32), "dds_take");
  return check(api().read(handle(), samples, infos, max, max32), "dds_read");
}

std::uint32_t ReaderCore::matchedWriters() const {
  dds_subscription_matched_status_t status{};
  check(api().get_subscription_matched_status(handle(), &status),
        "dds_get_subscription_matched_status");
  return status.current_count;
}

bool ReaderCore::matchesWriter(dds_instance_handle_t publication) const {
  dds_builtintopic_endpoint_t* endpoint = dds_get_matched_publication_data(handle(), publication);
  if (endpoint == nullptr) return false;
  dds_builtintopic_free_endpoint(endpoint);
  return true;
}

bool ReaderCore::waitForWriters(std::uint32_t count, std::chrono::nanoseconds timeout) const {
  return waitForStatus(
      *this, participant_, DDS_SUBSCRIPTION_MATCHED_STATUS,
      [&] { return matchedWriters() >= count; }, timeout);
}

}  // namespace detail
}  // namespace sensornet::dds
