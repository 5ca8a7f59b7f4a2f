// The words of a run: every value has exactly one spelling and reads back as itself; an unknown
// word is refused with the choices listed.
#include <gtest/gtest.h>

#include <set>
#include <string>

#include "sensornet/core/arrival_mode.hpp"
#include "sensornet/planning/planner.hpp"
#include "sensornet/emulator/vocabulary.hpp"

namespace sensornet::emulator {
namespace {

template <class E>
void expectOneSpellingEach() {
  std::set<std::string> texts;
  for (const WordOf<E>& w : Words<E>::kTable) {
    EXPECT_TRUE(texts.insert(std::string(w.text)).second) << "spelled twice: " << w.text;
    EXPECT_FALSE(w.text.empty());
    EXPECT_EQ(w.text.find_first_of(" ,A-Z"), std::string_view::npos) << w.text;
    const auto back = lookUpWord<E>(w.text);
    ASSERT_TRUE(back.has_value()) << w.text;
    EXPECT_EQ(*back, w.value) << w.text;
    EXPECT_EQ(wordOf(w.value), w.text);
  }
  std::set<E> values;
  for (const WordOf<E>& w : Words<E>::kTable) {
    EXPECT_TRUE(values.insert(w.value).second) << "a value listed twice: " << w.text;
  }
}

TEST(Vocabulary, EveryWordHasOneSpellingThatReadsBack) {
  expectOneSpellingEach<RunStatus>();
  expectOneSpellingEach<FaultKind>();
  expectOneSpellingEach<RejectionReason>();
  expectOneSpellingEach<PlanSurrogate>();
  expectOneSpellingEach<ArrivalMode>();
}

TEST(Vocabulary, TheLastEnumeratorOfEachVocabularyIsInItsTable) {
  // A value added to an enum but not to its table would print as "unknown".
  EXPECT_NE(wordOf(FaultKind::SensorDied), "unknown");
  EXPECT_NE(wordOf(RejectionReason::WrongIdentity), "unknown");
  EXPECT_NE(wordOf(FaultKind::CommandRefused), "unknown");
  EXPECT_NE(wordOf(RunStatus::Interrupted), "unknown");
  EXPECT_NE(wordOf(PlanSurrogate::MonteCarlo), "unknown");
}

TEST(Vocabulary, AnUnknownWordIsRefusedWithTheChoices) {
  EXPECT_FALSE(lookUpWord<RunStatus>("complete").has_value());
  try {
    (void)parseWord<PlanSurrogate>("unifrom", "--surrogate", "surrogate");
    FAIL() << "accepted a misspelt surrogate";
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()),
              "--surrogate: surrogate: expected info, cov, uniform or mc, got 'unifrom'");
  }
  EXPECT_EQ(wordChoices<ArrivalMode>(), "poisson or timetable");
}

}  // namespace
}  // namespace sensornet::emulator
