// The one description of the IDL's types (dds/sample_fields.hpp) against Cyclone itself: for
// every topic type, a sample with a distinct value in every field (seeded) is serialized by
// Cyclone (a real writer and dds_takecdr), and decodeCdr gives back every field bit for bit, so
// the table's offsets, kinds and order are the generated struct's and our CDR reading is
// Cyclone's writing. Damaged bytes (every prefix, every byte flipped) are an InputError naming
// a field or a decoded sample, never a crash (the sanitizer build checks the reads).
#include <dds/dds.h>
#include <dds/ddsi/ddsi_serdata.h>
#include <gtest/gtest.h>

#include <chrono>
#include <cstdint>
#include <cstring>
#include <deque>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include "dds_test_support.hpp"
#include "sensornet/core/input_error.hpp"
#include "sensornet/dds/participant.hpp"
#include "sensornet/dds/sample_fields.hpp"
#include "sensornet/dds/topics.hpp"

namespace sensornet::dds {
namespace {

// Owns what a filled sample points to.
struct Backing {
  std::deque<std::string> strings;
  std::deque<std::vector<std::byte>> buffers;
};

template <class V>
void put(void* s, std::size_t offset, V v) {
  std::memcpy(static_cast<char*>(s) + offset, &v, sizeof v);
}
template <class V>
V get(const void* s, std::size_t offset) {
  V v;
  std::memcpy(&v, static_cast<const char*>(s) + offset, sizeof v);
  return v;
}

template <class Seq, class Element, class Fill>
void fillSequence(void* s, std::size_t offset, std::mt19937_64& rng, Backing& b, Fill fill) {
  Seq seq{};
  seq._length = seq._maximum = static_cast<std::uint32_t>(1 + rng() % 4);
  b.buffers.emplace_back(sizeof(Element) * seq._length);
  seq._buffer = reinterpret_cast<Element*>(b.buffers.back().data());
  for (std::uint32_t i = 0; i < seq._length; ++i) fill(&seq._buffer[i]);
  put(s, offset, seq);
}

void fill(const SampleType& type, void* s, std::mt19937_64& rng, Backing& b) {
  for (const SampleField& f : type.fields) {
    switch (f.kind) {
      case FieldKind::U32: put(s, f.offset, static_cast<std::uint32_t>(rng())); break;
      case FieldKind::I32: put(s, f.offset, static_cast<std::int32_t>(rng())); break;
      case FieldKind::U64: put(s, f.offset, static_cast<std::uint64_t>(rng())); break;
      case FieldKind::I64: put(s, f.offset, static_cast<std::int64_t>(rng())); break;
      case FieldKind::F64: put(s, f.offset, static_cast<double>(rng() % 100000) / 7.0); break;
      case FieldKind::Bool: put(s, f.offset, (rng() & 1) == 1); break;
      case FieldKind::Enum:
        put(s, f.offset, static_cast<std::int32_t>(rng() % f.enum_names->size()));
        break;
      case FieldKind::String:
        b.strings.push_back(std::string(f.name) + "-" + std::to_string(rng() % 1000000));
        put(s, f.offset, b.strings.back().data());
        break;
      case FieldKind::SeqF64:
        fillSequence<dds_sequence_double, double>(s, f.offset, rng, b, [&](double* x) {
          *x = static_cast<double>(rng() % 1000) / 3.0;
        });
        break;
      case FieldKind::SeqU32:
        fillSequence<dds_sequence_uint32, std::uint32_t>(
            s, f.offset, rng, b, [&](std::uint32_t* x) { *x = static_cast<std::uint32_t>(rng()); });
        break;
      case FieldKind::SeqCounts:
        fillSequence<dds_sequence_sensornet_SensorCounts, sensornet_SensorCounts>(
            s, f.offset, rng, b, [&](sensornet_SensorCounts* x) { fill(sensorCountsType(), x, rng, b); });
        break;
      case FieldKind::Summary:
        fill(runSummaryType(), static_cast<char*>(s) + f.offset, rng, b);
        break;
    }
  }
}

template <class Seq, class Element>
void expectSameSequence(const void* want, const void* got, std::size_t offset, const std::string& where,
                        const SampleType* nested = nullptr);

void expectSame(const SampleType& type, const void* want, const void* got, const std::string& where) {
  for (const SampleField& f : type.fields) {
    const std::string name = where + "." + f.name;
    switch (f.kind) {
      case FieldKind::U32:
      case FieldKind::I32:
      case FieldKind::Enum:
        EXPECT_EQ(get<std::uint32_t>(want, f.offset), get<std::uint32_t>(got, f.offset)) << name;
        break;
      case FieldKind::U64:
      case FieldKind::I64:
      case FieldKind::F64:  // bit for bit
        EXPECT_EQ(get<std::uint64_t>(want, f.offset), get<std::uint64_t>(got, f.offset)) << name;
        break;
      case FieldKind::Bool: EXPECT_EQ(get<bool>(want, f.offset), get<bool>(got, f.offset)) << name; break;
      case FieldKind::String:
        EXPECT_STREQ(get<const char*>(want, f.offset), get<const char*>(got, f.offset)) << name;
        break;
      case FieldKind::SeqF64: expectSameSequence<dds_sequence_double, double>(want, got, f.offset, name); break;
      case FieldKind::SeqU32:
        expectSameSequence<dds_sequence_uint32, std::uint32_t>(want, got, f.offset, name);
        break;
      case FieldKind::SeqCounts:
        expectSameSequence<dds_sequence_sensornet_SensorCounts, sensornet_SensorCounts>(
            want, got, f.offset, name, &sensorCountsType());
        break;
      case FieldKind::Summary:
        expectSame(runSummaryType(), static_cast<const char*>(want) + f.offset,
                   static_cast<const char*>(got) + f.offset, name);
        break;
    }
  }
}

template <class Seq, class Element>
void expectSameSequence(const void* want, const void* got, std::size_t offset, const std::string& where,
                        const SampleType* nested) {
  const auto w = get<Seq>(want, offset);
  const auto g = get<Seq>(got, offset);
  ASSERT_EQ(w._length, g._length) << where;
  for (std::uint32_t i = 0; i < w._length; ++i) {
    if (nested != nullptr) {
      expectSame(*nested, &w._buffer[i], &g._buffer[i], where + "[" + std::to_string(i) + "]");
    } else {
      EXPECT_EQ(std::memcmp(&w._buffer[i], &g._buffer[i], sizeof(Element)), 0) << where << "[" << i << "]";
    }
  }
}

// A sample of T with every field filled, serialized by Cyclone: a writer and a reader of one
// participant, the reader taking the serialized form.
template <class T>
void checkType() {
  const SampleType* type = sampleTypeOfTopic(TopicType<T>::kName);
  ASSERT_NE(type, nullptr) << TopicType<T>::kName;
  ASSERT_EQ(type->size, sizeof(T));
  std::mt19937_64 rng(20261202 + sizeof(T));
  Backing backing;
  T sample{};
  fill(*type, &sample, rng, backing);

  Domain domain(testing::isolatedDomain());
  Participant participant(domain);
  const dds_entity_t topic = dds_create_topic(participant.handle(), &TopicType<T>::descriptor(),
                                              TopicType<T>::kName, nullptr, nullptr);
  ASSERT_GT(topic, 0);
  const Qos qos = TopicType<T>::qos();
  const dds_entity_t reader = dds_create_reader(participant.handle(), topic, qos.get(), nullptr);
  const dds_entity_t writer = dds_create_writer(participant.handle(), topic, qos.get(), nullptr);
  ASSERT_GT(reader, 0);
  ASSERT_GT(writer, 0);
  ASSERT_EQ(dds_write(writer, &sample), DDS_RETCODE_OK);
  ddsi_serdata* serialized = nullptr;
  dds_sample_info_t info;
  dds_return_t n = 0;
  for (int i = 0; i < 500 && n <= 0; ++i) {
    n = dds_takecdr(reader, &serialized, 1, &info, DDS_ANY_STATE);
    if (n <= 0) std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  ASSERT_EQ(n, 1);
  std::vector<std::byte> bytes(ddsi_serdata_size(serialized));
  ddsi_serdata_to_ser(serialized, 0, bytes.size(), bytes.data());
  ddsi_serdata_unref(serialized);

  T decoded{};
  decodeCdr(*type, bytes, &decoded, "test");
  expectSame(*type, &sample, &decoded, type->name);
  freeSampleContents(*type, &decoded);

  // Damage: every prefix short of the data (the options' low bits count trailing padding) and
  // every byte flipped is refused or decoded, never read out of bounds.
  const std::size_t padding = static_cast<std::size_t>(bytes[3]) & 3U;
  for (std::size_t cut = 0; cut + padding < bytes.size(); ++cut) {
    T partial{};
    EXPECT_THROW(decodeCdr(*type, std::span(bytes).first(cut), &partial, "test"), InputError)
        << type->name << " cut at " << cut << " of " << bytes.size();
  }
  for (std::size_t at = 0; at < bytes.size(); ++at) {
    std::vector<std::byte> flipped = bytes;
    flipped[at] ^= std::byte{0xA5};
    T damaged{};
    try {
      decodeCdr(*type, flipped, &damaged, "test");
      freeSampleContents(*type, &damaged);
    } catch (const InputError&) {
    }
  }
}

TEST(SampleFields, EveryTopicTypeDecodesFromCycloneBitForBitAndRefusesDamage) {
  checkType<sensornet_Scenario>();
  checkType<sensornet_Schedule>();
  checkType<sensornet_EpisodeControl>();
  checkType<sensornet_Measurement>();
  checkType<sensornet_EpisodeTally>();
  checkType<sensornet_SensorStatus>();
  checkType<sensornet_Report>();
  checkType<sensornet_Command>();
  checkType<sensornet_CommandReply>();
  checkType<sensornet_FusionState>();
  checkType<sensornet_ClockProbe>();
  checkType<sensornet_ClockEcho>();
  EXPECT_EQ(topicSampleTypes().size(), 12u);
}

}  // namespace
}  // namespace sensornet::dds
