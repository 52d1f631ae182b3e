#pragma once
/// \file error.h
/// The one exception type for bad input. Expected outcomes (a ray misses, a point is not seen) are
/// values, never exceptions.

#include <stdexcept>
#include <string>

namespace pandora {

/// Bad input: a malformed or inconsistent file, a number out of range, an unwritable output.
/// Carries the file, the JSON path of the offending field ("$" for the whole file, "" when no JSON
/// is involved), the reason and a hint on what to do next. `what()` is one line:
///   `FILE: JSON_PATH: REASON (hint: HINT)`.
class InputError : public std::runtime_error {
 public:
  InputError(std::string file, std::string json_path, std::string reason, std::string hint = {});

  const std::string& file() const { return file_; }
  const std::string& json_path() const { return json_path_; }
  const std::string& reason() const { return reason_; }
  const std::string& hint() const { return hint_; }

 private:
  std::string file_, json_path_, reason_, hint_;
};

}  // namespace pandora
