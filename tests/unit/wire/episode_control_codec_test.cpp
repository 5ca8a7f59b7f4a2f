// An episode control through the wire and back (wire/messages.hpp: wireControl, controlOf): every
// kind keeps its kind and every field its value, and a command the IDL does not define is
// refused, counted as a malformed episode control, while the run's inputs go on.
#include <gtest/gtest.h>

#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

#include "sensornet/core/input_error.hpp"
#include "sensornet/wire/messages.hpp"
#include "sensornet/wire/run_inputs.hpp"

namespace sensornet::wire {
namespace {

using emulator::ControlKind;

EpisodeControl distinctFields(ControlKind kind) {
  EpisodeControl control;
  control.kind = kind;
  control.episode = 5;
  control.start_wall_ns = 1'234'567'890'123;
  control.time_scale = 2.5;
  control.seed = 0xfedcba9876543210ULL;
  control.schedule_version = 3;
  control.episodes_planned = 11;
  control.failed_sensors = {4, 1, 7};  // not sorted: the order must survive
  control.failed_at_s = 0.75;
  control.aborted = true;
  control.detail = "sensors 1, 4 and 7 died";
  return control;
}

TEST(EpisodeControlCodec, EveryKindComesBackAsSent) {
  for (const ControlKind kind : {ControlKind::EpisodeStart, ControlKind::EpisodeStop,
                                 ControlKind::SensorsFailed, ControlKind::RunShutdown}) {
    const EpisodeControl sent = distinctFields(kind);
    const EpisodeControl back = controlOf(wireControl(sent, "run-7"));
    EXPECT_EQ(back.kind, sent.kind);
    EXPECT_EQ(back.episode, sent.episode);
    EXPECT_EQ(back.start_wall_ns, sent.start_wall_ns);
    EXPECT_EQ(back.time_scale, sent.time_scale);
    EXPECT_EQ(back.seed, sent.seed);
    EXPECT_EQ(back.schedule_version, sent.schedule_version);
    EXPECT_EQ(back.episodes_planned, sent.episodes_planned);
    EXPECT_EQ(back.failed_sensors, sent.failed_sensors);
    EXPECT_EQ(back.failed_at_s, sent.failed_at_s);
    EXPECT_EQ(back.aborted, sent.aborted);
    EXPECT_EQ(back.detail, sent.detail);
  }
}

TEST(EpisodeControlCodec, EachKindHasItsOwnCommand) {
  EXPECT_EQ(episodeCommandOf(ControlKind::EpisodeStart), sensornet_EPISODE_START);
  EXPECT_EQ(episodeCommandOf(ControlKind::EpisodeStop), sensornet_EPISODE_STOP);
  EXPECT_EQ(episodeCommandOf(ControlKind::SensorsFailed), sensornet_EPISODE_SENSORS_FAILED);
  EXPECT_EQ(episodeCommandOf(ControlKind::RunShutdown), sensornet_RUN_SHUTDOWN);
}

TEST(EpisodeControlCodec, AnUndefinedCommandIsRefusedAndCounted) {
  const EpisodeControl stop = distinctFields(ControlKind::EpisodeStop);
  sensornet_EpisodeControl sample = wireControl(stop, "run-7");
  // A value the IDL does not define, as a newer or broken writer's CDR may carry (the C enum's
  // own range holds only the defined ones, so it goes in as the 32-bit integer on the wire).
  const std::int32_t undefined = 99;
  static_assert(sizeof sample.command == sizeof undefined);
  std::memcpy(&sample.command, &undefined, sizeof undefined);
  EXPECT_THROW((void)controlOf(sample), InputError);

  RunInputState state;
  RunInputState::Update update;
  feedSample(state, sample, update);
  EXPECT_TRUE(update.stops.empty());
  EXPECT_FALSE(update.shutdown);
  ASSERT_EQ(state.rejected().count("malformed_episode_control"), 1u);
  EXPECT_EQ(state.rejected().at("malformed_episode_control"), 1u);

  // The next good control is taken as usual.
  feedSample(state, wireControl(stop, "run-7"), update);
  ASSERT_EQ(update.stops.size(), 1u);
  EXPECT_EQ(update.stops.front(), stop.episode);
}

}  // namespace
}  // namespace sensornet::wire
