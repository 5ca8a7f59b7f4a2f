#pragma once
// The schedule versions of a run, as every process keeps them. Version v is in force from its
// effective point (episode, emulated time) until a higher version's effective point; versions
// only increase, so a stale one (not above the highest seen) is refused. A version the book
// already holds with identical content (a restarted coordinator republishes its versions) is a
// duplicate: nothing changes, and it is no error.
//
//   ScheduleBook book;
//   book.add(initial);                                    // version 1 from (0, 0)
//   book.add(replanned);                                  // version 2 from (episode 3, 1.2 s)
//   const ScheduleVersion& v = book.inForce(3, 2.0);     // version 2
//   for (const ScheduleSegment& s : book.segments(3, T)) ... // [0, 1.2) v1, [1.2, T] v2

#include <cstdint>
#include <nlohmann/json_fwd.hpp>
#include <vector>

#include "sensornet/core/rate_schedule.hpp"
#include "sensornet/core/surrogate.hpp"
#include "sensornet/core/surrogate_kind.hpp"

namespace sensornet {

// A version's surrogate in JSON (the report, the coordinator's journal) is its word: "cov".
void to_json(nlohmann::json& j, SurrogateKind kind);

}  // namespace sensornet

namespace sensornet::emulator {

struct ScheduleVersion {
  std::uint32_t version = 0;
  std::uint32_t effective_episode = 0;
  double effective_time_s = 0.0;
  RateSchedule schedule;
  SurrogateKind surrogate = SurrogateKind::File;  // "info", "cov", "uniform", "mc", "file"
  CostBracket bracket;      // of the whole schedule over [0, T] from P0
  std::uint64_t command_id = 0;
};

// Same number, effective point, rates (bit for bit), surrogate, bracket and command id.
[[nodiscard]] bool identical(const ScheduleVersion& a, const ScheduleVersion& b);

// A stretch [from_s, to_s) of one episode under one version.
struct ScheduleSegment {
  double from_s = 0.0;
  double to_s = 0.0;
  const ScheduleVersion* version = nullptr;
};

class ScheduleBook {
 public:
  enum class Outcome { Accepted, Duplicate, Stale };

  // Accepted when v.version is above every version seen; Duplicate when the book holds a
  // version of that number with identical content; Stale otherwise (nothing changes but on
  // Accepted).
  Outcome add(ScheduleVersion v);

  [[nodiscard]] bool empty() const { return versions_.empty(); }
  [[nodiscard]] const ScheduleVersion& latest() const { return versions_.back(); }
  [[nodiscard]] const std::vector<ScheduleVersion>& versions() const { return versions_; }
  // The highest version whose effective point is at or before (episode, t); nullptr if none.
  [[nodiscard]] const ScheduleVersion* inForce(std::uint32_t episode, double t) const;
  // The stretches of `episode` over [0, horizon_s] in time order (empty when no version is in
  // force at time 0 of the episode).
  [[nodiscard]] std::vector<ScheduleSegment> segments(std::uint32_t episode,
                                                      double horizon_s) const;

 private:
  std::vector<ScheduleVersion> versions_;  // increasing version numbers
};

}  // namespace sensornet::emulator
