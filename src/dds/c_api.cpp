#include "sensornet/dds/c_api.hpp"

namespace sensornet::dds {

const CApi& realCApi() noexcept {
  static const CApi api{};
  return api;
}

}  // namespace sensornet::dds
