#pragma once
/// \file text.h
/// Small text helpers shared by the libraries' tables and messages.

#include <cstddef>
#include <string>
#include <vector>

namespace pandora {

/// printf into a std::string (any length).
std::string Format(const char* format, ...) __attribute__((format(printf, 1, 2)));

/// Standard base64 (RFC 4648, with padding): report images, glTF buffers.
std::string Base64(const std::string& bytes);

/// Empty when `s` is well-formed UTF-8 without control characters (U+0000..U+001F, U+007F);
/// otherwise what is wrong ("invalid UTF-8 at byte 5", "a control character (0x01) at byte 5"),
/// for the readers of names that end up as JSON strings (camera ids from calibration files).
std::string CheckPrintableUtf8(const std::string& s);

/// `s` in single quotes: 'name'.
std::string Quoted(const std::string& s);

/// 'a', 'b', 'c'.
std::string JoinQuoted(const std::vector<std::string>& items);

/// Levenshtein distance (insertions, deletions and substitutions of bytes).
std::size_t EditDistance(const std::string& a, const std::string& b);

/// A hint for an unknown `word`: "did you mean 'X'? " when a candidate is close (within a third of
/// its length in edits, at least 2, or a prefix of 3 or more), then "`what`: 'a', 'b', ...".
std::string DidYouMean(const std::string& word, const std::vector<std::string>& candidates,
                       const std::string& what);

}  // namespace pandora
