#include "sensornet/emulator/episode_controls.hpp"

#include <ctime>

namespace sensornet::emulator {

std::int64_t wallNowNs() {
  timespec now{};
  ::clock_gettime(CLOCK_REALTIME, &now);
  return static_cast<std::int64_t>(now.tv_sec) * 1'000'000'000 + now.tv_nsec;
}

}  // namespace sensornet::emulator
