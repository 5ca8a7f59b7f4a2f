#pragma once
// What an endpoint knows of the endpoints it matched, from their discovery data.
//
// - The partitions a matched writer writes in (who wrote a sample, emulator/run_partitions.hpp).
//   Known while the writer is matched: look it up when its first sample is taken and keep it.
// - The participants whose readers a writer matched, or whose writers a reader matched: a role
//   counts as present for a topic once *its* endpoint matched, not merely some endpoint of
//   another topic in the same process (discovery announces endpoints one by one, and on a lossy
//   link seconds apart).
//
// Not from a listener: dds_get_matched_publication_data and its kin take the entity's locks,
// which Cyclone's delivery path may hold while it calls the listener.
//
//   const auto names = partitionsOfMatchedWriter(reader, info.publication);
//   const bool both = sharesParticipant(participantsOfMatchedReaders(control_writer),
//                                       participantsOfMatchedWriters(report_reader));

#include <dds/dds.h>

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "sensornet/dds/reader.hpp"
#include "sensornet/dds/writer.hpp"

namespace sensornet::dds {

// The partitions of the writer `publication` that `reader` matched ("" for the default
// partition); nullopt when it is not (or no longer) matched.
[[nodiscard]] std::optional<std::vector<std::string>> partitionsOfMatchedWriter(
    const detail::ReaderCore& reader, dds_instance_handle_t publication);

// A participant's GUID (its discovery key), comparable.
using ParticipantKey = std::array<std::uint8_t, 16>;

// The participants of the readers `writer` matches now, sorted, without repeats.
[[nodiscard]] std::vector<ParticipantKey> participantsOfMatchedReaders(
    const detail::WriterCore& writer);
// The participants of the writers `reader` matches now, sorted, without repeats.
[[nodiscard]] std::vector<ParticipantKey> participantsOfMatchedWriters(
    const detail::ReaderCore& reader);
// The participant of the writer `publication` that `reader` matches; nullopt when it does not
// (or no longer).
[[nodiscard]] std::optional<ParticipantKey> participantOfMatchedWriter(
    const detail::ReaderCore& reader, dds_instance_handle_t publication);

// The participants of the writers a reader matches, looked up again only when its match
// changed (the total or the current count of its matched status): cheap to ask every turn.
class MatchedWriterParticipants {
 public:
  // Sorted, without repeats; `changed`, if given, says whether they were looked up anew.
  const std::vector<ParticipantKey>& of(const detail::ReaderCore& reader, bool* changed = nullptr);

 private:
  std::uint32_t total_ = 0;
  std::uint32_t current_ = 0;
  std::vector<ParticipantKey> participants_;
};

// True when a participant is in every one of `sets` (each sorted, as the two above return).
[[nodiscard]] bool sharesParticipant(const std::vector<std::vector<ParticipantKey>>& sets);

}  // namespace sensornet::dds
