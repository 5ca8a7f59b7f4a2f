// The flags a printed hint carries to reach a run: what was chosen away from the defaults, so
// that `sensornet status ...` as printed reaches the run the launcher started (issue 48).

#include "sensornet/wire/run_options.hpp"

#include <gtest/gtest.h>

#include <string>
#include <vector>

namespace sensornet::wire {
namespace {

using Flags = std::vector<std::string>;

TEST(RunOptions, AHintCarriesTheRunIdAndOnlyTheChoicesMadeAwayFromTheDefaults) {
  RunOptions run;
  run.run_id = "r1";
  EXPECT_EQ(run.reachFlags(), (Flags{"--run-id", "r1"}));
  run.domain_id = 34;
  run.security_dir = "pki";
  EXPECT_EQ(run.reachFlags(), (Flags{"--run-id", "r1", "--domain-id", "34", "--security", "pki"}));
  run.cyclone_config = "mine.xml";
  EXPECT_EQ(run.reachFlags(),
            (Flags{"--run-id", "r1", "--domain-id", "34", "--cyclone-config", "mine.xml",
                   "--security", "pki"}));
  // The launcher's own configuration of a run across hosts replaces the one given.
  EXPECT_EQ(run.reachFlags("logs/cyclone-launcher.xml"),
            (Flags{"--run-id", "r1", "--domain-id", "34", "--cyclone-config",
                   "logs/cyclone-launcher.xml", "--security", "pki"}));
}

// The domain a hint names is the one the run's processes use: the same domainConfig().
TEST(RunOptions, TheDomainOfAHintIsTheDomainOfTheRun) {
  RunOptions launched;
  launched.run_id = "hint-run";
  launched.domain_id = 34;
  RunOptions from_hint;
  const Flags flags = launched.reachFlags();
  for (std::size_t i = 0; i + 1 < flags.size(); i += 2) {
    if (flags[i] == "--run-id") from_hint.run_id = flags[i + 1];
    if (flags[i] == "--domain-id") from_hint.domain_id = std::stoi(flags[i + 1]);
  }
  EXPECT_EQ(from_hint.domainConfig().domain_id, launched.domainConfig().domain_id);
  EXPECT_EQ(from_hint.domainConfig().partition, launched.domainConfig().partition);
}

}  // namespace
}  // namespace sensornet::wire
