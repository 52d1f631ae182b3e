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

// Entry j of limbs `s` set to hold the integer v, split at random as sums of limbs can be: hi a
// multiple of 2^70, mid of 2^35 (beyond 2^70 and of either sign), lo an integer up to about 2^52.
void Split(std::mt19937_64& rng, Int128 v, SumLimbs* s, int j) {
  const Int128 two35 = Int128{1} << 35, two70 = Int128{1} << 70;
  const Int128 hi = v / two70 + Int128(int(rng() % 3) - 1);
  const Int128 rest = v - hi * two70;
  const Int128 mid = rest / two35 + Int128(int(rng() % 5) - 2) * Int128(rng() % (1u << 16));
  const Int128 lo = rest - mid * two35;
  s->hi[j] = static_cast<double>(static_cast<std::int64_t>(hi)) * 0x1p70;
  s->mid[j] = static_cast<double>(static_cast<std::int64_t>(mid)) * 0x1p35;
  s->lo[j] = static_cast<double>(static_cast<std::int64_t>(lo));
  ASSERT_TRUE(SumLimbsUnits(*s, j) == v);
}

// A random integer of exactly `bits` bits (at most 122), either sign; 0 for none.
Int128 RandomInteger(std::mt19937_64& rng, int bits) {
  if (bits == 0) return 0;
  const unsigned __int128 r = (static_cast<unsigned __int128>(rng()) << 64) | rng();
  const unsigned __int128 top = static_cast<unsigned __int128>(1) << (bits - 1);
  const Int128 v = static_cast<Int128>((r >> (128 - bits)) | top);
  return (rng() & 1) ? -v : v;
}

// Every entry of SumLimbsToDoubles has SumLimbsToDouble's bits.
void ExpectIntegerRoutesBits(const SumLimbs& s, int band) {
  const auto& scales = BandScales();
  double got[6];
  SumLimbsToDoubles(s, scales[band].up, got);
  for (int j = 0; j < 6; ++j)
    ASSERT_EQ(DoubleBits(got[j]), DoubleBits(SumLimbsToDouble(s, j, scales[band].up)))
        << "band " << band << " entry " << j << ": hi " << std::hexfloat << s.hi[j] << " mid "
        << s.mid[j] << " lo " << s.lo[j];
}

// The integer-free conversion gives the int128 route's bits: for limb sums of random
// contributions of every band (some taken out again), and for integers split into limbs at
// random, three quarters of them at or next to a tie of rounding to 53 bits (a midpoint between
// two doubles, plus -2..2) or at a power of two.
TEST(InformationSum, SumLimbsToDoublesGivesTheIntegerRoutesBits) {
  std::mt19937_64 rng(53);
  const auto& scales = BandScales();
  for (int k = 0; k < 63; ++k)
    for (int trial = 0; trial < 300; ++trial) {
      SumLimbs s{};
      const int terms = 1 + int(rng() % 40);
      for (int t = 0; t < terms; ++t) {
        const std::vector<double> c = Contribution(rng, int(rng() % std::uint64_t(k + 1)));
        AccumulateLimbs(s, c.data(), scales[k].down, (rng() % 4) != 0);
      }
      ExpectIntegerRoutesBits(s, k);
    }
  int ties = 0;
  for (int trial = 0; trial < 100000; ++trial) {
    SumLimbs s{};
    for (int j = 0; j < 6; ++j) {
      const int kind = int(rng() % 4);
      const int bits = kind == 0 ? int(rng() % 123) : 55 + int(rng() % 68);
      Int128 v = RandomInteger(rng, kind == 0 ? bits : 53);
      if (kind != 0) {
        // A midpoint between two doubles of `bits` bits, or a power of two, nudged by -2..2.
        const Int128 unit = Int128{1} << (bits - 53), sign = v < 0 ? -1 : 1;
        v = kind == 3 ? sign * (Int128{1} << (bits - 1)) : v * unit + sign * (unit / 2);
        const Int128 nudge = Int128(int(rng() % 5) - 2);
        ties += kind != 3 && nudge == 0 ? 1 : 0;
        v += nudge;
      }
      Split(rng, v, &s, j);
    }
    ExpectIntegerRoutesBits(s, int(rng() % 63));
  }
  EXPECT_GT(ties, 50000);
}

// AccumulateLimbList (AVX-512 where the CPU has it) leaves the bits of AccumulateLimbs pair by
// pair: 512 voxels on random bands, twelve cameras' contributions of every band up to the voxel's
// (subnormal, zero and band-top entries among them) added, then half of them taken out.
TEST(InformationSum, LimbListGivesThePairByPairBits) {
  std::mt19937_64 rng(53);
  const auto& scales = BandScales();
  std::vector<std::uint8_t> band(512);
  for (auto& b : band) b = static_cast<std::uint8_t>(rng() % 63);
  std::vector<SumLimbs> list_sums(512), pair_sums(512);
  for (int v = 0; v < 512; ++v)
    for (int j = 0; j < 6; ++j) Split(rng, RandomInteger(rng, 60), &list_sums[v], j);
  pair_sums = list_sums;
  for (int camera = 0; camera < 12; ++camera) {
    std::vector<std::int16_t> voxel, index;
    std::vector<double> information;
    for (int v = 0; v < 512; ++v) {
      if (rng() % 3 == 0) continue;  // not seen by this camera
      const std::vector<double> c = Contribution(rng, int(rng() % std::uint64_t(band[v] + 1)));
      voxel.push_back(static_cast<std::int16_t>(v));
      index.push_back(static_cast<std::int16_t>(index.size()));
      information.insert(information.end(), c.begin(), c.end());
    }
    const bool add = camera % 4 != 3;
    AccumulateLimbList(int(voxel.size()), voxel.data(), index.data(), information.data(),
                       band.data(), list_sums.data(), add);
    for (std::size_t j = 0; j < voxel.size(); ++j)
      AccumulateLimbs(pair_sums[voxel[j]], &information[6 * j], scales[band[voxel[j]]].down, add);
  }
  for (int v = 0; v < 512; ++v)
    for (int j = 0; j < 6; ++j) {
      ASSERT_EQ(DoubleBits(list_sums[v].hi[j]), DoubleBits(pair_sums[v].hi[j])) << v << " " << j;
      ASSERT_EQ(DoubleBits(list_sums[v].mid[j]), DoubleBits(pair_sums[v].mid[j])) << v << " " << j;
      ASSERT_EQ(DoubleBits(list_sums[v].lo[j]), DoubleBits(pair_sums[v].lo[j])) << v << " " << j;
    }
}

}  // namespace
}  // namespace pandora::information
