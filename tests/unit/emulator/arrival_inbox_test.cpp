// ArrivalInbox between two real threads: everything pushed comes out once and in order, and the
// consumer, which waits only after mayWait() and is woken only when push() says so, is never
// left asleep while items wait (a lost wake would show as a wait that runs out its timeout).
#include "sensornet/emulator/arrival_inbox.hpp"

#include <gtest/gtest.h>

#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <mutex>
#include <random>
#include <thread>
#include <vector>

namespace sensornet::emulator {
namespace {

using namespace std::chrono_literals;

// A guard condition like DDS's: set by wake(), consumed by the wait it ends.
class Wakeable {
 public:
  void wake() {
    {
      std::lock_guard lock(mutex_);
      set_ = true;
    }
    cv_.notify_one();
  }
  // False if the timeout ran out.
  bool wait(std::chrono::milliseconds timeout) {
    std::unique_lock lock(mutex_);
    const bool woken = cv_.wait_for(lock, timeout, [&] { return set_; });
    set_ = false;
    return woken;
  }

 private:
  std::mutex mutex_;
  std::condition_variable cv_;
  bool set_ = false;
};

TEST(ArrivalInbox, EveryItemArrivesOnceInOrderAndNoWakeIsLost) {
  constexpr std::uint64_t kItems = 200'000;
  ArrivalInbox<std::uint64_t> inbox;
  Wakeable guard;
  std::thread producer([&] {
    std::mt19937 rng(20261205);  // fixed: batch sizes and pauses are the same every run
    std::uniform_int_distribution<int> batch_size(1, 16);
    std::uniform_int_distribution<int> pause(0, 63);
    std::vector<std::uint64_t> batch;
    std::uint64_t next = 0;
    while (next < kItems) {
      for (int k = batch_size(rng); k > 0 && next < kItems; --k) batch.push_back(next++);
      if (inbox.push(batch)) guard.wake();
      EXPECT_TRUE(batch.empty());
      if (pause(rng) == 0) std::this_thread::sleep_for(50us);  // let the consumer fall asleep
    }
  });

  std::vector<std::uint64_t> drained;
  std::uint64_t expected = 0;
  int waits = 0;
  int timed_out = 0;
  const auto deadline = std::chrono::steady_clock::now() + 60s;
  while (expected < kItems && std::chrono::steady_clock::now() < deadline) {
    if (inbox.mayWait()) {
      ++waits;
      // Only the producer can end a wait; 2 s without a wake while items wait is a lost wake.
      if (!guard.wait(2s)) ++timed_out;
    }
    inbox.drainInto(drained);
    for (const std::uint64_t item : drained) {
      ASSERT_EQ(item, expected) << "out of order or twice";
      ++expected;
    }
  }
  producer.join();
  EXPECT_EQ(expected, kItems);
  EXPECT_EQ(timed_out, 0) << "of " << waits << " waits";
  EXPECT_GT(waits, 0) << "the consumer never waited: the test did not exercise the wake";
}

TEST(ArrivalInbox, AConsumerWithItemsWaitingMayNotWaitAndAProducerWakesOnlyAWaiter) {
  ArrivalInbox<int> inbox;
  std::vector<int> batch = {1, 2};
  EXPECT_FALSE(inbox.push(batch)) << "nobody waits yet";
  EXPECT_FALSE(inbox.mayWait()) << "two items wait";
  std::vector<int> drained;
  inbox.drainInto(drained);
  EXPECT_EQ(drained, (std::vector<int>{1, 2}));
  EXPECT_TRUE(inbox.mayWait());
  batch = {3};
  EXPECT_TRUE(inbox.push(batch)) << "the consumer announced its wait";
  batch = {4};
  EXPECT_FALSE(inbox.push(batch)) << "woken once is enough";
  inbox.drainInto(drained);
  EXPECT_EQ(drained, (std::vector<int>{3, 4}));
}

}  // namespace
}  // namespace sensornet::emulator
