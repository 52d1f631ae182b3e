#pragma once
/// \file information_sum.h
/// Internal to volume/: the exact (order-free) sum of per-camera information contributions and the
/// static statistics of its eigenvalues, shared by the field evaluation (volume/fields.cpp) and the
/// N-1 criticality (volume/robustness.cpp) so that both give the same bits. Files that include it
/// are compiled without floating-point contraction (volume/CMakeLists.txt).

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>

namespace pandora::information {

// Rows of the per-candidate statistics arrays.
enum StatRow {
  kObservable,   // 1 or 0
  kSigmaMaxMm,   // sqrt of the largest variance, mm
  kSigmaMeanMm,  // sqrt(trace / 3), mm
  kCond,         // largest / smallest eigenvalue of J
  kVar0,         // variances 1 / lambda_k, m^2 (descending); the steady pass overwrites them
  kVar1,
  kVar2,
  kSteadyMaxMm,
  kSteadyMeanMm,
  kStatRows
};

// From the eigenvalues of J (ascending, three arrays of n) the static statistics into out[row][m].
// Eigenvalues are clipped at 0 (round-off); a voxel is observable when the smallest exceeds
// kRelativeObservability times the largest, which is positive and finite. The other rows are
// meaningless (inf or NaN) where it is not, and never read there.
void StaticStatistics(int n, double* const* eigenvalues, double* const* out);

// The exact information sum. A voxel's information J is the sum of its cameras' contributions
// (six doubles each). Summed in double, the bits depend on the order, so an update would have to
// re-read every camera's contribution. Instead each contribution is rounded once to a fixed-point
// integer (int128) on a grid of spacing 2^q and the integers are summed: exact, so in any order
// and by subtracting one camera's old contribution and adding its new one, with the same bits.
// The grid depends on the voxel's largest contribution: its "band" is the largest IEEE exponent
// field e (biased, 0..2047) of the contribution's six entries, shifted right by 5 (bands of 32
// binades). A voxel's band k is the largest band of its contributions; then every entry is below
// 2^(32 (k + 1) - 1023), q = 32 (k + 1) - 1129, every rounded entry is below 2^106 in magnitude and
// the sum of up to 2^17 of them below 2^123: no overflow. The spacing is 2^-74 .. 2^-106 of the
// largest entry of the largest contribution, itself at most the largest eigenvalue of J (J is a
// sum of positive semi-definite matrices, so its largest entry is on the diagonal), so the
// rounding moves every eigenvalue by at most 2^-75 N lambda_max (Weyl), far below the 2^-53
// lambda_max of the double sum and of the eigenvalue solver. The integer sum is then rounded to
// double once (correctly rounded), so J is at least as accurate as a double sum in rig order.
// Voxels with a contribution in band 63 (an entry >= 2^993, inf or NaN) or more than 2^16 cameras
// are summed in double in rig order as before (a function of the contributions only, so a full
// evaluation and an update choose alike). Per voxel the evaluator keeps the sums, the band and how
// many contributions are in it; an update that removes the last one of the top band, or adds one
// above it, re-sums that voxel from every camera.
constexpr int kBandShift = 5;
constexpr std::uint8_t kNotExact = 63;  // also: a voxel without contributions
constexpr int kMaxExactCameras = 1 << 16;
using Int128 = __int128;
struct Sum6 {
  Int128 v[6];
};

inline std::uint64_t DoubleBits(double x) {
  std::uint64_t b;
  std::memcpy(&b, &x, sizeof(b));
  return b;
}
inline double BitsDouble(std::uint64_t b) {
  double x;
  std::memcpy(&x, &b, sizeof(x));
  return x;
}
// Written out with selects over six arguments so that it vectorises inside a SIMD loop over voxels.
inline std::uint64_t ExponentField(double c) { return (DoubleBits(c) >> 52) & 0x7ff; }
inline std::uint8_t Band(double c0, double c1, double c2, double c3, double c4, double c5) {
  const std::uint64_t e0 = ExponentField(c0), e1 = ExponentField(c1), e2 = ExponentField(c2),
                      e3 = ExponentField(c3), e4 = ExponentField(c4), e5 = ExponentField(c5);
  const std::uint64_t a = e0 > e1 ? e0 : e1, b = e2 > e3 ? e2 : e3, c = e4 > e5 ? e4 : e5;
  const std::uint64_t ab = a > b ? a : b;
  return static_cast<std::uint8_t>((ab > c ? ab : c) >> kBandShift);
}
inline std::uint8_t Band(const double* c) { return Band(c[0], c[1], c[2], c[3], c[4], c[5]); }

// Per band k < 63: its q, and 2^q as two factors (2^q itself may underflow).
struct BandScale {
  int q;
  double up[2];
  double down[2];  // 2^-q as two factors
};
inline const std::array<BandScale, 64>& BandScales() {
  static const std::array<BandScale, 64> table = [] {
    std::array<BandScale, 64> t{};
    for (int k = 0; k < 63; ++k) {
      const int q = 32 * (k + 1) - 1129;
      const int half = q / 2;
      t[k].q = q;
      t[k].up[0] = std::ldexp(1.0, half);
      t[k].up[1] = std::ldexp(1.0, q - half);
      t[k].down[0] = std::ldexp(1.0, -half);
      t[k].down[1] = std::ldexp(1.0, half - q);
    }
    return t;
  }();
  return table;
}

// c / 2^q rounded to the nearest integer (ties to even), from c's bits: no multiplication, no
// library call. For a contribution in band k or below with q = 32 (k + 1) - 1129 the result is
// below 2^106 in magnitude, so the left shift is at most 54.
inline Int128 ToFixed(double c, int q) {
  const std::uint64_t b = DoubleBits(c);
  int e = static_cast<int>((b >> 52) & 0x7ff);
  std::uint64_t m = b & ((std::uint64_t{1} << 52) - 1);
  if (e != 0)
    m |= std::uint64_t{1} << 52;
  else
    e = 1;                         // subnormal
  const int shift = e - 1075 - q;  // |c| / 2^q = m 2^shift
  Int128 v;
  if (shift >= 0) {
    v = static_cast<Int128>(static_cast<unsigned __int128>(m) << shift);
  } else if (shift < -63) {
    v = 0;  // m < 2^53: below one half
  } else {
    const int r = -shift;
    const std::uint64_t t = m >> r, rest = m & ((std::uint64_t{1} << r) - 1),
                        half = std::uint64_t{1} << (r - 1);
    v = static_cast<Int128>(t + ((rest > half) | ((rest == half) & (t & 1))));
  }
  return (b >> 63) ? -v : v;
}

// The int128 as the nearest double (ties to even), without a library call.
inline double ToDouble(Int128 s) {
  const bool negative = s < 0;
  const unsigned __int128 u = negative ? -static_cast<unsigned __int128>(s) : s;
  double d;
  if ((u >> 63) == 0) {
    d = static_cast<double>(static_cast<std::int64_t>(u));
  } else {
    // Keep the top 63 bits, the dropped ones as a sticky bit: one correct rounding to 53 bits.
    const std::uint64_t hi = static_cast<std::uint64_t>(u >> 64);
    const int bits = hi ? 128 - __builtin_clzll(hi) : 64;
    const int shift = bits - 63;
    std::uint64_t t = static_cast<std::uint64_t>(u >> shift);
    if (static_cast<std::uint64_t>(u) & ((std::uint64_t{1} << shift) - 1)) t |= 1;
    d = static_cast<double>(static_cast<std::int64_t>(t)) *
        BitsDouble(static_cast<std::uint64_t>(1023 + shift) << 52);
  }
  return negative ? -d : d;
}

// Adds (`add`) or subtracts contribution c rounded on its band's grid (N-1's per-voxel sums).
inline void Accumulate(Sum6& sum, const double* c, const BandScale& scale, bool add) {
  for (int k = 0; k < 6; ++k) {
    const Int128 v = ToFixed(c[k], scale.q);
    sum.v[k] = add ? sum.v[k] + v : sum.v[k] - v;
  }
}

}  // namespace pandora::information

