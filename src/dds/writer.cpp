#include "sensornet/dds/writer.hpp"

#include <memory>

#include "sensornet/dds/dds_error.hpp"
#include "sensornet/dds/waitset.hpp"
#include "whc_instance_ref.h"

namespace sensornet::dds::detail {
namespace {

WriteResult interpret(dds_return_t result, const char* call) {
  if (result == DDS_RETCODE_TIMEOUT) return WriteResult::TimedOut;
  check(result, call);
  return WriteResult::Written;
}

// Whether `writer` keeps its latest samples for late joiners: its unregistrations always pass
// through its history cache.
bool transientLocal(dds_entity_t writer) {
  const std::unique_ptr<dds_qos_t, decltype(&dds_delete_qos)> qos(dds_create_qos(),
                                                                   &dds_delete_qos);
  check(dds_get_qos(writer, qos.get()), "dds_get_qos");
  dds_durability_kind_t kind = DDS_DURABILITY_VOLATILE;
  return dds_qget_durability(qos.get(), &kind) && kind == DDS_DURABILITY_TRANSIENT_LOCAL;
}

}  // namespace

WriterCore::WriterCore(const Participant& participant, dds_entity_t topic, const Qos& qos)
    : Entity(participant.api(),
             check(participant.api().create_writer(participant.handle(), topic,
                                                   participant.endpointQos(qos).get(), nullptr),
                   "dds_create_writer")),
      participant_(participant.handle()),
      batching_(participant.writeBatching()) {}

WriteResult WriterCore::sentUnlessInBurst(WriteResult result) {
  if (open_bursts_ == 0) {
    flush();
  } else {
    held_ = true;
  }
  return result;
}

void WriterCore::flush() {
  if (batching_) api().write_flush(handle());
}

WriteResult WriterCore::writeUntyped(const void* sample) {
  return sentUnlessInBurst(interpret(api().write(handle(), sample), "dds_write"));
}

WriteResult WriterCore::writeUntyped(const void* sample, std::int64_t source_time_ns) {
  return sentUnlessInBurst(
      interpret(api().write_ts(handle(), sample, source_time_ns), "dds_write_ts"));
}

WriteResult WriterCore::disposeUntyped(const void* key_sample) {
  return sentUnlessInBurst(interpret(api().dispose(handle(), key_sample), "dds_dispose"));
}

WriteResult WriterCore::unregisterUntyped(const void* key_sample) {
  return sentUnlessInBurst(
      interpret(api().unregister_instance(handle(), key_sample), "dds_unregister_instance"));
}

WriteResult WriterCore::unregisterWrittenUntyped(const void* key_sample) {
  if (!transientLocal(handle())) {
    check(DDS_RETCODE_PRECONDITION_NOT_MET, "unregisterWrittenInstance (a transient-local writer)");
  }
  // Looked up while the instance is surely in Cyclone's key-to-instance map.
  const dds_instance_handle_t instance = dds_lookup_instance(handle(), key_sample);
  const WriteResult result = unregisterUntyped(key_sample);
  if (result == WriteResult::Written) {
    (void)sensornet_release_unregistered_instance(handle(), instance);
  }
  return result;
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

bool WriterCore::waitForAcks(std::chrono::nanoseconds timeout) {
  flush();
  const dds_return_t result = api().wait_for_acks(handle(), timeout.count());
  if (result == DDS_RETCODE_TIMEOUT) return false;
  check(result, "dds_wait_for_acks");
  return true;
}

}  // namespace sensornet::dds::detail
