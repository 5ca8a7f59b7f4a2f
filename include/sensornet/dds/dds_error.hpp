#pragma once
// The one exception type of the DDS layer, and the one helper that checks every Cyclone return
// code. A DdsError names the C call, the return code and its text (dds_strretcode), and where in
// the layer the call was made:
//
//   dds_entity_t writer = check(api.create_writer(pp, topic, qos, nullptr), "dds_create_writer");
//   // on failure, what(): "dds_create_writer failed: Out of resources (-5) at writer.hpp:88"
//
// Expected events are not errors and never throw: a reliable write that times out is a
// WriteResult (writer.hpp), an empty take is an empty batch.

#include <dds/dds.h>

#include <source_location>
#include <stdexcept>
#include <string>

namespace sensornet::dds {

class DdsError : public std::runtime_error {
 public:
  DdsError(std::string call, dds_return_t code, std::source_location where);

  [[nodiscard]] const std::string& call() const noexcept { return call_; }
  [[nodiscard]] dds_return_t code() const noexcept { return code_; }
  [[nodiscard]] const std::source_location& where() const noexcept { return where_; }

 private:
  std::string call_;
  dds_return_t code_;
  std::source_location where_;
};

// Returns `result` (a handle, a count or DDS_RETCODE_OK) when it is not negative; otherwise
// throws DdsError naming `call` and the caller's source location.
dds_return_t check(dds_return_t result, const char* call,
                   std::source_location where = std::source_location::current());

// Cyclone's text for a return code, e.g. "Timeout" (never null).
[[nodiscard]] std::string returnCodeText(dds_return_t code);

}  // namespace sensornet::dds