namespace pandora::information {

// The same exact sum held in three doubles per entry ("limbs"), which the field evaluation adds
// in SIMD instead of in 128-bit integers. A contribution c on band k's grid is y = c 2^-q (two
// exact power-of-two products: y is exact, or below 2^-1022 where it rounds to 0 either way),
// |y| < 2^106, split without error into y = hi + mid + lo + r with hi a multiple of 2^70, mid of
// 2^35 and lo an integer, each the nearest (ties to even) of what is left, by adding and
// subtracting 1.5 2^(52+g) (exact in round-to-nearest for |x| <= 2^(51+g); the file is compiled
// without contraction and without -ffast-math). Then hi + mid + lo is exactly ToFixed(c, q): each
// step rounds what is left on a grid that the later grids divide, ties to even on the sum, and
// hi, mid are even multiples of 2^0. Each limb has at most 36 significant bits (hi <= 2^36 units,
// mid and lo <= 2^34), so up to 2^17 of them sum exactly in double in any order, and an update
// may add the changed cameras' new views before it takes out their old ones (kMaxExactCameras is
// 2^16). SumLimbsToDouble assembles the same int128 as the Sum6 route and rounds it the same way.
struct SumLimbs {
  double hi[6], mid[6], lo[6];
};

typedef double V2 __attribute__((vector_size(16)));

// Entries k..k+W-1 of contribution c added (`add`) to or subtracted from s on band scale
// (down0, down1) = 2^-q as two factors: W = 2 or 4 doubles of vector type V.
template <typename V>
__attribute__((always_inline)) inline void AccumulateEntries(SumLimbs& s, const double* c, int k,
                                                             double down0, double down1, bool add) {
  const V d0 = V{} + down0, d1 = V{} + down1;
  const V m_hi = V{} + 0x1.8p122, m_mid = V{} + 0x1.8p87, m_lo = V{} + 0x1.8p52;
  V y;
  std::memcpy(&y, c + k, sizeof(y));
  y = (y * d0) * d1;
  const V hi = (y + m_hi) - m_hi;
  const V r1 = y - hi;
  const V mid = (r1 + m_mid) - m_mid;
  const V r2 = r1 - mid;
  const V lo = (r2 + m_lo) - m_lo;
  V a, b, e;
  std::memcpy(&a, s.hi + k, sizeof(a));
  std::memcpy(&b, s.mid + k, sizeof(b));
  std::memcpy(&e, s.lo + k, sizeof(e));
  if (add) {
    a += hi, b += mid, e += lo;
  } else {
    a -= hi, b -= mid, e -= lo;
  }
  std::memcpy(s.hi + k, &a, sizeof(a));
  std::memcpy(s.mid + k, &b, sizeof(b));
  std::memcpy(s.lo + k, &e, sizeof(e));
}

// Adds (`add`) or subtracts contribution c (six doubles) on band scale `down` (2^-q as two
// factors) to s: six entries as three pairs, so SSE2 adds two at a time.
__attribute__((always_inline)) inline void AccumulateLimbs(SumLimbs& s, const double* c,
                                                           const double* down, bool add) {
  for (int k = 0; k < 6; k += 2) AccumulateEntries<V2>(s, c, k, down[0], down[1], add);
}

// AccumulateLimbs for a list of (voxel, contribution) pairs, j < n: contribution
// information[6 index[j]] (one camera's, ascending seen voxel) added (`add`) to or subtracted from
// sums[voxel[j]] on that voxel's band, band[voxel[j]] (< kNotExact). Where the CPU has AVX2 a
// pair's six entries go as four and two (AccumulateEntries), with the same operations per entry
// as AccumulateLimbs, so the same bits (information_sum_test); elsewhere AccumulateLimbs pair by
// pair. (All six in one AVX-512 vector with masked loads and stores was slower on the capture
// stage, 0.161 s against 0.152 s for all nine fields.)
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
typedef double V4 __attribute__((vector_size(32)));
__attribute__((target("avx2"))) inline void AccumulateLimbListAvx2(
    int n, const std::int16_t* voxel, const std::int16_t* index, const double* information,
    const std::uint8_t* band, const BandScale* scales, SumLimbs* sums, bool add) {
  for (int j = 0; j < n; ++j) {
    const int o = voxel[j];
    const double* down = scales[band[o]].down;
    const double* c = information + 6 * index[j];
    AccumulateEntries<V4>(sums[o], c, 0, down[0], down[1], add);
    AccumulateEntries<V2>(sums[o], c, 4, down[0], down[1], add);
  }
}
#endif

inline void AccumulateLimbList(int n, const std::int16_t* voxel, const std::int16_t* index,
                               const double* information, const std::uint8_t* band, SumLimbs* sums,
                               bool add) {
  const BandScale* scales = BandScales().data();
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
  static const bool avx2 = __builtin_cpu_supports("avx2");
  if (avx2) return AccumulateLimbListAvx2(n, voxel, index, information, band, scales, sums, add);
#endif
  for (int j = 0; j < n; ++j)
    AccumulateLimbs(sums[voxel[j]], information + 6 * index[j], scales[band[voxel[j]]].down, add);
}

// s = 0 as nine 16-byte stores (a value-initialisation compiles to `rep stos`, whose start-up
// cost was a tenth of a full evaluation's information sums).
__attribute__((always_inline)) inline void ClearLimbs(SumLimbs& s) {
  const V2 zero = {0.0, 0.0};
  for (double* row : {s.hi, s.mid, s.lo})
    for (int k = 0; k < 6; k += 2) std::memcpy(row + k, &zero, sizeof(zero));
}

// Entry k of s in units of 2^q: the integer Sum6 holds for the same contributions.
inline Int128 SumLimbsUnits(const SumLimbs& s, int k) {
  return static_cast<Int128>(static_cast<std::int64_t>(s.hi[k] * 0x1p-70)) *
             (static_cast<Int128>(1) << 70) +
         static_cast<Int128>(static_cast<std::int64_t>(s.mid[k] * 0x1p-35)) *
             (static_cast<Int128>(1) << 35) +
         static_cast<Int128>(static_cast<std::int64_t>(s.lo[k]));
}

// Entry k of s as the nearest double, scaled by 2^q (`up`, two factors): the bits of
// ToDouble(sum of ToFixed(c, q)) * up[0] * up[1].
inline double SumLimbsToDouble(const SumLimbs& s, int k, const double* up) {
  return ToDouble(SumLimbsUnits(s, k)) * up[0] * up[1];
}

// The same six doubles without integers, two entries at a time in SSE2 (the field evaluation's
// route; SumLimbsToDouble is its reference). The limbs are integers (in units of 2^q) below 2^123
// in magnitude whose sum is SumLimbsUnits' int128, so ToDouble of it is the sum of three doubles
// rounded once to nearest, ties to even: Boldo and Melquiond's correctly rounded sum of any three
// doubles ("Emulation of a FMA and correctly rounded sums: proved algorithms using rounding to
// odd", IEEE Trans. Computers 57(4), 2008, proved in Coq) gives it with two exact 2Sums (Knuth),
// their two errors added rounded to odd, and that added to the larger part rounded to nearest.
// Round-to-odd is emulated: the nearest sum, and when that is inexact and its last significand
// bit is 0, its neighbour on the side of the error. Valid for finite values whose sum does not
// overflow, without underflow (all of them integers here). information_sum_test checks the bits
// against the int128 route, ties and near-ties included.
typedef std::uint64_t U2 __attribute__((vector_size(16)));

// a + b = s + TwoSumError(a, b, s) exactly, for s = a + b rounded to nearest (Knuth's 2Sum).
__attribute__((always_inline)) inline V2 TwoSumError(V2 a, V2 b, V2 s) {
  const V2 bb = s - a;
  return (a - (s - bb)) + (b - bb);
}

// x + y rounded to odd: x + y if it is a double, else of the two doubles around it the one whose
// last significand bit is 1 (one unit more in the magnitude when x + y's error has s's sign, one
// less when not).
__attribute__((always_inline)) inline V2 AddRoundToOdd(V2 x, V2 y) {
  const V2 s = x + y;
  const V2 e = TwoSumError(x, y, s);
  U2 sb, eb;
  std::memcpy(&sb, &s, sizeof(sb));
  std::memcpy(&eb, &e, sizeof(eb));
  const U2 inexact = (U2)(e != 0.0) & 1;
  const U2 to_other = inexact & ~sb;  // bit 0: inexact and even
  const U2 outward = ~((sb ^ eb) >> 63);
  const U2 r = sb + (to_other & outward & 1) - (to_other & ~outward & 1);
  V2 out;
  std::memcpy(&out, &r, sizeof(out));
  return out;
}

__attribute__((always_inline)) inline void SumLimbsToDoubles(const SumLimbs& s, const double* up,
                                                             double out[6]) {
  const V2 u0 = {up[0], up[0]}, u1 = {up[1], up[1]};
  for (int k = 0; k < 6; k += 2) {
    V2 a, b, c;
    std::memcpy(&a, s.hi + k, sizeof(a));
    std::memcpy(&b, s.mid + k, sizeof(b));
    std::memcpy(&c, s.lo + k, sizeof(c));
    const V2 uh = b + c, ul = TwoSumError(b, c, uh);
    const V2 th = a + uh, tl = TwoSumError(a, uh, th);
    const V2 v = (th + AddRoundToOdd(tl, ul)) * u0 * u1;
    std::memcpy(out + k, &v, sizeof(v));
  }
}

}  // namespace pandora::information
