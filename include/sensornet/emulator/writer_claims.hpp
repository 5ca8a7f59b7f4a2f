#pragma once
// Which DDS writer speaks for each sensor, so that a second writer claiming a sensor that already
// has one is kept out (issue 12, part 3). Without DDS Security anyone on the host can join a
// run's partition and write well-formed samples that claim to be sensor 0; the first live writer
// of a sensor wins, and a sample of another writer is refused while that first one lives.
//
// A claim is given up when the claiming writer is gone (the caller's `live` predicate: no longer
// matched by the reader, i.e. deleted or its participant's lease expired) or when the caller
// releases the sensor (the coordinator announced it failed: its process died, and a process that
// takes its place comes with a new writer). The first sample a writer sends decides nothing by
// itself: the caller claims only for a sample it accepted (well-formed, of this run), so a
// malformed sample cannot take a sensor away from its agent.
//
//   WriterClaims claims;
//   const auto live = [&](WriterId w) { return reader.matchesWriter(w); };
//   if (claims.isForeign(sensor, writer, live)) { count "foreign_writer"; return; }
//   if (fuse(sample) succeeded) claims.claim(sensor, writer);
//   if (claims.firstRefusalOf(writer)) log once;

#include <cstdint>
#include <functional>
#include <map>
#include <set>

#include "sensornet/emulator/vocabulary.hpp"

namespace sensornet::emulator {

using WriterId = std::uint64_t;  // a DDS publication (instance) handle; 0 = unknown

// The report's rejection reason for a sample of a second writer.
inline constexpr const char* kForeignWriter = wordOf(RejectionReason::ForeignWriter).data();

class WriterClaims {
 public:
  using LivePredicate = std::function<bool(WriterId)>;

  // True if `sensor` is claimed by a live writer other than `writer`. A claim whose writer is no
  // longer live is dropped here.
  [[nodiscard]] bool isForeign(int sensor, WriterId writer, const LivePredicate& live);
  // `writer` speaks for `sensor` from now on, unless a live claim exists (then nothing changes).
  void claim(int sensor, WriterId writer);
  // Forgets the claim of `sensor` (its process was declared failed).
  void release(int sensor);
  // True the first time `writer` is refused (to log and report it once per writer).
  [[nodiscard]] bool firstRefusalOf(WriterId writer);
  // The writer that speaks for `sensor`, or 0.
  [[nodiscard]] WriterId ownerOf(int sensor) const;

 private:
  std::map<int, WriterId> owner_;
  std::set<WriterId> refused_;
};

}  // namespace sensornet::emulator
