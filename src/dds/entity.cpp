#include "sensornet/dds/entity.hpp"

#include <utility>

#include "sensornet/dds/dds_error.hpp"

namespace sensornet::dds {
namespace {

// dds_delete's answer when the entity is gone already: deleted with its parent (bad parameter or
// already deleted), or the whole library torn down with the last entity (precondition not met).
bool alreadyGone(dds_return_t code) {
  return code == DDS_RETCODE_BAD_PARAMETER || code == DDS_RETCODE_ALREADY_DELETED ||
         code == DDS_RETCODE_PRECONDITION_NOT_MET;
}

}  // namespace

Entity::Entity(Entity&& other) noexcept
    : api_(other.api_), handle_(std::exchange(other.handle_, 0)) {}

Entity& Entity::operator=(Entity&& other) noexcept {
  if (this != &other) {
    try {
      close();
    } catch (...) {  // a move must not throw; the handle is released either way
    }
    api_ = other.api_;
    handle_ = std::exchange(other.handle_, 0);
  }
  return *this;
}

Entity::~Entity() {
  try {
    close();
  } catch (...) {  // destructors never throw
  }
}

void Entity::close() {
  if (handle_ <= 0) return;
  const dds_entity_t handle = std::exchange(handle_, 0);
  const dds_return_t result = api_->delete_entity(handle);
  if (result < 0 && !alreadyGone(result)) check(result, "dds_delete");
}

}  // namespace sensornet::dds
