#pragma once
// A run as a CI gate: `sensornet launch ... --require meets-bracket,no-loss,latency-p99<=5ms`.
// The criteria are parsed before the run starts (an unknown one is bad input) and checked
// against the final report afterwards, each printed as pass or fail with the value measured.
//
//   const std::vector<Requirement> required = parseRequirements("no-loss,latency-p99<=5ms");
//   ... run ...
//   const std::vector<RequirementCheck> checks = checkRequirements(required, report_json);
//   for (const RequirementCheck& c : checks) std::puts(describe(c).c_str());
//   return gatedExitCode(run_exit_code, checks);  // 4 when a criterion failed
//
// Grammar: a comma-separated list of criteria; a criterion is a property name (a yes/no
// property of the run) or `name OP value` with OP one of <=, <, >=, >, = (a measured
// quantity). Durations need a unit (us, ms or s: `latency-p99<=500us`), counts are whole
// numbers, the rest plain numbers. requirementsHelp() lists every name with its meaning.

#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "sensornet/report/run_record.hpp"

namespace sensornet::report {

// Exit code of a launch whose run ended (completed or degraded) but failed a --require
// criterion. A failed or interrupted run keeps its own exit code 1.
inline constexpr int kExitRequirementFailed = 4;

enum class Comparison { Holds, AtMost, Below, AtLeast, Above, Equal };

struct Requirement {
  std::string text;  // as written, e.g. "latency-p99<=5ms"
  std::string name;  // "latency-p99"
  Comparison comparison = Comparison::Holds;  // Holds for a yes/no property
  double limit = 0.0;  // in the property's unit (seconds for durations)
};

// Throws InputError (source "--require") naming the criterion and what was expected: an
// unknown name, a yes/no property with a comparison, a quantity without one, a duration
// without its unit, a count that is not a whole number, an empty list or criterion.
[[nodiscard]] std::vector<Requirement> parseRequirements(std::string_view spec);

struct RequirementCheck {
  Requirement requirement;
  bool pass = false;
  std::string measured;  // "1.84 ms", "yes", "0", or "not in the report (why)"
};

// Checks every requirement against a run's final record. A value the report does not have (no
// latency measured, a bracket not judged) fails its criterion.
[[nodiscard]] std::vector<RequirementCheck> checkRequirements(
    const std::vector<Requirement>& requirements, const RunRecord& report);
// The same of a report document, read through the record's codec; a document that does not
// decode fails every criterion, naming the field.
[[nodiscard]] std::vector<RequirementCheck> checkRequirements(
    const std::vector<Requirement>& requirements, const nlohmann::json& report);

// "require latency-p99<=5ms: pass (measured 1.84 ms)".
[[nodiscard]] std::string describe(const RequirementCheck& check);

// {"criterion", "pass", "measured"} per check, for the report and --json.
[[nodiscard]] nlohmann::json toJson(const std::vector<RequirementCheck>& checks);

// The run's exit code (0 completed, 3 degraded) becomes 4 when a check failed; 1 (failed,
// interrupted) stays 1.
[[nodiscard]] int gatedExitCode(int run_exit_code, const std::vector<RequirementCheck>& checks);

// One line per property for --help: "  latency-p99<=DURATION   99th percentile of ...".
[[nodiscard]] std::string requirementsHelp();

}  // namespace sensornet::report
