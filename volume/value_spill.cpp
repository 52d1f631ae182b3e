#include "volume/value_spill.h"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <map>

#include "analysis/util/error.h"

namespace pandora {
namespace {

constexpr std::size_t kChunk = 1 << 18;  // floats per read: 1 MiB

// Order-preserving key of a float: unsigned comparison of keys is the numeric order (-0 before +0).
std::uint32_t Key(float v) {
  std::uint32_t bits;
  std::memcpy(&bits, &v, 4);
  return (bits & 0x80000000u) ? ~bits : (bits | 0x80000000u);
}

float FromKey(std::uint32_t key) {
  const std::uint32_t bits = (key & 0x80000000u) ? (key & 0x7fffffffu) : ~key;
  float v;
  std::memcpy(&v, &bits, 4);
  return v;
}

}  // namespace

std::FILE* OpenTemporaryFile(const std::string& folder, const std::string& blame) {
  int fd = ::open(folder.c_str(), O_TMPFILE | O_RDWR | O_CLOEXEC, 0600);
  if (fd < 0) {  // file systems without O_TMPFILE: a named file, unlinked at once
    std::string name = folder + "/.pandora-values-XXXXXX";
    fd = ::mkstemp(name.data());
    if (fd >= 0) ::unlink(name.c_str());
  }
  std::FILE* file = fd >= 0 ? ::fdopen(fd, "w+b") : nullptr;
  if (!file) {
    const std::string why = std::strerror(errno);
    if (fd >= 0) ::close(fd);
    throw InputError(blame, "", "cannot create a temporary file in " + folder + ": " + why);
  }
  return file;
}

ValueSpill::ValueSpill(const std::string& folder, const std::string& blame)
    : file_(OpenTemporaryFile(folder, blame)), blame_(blame) {}

ValueSpill::~ValueSpill() {
  if (file_) std::fclose(file_);
}

void ValueSpill::Append(const std::vector<float>& values) {
  if (values.empty()) return;
  if (std::fseek(file_, 0, SEEK_END) != 0 ||
      std::fwrite(values.data(), sizeof(float), values.size(), file_) != values.size() ||
      std::fflush(file_) != 0)
    throw InputError(
        blame_, "",
        std::string("cannot write a temporary file of values: ") + std::strerror(errno));
  count_ += static_cast<std::int64_t>(values.size());
}

template <typename Fn>
void ValueSpill::ForEachChunk(Fn&& fn) const {
  std::vector<float> chunk(kChunk);
  if (std::fseek(file_, 0, SEEK_SET) != 0)
    throw InputError(blame_, "",
                     std::string("cannot read back a temporary file: ") + std::strerror(errno));
  std::int64_t left = count_;
  while (left > 0) {
    const std::size_t want = static_cast<std::size_t>(std::min<std::int64_t>(left, kChunk));
    if (std::fread(chunk.data(), sizeof(float), want, file_) != want)
      throw InputError(blame_, "", "a temporary file of values was cut short");
    fn(chunk.data(), want);
    left -= static_cast<std::int64_t>(want);
  }
}

void AddHighCounts(const float* values, std::size_t n, std::int64_t sign,
                   std::vector<std::int64_t>& high) {
  high.resize(1 << 16, 0);
  for (std::size_t i = 0; i < n; ++i) high[Key(values[i]) >> 16] += sign;
}

void AddLowCounts(const float* values, std::size_t n, std::int64_t sign,
                  const std::vector<std::uint32_t>& bins, std::vector<std::int64_t>& low) {
  low.resize(bins.size() << 16, 0);
  if (bins.empty()) return;
  // Each distinct bin's place: the first index asking for it (copied to the others at the end).
  std::map<std::uint32_t, std::size_t> first;
  for (std::size_t i = 0; i < bins.size(); ++i) first.emplace(bins[i], i);
  for (std::size_t i = 0; i < n; ++i) {
    const std::uint32_t k = Key(values[i]);
    const auto it = first.find(k >> 16);
    if (it != first.end()) low[(it->second << 16) | (k & 0xffffu)] += sign;
  }
  for (std::size_t i = 0; i < bins.size(); ++i) {
    const std::size_t from = first[bins[i]];
    if (from != i)
      std::copy(low.begin() + std::ptrdiff_t(from << 16),
                low.begin() + std::ptrdiff_t((from + 1) << 16),
                low.begin() + std::ptrdiff_t(i << 16));
  }
}

std::vector<std::int64_t> ValueSpill::HighCounts() const {
  std::vector<std::int64_t> high(1 << 16, 0);
  ForEachChunk([&](const float* v, std::size_t m) { AddHighCounts(v, m, 1, high); });
  return high;
}

std::vector<std::int64_t> ValueSpill::LowCounts(const std::vector<std::uint32_t>& bins) const {
  std::vector<std::int64_t> low(bins.size() << 16, 0);
  if (bins.empty()) return low;
  // (A bin asked for twice is counted once and copied, after every chunk: the copies end whole.)
  ForEachChunk([&](const float* v, std::size_t m) { AddLowCounts(v, m, 1, bins, low); });
  return low;
}

PercentileBins SelectPercentileBins(const std::vector<std::int64_t>& high,
                                    const std::vector<double>& p) {
  PercentileBins out;
  std::int64_t count = 0;
  for (std::int64_t c : high) count += c;
  if (count == 0) return out;
  const double n = static_cast<double>(count);
  for (double q : p) {
    // The 1-based rank, as NearestRankPercentile computes it, then its bin.
    const auto rank = static_cast<std::int64_t>(std::clamp(std::ceil(q / 100.0 * n), 1.0, n));
    std::int64_t below = 0;
    std::uint32_t b = 0;
    while (below + high[b] < rank) below += high[b++];
    out.bins.push_back(b);
    out.inside.push_back(rank - below);
  }
  return out;
}

std::vector<std::optional<double>> ResolvePercentiles(const PercentileBins& selection,
                                                      const std::vector<std::int64_t>& low,
                                                      std::size_t percentile_count) {
  std::vector<std::optional<double>> out(percentile_count);
  for (std::size_t i = 0; i < selection.bins.size() && i < percentile_count; ++i) {
    const std::int64_t* counts = low.data() + (std::ptrdiff_t(i) << 16);
    std::int64_t below = 0;
    std::uint32_t l = 0;
    while (below + counts[l] < selection.inside[i]) below += counts[l++];
    out[i] = FromKey((selection.bins[i] << 16) | l);
  }
  return out;
}

std::vector<std::optional<double>> ValueSpill::Percentiles(const std::vector<double>& p) const {
  const PercentileBins selection = SelectPercentileBins(HighCounts(), p);
  return ResolvePercentiles(selection, LowCounts(selection.bins), p.size());
}

std::int64_t ValueSpill::CountAtMost(double limit) const {
  std::int64_t count = 0;
  ForEachChunk([&](const float* v, std::size_t m) {
    for (std::size_t i = 0; i < m; ++i) count += (double(v[i]) <= limit);
  });
  return count;
}

}  // namespace pandora
