// sensornet._sensornet.Participant: a DDS participant of one run for Python, that reads and
// writes every topic of docs/wire-protocol.md as dicts. The samples are the C types idlc
// generates from idl/sensornet.idl, each described once, field by field, in
// dds/sample_fields.hpp; one pair of functions here turns any described sample into a dict and
// back.
// Topic names, type descriptors and QoS come from include/sensornet/dds/topics.hpp, the one
// place the run's processes take them from.
#include "participant.hpp"

#include <dds/dds.h>
#include <pybind11/stl.h>

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <deque>
#include <memory>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include "sensornet/dds/sample_fields.hpp"
#include "sensornet/dds/topics.hpp"

namespace sensornet::python {
namespace {

namespace py = pybind11;

using dds::EnumName;
using dds::FieldKind;
using dds::SampleType;
using Field = dds::SampleField;
using TypeInfo = dds::SampleType;
using Kind = dds::FieldKind;

const SampleType& countsInfo() { return dds::sensorCountsType(); }
const SampleType& summaryInfo() { return dds::runSummaryType(); }

template <class T>
const SampleType& infoOf() {
  return *dds::sampleTypeOfTopic(dds::TopicType<T>::kName);
}

// --- samples to dicts and back ------------------------------------------------------------

template <class V>
V at(const void* sample, std::size_t offset) {
  V v;
  std::memcpy(&v, static_cast<const char*>(sample) + offset, sizeof v);
  return v;
}

template <class V>
void put(void* sample, std::size_t offset, V v) {
  std::memcpy(static_cast<char*>(sample) + offset, &v, sizeof v);
}

template <class Seq, class V>
py::list listOf(const Seq& s) {
  py::list out;
  for (std::uint32_t i = 0; i < s._length; ++i) out.append(static_cast<V>(s._buffer[i]));
  return out;
}

py::dict dictOf(const TypeInfo& info, const void* sample);

py::object valueOf(const Field& f, const void* sample) {
  switch (f.kind) {
    case Kind::U32: return py::int_(at<std::uint32_t>(sample, f.offset));
    case Kind::I32: return py::int_(at<std::int32_t>(sample, f.offset));
    case Kind::U64: return py::int_(at<std::uint64_t>(sample, f.offset));
    case Kind::I64: return py::int_(at<std::int64_t>(sample, f.offset));
    case Kind::F64: return py::float_(at<double>(sample, f.offset));
    case Kind::Bool: return py::bool_(at<bool>(sample, f.offset));
    case Kind::String: {
      const char* s = at<const char*>(sample, f.offset);
      return py::str(s != nullptr ? s : "");
    }
    case Kind::Enum: {
      const auto v = at<std::int32_t>(sample, f.offset);
      for (const EnumName& e : *f.enum_names) {
        if (e.value == v) return py::str(e.name);
      }
      return py::int_(v);  // a value this build does not name
    }
    case Kind::SeqF64: return listOf<dds_sequence_double, double>(at<dds_sequence_double>(sample, f.offset));
    case Kind::SeqU32: return listOf<dds_sequence_uint32, std::uint32_t>(at<dds_sequence_uint32>(sample, f.offset));
    case Kind::SeqCounts: {
      const auto s = at<dds_sequence_sensornet_SensorCounts>(sample, f.offset);
      py::list out;
      for (std::uint32_t i = 0; i < s._length; ++i) out.append(dictOf(countsInfo(), &s._buffer[i]));
      return out;
    }
    case Kind::Summary: return dictOf(summaryInfo(), static_cast<const char*>(sample) + f.offset);
  }
  return py::none();
}

py::dict dictOf(const TypeInfo& info, const void* sample) {
  py::dict out;
  for (const Field& f : info.fields) out[f.name] = valueOf(f, sample);
  return out;
}

// What a sample written from a dict points to (strings, sequence buffers), alive until the write
// returns.
struct Arena {
  std::deque<std::string> strings;
  std::deque<std::vector<std::byte>> buffers;
  void* buffer(std::size_t bytes) {
    buffers.emplace_back(std::max<std::size_t>(bytes, 1));
    return buffers.back().data();
  }
};

[[noreturn]] void badField(const TypeInfo& info, const Field& f, const std::string& expected,
                           const py::handle& got) {
  throw py::type_error(std::string(info.name) + "." + f.name + ": expected " + expected +
                       ", got " + py::repr(got).cast<std::string>());
}

template <class V>
V integer(const TypeInfo& info, const Field& f, const py::handle& v) {
  if (!py::isinstance<py::int_>(v) || py::isinstance<py::bool_>(v)) badField(info, f, "an integer", v);
  try {
    return v.cast<V>();
  } catch (const py::cast_error&) {
    badField(info, f, "an integer in the field's range", v);
  }
}

double real(const TypeInfo& info, const Field& f, const py::handle& v) {
  if (!py::isinstance<py::float_>(v) && !(py::isinstance<py::int_>(v) && !py::isinstance<py::bool_>(v))) {
    badField(info, f, "a number", v);
  }
  return v.cast<double>();
}

template <class Seq, class Element, class Convert>
void putSequence(void* sample, std::size_t offset, const py::handle& v, Arena& arena,
                 Convert convert) {
  const auto items = py::reinterpret_borrow<py::sequence>(v);
  Seq s{};
  s._length = s._maximum = static_cast<std::uint32_t>(items.size());
  s._buffer = static_cast<Element*>(arena.buffer(sizeof(Element) * items.size()));
  s._release = false;
  for (std::uint32_t i = 0; i < s._length; ++i) convert(items[i], &s._buffer[i]);
  put(sample, offset, s);
}

void fill(const TypeInfo& info, void* sample, const py::dict& values, Arena& arena);

void fillField(const TypeInfo& info, const Field& f, void* sample, const py::handle& v,
               Arena& arena) {
  const bool listed = py::isinstance<py::list>(v) || py::isinstance<py::tuple>(v);
  switch (f.kind) {
    case Kind::U32: put(sample, f.offset, integer<std::uint32_t>(info, f, v)); return;
    case Kind::I32: put(sample, f.offset, integer<std::int32_t>(info, f, v)); return;
    case Kind::U64: put(sample, f.offset, integer<std::uint64_t>(info, f, v)); return;
    case Kind::I64: put(sample, f.offset, integer<std::int64_t>(info, f, v)); return;
    case Kind::F64: put(sample, f.offset, real(info, f, v)); return;
    case Kind::Bool:
      if (!py::isinstance<py::bool_>(v)) badField(info, f, "True or False", v);
      put(sample, f.offset, v.cast<bool>());
      return;
    case Kind::String: {
      if (!py::isinstance<py::str>(v)) badField(info, f, "a string", v);
      arena.strings.push_back(v.cast<std::string>());
      put(sample, f.offset, arena.strings.back().data());
      return;
    }
    case Kind::Enum: {
      std::string names;
      for (const EnumName& e : *f.enum_names) {
        if (py::isinstance<py::str>(v) && v.cast<std::string>() == e.name) {
          put(sample, f.offset, static_cast<std::int32_t>(e.value));
          return;
        }
        names += (names.empty() ? "" : ", ") + std::string(e.name);
      }
      badField(info, f, "one of " + names, v);
    }
    case Kind::SeqF64:
      if (!listed) badField(info, f, "a list of numbers", v);
      putSequence<dds_sequence_double, double>(
          sample, f.offset, v, arena, [&](const py::handle& x, double* out) { *out = real(info, f, x); });
      return;
    case Kind::SeqU32:
      if (!listed) badField(info, f, "a list of integers", v);
      putSequence<dds_sequence_uint32, std::uint32_t>(
          sample, f.offset, v, arena,
          [&](const py::handle& x, std::uint32_t* out) { *out = integer<std::uint32_t>(info, f, x); });
      return;
    case Kind::SeqCounts:
      if (!listed) badField(info, f, "a list of dicts", v);
      putSequence<dds_sequence_sensornet_SensorCounts, sensornet_SensorCounts>(
          sample, f.offset, v, arena, [&](const py::handle& x, sensornet_SensorCounts* out) {
            if (!py::isinstance<py::dict>(x)) badField(info, f, "a list of dicts", x);
            *out = {};
            fill(countsInfo(), out, py::reinterpret_borrow<py::dict>(x), arena);
          });
      return;
    case Kind::Summary:
      if (!py::isinstance<py::dict>(v)) badField(info, f, "a dict", v);
      fill(summaryInfo(), static_cast<char*>(sample) + f.offset,
           py::reinterpret_borrow<py::dict>(v), arena);
      return;
  }
}

// Fields the dict leaves out are zero, empty or the enum's first value; a key the type does not
// have is refused, naming the fields it has.
void fill(const TypeInfo& info, void* sample, const py::dict& values, Arena& arena) {
  for (const auto& [key, value] : values) {
    const std::string name = py::str(key);
    const Field* field = nullptr;
    for (const Field& f : info.fields) {
      if (name == f.name) field = &f;
    }
    if (field == nullptr) {
      std::string names;
      for (const Field& f : info.fields) names += (names.empty() ? "" : ", ") + std::string(f.name);
      throw py::key_error(std::string(info.name) + " has no field '" + name + "' (it has " +
                          names + ")");
    }
    fillField(info, *field, sample, value, arena);
  }
  for (const Field& f : info.fields) {  // strings are never null on the wire
    if (f.kind == Kind::String && at<const char*>(sample, f.offset) == nullptr) {
      arena.strings.emplace_back();
      put(sample, f.offset, arena.strings.back().data());
    }
  }
}

// --- topics -------------------------------------------------------------------------------

struct TopicEntry {
  const char* name;  // "sensornet/Measurement"
  const TypeInfo* info;
  const dds_topic_descriptor_t* descriptor;
  dds::Qos (*reader_qos)();
  dds::Qos (*writer_qos)();
};

template <class T>
TopicEntry entryOf(dds::Qos (*writer_qos)() = &dds::TopicType<T>::qos) {
  return {dds::TopicType<T>::kName, &infoOf<T>(), &dds::TopicType<T>::descriptor(),
          &dds::TopicType<T>::qos, writer_qos};
}

const std::vector<TopicEntry>& topics() {
  static const std::vector<TopicEntry> all = {
      entryOf<sensornet_Scenario>(),     entryOf<sensornet_Schedule>(),
      entryOf<sensornet_EpisodeControl>(), entryOf<sensornet_Measurement>(),
      entryOf<sensornet_EpisodeTally>(), entryOf<sensornet_SensorStatus>(),
      entryOf<sensornet_Report>(&dds::reportWriterQos), entryOf<sensornet_Command>(),
      entryOf<sensornet_CommandReply>(), entryOf<sensornet_FusionState>(),
      entryOf<sensornet_ClockProbe>(),   entryOf<sensornet_ClockEcho>()};
  return all;
}

const TopicEntry& topicNamed(const std::string& name) {
  std::string names;
  for (const TopicEntry& t : topics()) {
    if (name == t.name || name == t.info->name) return t;
    names += (names.empty() ? "" : ", ") + std::string(t.info->name);
  }
  throw py::value_error("no topic '" + name + "' in a sensornet run (topics: " + names + ")");
}

void check(dds_return_t rc, const std::string& what) {
  if (rc < 0) throw std::runtime_error(what + ": " + dds_strretcode(rc));
}

}  // namespace

// --- the participant ----------------------------------------------------------------------

struct Participant::Impl {
  std::string run_id;
  dds_entity_t participant = 0;
  std::vector<std::pair<const TopicEntry*, dds_entity_t>> topics;

