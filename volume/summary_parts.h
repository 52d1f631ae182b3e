#pragma once
/// \file summary_parts.h
/// A summary step computed part by part. N-1 criticality, pixel-size targets, the fields over time
/// and the PTZ fields each find, over part of the region, whole-number counts that add up and lists
/// of values whose nearest-rank percentiles they report; a finishing step turns the totals into the
/// summary. An in-memory run has one part; a streamed run (`pandora analyze --stream`) has one per
/// tile, its lists spilled to disk (volume/value_spill.h), and under MPI one set per process, whose
/// counts are summed across the processes (docs/scale.md). The summary is the same either way, bit
/// for bit: counts add exactly in any order, and a nearest-rank percentile depends only on the
/// multiset of values.

#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace pandora {

class ValueSpill;

/// What one part of the region gives a summary step. The step fixes the layout (which count and
/// which list is what); parts of one step add up index by index.
struct SummaryParts {
  std::vector<std::int64_t> counts;       ///< Added.
  std::vector<std::vector<float>> lists;  ///< Appended (multisets: the order does not matter).
  std::vector<double> seconds;            ///< Timings, added (not part of any comparison).

  /// Adds `other` (the same layout; a default-constructed part takes `other`'s).
  void Add(const SummaryParts& other);
};

/// One list of a percentile query with its sign: the query's multiset is the sum of its lists of
/// sign +1 less those of sign -1 (each of which must be contained in that sum).
struct ListTerm {
  std::size_t list = 0;
  int sign = 1;
};

/// A query's answer: the number of values in its multiset and the nearest-rank percentiles asked
/// for (NearestRankPercentile, volume/summary.h; nullopt when the multiset is empty).
struct ListPercentiles {
  std::int64_t count = 0;
  std::vector<std::optional<double>> values;
};

/// Where a finishing step reads its lists' percentiles from.
class PercentileSource {
 public:
  virtual ~PercentileSource() = default;
  /// Collective under MPI: every process asks the same queries in the same order.
  virtual ListPercentiles Percentiles(const std::vector<ListTerm>& terms,
                                      const std::vector<double>& p) = 0;
  /// Percentiles of one list.
  ListPercentiles Percentiles(std::size_t list, const std::vector<double>& p) {
    return Percentiles(std::vector<ListTerm>{{list, 1}}, p);
  }
};

/// The lists of an in-memory part. A query of one list uses NearestRankPercentile; a signed query
/// counts by the values' order-preserving keys as ValueSpill does (each list's upper counts kept
/// for the next query).
class InMemoryPercentiles : public PercentileSource {
 public:
  explicit InMemoryPercentiles(const std::vector<std::vector<float>>& lists) : lists_(lists) {}
  using PercentileSource::Percentiles;
  ListPercentiles Percentiles(const std::vector<ListTerm>& terms,
                              const std::vector<double>& p) override;

 private:
  const std::vector<std::vector<float>>& lists_;
  std::map<std::size_t, std::vector<std::int64_t>> high_;
};

/// Sums counts over the processes of an MPI run and returns the sum on every process (identity for
/// one process).
using CountReducer = std::function<std::vector<std::int64_t>(const std::vector<std::int64_t>&)>;

/// A streamed run's parts of one summary step: counts added in memory, lists appended to spill
/// files in `folder` (one per list, created as lists appear). The percentiles are those of every
/// process's lists (their counts summed by `reduce`); Counts() is this process's until Reduce().
class SpilledParts : public PercentileSource {
 public:
  SpilledParts(std::string folder, std::string blame, CountReducer reduce = nullptr);
  ~SpilledParts() override;
  SpilledParts(const SpilledParts&) = delete;
  SpilledParts& operator=(const SpilledParts&) = delete;

  /// Adds one tile's part (its lists written to disk, then freed).
  void Add(SummaryParts&& part);
  /// A collective under MPI: the counts and timings summed over every process, on every process,
  /// and the number of lists made the same everywhere. Call once, after the last Add.
  void Reduce();
  const std::vector<std::int64_t>& Counts() const { return counts_; }
  const std::vector<double>& Seconds() const { return seconds_; }

  using PercentileSource::Percentiles;
  ListPercentiles Percentiles(const std::vector<ListTerm>& terms,
                              const std::vector<double>& p) override;

 private:
  std::string folder_, blame_;
  CountReducer reduce_;
  std::vector<std::int64_t> counts_;
  std::vector<double> seconds_;
  std::vector<std::unique_ptr<ValueSpill>> spills_;
  // A list's HighCounts once it is asked for a second time (N-1 asks for the intact list with
  // every camera), and the lists asked for once.
  std::map<std::size_t, std::vector<std::int64_t>> high_;
  std::vector<std::uint8_t> asked_;
};

/// An exact sum of values in [0, 1] in any order: each value's round-toward-zero multiple of 2^-64
/// as three base-2^32 limbs, which add as counts (up to 2^31 values). What a mean over the region
/// adds up per tile and equals in memory.
inline constexpr int kFixedLimbs = 3;
void AddFixedLimbs(double value, std::int64_t* limbs);
/// The sum the limbs hold.
double FixedLimbsToDouble(const std::int64_t* limbs);

}  // namespace pandora
