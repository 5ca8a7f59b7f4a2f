#pragma once
// Whether a sensor participant keeps the protocol (`sensornet conform sensor`), rule by rule,
// judged from what a launched run with it in the sensor's role recorded (every sample of every
// topic, as it crossed the wire: recording/run_recorder.hpp) and from the run's report. Each
// rule names the section of docs/wire-protocol.md that states it, and its evidence is what the
// run showed: counts, the first offending sample, a test statistic with its level.
//
//   const McapReader file("run.mcap");
//   const RecordedRun run = readRecording(file, "run.mcap", {2});
//   const std::vector<RuleCheck> rules = checkSensor(run, 2, facts);
//   std::fputs(ruleTable(rules).c_str(), stdout);
//
// The arrival law is checked by time rescaling: under a Poisson process of intensity λ_j(t), the
// integrated rate between successive arrivals of a stretch is Exp(1), so 1 - exp(-ΔΛ) is
// uniform; a Kolmogorov-Smirnov test of those values, and a two-sided test of the count against
// its Poisson mean, each at a false-alarm rate of kConformAlpha. Timetable arrivals are
// deterministic: they must equal the timetable's instants. A sensor that claims to measure the
// plant's truth (--measures-truth) has its z judged against it: with e = z - H_j x(t), the sum
// of e' R_j^-1 e over its N samples is chi-square with p_j N degrees of freedom, tested two-sided
// at kConformAlpha; and the run's mean NEES must lie in its band.

#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "sensornet/emulator/coordinator_core.hpp"
#include "sensornet/emulator/run_input_state.hpp"
#include "sensornet/emulator/vocabulary.hpp"
#include "sensornet/io/mcap.hpp"
#include "sensornet/report/run_record.hpp"

