#pragma once
// Every type of idl/sensornet.idl described once, field by field: its name, kind and offset in
// the C struct idlc generates. What walks a sample generically uses it: the Python participant
// (samples as dicts, python/participant.cpp) and the decoder of recorded samples (their CDR back
// into C structs, for `sensornet replay`).
//
//   const SampleType& type = *sampleTypeOfTopic("sensornet/Measurement");
//   sensornet_Measurement m{};
//   decodeCdr(type, bytes, &m, "run.mcap, message 12");   // throws InputError on bad data
//   ...
//   freeSampleContents(type, &m);

#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace sensornet::dds {

enum class FieldKind {
  U32, I32, U64, I64, F64, Bool, String, Enum, SeqF64, SeqU32, SeqCounts, Summary
};

struct EnumName {
  int value;
  const char* name;  // the IDL's, "EPISODE_START"
};

struct SampleField {
  const char* name;
  FieldKind kind;
  std::size_t offset;
  const std::vector<EnumName>* enum_names = nullptr;  // FieldKind::Enum only
};

struct SampleType {
  const char* name;   // "Measurement"
  const char* topic;  // "sensornet/Measurement"; empty for the nested types
  std::size_t size;   // sizeof the C struct
  std::vector<SampleField> fields;
};

// The nested types (Report.counts, Report.summary).
[[nodiscard]] const SampleType& sensorCountsType();
[[nodiscard]] const SampleType& runSummaryType();
// The ten topic types, in the order of docs/wire-protocol.md's table.
[[nodiscard]] const std::vector<const SampleType*>& topicSampleTypes();
// By topic name ("sensornet/Measurement") or type name ("Measurement"); nullptr if none.
[[nodiscard]] const SampleType* sampleTypeOfTopic(std::string_view name);

// Decodes one serialized sample, as Cyclone writes it (a 4-byte encapsulation header, CDR_LE =
// XCDR1 little-endian, then the data) into `sample`, a zeroed C struct of `type`; strings and
// sequences are allocated with malloc, to be freed by freeSampleContents. Every length is
// checked against the bytes: malformed data is an InputError(source, "<Type>.<field>", ...), and
// what was allocated is freed first.
void decodeCdr(const SampleType& type, std::span<const std::byte> bytes, void* sample,
               const std::string& source);
// Frees what decodeCdr allocated in `sample` (and zeroes those fields).
void freeSampleContents(const SampleType& type, void* sample);

// A decoded sample of any topic type, in storage of its own, freed with its contents.
class DecodedSample {
 public:
  DecodedSample(const SampleType& type, std::span<const std::byte> bytes, const std::string& source)
      : type_(type), storage_((type.size + sizeof(std::max_align_t) - 1) / sizeof(std::max_align_t)) {
    decodeCdr(type, bytes, storage_.data(), source);
  }
  ~DecodedSample() { freeSampleContents(type_, storage_.data()); }
  DecodedSample(const DecodedSample&) = delete;
  DecodedSample& operator=(const DecodedSample&) = delete;
  [[nodiscard]] void* data() { return storage_.data(); }
  template <class T>
  [[nodiscard]] T& as() {
    return *reinterpret_cast<T*>(storage_.data());
  }
  template <class T>
  [[nodiscard]] const T& as() const {
    return *reinterpret_cast<const T*>(storage_.data());
  }

 private:
  const SampleType& type_;
  std::vector<std::max_align_t> storage_;  // zeroed, as decodeCdr expects
};

}  // namespace sensornet::dds
