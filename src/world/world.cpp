// The C API of include/sensornet/world.h over the same code our agents run: EmulatedPlant for
// the truth and the noise, sensorTimeline over a ScheduleBook for the arrivals. Nothing here
// computes a number of its own, so the values are those of our agents bit for bit.

#include "sensornet/world.h"

#include <algorithm>
#include <cstring>
#include <exception>
#include <optional>
#include <string>

#include "sensornet/core/emulated_plant.hpp"
#include "sensornet/core/scenario.hpp"
#include "sensornet/emulator/schedule_book.hpp"
#include "sensornet/emulator/sensor_timeline.hpp"
#include "sensornet/io/scenario_file.hpp"

#define SN_WORLD_EXPORT __attribute__((visibility("default")))

struct sn_world {
  sensornet::Scenario scenario;
  std::uint64_t seed = 0;
  std::optional<sensornet::EmulatedPlant> plant;
  sensornet::EmulatedPlant::Path path;
  sensornet::emulator::ScheduleBook book;
  std::string error;
};

namespace {

using sensornet::Scenario;

void copyMessage(const std::string& message, char* out, std::size_t size) {
  if (out == nullptr || size == 0) return;
  const std::size_t n = std::min(message.size(), size - 1);
  std::memcpy(out, message.data(), n);
  out[n] = '\0';
}

// Runs `body` with the world's error cleared; a failure (a false return or an exception) sets
// it and gives -1.
template <class Body>
int guarded(sn_world* w, Body body) {
  if (w == nullptr) return -1;
  w->error.clear();
  try {
    return body() ? 0 : -1;
  } catch (const std::exception& e) {
    w->error = e.what();
    return -1;
  }
}

bool checkTime(sn_world* w, double t) {
  if (t >= 0.0 && t <= w->scenario.horizon_s) return true;
  w->error = "t = " + std::to_string(t) + " s is outside [0, T = " +
             std::to_string(w->scenario.horizon_s) + " s]";
  return false;
}

bool checkSensor(sn_world* w, std::uint32_t sensor) {
  if (sensor < static_cast<std::uint32_t>(w->scenario.sensorCount())) return true;
  w->error = "sensor " + std::to_string(sensor) + " is not a sensor of the scenario (it has " +
             std::to_string(w->scenario.sensorCount()) + ")";
  return false;
}

bool checkOut(sn_world* w, const void* out, const char* what) {
  if (out != nullptr) return true;
  w->error = std::string(what) + " is NULL";
  return false;
}

Eigen::VectorXd stateOf(sn_world* w, std::uint32_t episode, double t) {
  return w->plant->stateAt(episode, w->plant->tickAt(t), w->path);
}

void copyOut(const Eigen::VectorXd& values, double* out) {
  std::copy(values.data(), values.data() + values.size(), out);
}

}  // namespace

