#pragma once
// Reacting to a reader's data in Cyclone's own receive thread, the moment it is delivered.
//
// A waitset wakes the application's thread after Cyclone's receive thread has stored a sample:
// two thread hops before the sample is in hand. A listener runs the callback in the receive
// thread itself, so a reader that must time-stamp arrivals (the fusion center) takes them there
// and hands them on to its own thread.
//
//   Reader<sensornet_Measurement> reader(participant, topic);
//   DataAvailableListener listener(reader, [&] { inbox.push(reader.take()); waitset.wake(); });
//
// The callback runs in a middleware thread: it must be quick, must not block on the thread that
// owns the listener, and should not throw (an exception is caught, counted in failedCalls() and
// otherwise dropped, since it cannot cross Cyclone's C frames). Declare the listener after the
// reader and everything the callback touches: its destructor removes the callback and returns
// only once a call in progress has finished, so nothing it uses can go away under it.

#include <atomic>
#include <cstdint>
#include <functional>

#include "sensornet/dds/reader.hpp"

namespace sensornet::dds {

class DataAvailableListener {
 public:
  DataAvailableListener(const detail::ReaderCore& reader, std::function<void()> on_data);
  ~DataAvailableListener();
  DataAvailableListener(const DataAvailableListener&) = delete;
  DataAvailableListener& operator=(const DataAvailableListener&) = delete;
  DataAvailableListener(DataAvailableListener&&) = delete;
  DataAvailableListener& operator=(DataAvailableListener&&) = delete;

  // Calls whose callback threw.
  [[nodiscard]] std::uint64_t failedCalls() const noexcept { return failed_calls_.load(); }

 private:
  static void trampoline(dds_entity_t reader, void* self) noexcept;

  const CApi& api_;
  dds_entity_t reader_;
  std::function<void()> on_data_;
  std::atomic<std::uint64_t> failed_calls_{0};
};

}  // namespace sensornet::dds
