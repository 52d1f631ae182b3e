#pragma once
/// \file text.h
/// Small text helpers shared by the libraries' tables and messages.

#include <string>

namespace pandora {

/// printf into a std::string (any length).
std::string Format(const char* format, ...) __attribute__((format(printf, 1, 2)));

/// Standard base64 (RFC 4648, with padding): report images, glTF buffers.
std::string Base64(const std::string& bytes);

/// Empty when `s` is well-formed UTF-8 without control characters (U+0000..U+001F, U+007F);
/// otherwise what is wrong ("invalid UTF-8 at byte 5", "a control character (0x01) at byte 5"),
/// for the readers of names that end up as JSON strings (camera ids from calibration files).
std::string CheckPrintableUtf8(const std::string& s);

}  // namespace pandora
