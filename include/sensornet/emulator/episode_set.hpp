#pragma once
// A set of episode numbers kept as disjoint ranges [first, last]: its memory depends on the
// gaps between the numbers, not on how many there are, so a run of 10,000,000 episodes that
// finish (nearly) in order costs a few ranges. The coordinator's reported episodes and the
// launcher's printed ones are such sets.
//
//   EpisodeSet done;
//   if (done.insert(episode)) print(episode);   // false: it was there already
//   done.contains(3); done.size();              // 1
//   for (const auto& [first, last] : done.ranges()) ...

#include <cstddef>
#include <cstdint>
#include <initializer_list>
#include <map>

namespace sensornet::emulator {

class EpisodeSet {
 public:
  EpisodeSet() = default;
  EpisodeSet(std::initializer_list<std::uint32_t> episodes);

  // Adds `episode`; true if it was not there.
  bool insert(std::uint32_t episode);
  // Adds every episode of [first, last] (first <= last).
  void insertRange(std::uint32_t first, std::uint32_t last);
  [[nodiscard]] bool contains(std::uint32_t episode) const;
  [[nodiscard]] std::size_t count(std::uint32_t episode) const { return contains(episode) ? 1 : 0; }
  [[nodiscard]] std::size_t size() const noexcept { return size_; }
  [[nodiscard]] bool empty() const noexcept { return size_ == 0; }
  // first -> last, in order, disjoint and not adjacent.
  [[nodiscard]] const std::map<std::uint32_t, std::uint32_t>& ranges() const noexcept {
    return ranges_;
  }
  bool operator==(const EpisodeSet&) const = default;

 private:
  std::map<std::uint32_t, std::uint32_t> ranges_;
  std::size_t size_ = 0;
};

}  // namespace sensornet::emulator
