#include "analysis/util/error.h"

#include <utility>

namespace pandora {
namespace {

std::string FormatMessage(const std::string& file, const std::string& path,
                          const std::string& reason, const std::string& hint) {
  std::string s = file.empty() ? std::string("<input>") : file;
  if (!path.empty()) s += ": " + path;
  s += ": " + reason;
  if (!hint.empty()) s += " (hint: " + hint + ")";
  // One line, whatever the parts contain.
  for (char& c : s)
    if (c == '\n' || c == '\r') c = ' ';
  return s;
}

}  // namespace

InputError::InputError(std::string file, std::string json_path, std::string reason,
                       std::string hint)
    : std::runtime_error(FormatMessage(file, json_path, reason, hint)),
      file_(std::move(file)),
      json_path_(std::move(json_path)),
      reason_(std::move(reason)),
      hint_(std::move(hint)) {}

}  // namespace pandora
