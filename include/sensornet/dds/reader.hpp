#pragma once
// A typed DDS reader. Samples come out in two ways:
// - take(n) / read(n) copy up to n samples out into a Batch: `samples` holds the valid ones
//   (each an OwnedSample that frees what Cyclone allocated for it), `changes` the instance
//   state changes (an instance disposed, or left without writers: a sensor that died);
// - takeEach(n, on_sample, on_change) calls a visitor on each sample in place, in samples the
//   reader keeps and Cyclone fills again on the next call (reusing their string and sequence
//   buffers): nothing is allocated or freed per sample once they are big enough.
//
//   Reader<sensornet_Measurement> reader(participant, topic);
//   Batch<sensornet_Measurement> batch = reader.take(256);
//   for (const auto& m : batch.samples) fuse(*m.sample, m.info.source_time_ns);
//   for (const auto& c : batch.changes)
//     if (c.info.instance_state == InstanceState::NoWriters) markDead(c.key->sensor_id);
//
// An instance change that happens while a valid sample of the instance is still unread is not a
// separate change: the valid sample's info.instance_state carries it. Code that must notice a
// dead writer looks at both (`samples[i].info` and `changes`).
//
// Within one writer, samples arrive in the order written; across writers, in order of arrival.

#include <dds/dds.h>

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <utility>
#include <vector>

#include "sensornet/dds/dds_error.hpp"
#include "sensornet/dds/entity.hpp"
#include "sensornet/dds/participant.hpp"
#include "sensornet/dds/qos.hpp"
#include "sensornet/dds/topic.hpp"

namespace sensornet::dds {

enum class InstanceState {
  Alive,      // some writer is alive and has not disposed it
  Disposed,   // a writer disposed it
  NoWriters,  // every writer of it unregistered, left, or lost liveliness (its process died)
};

struct SampleInfo {
  InstanceState instance_state = InstanceState::Alive;
  std::int64_t source_time_ns = 0;        // the writer's timestamp (wall clock, ns since epoch)
  dds_instance_handle_t instance = 0;     // local handle of the instance (key)
  dds_instance_handle_t publication = 0;  // local handle of the writer that wrote it
};

[[nodiscard]] SampleInfo toSampleInfo(const dds_sample_info_t& info) noexcept;

// A sample of an IDL type whose strings and sequences Cyclone allocated; frees them once.
template <IdlType T>
class OwnedSample {
 public:
  OwnedSample() noexcept : value_{} {}
  // Takes over the contents of `filled` (allocated by Cyclone) and empties it.
  [[nodiscard]] static OwnedSample adopt(T& filled) noexcept {
    OwnedSample owned;
    owned.value_ = std::exchange(filled, T{});
    return owned;
  }
  OwnedSample(OwnedSample&& other) noexcept : value_(std::exchange(other.value_, T{})) {}
  OwnedSample& operator=(OwnedSample&& other) noexcept {
    if (this != &other) {
      release();
      value_ = std::exchange(other.value_, T{});
    }
    return *this;
  }
  OwnedSample(const OwnedSample&) = delete;
  OwnedSample& operator=(const OwnedSample&) = delete;
  ~OwnedSample() { release(); }

  [[nodiscard]] const T& operator*() const noexcept { return value_; }
  [[nodiscard]] const T* operator->() const noexcept { return &value_; }
  // For Cyclone to deserialize into, reusing (or growing) the strings and sequences it holds.
  [[nodiscard]] T* fill() noexcept { return &value_; }

 private:
  void release() noexcept {
    dds_sample_free(&value_, &TopicType<T>::descriptor(), DDS_FREE_CONTENTS);
    value_ = T{};
  }
  T value_;
};

template <IdlType T>
struct Received {
  OwnedSample<T> sample;
  SampleInfo info;
};

// An instance state change: only the key fields of `key` are meaningful.
template <IdlType T>
struct InstanceChange {
  OwnedSample<T> key;
  SampleInfo info;
};

template <IdlType T>
struct Batch {
  std::vector<Received<T>> samples;
  std::vector<InstanceChange<T>> changes;
  [[nodiscard]] bool empty() const noexcept { return samples.empty() && changes.empty(); }
};

namespace detail {

// The untyped half of Reader<T>.
class ReaderCore : public Entity {
 public:
  // Writers currently matched (same topic, partition and compatible QoS).
  [[nodiscard]] std::uint32_t matchedWriters() const;
  // Waits until at least `count` writers are matched; false on timeout.
  [[nodiscard]] bool waitForWriters(std::uint32_t count, std::chrono::nanoseconds timeout) const;
  // True while the writer `publication` (SampleInfo::publication) is matched: false once it was
  // deleted or its participant's lease expired.
  [[nodiscard]] bool matchesWriter(dds_instance_handle_t publication) const;

