#pragma once
// sensornet from a test suite (CMake: find_package(sensornet), link sensornet::testing): a
// fixture that launches a run with `sensornet launch`, waits for it, gives the report as typed
// values, and tears everything down when it goes out of scope, also when the test failed
// before it waited. It needs only the installed programs and nlohmann-json; no DDS in your
// build.
//
//   #include <sensornet/testing/installed.hpp>     // written by `cmake --install`
//   sensornet::testing::LaunchOptions options;
//   options.program = sensornet::testing::installedProgram();
//   options.scenario = sensornet::testing::installedScenario("default.yaml");
//   options.episodes = 3;
//   options.external_sensors = {2, 5};           // your code speaks for them
//   sensornet::testing::LaunchedRun run(options);  // started; run.runId() names it
//   ... start your participant with run.runId() ...
//   const sensornet::testing::RunResult result = run.wait();
//   EXPECT_EQ(result.status, "completed");
//
// The run gets a run id of its own (so that runs of parallel tests never meet), and its logs
// and report go to a private folder under the system's temporary folder, removed on destruction
// unless keepFiles() was asked for (then logDir() says where they are).

#include <sys/types.h>

#include <chrono>
#include <cstdint>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

namespace sensornet::testing {

struct LaunchOptions {
  // The `sensornet` program; empty: $SENSORNET_PROGRAM, else `sensornet` on the PATH. The
  // installed package's is installedProgram() of <sensornet/testing/installed.hpp>.
  std::filesystem::path program;
  std::filesystem::path scenario;  // required
  int episodes = 4;
  double time_scale = 4.0;  // emulated seconds per wall second
  std::uint64_t seed = 1;
  std::vector<int> external_sensors;  // --external-sensors: your participant speaks for them
  bool external_fusion_center = false;  // --external-fusion-center: yours fuses
  bool reference_fusion = false;        // --reference-fusion: ours beside it
  std::string require;                  // --require criteria, e.g. "no-loss,meets-bracket"
  std::vector<std::string> extra_args;  // any other `sensornet launch` options
  std::chrono::seconds timeout{300};    // wait() gives up (and stops the run) after this
};

struct EpisodeResult {
  std::uint32_t episode = 0;
  std::optional<double> realized_cost;  // none: not fused
  bool complete = false;
  std::string incomplete_reason;
  std::vector<std::uint64_t> sent, received, lost;  // per sensor
};

struct RunResult {
  int exit_code = -1;  // the launcher's: 0 completed, 3 degraded, 4 a --require failed, 1 failed
  std::string status;  // the report's: completed, degraded, failed, interrupted
  std::vector<EpisodeResult> episodes;
  std::optional<double> mean;  // mean realized cost over the complete episodes
  std::optional<double> bracket_lower, bracket_upper;  // the mean bracket [info, cov]
  std::optional<bool> meets_bracket;
  std::optional<double> fusion_agreement;  // --reference-fusion: the largest relative difference
  std::vector<std::string> faults;  // "kind in process: detail", one per fault
  std::string output;               // what the launcher printed (standard output)
  std::string errors;               // ... and on standard error
  nlohmann::json report;            // the whole report, for anything else
};

class LaunchedRun {
 public:
  // Starts the run; throws std::runtime_error when the program cannot be started.
  explicit LaunchedRun(LaunchOptions options);
  // Stops a run still going (SIGINT, as Ctrl-C: the launcher stops its processes and writes
  // the report; SIGKILL of its process group after 20 s) and removes the files.
  ~LaunchedRun();
  LaunchedRun(const LaunchedRun&) = delete;
  LaunchedRun& operator=(const LaunchedRun&) = delete;

  [[nodiscard]] const std::string& runId() const noexcept { return run_id_; }
  [[nodiscard]] const std::filesystem::path& logDir() const noexcept { return log_dir_; }
  [[nodiscard]] pid_t launcherPid() const noexcept { return pid_; }
  void keepFiles() noexcept { keep_files_ = true; }

  // Waits for the run to end (up to the timeout: then it is stopped and the result says
  // `interrupted`) and reads its report. Once waited, the same result again.
  const RunResult& wait();

 private:
  void stop();
  [[nodiscard]] RunResult read(int exit_code) const;

  LaunchOptions options_;
  std::string run_id_;
  std::filesystem::path dir_;
  std::filesystem::path log_dir_;
  pid_t pid_ = -1;
  std::optional<RunResult> result_;
  bool keep_files_ = false;
};

}  // namespace sensornet::testing
