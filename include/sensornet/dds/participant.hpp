#pragma once
// A DDS domain participant on an explicitly created Domain. It carries the run's partition, so
// that every Writer and Reader made from it joins the run's partition without repeating it.
//
//   Domain domain(DomainConfig::forRun("run-42"));
//   Participant participant(domain);
//   Topic<sensornet_Measurement> topic(participant);
//   Writer<sensornet_Measurement> writer(participant, topic);   // in partition "sensornet/run-42"

#include <dds/dds.h>

#include <string>

#include "sensornet/dds/domain.hpp"
#include "sensornet/dds/entity.hpp"
#include "sensornet/dds/qos.hpp"

namespace sensornet::dds {

class Participant : public Entity {
 public:
  explicit Participant(const Domain& domain, const Qos& qos = Qos());

  [[nodiscard]] dds_domainid_t domainId() const noexcept { return domain_id_; }
  [[nodiscard]] const std::string& partition() const noexcept { return partition_; }
  // DomainConfig::write_batching of its domain.
  [[nodiscard]] bool writeBatching() const noexcept { return write_batching_; }

  // `qos` for a writer or reader of this participant: with the run's partition added unless
  // `qos` already names a partition.
  [[nodiscard]] Qos endpointQos(const Qos& qos) const;

 private:
  dds_domainid_t domain_id_ = 0;
  std::string partition_;
  bool write_batching_ = false;
};

}  // namespace sensornet::dds