namespace sensornet::conform {

// The false-alarm rate of each statistical rule: a conforming sensor fails it once in 1000 runs.
inline constexpr double kConformAlpha = 0.001;
// The page's status period (at least one SensorStatus every 1 s), and the slack allowed for the
// scheduling and delivery of a busy host.
inline constexpr double kStatusPeriodS = 1.0;
inline constexpr double kStatusSlackS = 0.5;

struct RuleCheck {
  std::string rule;       // "readiness"
  std::string statement;  // what the protocol asks, in one line
  bool pass = false;
  std::string evidence;  // what the run showed
  std::string section;   // "docs/wire-protocol.md#the-readiness-handshake"
};

// What a run's recording shows of one sensor, in receipt order.
struct SensorTrace {
  struct Sample {
    std::uint32_t episode = 0;
    std::uint64_t seq = 0;
    double time_s = 0.0;
    std::uint32_t version = 0;
    std::vector<double> z;
    std::int64_t received_ns = 0;
  };
  struct Tally {
    std::uint32_t episode = 0;
    std::uint64_t sent = 0;
    bool finished = false;
    std::int64_t received_ns = 0;
  };
  struct Status {
    emulator::SensorState state = emulator::SensorState::Starting;
    std::uint32_t version = 0;
    std::int64_t received_ns = 0;
    std::int64_t written_ns = 0;  // its source timestamp: when the sensor wrote it
  };
  std::vector<Sample> samples;
  std::vector<Tally> tallies;
  std::vector<Status> statuses;
};

// A Report as recorded: what a fusion center published for one episode.
struct RecordedReport {
  std::uint32_t episode = 0;
  double realized_cost = 0.0;
  double bracket_lower = 0.0, bracket_upper = 0.0;
  double nees = 0.0;
  bool complete = false;
  struct Counts {
    std::uint64_t sent = 0, received = 0, lost = 0;
    bool operator==(const Counts&) const = default;
  };
  std::vector<Counts> counts;  // by sensor id
  std::int64_t received_ns = 0;
};

// A Command as recorded: what it asked, the partition its writer wrote in, and its receipt.
struct RecordedCommand {
  emulator::CommandEvent command;  // sender: unused (the partition says it)
  std::string kind;                // the IDL's name, "COMMAND_REPLAN"
  std::string partition;           // "sensornet/<run id>/operator"
  // When its writer wrote it (the sample's source timestamp): a copy the middleware delivered
  // late (a repair of a sample sent before the recorder matched) still counts when written.
  std::int64_t written_ns = 0;
};

// A CommandReply as recorded (the coordinator answers each copy it hears of an answered command).
struct RecordedReply {
  std::uint64_t command_id = 0;
  bool accepted = false;
  std::uint32_t schedule_version = 0;
  std::string reason;
  std::int64_t written_ns = 0;  // the coordinator's source timestamp
};

struct RecordedRun {
  std::string run_id;
  emulator::RunInputState
      inputs;  // the scenario and every schedule version, as a process keeps them
  std::map<std::uint32_t, std::int64_t> starts_ns;  // EPISODE_START: the wall instant of time 0
  double time_scale = 1.0;
  std::optional<std::int64_t> shutdown_ns;  // RUN_SHUTDOWN's receipt
  std::int64_t shutdown_written_ns = 0;      // ... and when the coordinator wrote it
  std::int64_t first_ns = 0;                // the recording's first message
  std::map<int, SensorTrace> sensors;       // the sensors asked for (written in their partitions)
  std::vector<RecordedReport> reports;      // in the run's partition, in receipt order
  std::vector<RecordedReport> reference_reports;  // ours beside an outside one (P/reference)
  std::vector<RecordedCommand> commands;  // every Command of any writer, in receipt order
  std::vector<RecordedReply> replies;     // every CommandReply of the run, in receipt order
};

// Reads a recording of `sensornet launch --record`; InputError naming the file when it is none.
[[nodiscard]] RecordedRun readRecording(const McapReader& file, const std::string& source,
                                        const std::vector<int>& sensors);

// What the run's end says beside the recording.
struct RunFacts {
  int launcher_exit = 1;
  std::optional<report::RunRecord> report;  // none: no report was written
  bool measures_truth = false;              // the sensor claims to measure the plant's truth
  // The participant's own exit status: nullopt when a signal ended it or it had to be stopped.
  std::optional<int> program_exit;
  std::string program_end;  // how it ended, for the evidence: "exited with status 0", ...
};

// Every rule of a sensor's role, in the order the protocol meets them.
[[nodiscard]] std::vector<RuleCheck> checkSensor(const RecordedRun& run, int sensor,
                                                 const RunFacts& facts);

// Every rule of a fusion center's role, against our fusion center run beside it on the same
// measurements (--reference-fusion): a Report per episode after its end, costs, brackets and
// counts equal to the reference's (costs and brackets to a relative `tolerance`), leaving, the
// run's outcome; with facts.measures_truth, its NEES in the chi-square band.
[[nodiscard]] std::vector<RuleCheck> checkFusionCenter(const RecordedRun& run,
                                                       const RunFacts& facts, double tolerance);

// Every rule of a scheduler's (an operator's) role, judged from the Commands of a run whose
// coordinator left the first copy of each command unanswered
// (--drop-first-command-copy): at least one command; each in the operator's partition and of a
// kind an operator may send; its run and an id of its own (copies identical); written again
// every 2 s (1 to kResendMaxS) until its reply, and not after it (kReplySlackS); accepted; the
// program leaves by itself; the run completes.
inline constexpr double kResendMinS = 1.0;
inline constexpr double kResendMaxS = 3.5;
inline constexpr double kReplySlackS = 0.5;
[[nodiscard]] std::vector<RuleCheck> checkScheduler(const RecordedRun& run, const RunFacts& facts);

// The Kolmogorov-Smirnov test of values against the uniform law on [0, 1]: the statistic D and
// its asymptotic p-value (Stephens' correction; exact enough for n >= 5).
struct KsTest {
  std::size_t n = 0;
  double d = 0.0;
  double p_value = 1.0;
};
[[nodiscard]] KsTest ksUniform(std::vector<double> values);

// The rules as a table (rule, PASS/FAIL, evidence, section), and as JUnit XML (one test case
// per rule) under `suite`.
[[nodiscard]] std::string ruleTable(const std::vector<RuleCheck>& rules);
[[nodiscard]] std::string rulesJunit(const std::string& suite, const std::vector<RuleCheck>& rules,
                                     double seconds);

}  // namespace sensornet::conform
