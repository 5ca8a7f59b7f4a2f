#pragma once
// Keyed randomness: every stream is a pure function of (run seed, stream keys...), so that a run
// is reproducible whatever the thread count or process layout.
//
//   Rng rng = Rng::keyed(seed, kArrivalStream, episode);
//   double u = rng.uniform();           // in (0, 1)
//   double e = rng.exponential(2.0);    // rate 2
//   double z = rng.normal();
//
// The generator is xoshiro256++ seeded by SplitMix64 over the mixed keys; it satisfies
// UniformRandomBitGenerator so it also works with <random> distributions.

#include <cstdint>
#include <initializer_list>
#include <limits>

namespace sensornet {

class Rng {
 public:
  using result_type = std::uint64_t;

  explicit Rng(std::uint64_t seed);
  // A stream keyed by a seed and any number of integer keys (sensor, episode, level, ...).
  static Rng keyed(std::uint64_t seed, std::initializer_list<std::uint64_t> keys);
  template <typename... Keys>
  static Rng keyed(std::uint64_t seed, Keys... keys) {
    return keyed(seed, {static_cast<std::uint64_t>(keys)...});
  }

  static constexpr result_type min() { return 0; }
  static constexpr result_type max() { return std::numeric_limits<result_type>::max(); }
  result_type operator()();

  double uniform();                   // uniform in the open interval (0, 1)
  double exponential(double rate);    // rate > 0
  double normal();                    // standard normal (Box-Muller, no cached state)
  unsigned poisson(double mean);      // mean >= 0

 private:
  std::uint64_t s_[4];
};

// SplitMix64 finalizer: a good 64-bit mixing function, used to combine keys.
std::uint64_t mix64(std::uint64_t x);

}  // namespace sensornet
