#pragma once
// Filling and reading the strings and sequences of idlc-generated C structs without copies.
//
// Writing: a sample only borrows memory that the caller keeps alive until write() returns
// (Cyclone serializes during the call and never frees borrowed memory: _release is false).
//
//   std::vector<double> z = ...;  std::string run = "run-42";
//   sensornet_Measurement m{};
//   m.run_id = borrowString(run);
//   borrowSequence(m.z, z);
//   (void)writer.write(m);
//
// Reading: views into a received sample, valid while the sample (or its loan) lives.
//
//   std::span<const double> z = viewSequence(sample.z);
//   std::string_view run = viewString(sample.run_id);

#include <cstdint>
#include <limits>
#include <ranges>
#include <span>
#include <stdexcept>
#include <string>
#include <string_view>
#include <type_traits>
#include <vector>

namespace sensornet::dds {

// A generated sequence type (dds_sequence_double, dds_sequence_uint32, ...).
template <class Seq>
concept WireSequence = requires(Seq seq) {
  seq._maximum;
  seq._length;
  seq._buffer;
  seq._release;
};

template <WireSequence Seq>
using WireElement = std::remove_pointer_t<decltype(Seq::_buffer)>;

// Points `field` at `values` (not copied, not freed by Cyclone).
template <WireSequence Seq, std::ranges::contiguous_range Range>
requires std::same_as<std::ranges::range_value_t<Range>, WireElement<Seq>>
void borrowSequence(Seq& field, const Range& values) {
  const auto size = std::ranges::size(values);
  if (size > std::numeric_limits<std::uint32_t>::max()) {
    throw std::length_error("borrowSequence: more than 2^32 - 1 elements");
  }
  // Cyclone only reads a sample it writes; the cast drops a const it never violates.
  field._buffer = const_cast<WireElement<Seq>*>(std::ranges::data(values));
  field._length = static_cast<std::uint32_t>(size);
  field._maximum = field._length;
  field._release = false;
}

// The string as the char* a generated struct holds (not copied, not freed by Cyclone).
[[nodiscard]] inline char* borrowString(const std::string& text) {
  return const_cast<char*>(text.c_str());
}
// A temporary would be gone before write(): refused at compile time.
char* borrowString(const std::string&& text) = delete;

template <WireSequence Seq>
[[nodiscard]] std::span<const WireElement<Seq>> viewSequence(const Seq& field) {
  if (field._buffer == nullptr) return {};
  return {field._buffer, field._length};
}

[[nodiscard]] inline std::string_view viewString(const char* text) {
  return text != nullptr ? std::string_view(text) : std::string_view();
}

template <WireSequence Seq>
[[nodiscard]] std::vector<WireElement<Seq>> toVector(const Seq& field) {
  const auto view = viewSequence(field);
  return {view.begin(), view.end()};
}

}  // namespace sensornet::dds
