#pragma once
/// \file seeded.h
/// Reproducible pseudo-random numbers from counters: SplitMix64's finaliser (a bijective 64-bit
/// mix), so that draw (seed, a, b, c) is the same on every platform and thread count and does not
/// depend on how many other draws were made (unlike std:: engines and distributions).

#include <cstdint>

namespace pandora {

inline std::uint64_t SplitMix64(std::uint64_t x) {
  x += 0x9e3779b97f4a7c15ull;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ull;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebull;
  return x ^ (x >> 31);
}

/// Uniform in [0, 1) from 53 bits of a hash of (seed, a, b, c).
inline double SeededUniform(std::uint64_t seed, std::uint64_t a, std::uint64_t b = 0,
                            std::uint64_t c = 0) {
  const std::uint64_t h = SplitMix64(SplitMix64(SplitMix64(SplitMix64(seed) ^ a) ^ b) ^ c);
  return static_cast<double>(h >> 11) * 0x1.0p-53;
}

}  // namespace pandora
