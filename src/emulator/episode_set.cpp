#include "sensornet/emulator/episode_set.hpp"

#include <algorithm>
#include <iterator>

namespace sensornet::emulator {

EpisodeSet::EpisodeSet(std::initializer_list<std::uint32_t> episodes) {
  for (const std::uint32_t e : episodes) insert(e);
}

bool EpisodeSet::contains(std::uint32_t episode) const {
  auto after = ranges_.upper_bound(episode);  // the first range starting after it
  if (after == ranges_.begin()) return false;
  return std::prev(after)->second >= episode;
}

bool EpisodeSet::insert(std::uint32_t episode) {
  if (contains(episode)) return false;
  insertRange(episode, episode);
  return true;
}

void EpisodeSet::insertRange(std::uint32_t first, std::uint32_t last) {
  // Merge with every range that overlaps or touches [first, last].
  auto it = ranges_.upper_bound(first);
  if (it != ranges_.begin()) {
    auto before = std::prev(it);
    if (static_cast<std::uint64_t>(before->second) + 1 >= first) it = before;
  }
  std::uint32_t low = first;
  std::uint32_t high = last;
  while (it != ranges_.end() && static_cast<std::uint64_t>(high) + 1 >= it->first) {
    low = std::min(low, it->first);
    high = std::max(high, it->second);
    size_ -= static_cast<std::size_t>(it->second - it->first) + 1;
    it = ranges_.erase(it);
  }
  ranges_.emplace(low, high);
  size_ += static_cast<std::size_t>(high - low) + 1;
}

}  // namespace sensornet::emulator
