#include "sensornet/recording/live_replay.hpp"

#include <dds/dds.h>
#include <spdlog/spdlog.h>

#include <chrono>
#include <cstdlib>
#include <cstring>
#include <algorithm>
#include <map>
#include <set>
#include <memory>
#include <thread>
#include <vector>

#include "sensornet/core/input_error.hpp"
#include "sensornet/dds/domain.hpp"
#include "sensornet/dds/participant.hpp"
#include "sensornet/dds/sample_fields.hpp"
#include "sensornet/dds/topics.hpp"
#include "sensornet/recording/recording_replay.hpp"

namespace sensornet::recording {

using namespace sensornet::emulator;  // the cores and their events
using namespace sensornet::wire;      // the samples' codecs

namespace {

using Clock = std::chrono::system_clock;

std::int64_t wallNs() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(Clock::now().time_since_epoch())
      .count();
}

struct TopicEntry {
  const dds_topic_descriptor_t* descriptor;
  dds::Qos (*qos)();
};

// The topics a live replay writes again: the run's own side, not the fusion center's outputs.
const std::map<std::string, TopicEntry>& replayedTopics() {
  static const std::map<std::string, TopicEntry> topics = {
      {"sensornet/Scenario", {&sensornet_Scenario_desc, &dds::TopicType<sensornet_Scenario>::qos}},
      {"sensornet/Schedule", {&sensornet_Schedule_desc, &dds::TopicType<sensornet_Schedule>::qos}},
      {"sensornet/EpisodeControl",
       {&sensornet_EpisodeControl_desc, &dds::TopicType<sensornet_EpisodeControl>::qos}},
      {"sensornet/Measurement",
       {&sensornet_Measurement_desc, &dds::TopicType<sensornet_Measurement>::qos}},
      {"sensornet/EpisodeTally",
       {&sensornet_EpisodeTally_desc, &dds::TopicType<sensornet_EpisodeTally>::qos}},
      {"sensornet/SensorStatus",
       {&sensornet_SensorStatus_desc, &dds::TopicType<sensornet_SensorStatus>::qos}},
  };
  return topics;
}

// The run id field of every type is a char* named run_id.
void renameRun(const dds::SampleType& type, void* sample, const std::string& run_id) {
  for (const dds::SampleField& f : type.fields) {
    if (std::strcmp(f.name, "run_id") != 0) continue;
    char* old = nullptr;
    std::memcpy(&old, static_cast<char*>(sample) + f.offset, sizeof old);
    std::free(old);
    char* fresh = static_cast<char*>(std::malloc(run_id.size() + 1));
    std::memcpy(fresh, run_id.c_str(), run_id.size() + 1);
    std::memcpy(static_cast<char*>(sample) + f.offset, &fresh, sizeof fresh);
  }
}

}  // namespace

