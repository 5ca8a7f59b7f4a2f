#include "sensornet/core/random.hpp"

#include <bit>
#include <cmath>
#include <numbers>

namespace sensornet {

std::uint64_t mix64(std::uint64_t x) {
  x += 0x9e3779b97f4a7c15ULL;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ULL;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebULL;
  return x ^ (x >> 31);
}

Rng::Rng(std::uint64_t seed) {
  std::uint64_t state = seed;
  for (auto& word : s_) {
    state = mix64(state);
    word = state;
  }
}

Rng Rng::keyed(std::uint64_t seed, std::initializer_list<std::uint64_t> keys) {
  std::uint64_t h = mix64(seed);
  for (std::uint64_t k : keys) h = mix64(h ^ mix64(k + 0x632be59bd9b4e019ULL));
  return Rng(h);
}

Rng::result_type Rng::operator()() {
  const std::uint64_t result = std::rotl(s_[0] + s_[3], 23) + s_[0];
  const std::uint64_t t = s_[1] << 17;
  s_[2] ^= s_[0];
  s_[3] ^= s_[1];
  s_[1] ^= s_[2];
  s_[0] ^= s_[3];
  s_[2] ^= t;
  s_[3] = std::rotl(s_[3], 45);
  return result;
}

double Rng::uniform() {
  // 53 random bits, shifted by half a step so that 0 and 1 never occur.
  return (static_cast<double>((*this)() >> 11) + 0.5) * 0x1.0p-53;
}

double Rng::exponential(double rate) { return -std::log(uniform()) / rate; }

double Rng::normal() {
  const double u1 = uniform();
  const double u2 = uniform();
  return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * std::numbers::pi * u2);
}

unsigned Rng::poisson(double mean) {
  // Counting unit-rate exponential gaps up to `mean`: exact, O(mean) work, which suits the
  // small means of one rate interval.
  unsigned count = 0;
  double t = exponential(1.0);
  while (t <= mean) {
    ++count;
    t += exponential(1.0);
  }
  return count;
}

}  // namespace sensornet
