#include "sensornet/dds/matched_endpoints.hpp"

#include <algorithm>
#include <cstring>
#include <iterator>

namespace sensornet::dds {

std::optional<std::vector<std::string>> partitionsOfMatchedWriter(
    const detail::ReaderCore& reader, dds_instance_handle_t publication) {
  dds_builtintopic_endpoint_t* endpoint =
      dds_get_matched_publication_data(reader.handle(), publication);
  if (endpoint == nullptr) return std::nullopt;
  std::vector<std::string> names;
  std::uint32_t count = 0;
  char** partitions = nullptr;
  if (endpoint->qos != nullptr && dds_qget_partition(endpoint->qos, &count, &partitions)) {
    for (std::uint32_t i = 0; i < count; ++i) {
      names.emplace_back(partitions[i]);
      dds_free(partitions[i]);
    }
    dds_free(partitions);
  }
  dds_builtintopic_free_endpoint(endpoint);
  if (names.empty()) names.emplace_back();  // no partition QoS: the default partition ""
  return names;
}

namespace {

// The handles of the matched endpoints `list(entity, handles, capacity)` reports, grown until
// they fit (an endpoint may match between two calls).
template <typename List>
std::vector<dds_instance_handle_t> matchedHandles(dds_entity_t entity, List list) {
  std::vector<dds_instance_handle_t> handles(16);
  for (;;) {
    const dds_return_t n = list(entity, handles.data(), handles.size());
    if (n < 0) return {};
    if (static_cast<std::size_t>(n) <= handles.size()) {
      handles.resize(static_cast<std::size_t>(n));
      return handles;
    }
    handles.resize(static_cast<std::size_t>(n) + 8);
  }
}

template <typename Data>
std::vector<ParticipantKey> participantsOf(dds_entity_t entity,
                                           const std::vector<dds_instance_handle_t>& handles,
                                           Data data) {
  std::vector<ParticipantKey> keys;
  keys.reserve(handles.size());
  for (const dds_instance_handle_t handle : handles) {
    dds_builtintopic_endpoint_t* endpoint = data(entity, handle);
    if (endpoint == nullptr) continue;  // unmatched since the list was taken
    ParticipantKey key{};
    static_assert(sizeof(key) == sizeof(endpoint->participant_key.v));
    std::memcpy(key.data(), endpoint->participant_key.v, key.size());
    keys.push_back(key);
    dds_builtintopic_free_endpoint(endpoint);
  }
  std::sort(keys.begin(), keys.end());
  keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
  return keys;
}

}  // namespace

std::vector<ParticipantKey> participantsOfMatchedReaders(const detail::WriterCore& writer) {
  return participantsOf(writer.handle(),
                        matchedHandles(writer.handle(), dds_get_matched_subscriptions),
                        dds_get_matched_subscription_data);
}

std::vector<ParticipantKey> participantsOfMatchedWriters(const detail::ReaderCore& reader) {
  return participantsOf(reader.handle(),
                        matchedHandles(reader.handle(), dds_get_matched_publications),
                        dds_get_matched_publication_data);
}

const std::vector<ParticipantKey>& MatchedWriterParticipants::of(const detail::ReaderCore& reader,
                                                                 bool* changed) {
  if (changed != nullptr) *changed = false;
  dds_subscription_matched_status_t status{};
  if (dds_get_subscription_matched_status(reader.handle(), &status) < 0) {
    participants_.clear();
    return participants_;
  }
  // A match or an unmatch since the last look changes one of the two counts.
  if (status.total_count != total_ || status.current_count != current_) {
    total_ = status.total_count;
    current_ = status.current_count;
    participants_ = participantsOfMatchedWriters(reader);
    if (changed != nullptr) *changed = true;
  }
  return participants_;
}

std::optional<ParticipantKey> participantOfMatchedWriter(const detail::ReaderCore& reader,
                                                         dds_instance_handle_t publication) {
  const std::vector<ParticipantKey> keys =
      participantsOf(reader.handle(), {publication}, dds_get_matched_publication_data);
  if (keys.empty()) return std::nullopt;
  return keys.front();
}

bool sharesParticipant(const std::vector<std::vector<ParticipantKey>>& sets) {
  if (sets.empty()) return false;
  std::vector<ParticipantKey> common = sets.front();
  for (std::size_t i = 1; i < sets.size() && !common.empty(); ++i) {
    std::vector<ParticipantKey> both;
    std::set_intersection(common.begin(), common.end(), sets[i].begin(), sets[i].end(),
                          std::back_inserter(both));
    common = std::move(both);
  }
  return !common.empty();
}

}  // namespace sensornet::dds
