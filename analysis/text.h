#pragma once
/// \file text.h
/// Small text helpers shared by the libraries' tables and messages.

#include <string>

namespace pandora {

/// printf into a std::string (any length).
std::string Format(const char* format, ...) __attribute__((format(printf, 1, 2)));

/// Standard base64 (RFC 4648, with padding): report images, glTF buffers.
std::string Base64(const std::string& bytes);

}  // namespace pandora
