// A summary step computed part by part (volume/summary_parts.h).
#include "volume/summary_parts.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "volume/summary.h"
#include "volume/value_spill.h"

namespace pandora {
namespace {

// Adds `b` to `a` index by index (a grows to b's size).
template <typename T>
void AddInto(std::vector<T>& a, const std::vector<T>& b) {
  if (a.size() < b.size()) a.resize(b.size(), T{});
  for (std::size_t i = 0; i < b.size(); ++i) a[i] += b[i];
}

// The signed counting route: the multiset's upper counts, the bins its ranks fall in, its lower
// counts in those bins (`high()` and `low(bins)` give the terms' counts, signed and summed).
template <typename High, typename Low>
ListPercentiles CountedPercentiles(const std::vector<double>& p, High&& high_counts,
                                   Low&& low_counts) {
  const std::vector<std::int64_t> high = high_counts();
  ListPercentiles out;
  for (std::int64_t c : high) {
    if (c < 0) throw std::logic_error("a percentile query takes out values it does not hold");
    out.count += c;
  }
  const PercentileBins selection = SelectPercentileBins(high, p);
  out.values = ResolvePercentiles(selection, low_counts(selection.bins), p.size());
  return out;
}

}  // namespace

void SummaryParts::Add(const SummaryParts& other) {
  AddInto(counts, other.counts);
  AddInto(seconds, other.seconds);
  if (lists.size() < other.lists.size()) lists.resize(other.lists.size());
  for (std::size_t i = 0; i < other.lists.size(); ++i)
    lists[i].insert(lists[i].end(), other.lists[i].begin(), other.lists[i].end());
}

ListPercentiles InMemoryPercentiles::Percentiles(const std::vector<ListTerm>& terms,
                                                 const std::vector<double>& p) {
  static const std::vector<float> kNone;
  const auto list = [&](std::size_t i) -> const std::vector<float>& {
    return i < lists_.size() ? lists_[i] : kNone;
  };
  if (terms.size() == 1 && terms[0].sign == 1) {  // one list: no counting needed
    const std::vector<float>& values = list(terms[0].list);
    ListPercentiles out;
    out.count = static_cast<std::int64_t>(values.size());
    for (double q : p) out.values.push_back(NearestRankPercentile(values, q));
    return out;
  }
  return CountedPercentiles(
      p,
      [&] {
        std::vector<std::int64_t> high(1 << 16, 0);
        for (const ListTerm& t : terms) {
          auto it = high_.find(t.list);
          if (it == high_.end()) {
            std::vector<std::int64_t> h(1 << 16, 0);
            AddHighCounts(list(t.list).data(), list(t.list).size(), 1, h);
            it = high_.emplace(t.list, std::move(h)).first;
          }
          for (std::size_t b = 0; b < high.size(); ++b) high[b] += t.sign * it->second[b];
        }
        return high;
      },
      [&](const std::vector<std::uint32_t>& bins) {
        std::vector<std::int64_t> low(bins.size() << 16, 0);
        for (const ListTerm& t : terms)
          AddLowCounts(list(t.list).data(), list(t.list).size(), t.sign, bins, low);
        return low;
      });
}

SpilledParts::SpilledParts(std::string folder, std::string blame, CountReducer reduce)
    : folder_(std::move(folder)), blame_(std::move(blame)), reduce_(std::move(reduce)) {}

SpilledParts::~SpilledParts() = default;

void SpilledParts::Add(SummaryParts&& part) {
  high_.clear();
  asked_.clear();
  AddInto(counts_, part.counts);
  AddInto(seconds_, part.seconds);
  while (spills_.size() < part.lists.size())
    spills_.push_back(std::make_unique<ValueSpill>(folder_, blame_));
  for (std::size_t i = 0; i < part.lists.size(); ++i) {
    spills_[i]->Append(part.lists[i]);
    std::vector<float>().swap(part.lists[i]);
  }
}

void SpilledParts::Reduce() {
  if (!reduce_) return;
  // The layout first: every process with tiles has the same sizes, one without has none; the
  // sum of the sizes over the number of processes with some is that size.
  const auto some = [](std::size_t n) { return std::int64_t(n > 0 ? 1 : 0); };
  const std::vector<std::int64_t> sizes =
      reduce_({std::int64_t(counts_.size()), some(counts_.size()), std::int64_t(seconds_.size()),
               some(seconds_.size()), std::int64_t(spills_.size()), some(spills_.size())});
  const auto size = [&](int i) {
    return sizes[2 * i + 1] > 0 ? std::size_t(sizes[2 * i] / sizes[2 * i + 1]) : std::size_t(0);
  };
  counts_.resize(size(0), 0);
  seconds_.resize(size(1), 0.0);
  while (spills_.size() < size(2)) spills_.push_back(std::make_unique<ValueSpill>(folder_, blame_));
  counts_ = reduce_(counts_);
  // Timings travel as whole nanoseconds.
  std::vector<std::int64_t> ns(seconds_.size());
  for (std::size_t i = 0; i < ns.size(); ++i) ns[i] = std::llround(seconds_[i] * 1e9);
  ns = reduce_(ns);
  for (std::size_t i = 0; i < ns.size(); ++i) seconds_[i] = double(ns[i]) * 1e-9;
}

ListPercentiles SpilledParts::Percentiles(const std::vector<ListTerm>& terms,
                                          const std::vector<double>& p) {
  // Every process counts its own spills; the sums decide (the same on every process).
  const auto sum = [&](std::vector<std::int64_t> v) { return reduce_ ? reduce_(v) : v; };
  return CountedPercentiles(
      p,
      [&] {
        std::vector<std::int64_t> high(1 << 16, 0);
        for (const ListTerm& t : terms)
          if (t.list < spills_.size()) {
            if (asked_.size() < spills_.size()) asked_.resize(spills_.size(), 0);
            std::vector<std::int64_t> once;
            const std::vector<std::int64_t>* h = nullptr;
            if (const auto it = high_.find(t.list); it != high_.end())
              h = &it->second;
            else if (asked_[t.list]++ > 0)
              h = &(high_[t.list] = spills_[t.list]->HighCounts());
            else
              h = &(once = spills_[t.list]->HighCounts());
            for (std::size_t b = 0; b < high.size(); ++b) high[b] += t.sign * (*h)[b];
          }
        return sum(std::move(high));
      },
      [&](const std::vector<std::uint32_t>& bins) {
        std::vector<std::int64_t> low(bins.size() << 16, 0);
        for (const ListTerm& t : terms)
          if (t.list < spills_.size()) {
            const std::vector<std::int64_t> l = spills_[t.list]->LowCounts(bins);
            for (std::size_t i = 0; i < low.size(); ++i) low[i] += t.sign * l[i];
          }
        return sum(std::move(low));
      });
}

void AddFixedLimbs(double value, std::int64_t* limbs) {
  if (!(value >= 0.0) || value > 1.0) throw std::invalid_argument("AddFixedLimbs: not in [0, 1]");
  const auto fixed = static_cast<unsigned __int128>(std::ldexp(value, 64));  // toward zero
  for (int k = 0; k < kFixedLimbs; ++k)
    limbs[k] += static_cast<std::int64_t>((fixed >> (32 * k)) & 0xffffffffu);
}

double FixedLimbsToDouble(const std::int64_t* limbs) {
  unsigned __int128 total = 0;
  for (int k = kFixedLimbs - 1; k >= 0; --k)
    total = (total << 32) + static_cast<unsigned __int128>(limbs[k]);
  return std::ldexp(static_cast<double>(total), -64);
}

}  // namespace pandora
