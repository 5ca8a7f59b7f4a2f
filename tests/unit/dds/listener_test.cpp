// DataAvailableListener against real Cyclone DDS in one process: the callback runs as samples
// are delivered, a throwing callback is counted and does not stop later
// calls, and destroying the listener waits for a call in progress (so what the callback uses is
// never freed under it).
#include "sensornet/dds/listener.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <mutex>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "dds_test_support.hpp"
#include "sensornet/dds/dds_error.hpp"
#include "sensornet/dds/participant.hpp"
#include "sensornet/dds/reader.hpp"
#include "sensornet/dds/topics.hpp"
#include "sensornet/dds/wire.hpp"
#include "sensornet/dds/writer.hpp"

namespace sensornet::dds {
namespace {

using namespace std::chrono_literals;

const std::string kRun = "run-listener";

sensornet_Measurement measurement(std::uint64_t seq) {
  sensornet_Measurement m{};
  m.sensor_id = 7;
  m.run_id = borrowString(kRun);
  m.seq = seq;
  return m;
}

template <class Predicate>
bool eventually(Predicate done, std::chrono::milliseconds timeout) {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  while (!done()) {
    if (std::chrono::steady_clock::now() > deadline) return false;
    std::this_thread::sleep_for(5ms);
  }
  return true;
}

class Listener : public ::testing::Test {
 protected:
  Domain domain_{testing::isolatedDomain()};
  Participant publisher_side_{domain_};
  Participant subscriber_side_{domain_};
  Topic<sensornet_Measurement> pub_topic_{publisher_side_};
  Topic<sensornet_Measurement> sub_topic_{subscriber_side_};
  Writer<sensornet_Measurement> writer_{publisher_side_, pub_topic_};
  Reader<sensornet_Measurement> reader_{subscriber_side_, sub_topic_};
};

// Within one process Cyclone delivers in the writer's thread; across processes, in its receive
// thread. Either way every sample reaches the callback, in write order.
TEST_F(Listener, TakesEverySampleInWriteOrder) {
  std::mutex mutex;
  std::vector<std::uint64_t> seqs;
  DataAvailableListener listener(reader_, [&] {
    const Batch<sensornet_Measurement> batch = reader_.take();
    std::lock_guard lock(mutex);
    for (const auto& m : batch.samples) seqs.push_back(m.sample->seq);
  });
  ASSERT_TRUE(writer_.waitForReaders(1, 5s));
  for (std::uint64_t i = 0; i < 50; ++i) ASSERT_EQ(writer_.write(measurement(i)), WriteResult::Written);

  ASSERT_TRUE(eventually([&] { std::lock_guard lock(mutex); return seqs.size() >= 50; }, 5000ms));
  std::lock_guard lock(mutex);
  std::vector<std::uint64_t> expected(50);
  for (std::uint64_t i = 0; i < 50; ++i) expected[i] = i;
  EXPECT_EQ(seqs, expected);
  EXPECT_EQ(listener.failedCalls(), 0u);
}

TEST_F(Listener, ThrowingCallbackIsCountedAndLaterCallsStillHappen) {
  std::atomic<int> calls{0};
  std::atomic<int> taken{0};
  DataAvailableListener listener(reader_, [&] {
    taken += static_cast<int>(reader_.take().samples.size());
    if (++calls == 1) throw std::runtime_error("first call fails");
  });
  ASSERT_TRUE(writer_.waitForReaders(1, 5s));
  ASSERT_EQ(writer_.write(measurement(0)), WriteResult::Written);
  ASSERT_TRUE(eventually([&] { return listener.failedCalls() == 1; }, 5000ms));
  ASSERT_EQ(writer_.write(measurement(1)), WriteResult::Written);
  ASSERT_TRUE(eventually([&] { return taken.load() == 2; }, 5000ms));
  EXPECT_EQ(listener.failedCalls(), 1u);
}

TEST_F(Listener, DestructionWaitsForTheCallInProgress) {
  std::atomic<bool> entered{false};
  std::atomic<bool> finished{false};
  auto listener = std::make_unique<DataAvailableListener>(reader_, [&] {
    entered = true;
    std::this_thread::sleep_for(300ms);
    (void)reader_.take();
    finished = true;
  });
  ASSERT_TRUE(writer_.waitForReaders(1, 5s));
  // Delivery within a process runs the callback in the writing thread: write from another one.
  std::thread writing([&] { (void)writer_.write(measurement(0)); });
  ASSERT_TRUE(eventually([&] { return entered.load(); }, 5000ms));
  listener.reset();
  EXPECT_TRUE(finished.load()) << "the listener went away while its callback still ran";
  writing.join();

  // No callback after destruction: a new sample stays in the reader.
  ASSERT_EQ(writer_.write(measurement(1)), WriteResult::Written);
  const auto batch = testing::takeAtLeast(subscriber_side_, reader_, 1, 5s);
  ASSERT_EQ(batch.samples.size(), 1u);
  EXPECT_EQ(batch.samples[0].sample->seq, 1u);
}

TEST(ListenerSeam, RefusedListenerThrowsDdsErrorNamingTheCall) {
  CApi api = realCApi();
  api.set_listener = [](dds_entity_t, const dds_listener_t*) -> dds_return_t {
    return DDS_RETCODE_ERROR;
  };
  Domain domain(testing::isolatedDomain(), api);
  Participant participant(domain);
  Topic<sensornet_Measurement> topic(participant);
  Reader<sensornet_Measurement> reader(participant, topic);
  try {
    DataAvailableListener listener(reader, [] {});
    FAIL() << "no error";
  } catch (const DdsError& e) {
    EXPECT_NE(std::string(e.what()).find("dds_set_listener"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace sensornet::dds
