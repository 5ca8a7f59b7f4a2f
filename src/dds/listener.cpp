#include "sensornet/dds/listener.hpp"

#include <memory>
#include <utility>

#include "sensornet/dds/dds_error.hpp"

namespace sensornet::dds {

DataAvailableListener::DataAvailableListener(const detail::ReaderCore& reader,
                                             std::function<void()> on_data)
    : api_(reader.api()), reader_(reader.handle()), on_data_(std::move(on_data)) {
  const std::unique_ptr<dds_listener_t, decltype(&dds_delete_listener)> listener(
      dds_create_listener(this), &dds_delete_listener);
  dds_lset_data_available(listener.get(), &DataAvailableListener::trampoline);
  check(api_.set_listener(reader_, listener.get()), "dds_set_listener");
}

DataAvailableListener::~DataAvailableListener() {
  // Cyclone waits for a callback in progress before it replaces the listener. A reader already
  // deleted (with its participant, say) has no listener left to remove: the error is moot.
  (void)api_.set_listener(reader_, nullptr);
}

void DataAvailableListener::trampoline(dds_entity_t /*reader*/, void* self) noexcept {
  auto* listener = static_cast<DataAvailableListener*>(self);
  try {
    listener->on_data_();
  } catch (...) {
    ++listener->failed_calls_;
  }
}

}  // namespace sensornet::dds