LiveReplayResult replayLive(const McapReader& file, const std::string& source,
                            const RunOptions& new_run, double time_scale, double ready_timeout_s) {
  const std::string old_run = "sensornet/" + recordedRunId(file, source);
  const std::string new_partition = "sensornet/" + new_run.run_id;
  dds::Domain domain(new_run.domainConfig());
  dds::Participant participant(domain);
  std::map<std::string, dds_entity_t> topic_handles;
  std::map<std::uint16_t, dds_entity_t> writers;  // channel -> its writer in the new run
  std::vector<dds_entity_t> measurement_writers;
  for (const auto& [id, channel] : file.channels()) {
    const auto entry = replayedTopics().find(channel.topic);
    if (entry == replayedTopics().end() || channel.message_encoding != "cdr") continue;
    const auto p = channel.metadata.find("partition");
    std::string partition = p != channel.metadata.end() ? p->second : old_run;
    if (partition.rfind(old_run, 0) != 0) continue;  // not of the recorded run
    partition = new_partition + partition.substr(old_run.size());
    if (!topic_handles.contains(channel.topic)) {
      topic_handles[channel.topic] = dds_create_topic(participant.handle(), entry->second.descriptor,
                                                      channel.topic.c_str(), nullptr, nullptr);
    }
    dds::Qos qos = entry->second.qos();
    qos.partition(partition);
    const dds_entity_t w =
        dds_create_writer(participant.handle(), topic_handles[channel.topic], qos.get(), nullptr);
    if (w < 0) {
      throw std::runtime_error("cannot write " + channel.topic + " in " + partition + ": " +
                               dds_strretcode(w));
    }
    writers[id] = w;
    if (channel.topic == "sensornet/Measurement") measurement_writers.push_back(w);
  }
  // The topic is volatile: a fusion center must hold every measurement writer before the first
  // sample, or it never gets it.
  const auto deadline = std::chrono::steady_clock::now() +
                        std::chrono::duration<double>(ready_timeout_s);
  for (const dds_entity_t w : measurement_writers) {
    dds_publication_matched_status_t m{};
    while (dds_get_publication_matched_status(w, &m) == 0 && m.current_count == 0) {
      if (std::chrono::steady_clock::now() > deadline) {
        throw InputError("sensornet replay --live", "--ready-timeout",
                         "a fusion center of run " + new_run.run_id + " reading its measurements "
                         "within " + std::to_string(ready_timeout_s) + " s (none came)");
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
  }
  // The fusion center's Reports, to hold the run's end until it reported every episode started,
  // as the coordinator does: compressed in time, a RUN_SHUTDOWN could overtake the last tallies.
  const dds_entity_t report_topic = dds_create_topic(
      participant.handle(), &sensornet_Report_desc, "sensornet/Report", nullptr, nullptr);
  dds::Qos report_qos = dds::TopicType<sensornet_Report>::qos();
  report_qos.partition(new_partition);
  const dds_entity_t reports =
      dds_create_reader(participant.handle(), report_topic, report_qos.get(), nullptr);
  std::set<std::uint32_t> started, reported;
  const auto takeReports = [&] {
    void* samples[16] = {nullptr};
    dds_sample_info_t infos[16];
    const dds_return_t n = dds_take(reports, samples, infos, 16, 16);
    for (dds_return_t k = 0; k < n; ++k) {
      if (infos[k].valid_data) reported.insert(static_cast<const sensornet_Report*>(samples[k])->episode);
    }
    if (n > 0) (void)dds_return_loan(reports, samples, n);
  };
  std::this_thread::sleep_for(std::chrono::milliseconds(200));  // the rest of discovery settles

  LiveReplayResult result;
  if (file.messages().empty()) return result;
  const auto recorded_start = static_cast<std::int64_t>(file.messages().front().log_time_ns);
  const std::int64_t start = wallNs() + 200'000'000;
  const auto mapped = [&](std::int64_t recorded_ns) {
    return start + static_cast<std::int64_t>(static_cast<double>(recorded_ns - recorded_start) /
                                             time_scale);
  };
  const auto began = std::chrono::steady_clock::now();
  for (std::size_t i = 0; i < file.messages().size(); ++i) {
    const McapMessage& m = file.messages()[i];
    const auto w = writers.find(m.channel_id);
    if (w == writers.end()) continue;
    const std::string& topic = file.channels().at(m.channel_id).topic;
    const dds::SampleType& type = *dds::sampleTypeOfTopic(topic);
    dds::DecodedSample decoded(type, m.data, source + ", message " + std::to_string(i));
    void* sample = decoded.data();
    renameRun(type, sample, new_run.run_id);
    if (topic == "sensornet/EpisodeControl") {
      auto* c = static_cast<sensornet_EpisodeControl*>(sample);
      c->start_wall_time_ns = mapped(c->start_wall_time_ns);
      c->time_scale *= time_scale;
      if (c->command == sensornet_EPISODE_START) started.insert(c->episode);
      if (c->command == sensornet_RUN_SHUTDOWN) {
        const auto limit = std::chrono::steady_clock::now() +
                           std::chrono::duration<double>(ready_timeout_s);
        for (takeReports(); !std::includes(reported.begin(), reported.end(), started.begin(),
                                           started.end()) &&
                            std::chrono::steady_clock::now() < limit;
             takeReports()) {
          std::this_thread::sleep_for(std::chrono::milliseconds(10));
        }
      }
    } else if (topic == "sensornet/Measurement") {
      auto* s = static_cast<sensornet_Measurement*>(sample);
      s->publish_wall_time_ns = mapped(s->publish_wall_time_ns);
    } else if (topic == "sensornet/EpisodeTally") {
      auto* s = static_cast<sensornet_EpisodeTally*>(sample);
      s->wall_time_ns = mapped(s->wall_time_ns);
    } else if (topic == "sensornet/SensorStatus") {
      auto* s = static_cast<sensornet_SensorStatus*>(sample);
      s->wall_time_ns = mapped(s->wall_time_ns);
    } else if (topic == "sensornet/Schedule") {
      auto* s = static_cast<sensornet_Schedule*>(sample);
      s->issued_wall_time_ns = mapped(s->issued_wall_time_ns);
    }
    const std::int64_t due = mapped(static_cast<std::int64_t>(m.log_time_ns));
    const std::int64_t wait = due - wallNs();
    if (wait > 0) std::this_thread::sleep_for(std::chrono::nanoseconds(wait));
    if (topic == "sensornet/Measurement") {  // stamped as it goes out, as a sensor does
      static_cast<sensornet_Measurement*>(sample)->publish_wall_time_ns = wallNs();
    }
    dds_return_t rc = DDS_RETCODE_TIMEOUT;
    while (rc == DDS_RETCODE_TIMEOUT) rc = dds_write(w->second, sample);
    if (rc != DDS_RETCODE_OK) {
      throw std::runtime_error("cannot write " + topic + ": " + dds_strretcode(rc));
    }
    ++result.written;
  }
  for (const auto& [channel, w] : writers) (void)dds_wait_for_acks(w, DDS_SECS(2));
  result.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - began).count();
  return result;
}

}  // namespace sensornet::recording
