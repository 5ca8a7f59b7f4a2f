#include "sensornet/dds/topics.hpp"

namespace sensornet::dds {
namespace {

// Reliable and transient-local with the same depth for live readers and late joiners.
Qos lastKnownState(std::int32_t depth) {
  return Qos().reliable(kMaxBlockingTime).transientLocal().keepLast(depth).durabilityService(depth);
}

}  // namespace

Qos scenarioQos() { return lastKnownState(1); }

Qos scheduleQos() { return lastKnownState(kScheduleVersionsKept); }

Qos episodeControlQos() {
  return Qos()
      .reliable(kMaxBlockingTime)
      .transientLocal()
      .keepLast(kEpisodeControlsQueued)
      .durabilityService(1);
}

Qos measurementQos() {
  return Qos()
      .reliable(kMaxBlockingTime)
      .volatileDurability()
      .keepAll()
      .livelinessAutomatic(kSensorLivelinessLease)
      .autodisposeUnregistered(false);
}

Qos episodeTallyQos() {
  return lastKnownState(kEpisodeTalliesKept).autodisposeUnregistered(false);
}

Qos sensorStatusQos() {
  return lastKnownState(1)
      .livelinessAutomatic(kSensorLivelinessLease)
      .autodisposeUnregistered(false);
}

Qos reportQos() { return lastKnownState(1); }

Qos reportWriterQos() { return reportQos().keepAll(); }

Qos commandQos() { return Qos().reliable(kMaxBlockingTime).volatileDurability().keepAll(); }

Qos commandReplyQos() { return lastKnownState(1); }

Qos fusionStateQos() { return Qos().reliable(kMaxBlockingTime).volatileDurability().keepLast(1); }

Qos clockQos() { return Qos().bestEffort().volatileDurability().keepLast(1); }

}  // namespace sensornet::dds
