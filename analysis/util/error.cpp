#include "analysis/util/error.h"

#include <cctype>
#include <utility>

namespace pandora {
namespace {

// Each `{field}` of `text` replaced by rename(field) where that is not empty.
std::string Rename(const std::string& text,
                   const std::function<std::string(const std::string&)>& rename) {
  std::string out;
  for (std::size_t i = 0; i < text.size();) {
    std::size_t j = i + 1;
    if (text[i] == '{')
      while (j < text.size() &&
             (std::islower(static_cast<unsigned char>(text[j])) ||
              std::isdigit(static_cast<unsigned char>(text[j])) || text[j] == '_'))
        ++j;
    if (text[i] == '{' && j > i + 1 && j < text.size() && text[j] == '}') {
      const std::string field = text.substr(i + 1, j - i - 1);
      const std::string name = rename(field);
      out += name.empty() ? text.substr(i, j + 1 - i) : name;
      i = j + 1;
    } else {
      out += text[i++];
    }
  }
  return out;
}

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

std::string Option(const std::string& field) { return "{" + field + "}"; }

InputError RenameOptions(const InputError& e,
                         const std::function<std::string(const std::string& field)>& name) {
  return InputError(Rename(e.file(), name), Rename(e.json_path(), name), Rename(e.reason(), name),
                    Rename(e.hint(), name));
}

}  // namespace pandora
