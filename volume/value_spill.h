#pragma once
/// \file value_spill.h
/// Exact order statistics over more values than memory should hold: a streamed run's sigma_max and
/// resolution values (`pandora analyze --stream`, docs/scale.md) are appended tile by tile to an
/// unnamed temporary file and read back for the summary's nearest-rank percentiles, which equal
/// NearestRankPercentile (volume/summary.h) over all the values, with a few hundred kB of memory.

#include <cstdint>
#include <cstdio>
#include <optional>
#include <string>
#include <vector>

namespace pandora {

/// Opens an unnamed temporary file in `folder` for reading and writing (removed by the system when
/// it is closed, even when the process is killed; on file systems without O_TMPFILE a named file
/// unlinked at once). Throws InputError(blame, "", ...) when it cannot be created.
std::FILE* OpenTemporaryFile(const std::string& folder, const std::string& blame);

class ValueSpill {
 public:
  /// Opens an unnamed temporary file in `folder` (removed by the system when it is closed, even
  /// when the process is killed). Throws InputError(blame, "", ...) when it cannot be created.
  ValueSpill(const std::string& folder, const std::string& blame);
  ~ValueSpill();
  ValueSpill(const ValueSpill&) = delete;
  ValueSpill& operator=(const ValueSpill&) = delete;

  /// Appends `values` (finite). Throws InputError(blame, ...) when the file cannot be written (a
  /// full disk).
  void Append(const std::vector<float>& values);
  std::int64_t size() const { return count_; }

  /// The nearest-rank percentiles `p` (in [0, 100]) of every value appended, each equal to
  /// NearestRankPercentile(all values, p); nullopt when there are none. Two passes over the file:
  /// the upper 16 bits of each value's order-preserving key, then the lower 16 within the bins the
  /// ranks fall in.
  std::vector<std::optional<double>> Percentiles(const std::vector<double>& p) const;
  /// The number of values v with v <= limit (compared in double, as summary.json's shares are).
  std::int64_t CountAtMost(double limit) const;

  /// The two passes of Percentiles apart, for values spilled by several processes (`pandora analyze
  /// --stream --mpi`): every process's counts are summed before the next step. First the counts by
  /// the upper 16 bits of each value's order-preserving key (65,536 counts)...
  std::vector<std::int64_t> HighCounts() const;
  /// ...then, for each of `bins`, the counts by the lower 16 bits of the values in that bin (65,536
  /// per bin, bin after bin).
  std::vector<std::int64_t> LowCounts(const std::vector<std::uint32_t>& bins) const;

 private:
  template <typename Fn>
  void ForEachChunk(Fn&& fn) const;
  std::FILE* file_ = nullptr;
  std::string blame_;
  std::int64_t count_ = 0;
};

/// Where each nearest-rank percentile falls, from the (summed) HighCounts: the bin and the 1-based
/// rank inside it; no bins when there are no values.
struct PercentileBins {
  std::vector<std::uint32_t> bins;
  std::vector<std::int64_t> inside;
};
PercentileBins SelectPercentileBins(const std::vector<std::int64_t>& high,
                                    const std::vector<double>& p);
/// The counts of HighCounts and LowCounts over `n` values in memory, times `sign` (+1, or -1 for
/// values taken out of a multiset), added to `high` (65,536 counts) and `low` (65,536 per bin).
void AddHighCounts(const float* values, std::size_t n, std::int64_t sign,
                   std::vector<std::int64_t>& high);
void AddLowCounts(const float* values, std::size_t n, std::int64_t sign,
                  const std::vector<std::uint32_t>& bins, std::vector<std::int64_t>& low);
/// The percentiles (nullopt when there are no values), from the (summed) LowCounts(selection.bins).
std::vector<std::optional<double>> ResolvePercentiles(const PercentileBins& selection,
                                                      const std::vector<std::int64_t>& low,
                                                      std::size_t percentile_count);

}  // namespace pandora