  dds_entity_t topicOf(const TopicEntry& t) {
    for (const auto& [entry, handle] : topics) {
      if (entry == &t) return handle;
    }
    const dds_entity_t handle = dds_create_topic(participant, t.descriptor, t.name, nullptr, nullptr);
    check(handle, std::string("cannot create topic ") + t.name);
    topics.emplace_back(&t, handle);
    return handle;
  }
  // "" is the run's partition sensornet/<run id>; "sensors/1" or "operator" below it.
  std::string partition(const std::string& below) const {
    return "sensornet/" + run_id + (below.empty() ? "" : "/" + below);
  }
};

Participant::Participant(const std::string& run_id, int domain_id) : impl_(std::make_shared<Impl>()) {
  impl_->run_id = run_id;
  impl_->participant = dds_create_participant(
      domain_id < 0 ? DDS_DOMAIN_DEFAULT : static_cast<dds_domainid_t>(domain_id), nullptr, nullptr);
  check(impl_->participant, "cannot join DDS domain " + std::to_string(domain_id));
}

Participant::~Participant() { close(); }

void Participant::close() {
  if (impl_ && impl_->participant > 0) {
    dds_delete(impl_->participant);
    impl_->participant = 0;
  }
}

const std::string& Participant::runId() const { return impl_->run_id; }

namespace {

void requireOpen(const std::shared_ptr<Participant::Impl>& p) {
  if (p->participant <= 0) throw std::runtime_error("the participant is closed");
}

}  // namespace

struct Endpoint::Impl {
  std::shared_ptr<Participant::Impl> participant;  // the participant outlives its endpoints
  const TopicEntry* topic = nullptr;
  dds_entity_t handle = 0;
  bool is_reader = false;
};

Endpoint Participant::endpoint(const std::string& topic, const std::string& partition, bool reader) {
  requireOpen(impl_);
  const TopicEntry& t = topicNamed(topic);
  dds::Qos qos = reader ? t.reader_qos() : t.writer_qos();
  const std::string name = impl_->partition(partition);
  if (name.find_first_of("*?") != std::string::npos) {
    if (!reader) throw py::value_error("a writer's partition has no wildcards: " + name);
    qos.partitionPattern(name);
  } else {
    qos.partition(name);
  }
  const dds_entity_t topic_handle = impl_->topicOf(t);
  Endpoint e;
  e.impl_ = std::make_shared<Endpoint::Impl>();
  e.impl_->participant = impl_;
  e.impl_->topic = &t;
  e.impl_->is_reader = reader;
  e.impl_->handle = reader ? dds_create_reader(impl_->participant, topic_handle, qos.get(), nullptr)
                           : dds_create_writer(impl_->participant, topic_handle, qos.get(), nullptr);
  check(e.impl_->handle, std::string("cannot create a ") + (reader ? "reader" : "writer") +
                             " of " + t.name + " in " + name);
  return e;
}

std::string Endpoint::topic() const { return impl_->topic->name; }

int Endpoint::matched() const {
  requireOpen(impl_->participant);
  if (impl_->is_reader) {
    dds_subscription_matched_status_t s;
    return dds_get_subscription_matched_status(impl_->handle, &s) == 0 ? static_cast<int>(s.current_count) : 0;
  }
  dds_publication_matched_status_t s;
  return dds_get_publication_matched_status(impl_->handle, &s) == 0 ? static_cast<int>(s.current_count) : 0;
}

py::list Endpoint::take(int max_samples) {
  requireOpen(impl_->participant);
  if (!impl_->is_reader) throw py::type_error("take() on a writer of " + topic());
  const auto capacity = static_cast<std::size_t>(std::max(max_samples, 1));
  std::vector<void*> samples(capacity, nullptr);
  std::vector<dds_sample_info_t> infos(capacity);
  const dds_return_t n = dds_take(impl_->handle, samples.data(), infos.data(), capacity,
                                  static_cast<std::uint32_t>(capacity));
  check(n, "cannot take from " + topic());
  py::list out;
  for (dds_return_t i = 0; i < n; ++i) {
    if (infos[static_cast<std::size_t>(i)].valid_data) {
      out.append(dictOf(*impl_->topic->info, samples[static_cast<std::size_t>(i)]));
    }
  }
  if (n > 0) dds_return_loan(impl_->handle, samples.data(), n);
  return out;
}

void Endpoint::write(const py::dict& values) {
  requireOpen(impl_->participant);
  if (impl_->is_reader) throw py::type_error("write() on a reader of " + topic());
  const TypeInfo& info = *impl_->topic->info;
  std::vector<std::byte> sample(info.size);
  Arena arena;
  fill(info, sample.data(), values, arena);
  dds_return_t rc = DDS_RETCODE_TIMEOUT;
  {
    py::gil_scoped_release unlocked;  // a reliable write may wait for a reader's room
    while (rc == DDS_RETCODE_TIMEOUT) rc = dds_write(impl_->handle, sample.data());
  }
  check(rc, "cannot write " + topic());
}

bool Endpoint::waitForAcks(double seconds) {
  requireOpen(impl_->participant);
  if (impl_->is_reader) throw py::type_error("wait_for_acks() on a reader of " + topic());
  py::gil_scoped_release unlocked;
  return dds_wait_for_acks(impl_->handle, static_cast<dds_duration_t>(1e9 * seconds)) ==
         DDS_RETCODE_OK;
}

std::vector<std::string> topicNames() {
  std::vector<std::string> names;
  for (const TopicEntry& t : topics()) names.emplace_back(t.info->name);
  return names;
}

void bindParticipant(py::module_& m) {
  py::class_<Endpoint>(m, "Endpoint")
      .def_property_readonly("topic", &Endpoint::topic)
      .def("matched", &Endpoint::matched)
      .def("take", &Endpoint::take, py::arg("max_samples") = 256)
      .def("write", &Endpoint::write, py::arg("sample"))
      .def("wait_for_acks", &Endpoint::waitForAcks, py::arg("seconds") = 2.0);
  py::class_<Participant>(m, "Participant")
      .def(py::init<const std::string&, int>(), py::arg("run_id"), py::arg("domain_id") = -1)
      .def_property_readonly("run_id", &Participant::runId)
      .def(
          "reader",
          [](Participant& p, const std::string& topic, const std::string& partition) {
            return p.endpoint(topic, partition, true);
          },
          py::arg("topic"), py::arg("partition") = "")
      .def(
          "writer",
          [](Participant& p, const std::string& topic, const std::string& partition) {
            return p.endpoint(topic, partition, false);
          },
          py::arg("topic"), py::arg("partition") = "")
      .def("close", &Participant::close);
  m.def("topic_names", &topicNames);
}

}  // namespace sensornet::python
