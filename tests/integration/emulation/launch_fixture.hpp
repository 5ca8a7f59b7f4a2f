#pragma once
// `sensornet launch` runs for the integration tests: a fixture with a private temporary folder
// (the launcher's scratch folder and current-run record inside it, never the user's), a run id
// of its own per test, and helpers to read what a run leaves behind and to find its processes.
//
//   class MyTest : public sensornet::testing::LaunchTest {};
//   TEST_F(MyTest, X) {
//     const LeftoverGuard guard(run_id_);
//     RunningProgram launcher(launchArgs(6, "3"), 90s);
//     ASSERT_TRUE(waitUntil([&] { return readJsonLines(dir_ / "report.jsonl").size() >= 1; }, 30s));
//     ::kill(*processOf(run_id_, SENSORNET_FUSION_CENTER), SIGKILL);
//     const ProcessResult& r = launcher.result();
//   }

#include <gtest/gtest.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <thread>
#include <vector>
#include <yaml-cpp/yaml.h>

#include "emulation_fixture.hpp"
#include "sensornet/report/run_record.hpp"
#include "support/background_process.hpp"
#include "support/process.hpp"
#include "support/sanitizer.hpp"
#include "support/scratch_dir.hpp"

namespace sensornet::testing {

inline const std::string kLauncher = SENSORNET_LAUNCHER;

// A JSON file, parsed (discarded when it is not JSON). A run report among them also passes
// through the record's one codec (run_record.hpp): it must decode, encode back to the same
// document and hold to docs/report.schema.json, so that every real report of the suite (clean,
// faulted, aborted, interrupted, external roles, rebuilt) checks the codec and the schema
// against what the programs write.
inline nlohmann::json readJson(const std::filesystem::path& path) {
  nlohmann::json doc = nlohmann::json::parse(readText(path), nullptr, false);
  if (doc.is_object() && doc.contains("run_id") && doc.contains("summary") &&
      doc.contains("status")) {
    try {
      const nlohmann::json again = report::encode(report::decodeRunRecord(doc));
      if (again != doc) {
        ADD_FAILURE() << path << ": the record's codec does not give back the report: "
                      << nlohmann::json::diff(doc, again).dump();
      }
    } catch (const report::RecordError& e) {
      ADD_FAILURE() << path << ": the record's codec refuses the report: " << e.what();
    }
    // ... and holds to the schema in docs/ (python3-jsonschema).
    const ProcessResult valid = runProcess(
        {"/usr/bin/python3", std::string(SENSORNET_SOURCE_DIR) + "/tests/support/validate_report.py",
         path.string()},
        std::chrono::seconds(60));
    if (valid.exit_code != 0) {
      ADD_FAILURE() << path << " does not hold to docs/report.schema.json:\n" << valid.out
                    << valid.err;
    }
  }
  return doc;
}

// The whole lines of a JSON Lines file, parsed (a torn last line is left out).
inline std::vector<nlohmann::json> readJsonLines(const std::filesystem::path& path) {
  std::vector<nlohmann::json> lines;
  const std::string text = readText(path);
  std::size_t start = 0;
  for (std::size_t end = text.find('\n'); end != std::string::npos;
       start = end + 1, end = text.find('\n', start)) {
    nlohmann::json line = nlohmann::json::parse(text.substr(start, end - start), nullptr, false);
    if (line.is_object()) lines.push_back(std::move(line));
  }
  return lines;
}

// The process of the run whose command line starts with `program` and contains `token`.
inline std::optional<pid_t> processOf(const std::string& run_id, const std::string& program,
                                      const std::string& token = "") {
  for (const pid_t pid : processesMentioning(run_id)) {
    std::string cmdline = readText("/proc/" + std::to_string(pid) + "/cmdline");
    for (char& c : cmdline) c = c == '\0' ? ' ' : c;
    if (cmdline.starts_with(program + ' ') && cmdline.find(token) != std::string::npos) {
      return pid;
    }
  }
  return std::nullopt;
}

// Waits until `done()` or `limit` passes; returns done().
template <class Done>
bool waitUntil(Done done, std::chrono::milliseconds limit) {
  const auto deadline = std::chrono::steady_clock::now() + scaledLimit(limit);
  while (!done() && std::chrono::steady_clock::now() < deadline) {
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  return done();
}

class LaunchTest : public ::testing::Test {
 protected:
  void SetUp() override {
    ::setenv("XDG_RUNTIME_DIR", dir_.c_str(), 1);
    ::setenv("SENSORNET_SCRATCH_DIR", (dir_ / "scratch").c_str(), 1);
    ::unsetenv("SENSORNET_CYCLONE_CONFIG");
    ::unsetenv("SENSORNET_BIN_DIR");
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    run_id_ = "tr-" + std::to_string(::getpid()) + "-" + std::string(info->name()).substr(0, 24);
  }
  void TearDown() override {
    std::error_code ignored;
    // Undo what a test made unremovable or another user's before removing the folder.
    std::filesystem::permissions(dir_, std::filesystem::perms::owner_all, ignored);
  }

  // A launch of `scenario` with this test's run id; logs in dir_/logs unless `log_dir` is empty
  // (then the default folder, in the scratch folder).
  [[nodiscard]] std::vector<std::string> launchArgs(int episodes, const std::string& time_scale,
                                                    const std::filesystem::path& report,
                                                    const std::filesystem::path& log_dir,
                                                    const std::string& scenario = kDefaultScenario) const {
    std::vector<std::string> argv = {
        kLauncher,      "launch",   scenario,   "--episodes", std::to_string(episodes),
        "--time-scale", time_scale, "--run-id", run_id_};
    if (!report.empty()) argv.insert(argv.end(), {"--report", report.string()});
    if (!log_dir.empty()) argv.insert(argv.end(), {"--log-dir", log_dir.string()});
    return argv;
  }
  [[nodiscard]] std::vector<std::string> launchArgs(int episodes,
                                                    const std::string& time_scale) const {
    return launchArgs(episodes, time_scale, dir_ / "report.json", dir_ / "logs");
  }

  sensornet::testing::ScratchDir scratch_;  // removed unless the test failed
  std::filesystem::path dir_ = scratch_.path();
  std::string run_id_;
};

// What must hold of a run where a participant of the user's spoke for `sensor`, drawing its own
// arrivals (another draw than ours, as valid): the run completed, every measurement it sent was
// fused and nothing lost, in every episode; and its total count over the run, Poisson with mean
// the sum of the expected counts the report gives, lies within 4.5 standard deviations of it
// (false alarm 7e-6). `printed` is what the participant printed: "sent N measurements".
inline void expectExternalSensorTookItsRole(const nlohmann::json& report, int episodes,
                                            std::size_t sensor, const std::string& printed) {
  ASSERT_TRUE(report.is_object());
  EXPECT_EQ(report.at("status"), "completed") << report.at("faults").dump();
  const nlohmann::json& entries = report.at("per_episode");
  ASSERT_EQ(entries.size(), static_cast<std::size_t>(episodes));
  double expected = 0.0;
  std::uint64_t sent = 0;
  for (const nlohmann::json& e : entries) {
    EXPECT_TRUE(e.at("complete").get<bool>()) << e.dump();
    EXPECT_EQ(e.at("received").at(sensor), e.at("sent").at(sensor));
    EXPECT_EQ(e.at("lost").at(sensor), 0);
    sent += e.at("sent").at(sensor).get<std::uint64_t>();
    expected += e.at("expected").at(sensor).get<double>();
  }
  ASSERT_GT(expected, 10.0) << "sensor " << sensor << " must be scheduled for the test to mean "
                            << "something";
  EXPECT_LE(std::abs(static_cast<double>(sent) - expected), 4.5 * std::sqrt(expected))
      << "sent " << sent << ", expected " << expected;
  EXPECT_NE(printed.find("sent " + std::to_string(sent) + " measurements"), std::string::npos)
      << printed;
}

// The model flags of examples/c/external_fusion_center (a scalar plant) read from a scalar
// scenario file: --a --q --p0 --w --wt, and --h, --r with one value per sensor.
inline std::vector<std::string> scalarModelArgs(const std::filesystem::path& scenario) {
  const YAML::Node doc = YAML::LoadFile(scenario.string());
  const auto scalar = [](const YAML::Node& matrix) { return matrix[0][0].as<std::string>(); };
  std::string h, r;
  for (const YAML::Node& sensor : doc["sensors"]) {
    h += (h.empty() ? "" : ",") + scalar(sensor["H"]);
    r += (r.empty() ? "" : ",") + scalar(sensor["R"]);
  }
  return {"--a", scalar(doc["plant"]["A"]), "--q", scalar(doc["plant"]["Q"]), "--p0",
          scalar(doc["plant"]["P0"]), "--w", scalar(doc["cost"]["W"]), "--wt",
          scalar(doc["cost"]["WT"]), "--h", h, "--r", r};
}

}  // namespace sensornet::testing
