#pragma once
// Items handed from one producer thread (Cyclone's receive thread, in a listener) to a consumer
// loop that sleeps in a wait it can be woken from (a DDS WaitSet). Buffers are swapped, not
// allocated: after the first few calls neither side allocates for the hand-off.
//
// The consumer is woken only when it is waiting or about to wait. Waking costs the producer a
// few system calls (DDS's guard condition: its lock and the wait set's, both contended, and a
// condition-variable broadcast), and under load the consumer is mostly busy fusing what it
// drained last, so a wake per hand-off was most of the receive thread's futex calls
// (bench/README.md, "Issue 28, fourth step").
//
//   consumer:                                     producer:
//     if (inbox.mayWait()) waitset.wait(10ms);      if (inbox.push(batch)) waitset.wake();
//     inbox.drainInto(items);
//
// No wake is lost: mayWait() announces the wait before it looks at the inbox, and push() looks
// for the announcement after it has added its items, both under sequentially consistent
// ordering; so either the consumer sees the items and does not wait, or the producer sees the
// announcement and wakes it. drainInto() withdraws the announcement.

#include <atomic>
#include <iterator>
#include <mutex>
#include <utility>
#include <vector>

namespace sensornet::emulator {

template <class Item>
class ArrivalInbox {
 public:
  // Producer. Moves `items` in and leaves it empty, its capacity kept for the next call. Returns
  // true if the consumer waits (or is about to) and must be woken.
  [[nodiscard]] bool push(std::vector<Item>& items) {
    {
      std::lock_guard lock(mutex_);
      if (items_.empty()) {
        std::swap(items_, items);
      } else {
        std::move(items.begin(), items.end(), std::back_inserter(items_));
      }
    }
    items.clear();
    return waiting_.exchange(false);
  }

  // Consumer, before it waits: false if something is already here (then it must not wait).
  [[nodiscard]] bool mayWait() {
    waiting_.store(true);
    std::lock_guard lock(mutex_);
    if (items_.empty()) return true;
    waiting_.store(false);
    return false;
  }

  // Consumer. Everything pushed so far, swapped into `into` (whose old contents are dropped).
  void drainInto(std::vector<Item>& into) {
    waiting_.store(false);
    into.clear();
    std::lock_guard lock(mutex_);
    std::swap(items_, into);
  }

 private:
  std::mutex mutex_;
  std::vector<Item> items_;
  std::atomic<bool> waiting_{false};
};

}  // namespace sensornet::emulator
