#include "sensornet/dds/participant.hpp"

#include "sensornet/core/input_error.hpp"
#include "sensornet/dds/dds_error.hpp"

namespace sensornet::dds {

namespace {

// A secured participant that Cyclone refuses is bad input (the security files), not a failure.
dds_entity_t createParticipant(const Domain& domain, const Qos& qos) {
  const dds_entity_t handle =
      domain.api().create_participant(domain.config().domain_id, qos.get(), nullptr);
  if (handle < 0 && !domain.config().security_hint.empty()) {
    throw InputError("dds_create_participant", "", domain.config().security_hint);
  }
  return check(handle, "dds_create_participant");
}

}  // namespace

Participant::Participant(const Domain& domain, const Qos& qos)
    : Entity(domain.api(), createParticipant(domain, qos)),
      domain_id_(domain.config().domain_id),
      partition_(domain.config().partition),
      write_batching_(domain.config().write_batching) {}

Qos Participant::endpointQos(const Qos& qos) const {
  Qos joined(qos);
  if (!partition_.empty() && !joined.hasPartition()) joined.partition(partition_);
  return joined;
}

}  // namespace sensornet::dds
