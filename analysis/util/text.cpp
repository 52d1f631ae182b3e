#include "analysis/util/text.h"

#include <algorithm>
#include <cstdarg>
#include <cstdio>
#include <vector>

namespace pandora {

std::string Format(const char* format, ...) {
  va_list args;
  va_start(args, format);
  va_list again;
  va_copy(again, args);
  const int n = std::vsnprintf(nullptr, 0, format, args);
  va_end(args);
  std::string out;
  if (n > 0) {
    std::vector<char> buffer(static_cast<std::size_t>(n) + 1);
    std::vsnprintf(buffer.data(), buffer.size(), format, again);
    out.assign(buffer.data(), static_cast<std::size_t>(n));
  }
  va_end(again);
  return out;
}

std::string Base64(const std::string& bytes) {
  static constexpr char kAlphabet[] =
      "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  out.reserve((bytes.size() + 2) / 3 * 4);
  std::size_t i = 0;
  for (; i + 2 < bytes.size(); i += 3) {
    const unsigned v = (static_cast<unsigned char>(bytes[i]) << 16) |
                       (static_cast<unsigned char>(bytes[i + 1]) << 8) |
                       static_cast<unsigned char>(bytes[i + 2]);
    out += kAlphabet[v >> 18];
    out += kAlphabet[(v >> 12) & 63];
    out += kAlphabet[(v >> 6) & 63];
    out += kAlphabet[v & 63];
  }
  if (i < bytes.size()) {
    unsigned v = static_cast<unsigned char>(bytes[i]) << 16;
    if (i + 1 < bytes.size()) v |= static_cast<unsigned char>(bytes[i + 1]) << 8;
    out += kAlphabet[v >> 18];
    out += kAlphabet[(v >> 12) & 63];
    out += i + 1 < bytes.size() ? kAlphabet[(v >> 6) & 63] : '=';
    out += '=';
  }
  return out;
}

std::string CheckPrintableUtf8(const std::string& s) {
  const auto* b = reinterpret_cast<const unsigned char*>(s.data());
  const std::size_t n = s.size();
  for (std::size_t i = 0; i < n;) {
    const unsigned c = b[i];
    if (c < 0x20 || c == 0x7f) return Format("a control character (0x%02x) at byte %zu", c, i);
    if (c < 0x80) {
      ++i;
      continue;
    }
    int len = 0;
    unsigned code = 0;
    if (c >= 0xc2 && c <= 0xdf)
      len = 2, code = c & 0x1f;
    else if (c >= 0xe0 && c <= 0xef)
      len = 3, code = c & 0x0f;
    else if (c >= 0xf0 && c <= 0xf4)
      len = 4, code = c & 0x07;
    else
      return Format("invalid UTF-8 at byte %zu", i);
    if (i + len > n) return Format("invalid UTF-8 at byte %zu", i);
    for (int k = 1; k < len; ++k) {
      if ((b[i + k] & 0xc0) != 0x80) return Format("invalid UTF-8 at byte %zu", i);
      code = (code << 6) | (b[i + k] & 0x3f);
    }
    // Overlong forms, surrogates and code points past U+10FFFF.
    if ((len == 3 && code < 0x800) || (len == 4 && (code < 0x10000 || code > 0x10ffff)) ||
        (code >= 0xd800 && code <= 0xdfff))
      return Format("invalid UTF-8 at byte %zu", i);
    i += len;
  }
  return "";
}

std::string Quoted(const std::string& s) { return "'" + s + "'"; }

std::string JoinQuoted(const std::vector<std::string>& items) {
  std::string out;
  for (std::size_t i = 0; i < items.size(); ++i) out += (i ? ", " : "") + Quoted(items[i]);
  return out;
}

std::size_t EditDistance(const std::string& a, const std::string& b) {
  std::vector<std::size_t> row(b.size() + 1);
  for (std::size_t j = 0; j <= b.size(); ++j) row[j] = j;
  for (std::size_t i = 1; i <= a.size(); ++i) {
    std::size_t diagonal = row[0];
    row[0] = i;
    for (std::size_t j = 1; j <= b.size(); ++j) {
      const std::size_t above = row[j];
      row[j] = std::min({row[j] + 1, row[j - 1] + 1, diagonal + (a[i - 1] == b[j - 1] ? 0 : 1)});
      diagonal = above;
    }
  }
  return row[b.size()];
}

std::string DidYouMean(const std::string& word, const std::vector<std::string>& candidates,
                       const std::string& what) {
  std::string best;
  std::size_t best_distance = std::string::npos;
  for (const std::string& c : candidates) {
    std::size_t d = EditDistance(word, c);
    const bool prefix = word.size() >= 3 && (c.rfind(word, 0) == 0 || word.rfind(c, 0) == 0);
    const std::size_t limit = std::max<std::size_t>(2, c.size() / 3);
    if (d > limit && !prefix) continue;
    if (prefix) d = std::min(d, limit);
    if (d < best_distance) {
      best_distance = d;
      best = c;
    }
  }
  std::string hint;
  if (!best.empty()) hint = "did you mean " + Quoted(best) + "? ";
  return hint + what + ": " + JoinQuoted(candidates);
}

}  // namespace pandora