 protected:
  enum class Access { Take, Read };
  ReaderCore(const Participant& participant, dds_entity_t topic, const Qos& qos);
  // dds_take or dds_read into `samples`; returns the count.
  std::int32_t fetch(Access access, void** samples, dds_sample_info_t* infos, std::size_t max);

 private:
  dds_entity_t participant_ = 0;
};

}  // namespace detail

template <IdlType T>
class Reader : public detail::ReaderCore {
 public:
  // With the QoS TopicType<T> asks for, joined to the participant's partition.
  Reader(const Participant& participant, const Topic<T>& topic)
      : Reader(participant, topic, defaultEndpointQos<T>()) {}
  // With `qos` (joined to the participant's partition unless it names one).
  Reader(const Participant& participant, const Topic<T>& topic, const Qos& qos)
      : ReaderCore(participant, topic.handle(), qos) {}

  // Removes up to `max_samples` samples from the reader and copies them out.
  [[nodiscard]] Batch<T> take(std::size_t max_samples = 256) {
    return copyOut(Access::Take, max_samples);
  }
  // Copies up to `max_samples` samples out and leaves them in the reader, marked read.
  [[nodiscard]] Batch<T> read(std::size_t max_samples = 256) {
    return copyOut(Access::Read, max_samples);
  }

  // Removes up to `max_samples` samples and calls on_sample(const T&, const SampleInfo&) for each
  // valid one and on_change(const T& key, const SampleInfo&) for each instance change. The
  // samples live in the reader and are valid only during the call; one thread at a time.
  // Returns how many it visited.
  //
  // Not Cyclone's loan: returning a loan frees each sample's string and sequence, and the next
  // take allocates them again; in a listener that runs for nearly every sample that was about a
  // tenth of the fusion center's receive thread (bench/README.md, "Issue 28, fourth step").
  template <class OnSample, class OnChange>
  std::size_t takeEach(std::size_t max_samples, OnSample&& on_sample, OnChange&& on_change) {
    if (kept_.size() < max_samples) keepAtLeast(max_samples);
    const std::int32_t count = fetch(Access::Take, slots_.data(), infos_.data(), max_samples);
    for (std::size_t i = 0; i < static_cast<std::size_t>(count); ++i) {
      if (infos_[i].valid_data) {
        on_sample(*kept_[i], toSampleInfo(infos_[i]));
      } else {
        on_change(*kept_[i], toSampleInfo(infos_[i]));
      }
    }
    return static_cast<std::size_t>(count);
  }

 private:
  // Grows takeEach's samples (zeroed: Cyclone allocates their strings and sequences on first
  // use) and points the array Cyclone fills them through at them again: growing moves them.
  void keepAtLeast(std::size_t count) {
    kept_.resize(count);
    infos_.resize(count);
    slots_.resize(count);
    for (std::size_t i = 0; i < count; ++i) slots_[i] = kept_[i].fill();
  }

  Batch<T> copyOut(Access access, std::size_t max_samples) {
    // Cyclone fills zeroed samples in place, allocating their strings and sequences; every
    // filled sample is adopted by an OwnedSample before anything else can throw.
    std::vector<T> filled(max_samples);
    std::vector<void*> samples(max_samples);
    for (std::size_t i = 0; i < max_samples; ++i) samples[i] = &filled[i];
    std::vector<dds_sample_info_t> infos(max_samples);
    std::vector<OwnedSample<T>> owned;
    owned.reserve(max_samples);
    const std::int32_t count = fetch(access, samples.data(), infos.data(), max_samples);
    for (std::int32_t i = 0; i < count; ++i) owned.push_back(OwnedSample<T>::adopt(filled[i]));

    Batch<T> batch;
    for (std::int32_t i = 0; i < count; ++i) {
      if (infos[i].valid_data) {
        batch.samples.push_back({std::move(owned[i]), toSampleInfo(infos[i])});
      } else {
        batch.changes.push_back({std::move(owned[i]), toSampleInfo(infos[i])});
      }
    }
    return batch;
  }

  // takeEach's samples (whose strings and sequences Cyclone reuses from call to call), their
  // infos and the pointer array Cyclone fills them through.
  std::vector<OwnedSample<T>> kept_;
  std::vector<dds_sample_info_t> infos_;
  std::vector<void*> slots_;
};

}  // namespace sensornet::dds
