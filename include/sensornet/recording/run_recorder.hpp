#pragma once
// Records one run as it crossed the wire (`sensornet launch --record FILE.mcap`): every sample of
// every topic of the run, in every partition of it (run_partitions.hpp), as this participant
// received it, into an MCAP file (io/mcap.hpp). A message is the sample's serialized form as
// Cyclone received it (CDR with its encapsulation header: message encoding "cdr"), on a channel
// per topic and partition whose schema is the project's IDL (schema encoding "omgidl", name
// "sensornet::<Type>"), so that standard MCAP tools decode it without our code; log time is the
// receipt (wall clock), publish time the writer's source timestamp. There is a channel per topic
// and writer, made at the writer's first sample, whose metadata are the writer's partition (the
// one the sample came in: for a sensor topic it names the sensors the writer speaks for), its
// GUID and its participant's; a topic nobody wrote has no channel. The readers keep every
// sample (reliable, keep-all; transient-local where the topic is, so what was written before the
// recorder joined is there too). A thread of its own takes what arrived every few milliseconds.
//
//   RunRecorder recorder(participant, run_id, "run.mcap", {{"seed", "7"}});
//   ...                                  // the run
//   const RecordingSummary s = recorder.stop({{"status", "completed"}});
//
// stop() (or the destructor: an interrupted launch) takes what is left, adds the metadata and
// closes the file with its summary, so the file is valid however the run ended. A recorder that
// cannot write (a full disk) stops recording and says so in the summary's `error`; the run goes
// on, and `sensornet launch` lists it as a `recording_incomplete` fault.

#include <atomic>
#include <cstdint>
#include <filesystem>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <thread>

#include "sensornet/dds/participant.hpp"
#include "sensornet/io/mcap.hpp"

namespace sensornet::recording {

struct RecordingSummary {
  std::filesystem::path path;
  std::uint64_t messages = 0;
  std::map<std::string, std::uint64_t> per_topic;  // "sensornet/Measurement" -> messages
  std::uint64_t bytes = 0;                          // of the file
  std::string error;                                // why recording stopped early; empty if not
};

class RunRecorder {
 public:
  RunRecorder(const dds::Participant& participant, const std::string& run_id,
              const std::filesystem::path& path, const McapMap& run_metadata);
  ~RunRecorder();
  RunRecorder(const RunRecorder&) = delete;
  RunRecorder& operator=(const RunRecorder&) = delete;

  // Stops taking: the thread ends, what is left in the readers goes into the file, the readers
  // are deleted, and the disk holds every sample taken and room for the file's end (the
  // summary, and run-end metadata of up to kRunEndBytes: McapWriter::reserveEnd). The summary
  // says whether all of it went in (`error` empty): the launcher drains before it settles the
  // run, so that a recording that fell short is one of the run's faults, and stop() cannot
  // fail for want of space after it. Idempotent.
  const RecordingSummary& drain();
  // Drains, writes `final_metadata` (a "run-end" metadata record) and closes the file with its
  // summary section. Idempotent: a second call returns the same summary.
  RecordingSummary stop(const McapMap& final_metadata = {});

  static constexpr std::size_t kRunEndBytes = 4096;  // stop()'s metadata, reserved by drain()
  // What is recorded reaches the disk a chunk at a time: a disk that fills shows during the run,
  // and a launcher that dies loses at most one chunk.
  static constexpr std::size_t kChunkBytes = 64 * 1024;
  // The IDL the schemas carry (idl/sensornet.idl, compiled in).
  [[nodiscard]] static const std::string& idlText();

 private:
  struct Channel;
  void loop();
  void takeAll();

  std::unique_ptr<McapWriter> writer_;
  std::vector<std::unique_ptr<Channel>> channels_;
  std::mutex mutex_;  // the writer and the channels, between the thread and stop()
  std::atomic<bool> stopping_{false};
  bool drained_ = false;
  bool stopped_ = false;
  RecordingSummary summary_;
  std::thread thread_;
};

}  // namespace sensornet::recording
