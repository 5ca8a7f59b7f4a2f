// The coordinator's journal (--state, --resume) and what a resume relies on in the schedule
// book: the journal comes back field for field and bit for bit, bad journals are refused with
// the field named, a book rebuilt from it equals the original, and republishing a version a
// reader holds is a harmless duplicate while a different version under a used number is not.

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "sensornet/core/input_error.hpp"
#include "sensornet/core/surrogate.hpp"
#include "sensornet/emulator/coordinator_journal.hpp"
#include "sensornet/emulator/schedule_book.hpp"

#include "emulator_test_support.hpp"
#include "../../support/scratch_dir.hpp"

namespace sensornet::emulator {
namespace {

using test::smallScenario;

// Rates with digits that only survive a round trip if every bit does.
RateSchedule awkwardSchedule(const Scenario& s, double scale) {
  Eigen::MatrixXd rates(s.intervals, s.sensorCount());
  for (int k = 0; k < s.intervals; ++k) {
    for (int j = 0; j < s.sensorCount(); ++j) rates(k, j) = scale * (1.0 / 3.0 + 0.1 * k + j / 7.0);
  }
  rates(2, 1) = 0.0;
  return RateSchedule(s.horizon_s, rates);
}

ScheduleVersion versionOf(const Scenario& s, std::uint32_t number, std::uint32_t episode, double at,
                          double scale) {
  ScheduleVersion v;
  v.version = number;
  v.effective_episode = episode;
  v.effective_time_s = at;
  v.schedule = awkwardSchedule(s, scale);
  v.surrogate = number == 1 ? SurrogateKind::Information : SurrogateKind::Covariance;
  v.bracket = computeBracket(s, v.schedule);
  v.command_id = number == 1 ? 0 : 1764512345678901234ULL + number;
  return v;
}

CoordinatorJournal sampleJournal(const Scenario& s) {
  CoordinatorJournal j;
  j.run_id = "journal-test";
  j.scenario_digest = "0123456789abcdef";
  j.seed = 18446744073709551615ULL;  // 2^64 - 1
  j.episodes_planned = 20;
  j.time_scale = 2.5;
  j.settings = initialSettings(s, PlanSurrogate::Covariance);
  j.settings.budget(0) = 6.1 / 3.0;
  j.settings.excluded = {3};
  j.settings.failed = {0, 2};
  j.versions = {versionOf(s, 1, 0, 0.0, 1.0), versionOf(s, 2, 3, 1.2499990463256836, 0.9),
                versionOf(s, 3, 4, 0.0, 0.8)};
  j.episodes_reported = {0, 1, 2, 3, 5, 6};
  j.announced = AnnouncedEpisode{7, 1764512345123456789LL};
  j.answered[1764512345678901236ULL] = {true, 2, "version 2 from 1.25 s of episode 3; ..."};
  j.answered[17] = {false, 0, "command 17: surrogate: expected info, cov or uniform, got 'x'"};
  j.shutdown_requested = true;
  j.abort_detail = "sensor(s) 0, 2 failed; --on-sensor-failure stop";
  return j;
}

void expectSameJournal(const CoordinatorJournal& a, const CoordinatorJournal& b) {
  EXPECT_EQ(a.run_id, b.run_id);
  EXPECT_EQ(a.scenario_digest, b.scenario_digest);
  EXPECT_EQ(a.seed, b.seed);
  EXPECT_EQ(a.episodes_planned, b.episodes_planned);
  EXPECT_EQ(a.time_scale, b.time_scale);
  EXPECT_EQ(a.settings, b.settings);
  ASSERT_EQ(a.versions.size(), b.versions.size());
  for (std::size_t i = 0; i < a.versions.size(); ++i) {
    EXPECT_TRUE(identical(a.versions[i], b.versions[i])) << "version " << a.versions[i].version;
  }
  EXPECT_EQ(a.episodes_reported, b.episodes_reported);
  EXPECT_EQ(a.announced, b.announced);
  EXPECT_EQ(a.answered, b.answered);
  EXPECT_EQ(a.shutdown_requested, b.shutdown_requested);
  EXPECT_EQ(a.abort_detail, b.abort_detail);
}

class JournalFile : public ::testing::Test {
 protected:
  std::string path(const char* name) const { return scratch_.file(name); }

