#pragma once
/// \file sha256.h
/// SHA-256 (FIPS 180-4) of a byte string, used to fingerprint input files in outputs.

#include <string>

namespace pandora {

/// SHA-256 digest of `bytes` (any content, binary included) as 64 lowercase hexadecimal digits.
/// Never throws except std::bad_alloc.
std::string Sha256Hex(const std::string& bytes);

}  // namespace pandora
