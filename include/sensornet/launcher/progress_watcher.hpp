#pragma once
// The launcher's view of a run: the run's follower (run_follower.hpp) feeds a RunView
// (sensornet/launcher/run_view.hpp), and this prints, on standard error, one line per episode
// reported and, until the first episode starts, the sensors that are ready (their status names a
// schedule version, as the coordinator counts them), at most once a second when the count
// changed: "ready 143/200 sensors (4.2 s)". Before the launcher starts anything it tells whether
// a run with this id is already live (its coordinator or fusion center answers).
//
//   ProgressWatcher progress(run.domainConfig(), 20, scenario.horizon_s, scenario.sensorCount());
//   if (progress.seesLiveRun(500ms)) refuse();       // before starting any process
//   progress.poll(std::chrono::milliseconds(50));   // prints the episodes reported meanwhile
//   // [3/20] episode 2: realized 12.3, mean 11.8 over 3 complete (95%: ...), bracket [...]
//   RunPosition at = progress.positionAt(wallNowNs());   // episode 3, emulated time 1.25 s

#include <chrono>
#include <cstdint>
#include <functional>
#include <string>
#include <utility>

#include "sensornet/launcher/run_follower.hpp"
#include <algorithm>
#include <cstdint>

#include "sensornet/dds/domain.hpp"
#include "sensornet/launcher/fault.hpp"  // RunPosition
#include "sensornet/launcher/run_view.hpp"

namespace sensornet::launcher {

class ProgressWatcher {
 public:
  ProgressWatcher(const dds::DomainConfig& config, int episodes_planned, double horizon_s,
                  int sensor_count);

  // True if, within `wait`, a writer of the run's Scenario or (with `fusion_centers`) Report
  // topic matches: a coordinator or fusion center of this run id is alive in this domain and
  // partition. Returns as soon as one matches. Call it before starting the run's own processes.
  [[nodiscard]] bool seesLiveRun(std::chrono::milliseconds wait, bool fusion_centers = true) const {
    return follower_.seesLiveRun(wait, fusion_centers);
  }

  // Waits up to `wait` for the run's topics; prints a line for each episode reported meanwhile.
  void poll(std::chrono::milliseconds wait);
  // Once `delay` after this watcher was made, if no episode has started yet, prints what
  // `advice` returns (nothing when it returns ""): what an outside role still silent needs.
  void adviseAfter(std::chrono::seconds delay, std::function<std::string()> advice) {
    advice_delay_ = delay;
    advice_ = std::move(advice);
  }
  [[nodiscard]] std::size_t episodesSeen() const noexcept { return view_.episodesReported(); }
  [[nodiscard]] bool heardFrom(int sensor) const {
    return view_.heardFrom(static_cast<std::uint32_t>(sensor));
  }
  [[nodiscard]] bool gone(int sensor) const { return view_.gone(static_cast<std::uint32_t>(sensor)); }
  [[nodiscard]] RunPosition positionAt(std::int64_t wall_ns) const {
    return view_.positionAt(wall_ns);
  }
  // The wall time of the latest SensorStatus the process `pid` wrote (0: none came): it was alive
  // then.
  [[nodiscard]] std::int64_t lastStatusWallNs(std::int32_t pid) const {
    std::int64_t latest = 0;
    for (const auto& [sensor, view] : view_.sensors()) {
      if (view.process_id == pid) latest = std::max(latest, view.status_wall_ns);
    }
    return latest;
  }
  // The external fusion center's Reports into the episode log (RunFollower::recordReportsTo).
  void recordReportsTo(const std::filesystem::path& path, int sensor_count) {
    follower_.recordReportsTo(path, sensor_count);
  }
  [[nodiscard]] std::uint64_t reportsRefused() const noexcept { return follower_.reportsRefused(); }
  [[nodiscard]] bool reportWriterSeen() const noexcept { return follower_.reportWriterSeen(); }
  // Its participant in the run's domain and partition, for other launcher entities of the run.
  [[nodiscard]] const dds::Participant& participant() const noexcept {
    return follower_.participant();
  }

 private:
  void sayReady(std::size_t count);

  RunFollower follower_;
  RunView view_;
  int sensor_count_;
  bool started_ = false;        // the first episode was announced
  std::size_t ready_said_ = 0;  // the count last printed
  std::chrono::steady_clock::time_point created_ = std::chrono::steady_clock::now();
  std::chrono::steady_clock::time_point ready_said_at_{};
  std::chrono::seconds advice_delay_{0};
  std::function<std::string()> advice_;  // called once, then dropped
};

}  // namespace sensornet::launcher
