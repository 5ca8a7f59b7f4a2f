#pragma once
// The surrogates by name, without the planner: what a plan minimizes (PlanSurrogate, the
// `--surrogate` of `coordinator plan`, `coordinator serve`, `sensornet launch` and `replan`) and
// what a schedule version was made with (SurrogateKind: one of those, or File, a schedule read
// from a file and not planned). Both are words (core/words.hpp) with one spelling each; the
// spellings of SurrogateKind are those of PlanSurrogate plus "file", taken from its table:
//
//   const PlanSurrogate planned = parseWord<PlanSurrogate>("cov", "--surrogate", "");
//   ScheduleVersion v;
//   v.surrogate = surrogateKindOf(planned);          // SurrogateKind::Covariance, "cov"
//   v.surrogate = SurrogateKind::File;               // "file" in the report and on the wire
//   plannedSurrogate(v.surrogate);                   // nullopt for File

#include <array>
#include <cstddef>
#include <optional>

#include "sensornet/core/words.hpp"

namespace sensornet {

// MonteCarlo ("mc") minimizes E[J(P)] of the exact CD-KF by Monte Carlo (mc_planner.hpp);
// planSchedule dispatches to planForRealizedCost.
enum class PlanSurrogate { Information, Covariance, Uniform, MonteCarlo };

template <>
struct Words<PlanSurrogate> {
  static constexpr std::array<WordOf<PlanSurrogate>, 4> kTable{
      {{PlanSurrogate::Information, "info"},
       {PlanSurrogate::Covariance, "cov"},
       {PlanSurrogate::Uniform, "uniform"},
       {PlanSurrogate::MonteCarlo, "mc"}}};
};

// What a schedule version was made with: a planner's surrogate, or a schedule file.
enum class SurrogateKind { Information, Covariance, Uniform, MonteCarlo, File };

[[nodiscard]] constexpr SurrogateKind surrogateKindOf(PlanSurrogate surrogate) {
  switch (surrogate) {
    case PlanSurrogate::Information:
      return SurrogateKind::Information;
    case PlanSurrogate::Covariance:
      return SurrogateKind::Covariance;
    case PlanSurrogate::Uniform:
      return SurrogateKind::Uniform;
    case PlanSurrogate::MonteCarlo:
      return SurrogateKind::MonteCarlo;
  }
  return SurrogateKind::File;
}

// The planner's surrogate of a version; nullopt for File.
[[nodiscard]] constexpr std::optional<PlanSurrogate> plannedSurrogate(SurrogateKind kind) {
  for (const WordOf<PlanSurrogate>& w : Words<PlanSurrogate>::kTable) {
    if (surrogateKindOf(w.value) == kind) return w.value;
  }
  return std::nullopt;
}

template <>
struct Words<SurrogateKind> {
  static constexpr std::array<WordOf<SurrogateKind>, 5> kTable = [] {
    std::array<WordOf<SurrogateKind>, 5> table{};
    std::size_t i = 0;
    for (const WordOf<PlanSurrogate>& w : Words<PlanSurrogate>::kTable) {
      table[i++] = {surrogateKindOf(w.value), w.text};
    }
    table[i] = {SurrogateKind::File, "file"};
    return table;
  }();
};

}  // namespace sensornet