  sensornet::testing::ScratchDir scratch_;
  const std::filesystem::path dir_ = scratch_.path();
  Scenario scenario_ = smallScenario();
};

TEST_F(JournalFile, RoundTripsEveryFieldBitForBit) {
  const CoordinatorJournal original = sampleJournal(scenario_);
  const std::string file = path("state.json");
  saveJournal(file, original);
  EXPECT_FALSE(std::filesystem::exists(file + ".tmp"));
  expectSameJournal(loadJournal(file, scenario_), original);
  // Reported episodes are stored as ranges.
  EXPECT_NE(journalToJson(original).find("[\n   0,\n   3\n  ]"), std::string::npos)
      << journalToJson(original);
}

TEST_F(JournalFile, AFreshJournalWithNothingAnnouncedRoundTrips) {
  CoordinatorJournal fresh;
  fresh.run_id = "fresh";
  fresh.scenario_digest = "d";
  fresh.seed = 1;
  fresh.episodes_planned = 1;
  fresh.settings = initialSettings(scenario_, PlanSurrogate::Information);
  fresh.versions = {versionOf(scenario_, 1, 0, 0.0, 1.0)};
  expectSameJournal(journalFromJson(journalToJson(fresh), "fresh", scenario_), fresh);
}

TEST_F(JournalFile, SavingReplacesTheWholeFile) {
  const std::string file = path("state.json");
  CoordinatorJournal journal = sampleJournal(scenario_);
  saveJournal(file, journal);
  journal.versions.resize(1);
  journal.answered.clear();
  journal.announced.reset();
  saveJournal(file, journal);
  expectSameJournal(loadJournal(file, scenario_), journal);
}

// Each bad journal is refused with its source and field named.
TEST_F(JournalFile, RefusesMalformedJournalsNamingTheField) {
  const std::string good = journalToJson(sampleJournal(scenario_));
  const auto refusal = [&](const std::string& from, const std::string& to) {
    std::string text = good;
    const auto at = text.find(from);
    EXPECT_NE(at, std::string::npos) << from;
    text.replace(at, from.size(), to);
    try {
      (void)journalFromJson(text, "state.json", scenario_);
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  EXPECT_EQ(refusal("\"seed\"", "\"sead\""), "state.json: seed: expected present");
  EXPECT_EQ(refusal("\"surrogate\": \"cov\"", "\"surrogate\": \"newton\""),
            "state.json: settings.surrogate: expected info, cov, uniform or mc, got 'newton'");
  EXPECT_EQ(refusal("\"excluded\": [\n   3", "\"excluded\": [\n   4"),
            "state.json: settings.excluded[0]: expected a sensor id below M = 4");
  EXPECT_EQ(refusal("\"time_scale\": 2.5", "\"time_scale\": -1"),
            "state.json: time_scale: expected a number > 0");
  EXPECT_EQ(refusal("\"version\": 2", "\"version\": 1"),
            "state.json: versions[1].version: expected numbers that increase");
  EXPECT_EQ(refusal("\"shutdown_requested\": true", "\"shutdown_requested\": 1"),
            "state.json: shutdown_requested: expected true or false");
  EXPECT_EQ(refusal("\"format\": \"sensornet coordinator journal 1\"", "\"format\": \"x\""),
            "state.json: format: expected 'sensornet coordinator journal 1'");
  EXPECT_NE(refusal("{", "[").find("state.json: "), std::string::npos);
  // Rates of the wrong shape for the scenario.
  Scenario wider = scenario_;
  wider.sensors.push_back(wider.sensors.back());
  wider.constraints.C.conservativeResize(Eigen::NoChange, 5);
  wider.constraints.C.col(4).setOnes();
  try {
    (void)journalFromJson(good, "state.json", wider);
    ADD_FAILURE() << "a journal of 4 sensors was read for 5";
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()),
              "state.json: versions[0].rates[0]: expected an array of 5 rates (M)");
  }
  EXPECT_THROW((void)loadJournal(path("missing.json"), scenario_), InputError);
}

// What a resume does: a book rebuilt from the journal equals the one the coordinator had.
TEST_F(JournalFile, AResumedBookEqualsTheOriginal) {
  const CoordinatorJournal journal = sampleJournal(scenario_);
  ScheduleBook original;
  for (const ScheduleVersion& v : journal.versions) original.add(v);
  const std::string file = path("state.json");
  saveJournal(file, journal);
  ScheduleBook resumed;
  for (const ScheduleVersion& v : loadJournal(file, scenario_).versions) {
    EXPECT_EQ(resumed.add(v), ScheduleBook::Outcome::Accepted);
  }
  ASSERT_EQ(resumed.versions().size(), original.versions().size());
  for (std::size_t i = 0; i < original.versions().size(); ++i) {
    EXPECT_TRUE(identical(resumed.versions()[i], original.versions()[i]));
  }
  for (std::uint32_t episode : {0u, 3u, 4u, 9u}) {
    const auto a = original.segments(episode, scenario_.horizon_s);
    const auto b = resumed.segments(episode, scenario_.horizon_s);
    ASSERT_EQ(a.size(), b.size());
    for (std::size_t i = 0; i < a.size(); ++i) {
      EXPECT_EQ(a[i].from_s, b[i].from_s);
      EXPECT_EQ(a[i].to_s, b[i].to_s);
      EXPECT_EQ(a[i].version->version, b[i].version->version);
    }
  }
  // A reader that has the versions sees each republished one as a duplicate.
  for (const ScheduleVersion& v : resumed.versions()) {
    EXPECT_EQ(original.add(v), ScheduleBook::Outcome::Duplicate);
  }
  EXPECT_EQ(original.versions().size(), 3u);
}

TEST(ScheduleBookReAdd, AnIdenticalVersionIsADuplicateAndADifferentOneUnderItsNumberIsStale) {
  const Scenario s = smallScenario();
  ScheduleBook book;
  ASSERT_EQ(book.add(versionOf(s, 1, 0, 0.0, 1.0)), ScheduleBook::Outcome::Accepted);
  ASSERT_EQ(book.add(versionOf(s, 2, 3, 1.25, 0.9)), ScheduleBook::Outcome::Accepted);
  EXPECT_EQ(book.add(versionOf(s, 1, 0, 0.0, 1.0)), ScheduleBook::Outcome::Duplicate);
  EXPECT_EQ(book.add(versionOf(s, 2, 3, 1.25, 0.9)), ScheduleBook::Outcome::Duplicate);

  ScheduleVersion other_rates = versionOf(s, 2, 3, 1.25, 0.9);
  Eigen::MatrixXd rates = other_rates.schedule.rates();
  rates(0, 0) = std::nextafter(rates(0, 0), 1.0);  // one bit
  other_rates.schedule = RateSchedule(s.horizon_s, rates);
  EXPECT_EQ(book.add(other_rates), ScheduleBook::Outcome::Stale);
  EXPECT_EQ(book.add(versionOf(s, 2, 3, 1.5, 0.9)), ScheduleBook::Outcome::Stale);
  ScheduleVersion other_command = versionOf(s, 2, 3, 1.25, 0.9);
  other_command.command_id += 1;
  EXPECT_EQ(book.add(other_command), ScheduleBook::Outcome::Stale);
  ASSERT_EQ(book.versions().size(), 2u);
  EXPECT_TRUE(identical(book.latest(), versionOf(s, 2, 3, 1.25, 0.9)));
}

}  // namespace
}  // namespace sensornet::emulator
