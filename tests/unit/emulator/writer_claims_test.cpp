// WriterClaims: the first live writer of a sensor speaks for it; a second one is refused while
// the first lives, and may take over once the first is gone or the sensor was released.

#include "sensornet/emulator/writer_claims.hpp"

#include <gtest/gtest.h>

#include <set>

namespace sensornet::emulator {
namespace {

TEST(WriterClaims, ASecondLiveWriterOfAClaimedSensorIsForeign) {
  WriterClaims claims;
  const auto all_live = [](WriterId) { return true; };
  EXPECT_FALSE(claims.isForeign(0, 11, all_live));  // nobody speaks for sensor 0 yet
  claims.claim(0, 11);
  EXPECT_FALSE(claims.isForeign(0, 11, all_live));
  EXPECT_TRUE(claims.isForeign(0, 22, all_live));
  EXPECT_FALSE(claims.isForeign(1, 22, all_live));  // claims are per sensor
  claims.claim(0, 22);                              // a live claim is not overwritten
  EXPECT_EQ(claims.ownerOf(0), 11u);
}

TEST(WriterClaims, ANewWriterTakesOverOnceTheFirstIsGone) {
  WriterClaims claims;
  std::set<WriterId> live = {11, 22};
  const auto is_live = [&](WriterId w) { return live.count(w) > 0; };
  claims.claim(3, 11);
  EXPECT_TRUE(claims.isForeign(3, 22, is_live));
  live.erase(11);  // unmatched: its process ended or its lease expired
  EXPECT_FALSE(claims.isForeign(3, 22, is_live));
  EXPECT_EQ(claims.ownerOf(3), 0u);
  claims.claim(3, 22);
  EXPECT_TRUE(claims.isForeign(3, 33, [](WriterId) { return true; }));
}

TEST(WriterClaims, AReleasedSensorIsClaimedByTheNextWriter) {
  WriterClaims claims;
  const auto all_live = [](WriterId) { return true; };
  claims.claim(2, 11);
  claims.release(2);  // declared failed by the coordinator
  EXPECT_FALSE(claims.isForeign(2, 22, all_live));
  claims.claim(2, 22);
  EXPECT_EQ(claims.ownerOf(2), 22u);
}

TEST(WriterClaims, EachRefusedWriterIsReportedOnce) {
  WriterClaims claims;
  EXPECT_TRUE(claims.firstRefusalOf(22));
  EXPECT_FALSE(claims.firstRefusalOf(22));
  EXPECT_TRUE(claims.firstRefusalOf(33));
}

}  // namespace
}  // namespace sensornet::emulator
