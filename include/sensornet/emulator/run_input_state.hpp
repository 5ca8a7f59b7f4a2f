#pragma once
// What the sensor agents and the fusion center follow of a run, free of DDS: the scenario (once),
// the schedule versions (stale ones refused, counted and logged) and the episode controls. An
// episode start that overtook the scenario or its schedule versions (they travel on other
// topics) is held back until the scenario and the version the start names (the one in force at
// the episode's start, and so every version before it) are there; a repeated start (durability
// replays the last ones to a late joiner) is dropped. A start may come well before its start
// time (the coordinator announces the next episode while the current one runs).
//
// The state takes decoded values; the wire decodes the three topics' samples and reports those it
// cannot decode with reject() (wire/run_inputs.hpp: RunInputs live, feedSample for a recording
// or a test).
//
//   RunInputState::Update update;
//   state.onScenario(run, update);            // the first scenario counts
//   state.onSchedule(version, update);
//   state.onControl(control, update);
//   state.releaseStarts(update);              // after every batch
//   for (const EpisodeStart& s : update.starts) ...;  // in order, each episode once

#include <cstdint>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <string_view>
#include <vector>

#include "sensornet/core/digest.hpp"  // digestOf: processes agree on the scenario by it
#include "sensornet/core/emulated_plant.hpp"
#include "sensornet/core/scenario.hpp"
#include "sensornet/emulator/episode_controls.hpp"
#include "sensornet/emulator/schedule_book.hpp"
#include "sensornet/emulator/vocabulary.hpp"

namespace sensornet::emulator {

// What a process learns from the Scenario topic.
struct RunScenario {
  Scenario scenario;
  std::string digest;
  std::string yaml;
  std::uint64_t seed = 0;
};

class RunInputState {
 public:
  struct Update {
    bool scenario_arrived = false;
    std::size_t new_versions = 0;  // the last new_versions entries of book().versions()
    std::vector<EpisodeStart> starts;
    std::vector<std::uint32_t> stops;
    std::vector<SensorFailure> failures;
    bool shutdown = false;
    RunEnd end;  // when shutdown
  };

  // The run's scenario; later ones are ignored (one scenario per run). A scenario whose plant
  // cannot be built is rejected as malformed.
  void onScenario(RunScenario run, Update& update);
  // A schedule version decoded against scenario() (call only once hasScenario()): a repeat is
  // dropped, an older one than the latest refused as stale.
  void onSchedule(ScheduleVersion version, Update& update);
  void onControl(const EpisodeControl& control, Update& update);
  // Releases the starts held back until the scenario and the versions they name are there.
  void releaseStarts(Update& update);
  // Counts and logs a sample refused for `reason`; `detail` says what was wrong with it.
  void reject(RejectionReason reason, std::string_view detail);

  [[nodiscard]] bool hasScenario() const { return run_.has_value(); }
  [[nodiscard]] const RunScenario& run() const { return *run_; }
  [[nodiscard]] const Scenario& scenario() const { return run_->scenario; }
  [[nodiscard]] const EmulatedPlant& plant() const { return *plant_; }
  [[nodiscard]] const ScheduleBook& book() const { return book_; }
  // The last episode handed out in Update::starts.
  [[nodiscard]] std::optional<std::uint32_t> lastStarted() const { return last_started_; }
  // Every sensor the coordinator has said is dead (from starts and failure notices).
  [[nodiscard]] const std::set<int>& failedSensors() const { return failed_sensors_; }
  // Samples refused, by reason (the words of RejectionReason).
  [[nodiscard]] const std::map<std::string, std::uint64_t>& rejected() const { return rejected_; }

 private:
  std::optional<RunScenario> run_;
  std::optional<EmulatedPlant> plant_;
  ScheduleBook book_;
  struct HeldStart {
    EpisodeStart start;
    std::uint64_t seed = 0;               // must be the run's
    std::uint32_t schedule_version = 0;   // the book must hold it before the start goes out
  };
  std::vector<HeldStart> held_starts_;
  std::optional<std::uint32_t> last_started_;
  std::set<int> failed_sensors_;
  std::map<std::string, std::uint64_t> rejected_;
};

}  // namespace sensornet::emulator
