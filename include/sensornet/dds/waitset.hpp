#pragma once
// Waiting on DDS events with a timeout, and waking the wait from another thread.
//
//   ReadCondition has_data(reader);              // triggers while unread samples (or instance
//   WaitSet waitset(participant);                // changes) are in the reader
//   waitset.attach(has_data, kMeasurements);
//   std::jthread stopper([&] { ...; waitset.wake(); });   // clean shutdown from elsewhere
//   for (;;) {
//     WaitResult r = waitset.wait(100ms);
//     if (r.woken) break;
//     if (r.triggered(kMeasurements)) handle(reader.take());
//   }

#include <dds/dds.h>

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <functional>
#include <limits>
#include <vector>

#include "sensornet/dds/entity.hpp"
#include "sensornet/dds/participant.hpp"
#include "sensornet/dds/reader.hpp"

namespace sensornet::dds {

// Samples not yet read, in any view and instance state: new data and instance changes alike.
inline constexpr std::uint32_t kUnreadSamples =
    DDS_NOT_READ_SAMPLE_STATE | DDS_ANY_VIEW_STATE | DDS_ANY_INSTANCE_STATE;

// A condition that is true while `reader` holds samples matching `mask`.
class ReadCondition : public Entity {
 public:
  explicit ReadCondition(const detail::ReaderCore& reader, std::uint32_t mask = kUnreadSamples);
};

struct WaitResult {
  std::vector<dds_attach_t> tokens;  // tokens of the attached entities that triggered
  bool woken = false;                // wake() was called
  [[nodiscard]] bool triggered(dds_attach_t token) const {
    return std::find(tokens.begin(), tokens.end(), token) != tokens.end();
  }
  [[nodiscard]] bool timedOut() const noexcept { return tokens.empty() && !woken; }
};

class WaitSet {
 public:
  // Reserved for wake(); attach() refuses it.
  static constexpr dds_attach_t kWakeToken = std::numeric_limits<dds_attach_t>::min();

  explicit WaitSet(const Participant& participant);

  // `entity` (a ReadCondition, or a reader or writer for its enabled statuses) makes wait()
  // return with `token` while it is triggered. The entity must stay open while attached.
  void attach(const Entity& entity, dds_attach_t token);
  void detach(const Entity& entity);
  // Blocks until something attached triggers, wake() is called, or `timeout` passes.
  [[nodiscard]] WaitResult wait(std::chrono::nanoseconds timeout);
  // Makes the current (or next) wait() return with woken = true. Safe from any thread.
  void wake();

 private:
  Entity waitset_;
  Entity guard_;
  std::size_t attached_ = 0;
};

// Waits until `done()` holds, re-checking whenever a status in `status_mask` of `entity` changes
// (a writer's publication-matched, a reader's subscription-matched, ...); false if `timeout`
// passes first. `participant` is the entity's participant. The entity's status mask is narrowed
// to `status_mask` during the wait and restored after.
[[nodiscard]] bool waitForStatus(const Entity& entity, dds_entity_t participant,
                                 std::uint32_t status_mask, const std::function<bool()>& done,
                                 std::chrono::nanoseconds timeout);

}  // namespace sensornet::dds
