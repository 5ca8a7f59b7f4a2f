#pragma once
// The Fast DDS participant of the interoperability programs (fastdds_probe.cpp,
// fastdds_sensor.cpp): traffic stays on 127.0.0.1, UDPv4 only (no shared memory), no multicast,
// the interface white list holding only the loopback address, and the initial peers covering
// the participant indices Cyclone's loopback configuration uses.

#include <fastdds/dds/domain/DomainParticipant.hpp>
#include <fastdds/dds/domain/DomainParticipantFactory.hpp>
#include <fastdds/rtps/transport/UDPv4TransportDescriptor.h>
#include <fastrtps/utils/IPLocator.h>

#include <chrono>
#include <cstdint>
#include <memory>
#include <string>

namespace sensornet::interop {

inline eprosima::fastrtps::rtps::Locator_t loopbackLocator() {
  eprosima::fastrtps::rtps::Locator_t locator;
  locator.kind = LOCATOR_KIND_UDPv4;
  eprosima::fastrtps::rtps::IPLocator::setIPv4(locator, 127, 0, 0, 1);
  return locator;
}

inline eprosima::fastdds::dds::DomainParticipantQos loopbackParticipantQos(const std::string& name) {
  eprosima::fastdds::dds::DomainParticipantQos qos;
  qos.name(name);
  qos.transport().use_builtin_transports = false;
  auto udp = std::make_shared<eprosima::fastdds::rtps::UDPv4TransportDescriptor>();
  udp->interfaceWhiteList.push_back("127.0.0.1");
  udp->maxInitialPeersRange = 32;  // the hubs' participant indices 0..31 (the loopback config)
  qos.transport().user_transports.push_back(udp);
  qos.wire_protocol().builtin.initialPeersList.push_back(loopbackLocator());
  qos.wire_protocol().builtin.metatrafficUnicastLocatorList.push_back(loopbackLocator());
  qos.wire_protocol().default_unicast_locator_list.push_back(loopbackLocator());
  return qos;
}

inline std::int64_t wallNowNs() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}

}  // namespace sensornet::interop
