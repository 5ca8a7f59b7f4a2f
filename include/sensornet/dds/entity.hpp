#pragma once
// The owner of one Cyclone entity handle: deletes it exactly once, is move-only, and has an
// explicit, repeatable close(). Every typed owner (Domain, Participant, Topic, Writer, Reader,
// ReadCondition, WaitSet) is an Entity.
//
//   {
//     Participant participant(domain);
//     Writer<sensornet_Measurement> writer(participant, topic);
//     Writer<sensornet_Measurement> other = std::move(writer);  // `writer` is now empty
//   }  // `other` then `participant` are deleted, each once
//
// Cyclone deletes children with their parent (a domain takes its participants, a participant its
// topics, writers and readers). Declaring parents before children gives the natural order; when a
// parent goes first, the child's later close() finds its handle gone and does nothing.

#include <dds/dds.h>

#include "sensornet/dds/c_api.hpp"

namespace sensornet::dds {

class Entity {
 public:
  Entity() noexcept = default;
  // Takes ownership of `handle`, to be deleted through `api` (which must outlive this owner).
  Entity(const CApi& api, dds_entity_t handle) noexcept : api_(&api), handle_(handle) {}
  Entity(Entity&& other) noexcept;
  Entity& operator=(Entity&& other) noexcept;
  Entity(const Entity&) = delete;
  Entity& operator=(const Entity&) = delete;
  ~Entity();

  // Deletes the entity now. Safe to call again, on an empty owner, or after the parent has
  // already taken the entity with it; throws DdsError only if Cyclone refuses the delete.
  void close();

  [[nodiscard]] bool isOpen() const noexcept { return handle_ > 0; }
  // The Cyclone handle, for calls the layer does not wrap; 0 when empty.
  [[nodiscard]] dds_entity_t handle() const noexcept { return handle_; }
  // The C API this entity and its children use (kept by a moved-from owner, so that using one
  // is a DdsError from Cyclone, "bad parameter", not a crash).
  [[nodiscard]] const CApi& api() const noexcept { return *api_; }

 private:
  const CApi* api_ = &realCApi();
  dds_entity_t handle_ = 0;
};

}  // namespace sensornet::dds
