#include "sensornet/dds/participant.hpp"

#include "sensornet/dds/dds_error.hpp"

namespace sensornet::dds {

Participant::Participant(const Domain& domain, const Qos& qos)
    : Entity(domain.api(),
             check(domain.api().create_participant(domain.config().domain_id, qos.get(), nullptr),
                   "dds_create_participant")),
      domain_id_(domain.config().domain_id),
      partition_(domain.config().partition) {}

Qos Participant::endpointQos(const Qos& qos) const {
  Qos joined(qos);
  if (!partition_.empty() && !joined.hasPartition()) joined.partition(partition_);
  return joined;
}

}  // namespace sensornet::dds
