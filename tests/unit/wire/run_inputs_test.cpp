// RunInputs holds an episode start back until the schedule version it names is in the book
// (issue 15): with episodes back to back the next start is announced while the current episode
// runs, and a version published just before it travels on another topic; a sensor that began
// the episode without it would draw the wrong arrivals. Over Cyclone DDS in this process, on a
// run id (partition and domain) of its own.

#include <gtest/gtest.h>
#include <unistd.h>

#include <chrono>
#include <string>
#include <thread>
#include <vector>

#include "sensornet/dds/participant.hpp"
#include "sensornet/dds/topics.hpp"
#include "sensornet/dds/wire.hpp"
#include "sensornet/dds/writer.hpp"
#include "sensornet/wire/messages.hpp"
#include "sensornet/wire/run_inputs.hpp"
#include "sensornet/wire/run_options.hpp"
#include "sensornet/io/scenario_file.hpp"

namespace sensornet::wire {
namespace {

using namespace sensornet::emulator;  // the core types the samples carry

using namespace std::chrono_literals;

constexpr const char* kScenarioYaml =
    "horizon: 1.0\nintervals: 2\nplant:\n  A: [[0]]\n  Q: [[1]]\n  P0: [[1]]\n"
    "sensors:\n  - H: [[1]]\n    R: [[1]]\nconstraints:\n  C: [[1]]\n  b: [10]\n";
constexpr std::uint64_t kSeed = 3;

class RunInputsStart : public ::testing::Test {
 protected:
  RunInputsStart()
      : run_id_("run-inputs-" + std::to_string(::getpid())),
        domain_(optionsOf(run_id_).domainConfig()),
        participant_(domain_),
        inputs_(participant_),
        scenario_topic_(participant_),
        schedule_topic_(participant_),
        control_topic_(participant_),
        scenario_writer_(participant_, scenario_topic_),
        schedule_writer_(participant_, schedule_topic_),
        control_writer_(participant_, control_topic_) {
    run_.yaml = kScenarioYaml;
    run_.scenario = parseScenarioYaml(run_.yaml, "test");
    run_.digest = digestOf(run_.yaml);
    run_.seed = kSeed;
  }

  static RunOptions optionsOf(const std::string& run_id) {
    RunOptions options;
    options.run_id = run_id;
    return options;
  }

  void publishVersion(std::uint32_t number, std::uint32_t episode) {
    ScheduleVersion v;
    v.version = number;
    v.effective_episode = episode;
    v.schedule = RateSchedule(run_.scenario.horizon_s, Eigen::MatrixXd::Constant(2, 1, static_cast<double>(number)));
    v.surrogate = SurrogateKind::File;
    ASSERT_EQ(publishSchedule(schedule_writer_, run_id_, run_.digest, v),
              dds::WriteResult::Written);
  }

  void announce(std::uint32_t episode, std::uint32_t version) {
    const std::string empty;
    sensornet_EpisodeControl c{};
    c.run_id = dds::borrowString(run_id_);
    c.episode = episode;
    c.command = sensornet_EPISODE_START;
    c.start_wall_time_ns = wallNowNs() + 1'000'000'000;
    c.time_scale = 1.0;
    c.seed = kSeed;
    c.schedule_version = version;
    c.episodes_planned = 5;
    c.detail = dds::borrowString(empty);
    ASSERT_EQ(control_writer_.write(c), dds::WriteResult::Written);
  }

  // The episodes RunInputs hands out as starts within `wait`.
  std::vector<std::uint32_t> startsWithin(std::chrono::milliseconds wait) {
    std::vector<std::uint32_t> starts;
    const auto deadline = std::chrono::steady_clock::now() + wait;
    while (std::chrono::steady_clock::now() < deadline) {
      for (const EpisodeStart& s : inputs_.poll().starts) starts.push_back(s.episode);
      std::this_thread::sleep_for(5ms);
    }
    return starts;
  }

  std::string run_id_;
  dds::Domain domain_;
  dds::Participant participant_;
  RunInputs inputs_;
  dds::Topic<sensornet_Scenario> scenario_topic_;
  dds::Topic<sensornet_Schedule> schedule_topic_;
  dds::Topic<sensornet_EpisodeControl> control_topic_;
  dds::Writer<sensornet_Scenario> scenario_writer_;
  dds::Writer<sensornet_Schedule> schedule_writer_;
  dds::Writer<sensornet_EpisodeControl> control_writer_;
  RunScenario run_;
};

TEST_F(RunInputsStart, WaitsForTheVersionItNamesAndNotLonger) {
  ASSERT_EQ(publishScenario(scenario_writer_, run_id_, run_), dds::WriteResult::Written);
  publishVersion(1, 0);
  announce(0, 1);
  EXPECT_EQ(startsWithin(500ms), std::vector<std::uint32_t>{0});
  ASSERT_EQ(inputs_.book().latest().version, 1u);

  // Episode 1 is announced under version 2, which has not come yet: version 1 would be in
  // force at its start, but the start is held.
  announce(1, 2);
  EXPECT_TRUE(startsWithin(300ms).empty());
  publishVersion(2, 1);
  EXPECT_EQ(startsWithin(500ms), std::vector<std::uint32_t>{1});
  EXPECT_EQ(inputs_.book().inForce(1, 0.0)->version, 2u);
}

}  // namespace
}  // namespace sensornet::wire
