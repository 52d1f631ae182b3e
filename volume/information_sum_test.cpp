// The two exact information sums agree: the limbs the field evaluation adds in SIMD (SumLimbs)
// hold, entry by entry, the same integer as the 128-bit fixed-point sum (Sum6) that N-1 uses, for
// contributions in every band, subnormal ones, ones at a band's top, and sums of up to 2^17 terms
// added and taken out in any order.
#include "volume/information_sum.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <limits>
#include <random>
#include <vector>

namespace pandora::information {
namespace {

// A double with a random sign and mantissa whose IEEE exponent field is `e` (0: subnormal).
double WithExponent(std::mt19937_64& rng, int e) {
  const std::uint64_t mantissa = rng() & ((std::uint64_t{1} << 52) - 1);
  const std::uint64_t sign = rng() & 1;
  return BitsDouble(sign << 63 | std::uint64_t(e) << 52 | mantissa);
}

// A contribution in band k: its largest entry's exponent field in the band, others anywhere below
// (down to subnormal and zero).
std::vector<double> Contribution(std::mt19937_64& rng, int k) {
  const int top_lo = std::max(0, 32 * k), top_hi = 32 * k + 31;
  std::vector<double> c(6);
  const int top = top_lo + int(rng() % std::uint64_t(top_hi - top_lo + 1));
  for (int j = 0; j < 6; ++j) {
    const std::uint64_t pick = rng() % 8;
    int e = pick == 0 ? 0 : pick == 1 ? top : int(rng() % std::uint64_t(top + 1));
    c[j] = pick == 2 ? 0.0 : WithExponent(rng, e);
  }
  c[rng() % 6] = WithExponent(rng, top);
  EXPECT_EQ(Band(c.data()), k);
  return c;
}

TEST(InformationSum, LimbsHoldTheFixedPointOfEveryContribution) {
  std::mt19937_64 rng(29);
  const auto& scales = BandScales();
  for (int k = 0; k < 63; ++k) {
    for (int trial = 0; trial < 2000; ++trial) {
      const std::vector<double> c = Contribution(rng, k);
      SumLimbs s{};
      AccumulateLimbs(s, c.data(), scales[k].down, true);
      for (int j = 0; j < 6; ++j) {
        const Int128 want = ToFixed(c[j], scales[k].q);
        ASSERT_TRUE(SumLimbsUnits(s, j) == want)
            << "band " << k << " entry " << c[j] << " (" << std::hexfloat << c[j] << ")";
        ASSERT_EQ(DoubleBits(SumLimbsToDouble(s, j, scales[k].up)),
                  DoubleBits(ToDouble(want) * scales[k].up[0] * scales[k].up[1]));
      }
    }
    // The largest contribution of the band: every entry just below 2^(q + 106).
    std::vector<double> top(6, std::nextafter(std::ldexp(1.0, scales[k].q + 106), 0.0));
    if (k < 62 || std::isfinite(top[0])) {
      SumLimbs s{};
      AccumulateLimbs(s, top.data(), scales[k].down, true);
      for (int j = 0; j < 6; ++j) ASSERT_TRUE(SumLimbsUnits(s, j) == ToFixed(top[j], scales[k].q));
    }
  }
}

TEST(InformationSum, LimbSumsAreExactInAnyOrderUpToTwoToTheSeventeen) {
  std::mt19937_64 rng(17);
  const auto& scales = BandScales();
  for (int k : {1, 31, 32, 33, 40, 62}) {
    // 2^17 contributions at the band's top (the worst case for the hi limb), then a mix of
    // bands k and below, added in one order and taken out in another.
    const int n = 1 << 17;
    std::vector<std::vector<double>> all;
    for (int i = 0; i < n; ++i) {
      if (i % 3 == 0) {
        all.push_back(std::vector<double>(
            6, std::nextafter(std::ldexp(1.0, scales[k].q + 106), 0.0) * ((i & 4) ? -1 : 1)));
      } else {
        all.push_back(Contribution(rng, int(rng() % std::uint64_t(k + 1))));
      }
    }
    SumLimbs s{};
    Sum6 want{};
    for (const auto& c : all) {
      AccumulateLimbs(s, c.data(), scales[k].down, true);
      Accumulate(want, c.data(), scales[k], true);
    }
    for (int j = 0; j < 6; ++j) ASSERT_TRUE(SumLimbsUnits(s, j) == want.v[j]) << "band " << k;
    // Take out every other contribution, from the back.
    for (int i = n - 1; i >= 0; i -= 2) {
      AccumulateLimbs(s, all[i].data(), scales[k].down, false);
      Accumulate(want, all[i].data(), scales[k], false);
    }
    for (int j = 0; j < 6; ++j) ASSERT_TRUE(SumLimbsUnits(s, j) == want.v[j]) << "band " << k;
  }
}

}  // namespace
}  // namespace pandora::information