extern "C" {

SN_WORLD_EXPORT int sn_world_abi_version(void) { return SN_WORLD_ABI_VERSION; }

SN_WORLD_EXPORT sn_world* sn_world_open(const char* scenario_yaml, uint64_t seed, char* error,
                                        size_t error_size) {
  copyMessage("", error, error_size);
  if (scenario_yaml == nullptr) {
    copyMessage("sn_world_open: the scenario text is NULL", error, error_size);
    return nullptr;
  }
  try {
    auto* w = new sn_world;
    try {
      w->scenario = sensornet::parseScenarioYaml(scenario_yaml, "sn_world_open scenario");
      w->seed = seed;
      w->plant.emplace(w->scenario, seed);
    } catch (...) {
      delete w;
      throw;
    }
    return w;
  } catch (const std::exception& e) {
    copyMessage(e.what(), error, error_size);
    return nullptr;
  }
}

SN_WORLD_EXPORT void sn_world_close(sn_world* world) { delete world; }

SN_WORLD_EXPORT const char* sn_world_error(const sn_world* world) {
  return world == nullptr ? "no world (NULL)" : world->error.c_str();
}

SN_WORLD_EXPORT uint32_t sn_world_states(const sn_world* world) {
  return world == nullptr ? 0 : static_cast<uint32_t>(world->scenario.stateDim());
}

SN_WORLD_EXPORT uint32_t sn_world_sensors(const sn_world* world) {
  return world == nullptr ? 0 : static_cast<uint32_t>(world->scenario.sensorCount());
}

SN_WORLD_EXPORT double sn_world_horizon(const sn_world* world) {
  return world == nullptr ? 0.0 : world->scenario.horizon_s;
}

SN_WORLD_EXPORT uint32_t sn_world_measurement_dim(const sn_world* world, uint32_t sensor) {
  if (world == nullptr || sensor >= static_cast<uint32_t>(world->scenario.sensorCount())) return 0;
  return static_cast<uint32_t>(world->scenario.sensors[sensor].H.rows());
}

SN_WORLD_EXPORT double sn_world_on_tick(const sn_world* world, double t) {
  if (world == nullptr) return 0.0;
  return world->plant->timeOf(world->plant->tickAt(t));
}

SN_WORLD_EXPORT int sn_world_state(sn_world* world, uint32_t episode, double t, double* x) {
  return guarded(world, [&] {
    if (!checkOut(world, x, "x") || !checkTime(world, t)) return false;
    copyOut(stateOf(world, episode, t), x);
    return true;
  });
}

SN_WORLD_EXPORT int sn_world_noise(sn_world* world, uint32_t episode, uint32_t sensor,
                                   uint64_t seq, double* v) {
  return guarded(world, [&] {
    if (!checkOut(world, v, "v") || !checkSensor(world, sensor)) return false;
    // measure(x = 0) = H 0 + v: the noise alone, from the same stream.
    const Eigen::VectorXd zero = Eigen::VectorXd::Zero(world->scenario.stateDim());
    copyOut(world->plant->measure(zero, static_cast<int>(sensor), episode, seq), v);
    return true;
  });
}

SN_WORLD_EXPORT int sn_world_measure(sn_world* world, uint32_t episode, uint32_t sensor,
                                     uint64_t seq, double t, double* z) {
  return guarded(world, [&] {
    if (!checkOut(world, z, "z") || !checkSensor(world, sensor) || !checkTime(world, t)) {
      return false;
    }
    const Eigen::VectorXd x = stateOf(world, episode, t);
    copyOut(world->plant->measure(x, static_cast<int>(sensor), episode, seq), z);
    return true;
  });
}

SN_WORLD_EXPORT int sn_world_set_arrivals(sn_world* world, const char* mode) {
  return guarded(world, [&] {
    const std::string_view text = mode == nullptr ? "" : mode;
    world->scenario.arrivals =
        text.empty() ? sensornet::ArrivalMode::Poisson
                     : sensornet::parseArrivalMode(text, "sn_world_set_arrivals", "mode");
    return true;
  });
}

SN_WORLD_EXPORT int sn_world_add_schedule(sn_world* world, uint32_t version,
                                          uint32_t effective_episode, double effective_time_s,
                                          const double* rates, uint32_t intervals) {
  return guarded(world, [&] {
    if (!checkOut(world, rates, "rates")) return false;
    const Scenario& s = world->scenario;
    if (intervals != static_cast<uint32_t>(s.intervals)) {
      world->error = "a schedule has the scenario's " + std::to_string(s.intervals) +
                     " intervals (got " + std::to_string(intervals) + ")";
      return false;
    }
    if (!(effective_time_s >= 0.0 && effective_time_s <= s.horizon_s)) {
      world->error = "a schedule's effective time lies in [0, T]";
      return false;
    }
    const auto m = static_cast<Eigen::Index>(s.sensorCount());
    Eigen::MatrixXd table(static_cast<Eigen::Index>(intervals), m);
    for (Eigen::Index k = 0; k < table.rows(); ++k) {
      for (Eigen::Index j = 0; j < m; ++j) {
        const double rate = rates[k * m + j];
        if (!(rate >= 0.0) || !std::isfinite(rate)) {
          world->error = "rates[" + std::to_string(k) + "][" + std::to_string(j) +
                         "] is not a finite rate >= 0";
          return false;
        }
        table(k, j) = rate;
      }
    }
    sensornet::emulator::ScheduleVersion v;
    v.version = version;
    v.effective_episode = effective_episode;
    v.effective_time_s = effective_time_s;
    v.schedule = sensornet::RateSchedule(s.horizon_s, std::move(table));
    using Outcome = sensornet::emulator::ScheduleBook::Outcome;
    if (world->book.add(std::move(v)) == Outcome::Stale) {
      world->error = "schedule version " + std::to_string(version) +
                     " is not above the versions added (they must come in increasing order)";
      return false;
    }
    return true;
  });
}

SN_WORLD_EXPORT long sn_world_arrivals(sn_world* world, uint32_t episode, uint32_t sensor,
                                       double* times, uint32_t* versions, size_t capacity) {
  long count = -1;
  const int status = guarded(world, [&] {
    if ((capacity > 0 && !checkOut(world, times, "times")) || !checkSensor(world, sensor)) {
      return false;
    }
    const std::vector<sensornet::emulator::TimedArrival> timeline = sensornet::emulator::sensorTimeline(
        world->book, *world->plant, world->seed, episode, {static_cast<int>(sensor)},
        world->scenario.horizon_s, world->scenario.arrivals);
    for (std::size_t i = 0; i < timeline.size() && i < capacity; ++i) {
      times[i] = timeline[i].time_s;
      if (versions != nullptr) versions[i] = timeline[i].version;
    }
    count = static_cast<long>(timeline.size());
    return true;
  });
  return status == 0 ? count : -1;
}

}  // extern "C"
