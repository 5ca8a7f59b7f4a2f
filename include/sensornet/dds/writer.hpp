#pragma once
// A typed DDS writer. A write either succeeds or, on a reliable writer whose unacknowledged
// history stayed full for the QoS's max blocking time, times out; the timeout is a result the
// caller must look at ([[nodiscard]]), never an exception and never silently dropped. Every
// other failure throws DdsError.
//
//   Writer<sensornet_Measurement> writer(participant, topic);     // QoS from TopicType
//   if (!writer.waitForReaders(1, 2s)) ...;                       // reliability covers only
//                                                                  // matched readers
//   switch (writer.write(sample)) {
//     case WriteResult::Written: break;
//     case WriteResult::TimedOut: ++timeouts; /* retry, or give up */ break;
//   }
//
// On a domain with DomainConfig::write_batching, the writes of a burst share packets:
//
//   {
//     const auto burst = writer.burst();
//     for (const auto& s : ready) (void)writer.write(s);  // queued in the writer's packet
//   }                                                     // sent here, in as few as fit
//
// Outside a burst, and on any other domain, a write is sent before write() returns.

#include <dds/dds.h>

#include <chrono>
#include <cstdint>
#include <utility>

#include "sensornet/dds/entity.hpp"
#include "sensornet/dds/participant.hpp"
#include "sensornet/dds/qos.hpp"
#include "sensornet/dds/topic.hpp"

namespace sensornet::dds {

enum class [[nodiscard]] WriteResult{
    Written,   // handed to DDS (for a reliable writer: will reach every matched, alive reader)
    TimedOut,  // DDS_RETCODE_TIMEOUT: the history stayed full for max_blocking_time; not written
};

namespace detail {

// The untyped half of Writer<T>.
class WriterCore : public Entity {
 public:
  // Readers currently matched (same topic, partition and compatible QoS).
  [[nodiscard]] std::uint32_t matchedReaders() const;
  // Waits until at least `count` readers are matched; false on timeout.
  [[nodiscard]] bool waitForReaders(std::uint32_t count, std::chrono::nanoseconds timeout) const;
  // Waits until every matched reliable reader acknowledged everything written; false on timeout.
  // Sends what an open burst holds first.
  [[nodiscard]] bool waitForAcks(std::chrono::nanoseconds timeout);

  // Ends with the scope: until then writes on a batching domain wait in the writer's packet
  // (a full packet, or a full history that blocks the write, sends them earlier). Bursts nest;
  // one without writes (an agent's idle wake) costs no call into Cyclone at its end.
  class [[nodiscard]] Burst {
   public:
    explicit Burst(WriterCore& writer) : writer_(&writer) { ++writer_->open_bursts_; }
    ~Burst() {
      if (--writer_->open_bursts_ == 0 && std::exchange(writer_->held_, false)) writer_->flush();
    }
    Burst(const Burst&) = delete;
    Burst& operator=(const Burst&) = delete;

   private:
    WriterCore* writer_;
  };
  [[nodiscard]] Burst burst() { return Burst(*this); }
  // Sends what the writer's packet holds now (before the process dies, say). Nothing to do
  // outside a batching domain.
  void flush();

 protected:
  WriterCore(const Participant& participant, dds_entity_t topic, const Qos& qos);
  WriteResult writeUntyped(const void* sample);
  WriteResult writeUntyped(const void* sample, std::int64_t source_time_ns);
  WriteResult disposeUntyped(const void* key_sample);
  WriteResult unregisterUntyped(const void* key_sample);
  WriteResult unregisterWrittenUntyped(const void* key_sample);

 private:
  // Sends at once unless a burst is open (on a batching domain).
  WriteResult sentUnlessInBurst(WriteResult result);

  dds_entity_t participant_ = 0;
  bool batching_ = false;
  int open_bursts_ = 0;
  bool held_ = false;  // written to since the outermost burst opened: its end sends
};

}  // namespace detail

template <IdlType T>
class Writer : public detail::WriterCore {
 public:
  // With the QoS TopicType<T> asks for, joined to the participant's partition.
  Writer(const Participant& participant, const Topic<T>& topic)
      : Writer(participant, topic, defaultEndpointQos<T>()) {}
  // With `qos` (joined to the participant's partition unless it names one).
  Writer(const Participant& participant, const Topic<T>& topic, const Qos& qos)
      : WriterCore(participant, topic.handle(), qos) {}

  WriteResult write(const T& sample) { return writeUntyped(&sample); }
  // With an explicit source timestamp (wall-clock ns since the epoch) instead of "now".
  WriteResult write(const T& sample, std::int64_t source_time_ns) {
    return writeUntyped(&sample, source_time_ns);
  }
  // Disposes the instance named by the key fields of `key_sample` (readers see "disposed").
  WriteResult dispose(const T& key_sample) { return disposeUntyped(&key_sample); }
  // Stops writing the instance; when no writer is left, readers see "no writers".
  WriteResult unregisterInstance(const T& key_sample) { return unregisterUntyped(&key_sample); }
  // The same for an instance this writer wrote since its last unregistration, on a
  // transient-local writer: also gives back what Cyclone 0.10 would keep of the instance for
  // the writer's whole life (src/dds/whc_instance_ref.h), so that a writer of one instance per
  // episode stays flat. Throws DdsError if the writer is not transient-local.
  WriteResult unregisterWrittenInstance(const T& key_sample) {
    return unregisterWrittenUntyped(&key_sample);
  }
};

}  // namespace sensornet::dds
