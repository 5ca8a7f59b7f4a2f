#pragma once
// A DDS quality-of-service value: owns one dds_qos_t (created and deleted here, never by hand),
// copyable and movable, built with chained setters. A policy never set keeps Cyclone's default.
//
//   Qos qos = Qos().reliable(100ms).transientLocal().keepLast(8).durabilityService(8);
//   Writer<sensornet_Schedule> writer(participant, topic, qos);
//
// The per-topic choices of sensornet live in topics.hpp; this type only spells the policies.
// Setters validate their arguments and throw InputError (source "qos") on nonsense.

#include <dds/dds.h>

#include <chrono>
#include <cstdint>
#include <string>

namespace sensornet::dds {

class Qos {
 public:
  Qos();
  Qos(const Qos& other);
  Qos& operator=(const Qos& other);
  Qos(Qos&& other) noexcept;
  Qos& operator=(Qos&& other) noexcept;
  ~Qos();

  // Reliability. A reliable writer whose unacknowledged history is full blocks for at most
  // `max_blocking` before its write returns a timeout (Cyclone's default is 100 ms).
  Qos& reliable(std::chrono::nanoseconds max_blocking = std::chrono::milliseconds(100));
  Qos& bestEffort();

  // Durability. Late-joining readers of a transient-local writer get what the durability
  // service history keeps (per instance), not the writer history: set both.
  Qos& volatileDurability();
  Qos& transientLocal();
  Qos& durabilityService(std::int32_t history_depth);

  // History: the last `depth` samples per instance, or everything (bounded by resourceLimits).
  Qos& keepLast(std::int32_t depth);
  Qos& keepAll();
  // Limits for keep-all histories; DDS_LENGTH_UNLIMITED (-1) for no limit.
  Qos& resourceLimits(std::int32_t max_samples, std::int32_t max_instances,
                      std::int32_t max_samples_per_instance);

  // Liveliness: a writer that stays silent (its process dead) longer than `lease` is taken as
  // not alive, and the instances only it wrote become not-alive (no writers) at the readers.
  Qos& livelinessAutomatic(std::chrono::nanoseconds lease);
  // The period within which each instance expects a new sample (requested/offered deadline).
  Qos& deadline(std::chrono::nanoseconds period);
  // One partition name (no wildcards) on the publisher/subscriber side.
  Qos& partition(const std::string& name);
  // A partition pattern ('*', '?') for a reader: it matches the writers of every partition the
  // pattern matches (emulator/run_partitions.hpp).
  Qos& partitionPattern(const std::string& pattern);
  // Whether deleting a writer also disposes its instances (Cyclone's default: true). With false,
  // readers see a writer that leaves as "no writers", like one that died.
  Qos& autodisposeUnregistered(bool autodispose);

  [[nodiscard]] bool hasPartition() const;
  // The C object for Cyclone calls; owned by this value.
  [[nodiscard]] const dds_qos_t* get() const noexcept { return qos_; }

  friend bool operator==(const Qos& a, const Qos& b);

 private:
  dds_qos_t* mutableQos();
  dds_qos_t* qos_ = nullptr;  // null only when moved from; setters recreate it
};

}  // namespace sensornet::dds
