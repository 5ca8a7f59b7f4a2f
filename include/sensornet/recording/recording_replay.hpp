#pragma once
// Re-fusing a recording (run_recorder.hpp) offline, `sensornet replay RUN.mcap`: the recorded
// samples, in recorded order, each at its recorded receipt time, go through the fusion center's
// own decisions (FusionCenterCore, with RunInputState and the codecs of fusion_center_events.hpp)
// as if the fusion center were receiving them live; no DDS, no wall clock. The result is that
// fusion center's report, written like the live one's, and per episode the replayed realized
// cost beside the one the recorded run's fusion center published (its Report, recorded too): a
// recording of a run equals its replay to the bit, since fusion is exact and in timestamp order.
//
//   const McapReader file("run.mcap");
//   const ReplayResult r = replayRecording(file, "run.mcap", "replay.json");
//   for (const ReplayedEpisode& e : r.episodes) ... e.replayed_cost == *e.recorded_cost ...
//
// A recording without the run's metadata, or a sample that does not decode, is an InputError
// naming the file, the message and the field.

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "sensornet/emulator/vocabulary.hpp"
#include "sensornet/io/mcap.hpp"

namespace sensornet::recording {

struct ReplayedEpisode {
  std::uint32_t episode = 0;
  std::optional<double> replayed_cost;  // nullopt: not fused (incomplete in a way without a cost)
  std::optional<double> recorded_cost;  // the recorded run's Report; nullopt: none was recorded
  bool complete = false;
};

struct ReplayResult {
  std::string run_id;
  emulator::RunStatus status = emulator::RunStatus::Failed;
  std::vector<ReplayedEpisode> episodes;
  std::uint64_t samples_fused = 0;   // Measurements handed to the fusion center
  std::uint64_t samples_read = 0;    // every message of the file
};

// The run id a recording's `run` metadata names; InputError naming the file when it has none.
[[nodiscard]] std::string recordedRunId(const McapReader& file, const std::string& source);

[[nodiscard]] ReplayResult replayRecording(const McapReader& file, const std::string& source,
                                           const std::filesystem::path& report_path);

}  // namespace sensornet::recording
