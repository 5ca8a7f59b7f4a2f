#include "sensornet/dds/writer.hpp"

#include "sensornet/dds/dds_error.hpp"
#include "sensornet/dds/waitset.hpp"

namespace sensornet::dds::detail {
namespace {

WriteResult interpret(dds_return_t result, const char* call) {
  if (result == DDS_RETCODE_TIMEOUT) return WriteResult::TimedOut;
  check(result, call);
  return WriteResult::Written;
}

}  // namespace

WriterCore::WriterCore(const Participant& participant, dds_entity_t topic, const Qos& qos)
    : Entity(participant.api(),
             check(participant.api().create_writer(participant.handle(), topic,
                                                   participant.endpointQos(qos).get(), nullptr),
                   "dds_create_writer")),
      participant_(participant.handle()) {}

WriteResult WriterCore::writeUntyped(const void* sample) {
  return interpret(api().write(handle(), sample), "dds_write");
}

WriteResult WriterCore::writeUntyped(const void* sample, std::int64_t source_time_ns) {
  return interpret(api().write_ts(handle(), sample, source_time_ns), "dds_write_ts");
}

WriteResult WriterCore::disposeUntyped(const void* key_sample) {
  return interpret(api().dispose(handle(), key_sample), "dds_dispose");
}

WriteResult WriterCore::unregisterUntyped(const void* key_sample) {
  return interpret(api().unregister_instance(handle(), key_sample), "dds_unregister_instance");
}

std::uint32_t WriterCore::matchedReaders() const {
  dds_publication_matched_status_t status{};
  check(api().get_publication_matched_status(handle(), &status),
        "dds_get_publication_matched_status");
  return status.current_count;
}

bool WriterCore::waitForReaders(std::uint32_t count, std::chrono::nanoseconds timeout) const {
  return waitForStatus(
      *this, participant_, DDS_PUBLICATION_MATCHED_STATUS,
      [&] { return matchedReaders() >= count; }, timeout);
}

bool WriterCore::waitForAcks(std::chrono::nanoseconds timeout) const {
  const dds_return_t result = api().wait_for_acks(handle(), timeout.count());
  if (result == DDS_RETCODE_TIMEOUT) return false;
  check(result, "dds_wait_for_acks");
  return true;
}

}  // namespace sensornet::dds::detail
