// Qos: a value type over dds_qos_t. Equality is Cyclone's own dds_qos_equal, an independent
// judge of which policies a value holds.
#include "sensornet/dds/qos.hpp"

#include <gtest/gtest.h>

#include <chrono>
#include <utility>

#include "sensornet/core/input_error.hpp"

namespace sensornet::dds {
namespace {

using namespace std::chrono_literals;

TEST(Qos, CopyIsEqualAndIndependentOfTheOriginal) {
  Qos original = Qos().reliable(50ms).transientLocal().keepLast(4);
  Qos copy(original);
  EXPECT_TRUE(copy == original);

  copy.keepLast(5);
  EXPECT_FALSE(copy == original);
  EXPECT_TRUE(original == Qos().reliable(50ms).transientLocal().keepLast(4));
}

TEST(Qos, SettingThePolicyAgainReplacesIt) {
  EXPECT_TRUE(Qos().keepLast(3).keepAll() == Qos().keepAll());
  EXPECT_TRUE(Qos().bestEffort().reliable(20ms) == Qos().reliable(20ms));
  EXPECT_FALSE(Qos().reliable(20ms) == Qos().reliable(30ms));
}

TEST(Qos, MovedFromValueIsEmptyAndUsableAgain) {
  Qos source = Qos().keepLast(2);
  Qos target(std::move(source));
  EXPECT_TRUE(target == Qos().keepLast(2));
  EXPECT_EQ(source.get(), nullptr);  // NOLINT(bugprone-use-after-move): the documented state

  source.keepAll();  // setters recreate the object
  EXPECT_TRUE(source == Qos().keepAll());
}

TEST(Qos, KnowsWhetherItNamesAPartition) {
  EXPECT_FALSE(Qos().reliable().hasPartition());
  EXPECT_TRUE(Qos().partition("sensornet/run-1").hasPartition());
}

TEST(Qos, RefusesNonsenseWithAnInputErrorNamingThePolicy) {
  try {
    (void)Qos().keepLast(0);
    FAIL() << "keepLast(0) accepted";
  } catch (const InputError& e) {
    EXPECT_EQ(e.field(), "history.depth");
  }
  EXPECT_THROW((void)Qos().durabilityService(-1), InputError);
  EXPECT_THROW((void)Qos().resourceLimits(0, 1, 1), InputError);
  EXPECT_NO_THROW((void)Qos().resourceLimits(DDS_LENGTH_UNLIMITED, 1, 1));
  EXPECT_THROW((void)Qos().reliable(-1ms), InputError);
  EXPECT_THROW((void)Qos().partition("run*"), InputError);
}

}  // namespace
}  // namespace sensornet::dds
