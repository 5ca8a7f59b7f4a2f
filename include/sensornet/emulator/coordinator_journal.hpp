#pragma once
// The coordinator's journal of a run (`coordinator serve --state FILE`): everything a restarted
// coordinator needs to carry the run on (`--resume`): which run and scenario, the live
// settings, every schedule version it published, the episodes reported, the episode it
// announced last and when it starts, and the commands it answered with their replies. It is
// written after every change and before the DDS write that makes the change known, so what the
// others have heard of is always in the journal.
//
//   CoordinatorJournal journal{.run_id = "demo", .scenario_digest = digest, ...};
//   journal.versions.push_back(v1);
//   saveJournal("state.json", journal);                          // temp file + rename
//   const CoordinatorJournal back = loadJournal("state.json", scenario);  // InputError if bad
//
// The file is JSON (doubles in their shortest round-trip form, so rates and brackets come back
// bit for bit). Reported episodes are kept as ranges [first, last], so the file stays small
// over a long run. Saving replaces the file atomically: a reader (or a restart after kill -9)
// sees the old journal or the new one, never a mix. It does not fsync: it survives the death of
// the process, not of the machine.

#include <cstdint>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "sensornet/core/scenario.hpp"
#include "sensornet/emulator/episode_set.hpp"
#include "sensornet/emulator/replanner.hpp"
#include "sensornet/emulator/schedule_book.hpp"

namespace sensornet::emulator {

// The coordinator's answer to one command, sent again if the command comes again.
struct AnsweredCommand {
  bool accepted = false;
  std::uint32_t schedule_version = 0;
  std::string reason;
  bool operator==(const AnsweredCommand&) const = default;
};

// The episode announced last (EPISODE_START) and its emulated time 0 on the wall clock.
struct AnnouncedEpisode {
  std::uint32_t episode = 0;
  std::int64_t start_wall_ns = 0;
  bool operator==(const AnnouncedEpisode&) const = default;
};

struct CoordinatorJournal {
  std::string run_id;
  std::string scenario_digest;
  std::uint64_t seed = 0;
  std::uint32_t episodes_planned = 0;
  double time_scale = 1.0;
  ReplanSettings settings;                // surrogate, excluded, failed, budget
  std::vector<ScheduleVersion> versions;  // increasing numbers, from version 1
  EpisodeSet episodes_reported;           // as ranges, like the file
  std::optional<AnnouncedEpisode> announced;
  std::map<std::uint64_t, AnsweredCommand> answered;  // by command id
  bool shutdown_requested = false;  // COMMAND_SHUTDOWN: the run ends after the episode
  std::string abort_detail;         // not empty: the run ends as failed, for this reason
};

// The journal as JSON text, and back. journalFromJson checks every field against `scenario`
// (sensor ids below M, budget of one value per row of C, N x M rates, increasing versions) and
// throws InputError naming `source` and the field.
[[nodiscard]] std::string journalToJson(const CoordinatorJournal& journal);
[[nodiscard]] CoordinatorJournal journalFromJson(const std::string& text, const std::string& source,
                                                 const Scenario& scenario);

// Writes `path` atomically (writeJsonFile: a temporary beside it, then rename); throws naming
// the file and, when the disk refuses the bytes, the system's reason.
void saveJournal(const std::string& path, const CoordinatorJournal& journal);
// Reads and checks `path` (InputError when missing or malformed).
[[nodiscard]] CoordinatorJournal loadJournal(const std::string& path, const Scenario& scenario);

}  // namespace sensornet::emulator
