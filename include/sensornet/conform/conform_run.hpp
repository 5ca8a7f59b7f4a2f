#pragma once
// `sensornet conform sensor|fusion-center|scheduler`: a launched run with the user's program in
// one sensor's role, the fusion center's or an operator's, recorded, and then judged rule by rule
// (sensor_conformance.hpp). The run is a plain `sensornet launch --external-sensors J --record
// ...` (or `--external-fusion-center --reference-fusion`: ours beside it is the yardstick; or,
// for a scheduler, `--drop-first-command-copy`) on a run id and domain of its own; the program is
// started beside it with the run's Cyclone
// configuration in CYCLONEDDS_URI and the placeholders of its command line filled in:
//
//   {run_id} {domain_id} {config}, and for a sensor {sensor} {dim}   (also SENSORNET_RUN_ID,
//   SENSORNET_DOMAIN_ID and SENSORNET_SENSOR in its environment)
//
//   ConformOptions options;
//   options.program = {"./my_sensor", "--run-id", "{run_id}", "--domain-id", "{domain_id}"};
//   const ConformResult result = conform(options, print);
//   exit(result.allPass() ? 0 : 1);
//
// Everything the run wrote (the launcher's and the program's logs, the report, the recording)
// stays in result.dir.

#include <chrono>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <map>
#include <string>
#include <vector>

#include "sensornet/conform/sensor_conformance.hpp"

namespace sensornet::conform {

enum class ConformRole { Sensor, FusionCenter, Scheduler };

struct ConformOptions {
  ConformRole role = ConformRole::Sensor;
  std::string run_id;               // empty: "conform-" and 8 random hex digits
  std::filesystem::path sensornet;  // the `sensornet` program whose `launch` runs the run
  std::filesystem::path scenario;
  int sensor = 0;
  int episodes = 3;
  double time_scale = 2.0;
  std::uint64_t seed = 1;
  bool measures_truth = false;
  std::vector<std::string> program;  // the participant's command line, with placeholders
  std::filesystem::path dir;         // the run's files (made if missing; empty: a new folder
                                     // under the system's temporary folder)
  std::chrono::seconds timeout{600};
  std::vector<std::string> launch_args;  // more `sensornet launch` options
  double tolerance = 1e-9;  // a fusion center's costs and brackets against ours, relative
};

struct ConformResult {
  std::string run_id;
  std::filesystem::path dir;  // where the run's files are
  std::vector<RuleCheck> rules;
  double seconds = 0.0;
  [[nodiscard]] bool allPass() const;
};

// `args` with every "{name}" of `values` replaced; InputError naming `source` for a "{...}"
// that is not one of them.
[[nodiscard]] std::vector<std::string> fillPlaceholders(
    const std::vector<std::string>& args, const std::map<std::string, std::string>& values,
    const std::string& source);

// Runs the run and judges it; `say` gets each progress line. Throws InputError for a bad
// scenario or sensor, std::runtime_error when the run left no recording to judge.
[[nodiscard]] ConformResult conform(const ConformOptions& options,
                                    const std::function<void(const std::string&)>& say);

}  // namespace sensornet::conform
