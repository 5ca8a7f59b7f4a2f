#include "sensornet/dds/qos.hpp"

#include <utility>

#include "sensornet/core/input_error.hpp"

namespace sensornet::dds {
namespace {

dds_duration_t toDuration(std::chrono::nanoseconds span, const char* field) {
  if (span.count() < 0) throw InputError("qos", field, "a duration >= 0");
  return span.count();  // nanoseconds::max() is DDS_INFINITY
}

void requirePositive(std::int32_t value, const char* field) {
  if (value < 1) throw InputError("qos", field, ">= 1 (got " + std::to_string(value) + ")");
}

void requireLimit(std::int32_t value, const char* field) {
  if (value < 1 && value != DDS_LENGTH_UNLIMITED) {
    throw InputError("qos", field,
                     ">= 1 or DDS_LENGTH_UNLIMITED (got " + std::to_string(value) + ")");
  }
}

}  // namespace

Qos::Qos() : qos_(dds_create_qos()) {}

Qos::Qos(const Qos& other) : qos_(dds_create_qos()) {
  if (other.qos_ != nullptr) dds_copy_qos(qos_, other.qos_);
}

Qos& Qos::operator=(const Qos& other) {
  if (this != &other) {
    Qos copy(other);
    std::swap(qos_, copy.qos_);
  }
  return *this;
}

Qos::Qos(Qos&& other) noexcept : qos_(std::exchange(other.qos_, nullptr)) {}

Qos& Qos::operator=(Qos&& other) noexcept {
  std::swap(qos_, other.qos_);
  return *this;
}

Qos::~Qos() {
  if (qos_ != nullptr) dds_delete_qos(qos_);
}

dds_qos_t* Qos::mutableQos() {
  if (qos_ == nullptr) qos_ = dds_create_qos();
  return qos_;
}

Qos& Qos::reliable(std::chrono::nanoseconds max_blocking) {
  dds_qset_reliability(mutableQos(), DDS_RELIABILITY_RELIABLE,
                       toDuration(max_blocking, "reliability.max_blocking_time"));
  return *this;
}

Qos& Qos::bestEffort() {
  dds_qset_reliability(mutableQos(), DDS_RELIABILITY_BEST_EFFORT, 0);
  return *this;
}

Qos& Qos::volatileDurability() {
  dds_qset_durability(mutableQos(), DDS_DURABILITY_VOLATILE);
  return *this;
}

Qos& Qos::transientLocal() {
  dds_qset_durability(mutableQos(), DDS_DURABILITY_TRANSIENT_LOCAL);
  return *this;
}

Qos& Qos::durabilityService(std::int32_t history_depth) {
  requirePositive(history_depth, "durability_service.history.depth");
  dds_qset_durability_service(mutableQos(), 0, DDS_HISTORY_KEEP_LAST, history_depth,
                              DDS_LENGTH_UNLIMITED, DDS_LENGTH_UNLIMITED, DDS_LENGTH_UNLIMITED);
  return *this;
}

Qos& Qos::keepLast(std::int32_t depth) {
  requirePositive(depth, "history.depth");
  dds_qset_history(mutableQos(), DDS_HISTORY_KEEP_LAST, depth);
  return *this;
}

Qos& Qos::keepAll() {
  dds_qset_history(mutableQos(), DDS_HISTORY_KEEP_ALL, DDS_LENGTH_UNLIMITED);
  return *this;
}

Qos& Qos::resourceLimits(std::int32_t max_samples, std::int32_t max_instances,
                         std::int32_t max_samples_per_instance) {
  requireLimit(max_samples, "resource_limits.max_samples");
  requireLimit(max_instances, "resource_limits.max_instances");
  requireLimit(max_samples_per_instance, "resource_limits.max_samples_per_instance");
  dds_qset_resource_limits(mutableQos(), max_samples, max_instances, max_samples_per_instance);
  return *this;
}

Qos& Qos::livelinessAutomatic(std::chrono::nanoseconds lease) {
  dds_qset_liveliness(mutableQos(), DDS_LIVELINESS_AUTOMATIC,
                      toDuration(lease, "liveliness.lease_duration"));
  return *this;
}

Qos& Qos::deadline(std::chrono::nanoseconds period) {
  dds_qset_deadline(mutableQos(), toDuration(period, "deadline.period"));
  return *this;
}

Qos& Qos::partition(const std::string& name) {
  if (name.find_first_of("*?") != std::string::npos) {
    throw InputError("qos", "partition",
                     "a name without the wildcards '*' and '?' (got '" + name + "')");
  }
  dds_qset_partition1(mutableQos(), name.c_str());
  return *this;
}

Qos& Qos::partitionPattern(const std::string& pattern) {
  dds_qset_partition1(mutableQos(), pattern.c_str());
  return *this;
}

Qos& Qos::autodisposeUnregistered(bool autodispose) {
  dds_qset_writer_data_lifecycle(mutableQos(), autodispose);
  return *this;
}

bool Qos::hasPartition() const {
  if (qos_ == nullptr) return false;
  return dds_qget_partition(qos_, nullptr, nullptr);
}

bool operator==(const Qos& a, const Qos& b) {
  if (a.qos_ == nullptr || b.qos_ == nullptr) return a.qos_ == b.qos_;
  return dds_qos_equal(a.qos_, b.qos_);
}

}  // namespace sensornet::dds
