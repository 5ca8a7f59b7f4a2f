#pragma once
// The emulator's messages between the core types and their DDS form (idl/sensornet.idl):
// publishing scenario, schedule versions and fusion states, and reading them back with every
// field checked. A malformed sample throws InputError naming the topic and field; the
// receiving process counts and logs it and goes on (it never crashes on a bad sample).
//
//   publishSchedule(writer, run_id, digest, version);                // coordinator
//   ScheduleVersion v = scheduleFromWire(sample, scenario, digest);  // everyone else

#include <cstdint>
#include <functional>
#include <optional>
#include <nlohmann/json.hpp>
#include <string>
#include <string_view>
#include <vector>

#include "sensornet/core/scenario.hpp"
#include "sensornet/dds/topics.hpp"
#include "sensornet/dds/writer.hpp"
#include "sensornet/emulator/episode_controls.hpp"
#include "sensornet/emulator/run_input_state.hpp"
#include "sensornet/emulator/run_report.hpp"
#include "sensornet/emulator/schedule_book.hpp"
#include "sensornet/emulator/vocabulary.hpp"

namespace sensornet::wire {

using emulator::EpisodeControl;
using emulator::EpisodeResult;
using emulator::RunScenario;
using emulator::RunSummary;
using emulator::ScheduleVersion;
using emulator::SensorState;

// A SensorStatus's state in the vocabulary (vocabulary.hpp), and back; nullopt for a value the
// IDL does not define (a malformed sample).
[[nodiscard]] std::optional<SensorState> sensorStateOf(sensornet_SensorState state);
[[nodiscard]] sensornet_SensorState wireSensorState(SensorState state);

// The sample publishScenario writes, handed to `use` instead (it borrows from the arguments):
// for a core fed in-process, or a test.
void withScenarioSample(const std::string& run_id, const RunScenario& scenario,
                        const std::function<void(const sensornet_Scenario&)>& use);
[[nodiscard]] dds::WriteResult publishScenario(dds::Writer<sensornet_Scenario>& writer,
                                               const std::string& run_id,
                                               const RunScenario& scenario);
// Parses the YAML, checks the digest and the announced dimensions; throws InputError. The
// arrival mode is the announced `arrivals` (scenario.arrivals as published), not the YAML's;
// empty (a writer that does not set it) means Poisson.
[[nodiscard]] RunScenario scenarioFromWire(const sensornet_Scenario& sample);

// The sample publishSchedule writes, handed to `use` instead (it borrows from the arguments).
void withScheduleSample(const std::string& run_id, const std::string& scenario_digest,
                        const ScheduleVersion& version,
                        const std::function<void(const sensornet_Schedule&)>& use);
[[nodiscard]] dds::WriteResult publishSchedule(dds::Writer<sensornet_Schedule>& writer,
                                               const std::string& run_id,
                                               const std::string& scenario_digest,
                                               const ScheduleVersion& version);
// Checks version >= 1, the scenario digest, N, M, T, the effective time and finite
// non-negative rates; throws InputError. Feasibility is the coordinator's business: a live
// budget change may move b away from the scenario file's.
[[nodiscard]] ScheduleVersion scheduleFromWire(const sensornet_Schedule& sample,
                                               const Scenario& scenario,
                                               const std::string& scenario_digest);

// The Report sample of an episode's result and the run's summary after it. It borrows from
// `run_id`, `e` and `counts` (which receives its per-sensor counts): all must outlive it.
[[nodiscard]] sensornet_Report reportSample(const std::string& run_id, const EpisodeResult& e,
                                            const RunSummary& s,
                                            std::vector<sensornet_SensorCounts>& counts);

// The per_episode entry (episodeEntry) of a Report sample, for the report the launcher builds
// from an external fusion center's Reports. What the wire does not carry is null (the
// received-real-time cost) or zero (switch time, failed sensors, rejections, drain, backlog,
// network delays); the latencies are the Report's, a NEES or real-time cost that is not a number
// is null (not computed). Throws InputError naming the field when a count names a sensor outside
// [0, sensor_count) or twice, or a complete episode's realized cost is not finite.
[[nodiscard]] nlohmann::json episodeEntryOfReport(const sensornet_Report& r, int sensor_count);

// The EpisodeControl sample of `control`, borrowing from it and `run_id` (which must outlive
// it), and back: controlOf throws InputError for a command the IDL does not define.
[[nodiscard]] sensornet_EpisodeCommand episodeCommandOf(emulator::ControlKind kind);
[[nodiscard]] sensornet_EpisodeControl wireControl(const EpisodeControl& control,
                                                   const std::string& run_id);
[[nodiscard]] EpisodeControl controlOf(const sensornet_EpisodeControl& sample);

}  // namespace sensornet::wire
