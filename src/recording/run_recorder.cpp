#include "sensornet/recording/run_recorder.hpp"

#include <dds/dds.h>
#include <dds/ddsi/ddsi_serdata.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cstddef>
#include <utility>
#include <vector>

#include "sensornet/dds/topics.hpp"
#include "sensornet/emulator/run_partitions.hpp"
#include "sensornet_idl_text.hpp"  // generated: kSensornetIdlText, idl/sensornet.idl verbatim

namespace sensornet::recording {

using namespace sensornet::emulator;  // the run's partitions


// One reader of one topic in one partition (pattern), and the MCAP channel of each writer it
// received from.
struct RunRecorder::Channel {
  std::string topic;
  std::uint16_t schema = 0;
  dds_entity_t reader = 0;
  std::map<dds_instance_handle_t, std::uint16_t> writers;  // publication handle -> channel
  std::uint64_t messages = 0;
};

namespace {

// The topic's own QoS (topics.hpp), keeping every sample: a recorder drops nothing.
template <class T>
dds::Qos recorderQos(const std::string& partition) {
  dds::Qos qos = dds::TopicType<T>::qos();
  qos.keepAll();
  if (partition.find('*') != std::string::npos) {
    qos.partitionPattern(partition);
  } else {
    qos.partition(partition);
  }
  return qos;
}

std::string hexOf(const dds_guid_t& guid) {
  static const char* digits = "0123456789abcdef";
  std::string out;
  for (const std::uint8_t b : guid.v) {
    out += digits[b >> 4];
    out += digits[b & 15];
  }
  return out;
}

// What the reader knows of a writer it matched: its partitions (comma-separated), its GUID and
// its participant's; empty when the writer is gone already.
McapMap writerMetadata(dds_entity_t reader, dds_instance_handle_t writer) {
  McapMap m;
  dds_builtintopic_endpoint_t* endpoint = dds_get_matched_publication_data(reader, writer);
  if (endpoint == nullptr) {
    m["partition"] = "";
    m["writer"] = "gone before its first sample was recorded";
    return m;
  }
  uint32_t count = 0;
  char** names = nullptr;
  std::string partitions;
  if (dds_qget_partition(endpoint->qos, &count, &names)) {
    for (uint32_t i = 0; i < count; ++i) {
      partitions += (i == 0 ? "" : ",") + std::string(names[i]);
      dds_free(names[i]);
    }
    dds_free(names);
  }
  m["partition"] = partitions;
  m["writer"] = hexOf(endpoint->key);
  m["participant"] = hexOf(endpoint->participant_key);
  dds_builtintopic_free_endpoint(endpoint);
  return m;
}

std::string typeNameOf(const char* topic) {  // "sensornet/Measurement" -> "sensornet::Measurement"
  const std::string t(topic);
  return "sensornet::" + t.substr(t.find('/') + 1);
}

}  // namespace

const std::string& RunRecorder::idlText() {
  static const std::string text(kSensornetIdlText);
  return text;
}

RunRecorder::RunRecorder(const dds::Participant& participant, const std::string& run_id,
                         const std::filesystem::path& path, const McapMap& run_metadata)
    : writer_(std::make_unique<McapWriter>(path, "sensornet", kChunkBytes)) {
  summary_.path = path;
  const std::string run = "sensornet/" + run_id;
  const std::string sensors = sensorPartitionPattern(run);
  const std::string launcher = commandPartition(run, CommandSender::Launcher);
  const std::string operator_partition = commandPartition(run, CommandSender::Operator);
  const std::string reference = referencePartition(run);
  std::map<std::string, std::uint16_t> schemas;
  const auto add = [&]<class T>(T*, const std::string& partition) {
    const char* topic = dds::TopicType<T>::kName;
    const std::string type = typeNameOf(topic);
    if (!schemas.contains(type)) schemas[type] = writer_->addSchema(type, "omgidl", idlText());
    auto c = std::make_unique<Channel>();
    c->topic = topic;
    const dds_entity_t t = dds_create_topic(participant.handle(), &dds::TopicType<T>::descriptor(),
                                            topic, nullptr, nullptr);
    c->reader = t < 0 ? t
                      : dds_create_reader(participant.handle(), t,
                                          recorderQos<T>(partition).get(), nullptr);
    if (c->reader < 0) {
      throw std::runtime_error(std::string("cannot record ") + topic + " in " + partition + ": " +
                               dds_strretcode(c->reader));
    }
    c->schema = schemas[type];
    channels_.push_back(std::move(c));
  };
  add(static_cast<sensornet_Scenario*>(nullptr), run);
  add(static_cast<sensornet_Schedule*>(nullptr), run);
  add(static_cast<sensornet_EpisodeControl*>(nullptr), run);
  add(static_cast<sensornet_Measurement*>(nullptr), sensors);
  add(static_cast<sensornet_EpisodeTally*>(nullptr), sensors);
  add(static_cast<sensornet_SensorStatus*>(nullptr), sensors);
  add(static_cast<sensornet_Report*>(nullptr), run);
  add(static_cast<sensornet_FusionState*>(nullptr), run);
  add(static_cast<sensornet_Report*>(nullptr), reference);
  add(static_cast<sensornet_FusionState*>(nullptr), reference);
  add(static_cast<sensornet_Command*>(nullptr), launcher);
  add(static_cast<sensornet_Command*>(nullptr), operator_partition);
  // No one may write Command here; a scheduler that does is shown (sensornet conform scheduler).
  add(static_cast<sensornet_Command*>(nullptr), run);
  add(static_cast<sensornet_CommandReply*>(nullptr), run);
  McapMap run_record = run_metadata;
  run_record["run_id"] = run_id;
  // The first write to disk (the schemas go out with it): a disk that refuses it is the same
  // fault as one that fills later, and the run goes on.
  try {
    writer_->addMetadata("run", run_record);
  } catch (const std::exception& e) {
    summary_.error = e.what();
  }
  thread_ = std::thread([this] { loop(); });
}

RunRecorder::~RunRecorder() {
  try {
    (void)stop();
  } catch (const std::exception& e) {
    spdlog::error("recording {}: {}", summary_.path.string(), e.what());
  }
}

void RunRecorder::loop() {
  while (!stopping_.load()) {
    {
      const std::lock_guard lock(mutex_);
      takeAll();
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
}

// Takes every sample each reader holds into the file; after a write error, only takes (the
// samples must not pile up in the readers) and keeps the error for the summary. What one pass
// took from all readers is written in the order of the writers' source timestamps (one host's
// clock), not reader by reader: so a sensor's last tally goes before the coordinator's
// RUN_SHUTDOWN that followed it, as they were sent.
void RunRecorder::takeAll() {
  constexpr std::uint32_t kBatch = 64;
  std::array<ddsi_serdata*, kBatch> samples{};
  std::array<dds_sample_info_t, kBatch> infos{};
  struct Taken {
    std::int64_t source_ns;
    Channel* reader;
    dds_instance_handle_t writer;
    std::vector<std::byte> bytes;
  };
  std::vector<Taken> taken;
  for (const auto& c : channels_) {
    for (;;) {
      const dds_return_t n = dds_takecdr(c->reader, samples.data(), kBatch, infos.data(),
                                         DDS_ANY_STATE);
      if (n <= 0) break;
      for (dds_return_t i = 0; i < n; ++i) {
        ddsi_serdata* sample = samples[static_cast<std::size_t>(i)];
        const dds_sample_info_t& info = infos[static_cast<std::size_t>(i)];
        if (info.valid_data && writer_ && summary_.error.empty()) {
          Taken t{info.source_timestamp, c.get(), info.publication_handle,
                  std::vector<std::byte>(ddsi_serdata_size(sample))};
          ddsi_serdata_to_ser(sample, 0, t.bytes.size(), t.bytes.data());
          taken.push_back(std::move(t));
        }
        ddsi_serdata_unref(sample);
      }
    }
  }
  std::stable_sort(taken.begin(), taken.end(),
                   [](const Taken& a, const Taken& b) { return a.source_ns < b.source_ns; });
  const auto now = static_cast<std::uint64_t>(dds_time());
  for (Taken& t : taken) {
    if (!summary_.error.empty()) break;
    Channel& c = *t.reader;
    try {
      auto channel = c.writers.find(t.writer);
      if (channel == c.writers.end()) {
        channel = c.writers
                      .emplace(t.writer, writer_->addChannel(c.schema, c.topic, "cdr",
                                                             writerMetadata(c.reader, t.writer)))
                      .first;
      }
      writer_->write(channel->second, now, static_cast<std::uint64_t>(t.source_ns), t.bytes);
      ++c.messages;
    } catch (const std::exception& e) {
      summary_.error = e.what();
      spdlog::error("recording stopped: {}", e.what());
    }
  }
}

const RecordingSummary& RunRecorder::drain() {
  if (drained_) return summary_;
  stopping_ = true;
  if (thread_.joinable()) thread_.join();
  const std::lock_guard lock(mutex_);
  drained_ = true;
  takeAll();
  for (const auto& c : channels_) {
    summary_.per_topic[c->topic] += c->messages;
    summary_.messages += c->messages;
    (void)dds_delete(c->reader);
  }
  // What the run sent is on disk now, with room for the file's end: a disk too full for either
  // is known while the launcher can still count it a fault.
  if (writer_ && summary_.error.empty()) {
    try {
      writer_->reserveEnd(kRunEndBytes);
    } catch (const std::exception& e) {
      summary_.error = e.what();  // the launcher's fault says it
    }
  }
  return summary_;
}

RecordingSummary RunRecorder::stop(const McapMap& final_metadata) {
  if (stopped_) return summary_;
  (void)drain();
  const std::lock_guard lock(mutex_);
  stopped_ = true;
  if (summary_.error.empty()) {
    try {
      if (!final_metadata.empty()) writer_->addMetadata("run-end", final_metadata);
      writer_->close();
    } catch (const std::exception& e) {
      summary_.error = e.what();
    }
  }
  writer_.reset();  // closes what it can
  std::error_code ec;
  summary_.bytes = std::filesystem::file_size(summary_.path, ec);
  return summary_;
}

}  // namespace sensornet::recording
