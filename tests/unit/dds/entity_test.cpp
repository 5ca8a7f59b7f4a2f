// RAII owners: every Cyclone entity is deleted exactly once, whatever moves and closes happen.
// The C API seam records each dds_delete (and forwards it to Cyclone), so the count of deletes
// per handle is observed, not inferred.
#include "sensornet/dds/entity.hpp"

#include <gtest/gtest.h>

#include <map>
#include <utility>
#include <vector>

#include "dds_test_support.hpp"
#include "sensornet/dds/dds_error.hpp"
#include "sensornet/dds/participant.hpp"
#include "sensornet/dds/reader.hpp"
#include "sensornet/dds/topics.hpp"
#include "sensornet/dds/waitset.hpp"
#include "sensornet/dds/writer.hpp"

namespace sensornet::dds {
namespace {

// Test-only recorder behind a captureless function pointer.
std::vector<dds_entity_t>& deletedHandles() {
  static std::vector<dds_entity_t> handles;
  return handles;
}

CApi countingApi() {
  CApi api = realCApi();
  api.delete_entity = [](dds_entity_t handle) -> dds_return_t {
    deletedHandles().push_back(handle);
    return dds_delete(handle);
  };
  return api;
}

std::map<dds_entity_t, int> deleteCounts() {
  std::map<dds_entity_t, int> counts;
  for (dds_entity_t h : deletedHandles()) ++counts[h];
  return counts;
}

class EntityOwnership : public ::testing::Test {
 protected:
  void SetUp() override { deletedHandles().clear(); }
  const CApi api_ = countingApi();
};

TEST_F(EntityOwnership, MovedFromOwnersDoNotDeleteAgain) {
  std::vector<dds_entity_t> created;
  {
    Domain domain(testing::isolatedDomain(), api_);
    Participant participant(domain);
    Topic<sensornet_Measurement> topic(participant);
    Writer<sensornet_Measurement> first(participant, topic);
    Writer<sensornet_Measurement> second(participant, topic);
    created = {domain.handle(), participant.handle(), topic.handle(), first.handle(),
               second.handle()};

    Writer<sensornet_Measurement> moved(std::move(first));  // construct from
    EXPECT_FALSE(first.isOpen());                           // NOLINT(bugprone-use-after-move)
    second = std::move(moved);     // assign over: the old `second` is deleted now, once
    EXPECT_FALSE(moved.isOpen());  // NOLINT(bugprone-use-after-move)
    EXPECT_EQ(deleteCounts()[created[4]], 1);
    Writer<sensornet_Measurement> self_moved(participant, topic);
    created.push_back(self_moved.handle());
    auto& alias = self_moved;
    self_moved = std::move(alias);  // self-move keeps the entity
    EXPECT_TRUE(self_moved.isOpen());
  }
  const auto counts = deleteCounts();
  for (dds_entity_t h : created) EXPECT_EQ(counts.at(h), 1) << "handle " << h;
  EXPECT_EQ(counts.count(0), 0u) << "an empty owner called dds_delete";
}

TEST_F(EntityOwnership, UsingAMovedFromOwnerIsADdsErrorNotACrash) {
  Domain domain(testing::isolatedDomain(), api_);
  Participant participant(domain);
  Topic<sensornet_Measurement> topic(participant);
  Writer<sensornet_Measurement> writer(participant, topic);
  Writer<sensornet_Measurement> taken(std::move(writer));
  sensornet_Measurement sample{};
  EXPECT_THROW((void)writer.write(sample), DdsError);  // NOLINT(bugprone-use-after-move)
  EXPECT_EQ(taken.write(sample), WriteResult::Written);
}

TEST_F(EntityOwnership, CloseTwiceDeletesOnce) {
  Domain domain(testing::isolatedDomain(), api_);
  Participant participant(domain);
  const dds_entity_t handle = participant.handle();
  participant.close();
  participant.close();
  EXPECT_FALSE(participant.isOpen());
  EXPECT_EQ(deleteCounts()[handle], 1);
}

TEST_F(EntityOwnership, ChildOutlivingItsParentClosesQuietly) {
  Domain domain(testing::isolatedDomain(), api_);
  auto participant = std::make_unique<Participant>(domain);
  Topic<sensornet_Measurement> topic(*participant);
  Reader<sensornet_Measurement> reader(*participant, topic);
  ReadCondition condition(reader);
  participant->close();  // Cyclone deletes topic, reader and condition with it
  EXPECT_NO_THROW(condition.close());
  EXPECT_NO_THROW(reader.close());
  EXPECT_NO_THROW(topic.close());
}

TEST_F(EntityOwnership, EveryOwnerKindIsDeletedOnceAtScopeEnd) {
  std::vector<dds_entity_t> created;
  {
    Domain domain(testing::isolatedDomain(), api_);
    Participant participant(domain);
    Topic<sensornet_Schedule> topic(participant);
    Reader<sensornet_Schedule> reader(participant, topic);
    ReadCondition condition(reader);
    WaitSet waitset(participant);
    waitset.attach(condition, 7);
    created = {domain.handle(), participant.handle(), topic.handle(), reader.handle(),
               condition.handle()};
  }
  const auto counts = deleteCounts();
  for (dds_entity_t h : created) EXPECT_EQ(counts.at(h), 1) << "handle " << h;
  // The waitset owns a waitset and a guard condition: two more deletes, each of its own handle.
  EXPECT_EQ(counts.size(), created.size() + 2);
}

}  // namespace
}  // namespace sensornet::dds
