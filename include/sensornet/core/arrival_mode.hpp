#pragma once
// How a sensor's measurement instants follow from its rate schedule: a Poisson process
// (poisson_arrivals.hpp) or the deterministic timetable (arrival_timetable.hpp). A scenario
// carries one (its `arrivals:`), which --arrivals overrides.
//
//   const ArrivalMode mode = parseArrivalMode("timetable", "scenario.yaml:4", "arrivals");
//   std::printf("%s\n", std::string(arrivalModeName(mode)).c_str());  // "timetable"

#include <string>
#include <string_view>

#include "sensornet/core/words.hpp"

namespace sensornet {

enum class ArrivalMode {
  Poisson,    // a Poisson process of intensity λ_j(t), drawn afresh in every episode
  Timetable,  // the instants where Λ_j(t) = ∫_0^t λ_j reaches k - 1/2, the same every episode
};

template <>
struct Words<ArrivalMode> {
  static constexpr std::array<WordOf<ArrivalMode>, 2> kTable{
      {{ArrivalMode::Poisson, "poisson"}, {ArrivalMode::Timetable, "timetable"}}};
};

// "poisson" or "timetable".
[[nodiscard]] std::string_view arrivalModeName(ArrivalMode mode);
// The inverse of arrivalModeName; throws InputError naming `source` and `field` otherwise.
[[nodiscard]] ArrivalMode parseArrivalMode(std::string_view text, const std::string& source,
                                           const std::string& field);

}  // namespace sensornet
