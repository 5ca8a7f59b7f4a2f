// The numeric checks of the command-line plumbing: they accept exactly their range, refuse NaN,
// infinities and overflowing numbers, and print numbers readably (never 300 digits).

#include <gtest/gtest.h>

#include <limits>
#include <string>
#include <vector>

#include "sensornet/io/command_line.hpp"

namespace sensornet {
namespace {

// What the check says of `input` ("" when it accepts it).
std::string verdict(const CLI::Validator& check, std::string input) { return check(input); }

TEST(NumberRange, AcceptsItsBoundsAndWhatLiesBetween) {
  const CLI::Validator check = numberRange(1e-3, 1e4);
  for (const char* ok : {"0.001", "1e-3", "1", "10000", " 2.5 ", "+7"}) {
    EXPECT_EQ(verdict(check, ok), "") << ok;
  }
}

TEST(NumberRange, NamesTheRangeAndTheValueInShortNumbers) {
  const CLI::Validator check = numberRange(1e-3, 1e4);
  EXPECT_EQ(verdict(check, "1e308"), "expected a number from 0.001 to 10000, got 1e+308");
  EXPECT_EQ(verdict(check, "0.0009"), "expected a number from 0.001 to 10000, got 0.0009");
  EXPECT_EQ(verdict(check, "-1"), "expected a number from 0.001 to 10000, got -1");
  EXPECT_EQ(verdict(check, "10000.5"), "expected a number from 0.001 to 10000, got 10000.5");
}

TEST(NumberRange, RefusesNanInfinityOverflowAndText) {
  const CLI::Validator check = numberRange(0, std::numeric_limits<double>::max());
  EXPECT_NE(verdict(check, "nan"), "");
  EXPECT_NE(verdict(check, "inf").find("not a finite number"), std::string::npos);
  EXPECT_NE(verdict(check, "-Infinity").find("not a finite number"), std::string::npos);
  EXPECT_NE(verdict(check, "1e309").find("overflows a double"), std::string::npos);
  EXPECT_EQ(verdict(check, "fast"),
            "expected a number from 0 to 1.7976931348623157e+308, got 'fast'");
  EXPECT_NE(verdict(check, "3x"), "");
  EXPECT_NE(verdict(check, ""), "");
}

TEST(NumberRange, NeverRepeatsAHugeArgument) {
  const std::string digits(400, '9');  // 1e400: overflows
  const std::string message = verdict(numberRange(0, 1), digits);
  EXPECT_LT(message.size(), 160u) << message;
  EXPECT_NE(message.find("400 characters"), std::string::npos) << message;
  const std::string finite = "1" + std::string(300, '0');  // 1e300: finite, out of range
  EXPECT_EQ(verdict(numberRange(0, 1), finite), "expected a number from 0 to 1, got 1e+300");
}

TEST(PositiveNumber, RefusesZeroAndNegativesAndOptionallyBoundsAbove) {
  EXPECT_EQ(verdict(positiveNumber(), "1e-300"), "");
  EXPECT_EQ(verdict(positiveNumber(), "0"), "expected a finite number > 0, got 0");
  EXPECT_EQ(verdict(positiveNumber(), "-0.5"), "expected a finite number > 0, got -0.5");
  EXPECT_EQ(verdict(positiveNumber(1e6), "1e308"),
            "expected a number > 0 and at most 1000000, got 1e+308");
  EXPECT_EQ(verdict(positiveNumber(1e6), "1e6"), "");
}

TEST(NonNegativeNumber, AcceptsZero) {
  EXPECT_EQ(verdict(nonNegativeNumber(), "0"), "");
  EXPECT_EQ(verdict(nonNegativeNumber(), "-1"), "expected a finite number >= 0, got -1");
  EXPECT_EQ(verdict(nonNegativeNumber(5), "6"), "expected a number from 0 to 5, got 6");
}

TEST(IntegerRange, AcceptsIntegersOnly) {
  const CLI::Validator check = integerRange(1, 10'000'000);
  EXPECT_EQ(verdict(check, "1"), "");
  EXPECT_EQ(verdict(check, "10000000"), "");
  EXPECT_EQ(verdict(check, "0"), "expected an integer from 1 to 10000000, got 0");
  EXPECT_EQ(verdict(check, "10000001"), "expected an integer from 1 to 10000000, got 10000001");
  EXPECT_EQ(verdict(check, "2.5"), "expected an integer from 1 to 10000000, got 2.5");
  EXPECT_EQ(verdict(check, "1e308"), "expected an integer from 1 to 10000000, got 1e+308");
  EXPECT_EQ(verdict(check, "99999999999999999999"),
            "expected an integer from 1 to 10000000, got 1e+20");
  EXPECT_EQ(verdict(check, "many"), "expected an integer from 1 to 10000000, got 'many'");
}

TEST(IntegerRange, ItsMessageReachesTheUserWithTheOptionName) {
  CLI::App app{"test"};
  int episodes = 0;
  app.add_option("--episodes", episodes)->check(integerRange(1, 10));
  std::vector<std::string> args = {"11", "--episodes"};  // CLI11 parses a reversed vector
  try {
    app.parse(args);
    FAIL() << "parsed";
  } catch (const CLI::ValidationError& e) {
    EXPECT_EQ(std::string(e.what()), "--episodes: expected an integer from 1 to 10, got 11");
  }
}

TEST(FormatNumber, IsTheShortestTextThatReadsBack) {
  EXPECT_EQ(formatNumber(0.001), "0.001");
  EXPECT_EQ(formatNumber(1e4), "10000");
  EXPECT_EQ(formatNumber(1e308), "1e+308");
  EXPECT_EQ(formatNumber(0.0009), "0.0009");
  EXPECT_EQ(formatNumber(1e7), "10000000");
  EXPECT_EQ(formatNumber(1e12), "1e+12");
  EXPECT_EQ(formatNumber(-2.5e-9), "-2.5e-09");
  EXPECT_EQ(formatNumber(0.1 + 0.2), "0.30000000000000004");
  EXPECT_EQ(std::stod(formatNumber(std::numeric_limits<double>::max())),
            std::numeric_limits<double>::max());
}

}  // namespace
}  // namespace sensornet
