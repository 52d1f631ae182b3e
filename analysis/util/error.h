#pragma once
/// \file error.h
/// The one exception type for bad input. Expected outcomes (a ray misses, a point is not seen) are
/// values, never exceptions.

#include <functional>
#include <stdexcept>
#include <string>

namespace pandora {

/// Bad input: a malformed or inconsistent file, a number out of range, an unwritable output.
/// Carries the file, the JSON path of the offending field ("$" for the whole file, "" when no JSON
/// is involved), the reason and a hint on what to do next. `what()` is one line:
///   `FILE: JSON_PATH: REASON (hint: HINT)`.
///
/// Options: a library never spells a front end's option ("--max-move" is the command line's,
/// "max_rotate_deg" Python's, "'max_move'" a viewer script's). It names the option struct's field
/// in braces, `{max_move}` (Option("max_move")), in any of the four parts; each front end writes
/// the names its own way with RenameOptions and one table (app/cli/flags.h for the command line,
/// python/keywords.h for Python, the viewer's action keys); `what()` shows `{max_move}` as it is.
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

/// `{field}`: an option named in an error's text (see InputError).
std::string Option(const std::string& field);

/// `e` with every `{field}` in its file, JSON path, reason and hint replaced by `name(field)`; a
/// name `name` returns empty is left as `{field}`.
InputError RenameOptions(const InputError& e,
                         const std::function<std::string(const std::string& field)>& name);

}  // namespace pandora
