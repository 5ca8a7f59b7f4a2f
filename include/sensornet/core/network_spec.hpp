#pragma once
// The emulated network of a scenario (its optional `network:` section) and the faults it
// injects (its `faults:` list). The semantics and the scenario syntax are in network.hpp.

#include <cstdint>
#include <vector>

namespace sensornet {

enum class Jitter { None, Exponential, Lognormal };

// One sensor's link to the fusion center.
struct LinkSpec {
  double loss = 0.0;            // probability a measurement is dropped, in [0, 1)
  double duplicate = 0.0;       // probability a delivered measurement is delivered twice, [0, 1)
  double delay_fixed_s = 0.0;   // emulated seconds every delivered measurement is held back
  Jitter jitter = Jitter::None;
  double jitter_mean_s = 0.0;   // mean of the random part (exponential, lognormal)
  double jitter_sigma = 0.0;    // lognormal: standard deviation of log(delay)
  [[nodiscard]] bool perfect() const {
    return loss == 0.0 && duplicate == 0.0 && delay_fixed_s == 0.0 && jitter == Jitter::None;
  }
};

// The link of `sensor` is down on [from_s, to_s) of the listed episodes (all when empty).
struct Outage {
  int sensor = 0;
  std::vector<std::uint32_t> episodes;  // empty: every episode
  double from_s = 0.0;
  double to_s = 0.0;
  [[nodiscard]] bool appliesTo(std::uint32_t episode) const;
};

struct NetworkSpec {
  std::vector<LinkSpec> links;  // one per sensor, the default with its overrides applied
  std::vector<Outage> outages;
};

// A scripted fault: the process hosting `sensor` exits (like kill -9) at emulated time `at_s`
// of `episode`.
struct CrashFault {
  int sensor = 0;
  std::uint32_t episode = 0;
  double at_s = 0.0;
};

}  // namespace sensornet
