#pragma once
/// \file json_reader.h
/// The one way Pandora reads a JSON input (scene files, viewer scripts, suggestion files, the
/// viewer's autosave): the text is checked for size and nesting before it is parsed, duplicate keys
/// are refused, and every value is read through a JsonNode, whose accessors check the value and
/// throw an InputError naming the file and the JSON path ($.rigs[0].cameras[2].hfov_deg).

#include <Eigen/Core>
#include <cstddef>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

namespace pandora {

/// The JSON path of member `key` of the value at `path`: $.a.b, or $.a["odd key"].
std::string JsonMemberPath(const std::string& path, const std::string& key);

/// The JSON path of element `index` of the array at `path`: $.a[3].
std::string JsonElementPath(const std::string& path, std::size_t index);

/// Parses `text` read from `file` after CheckJsonLimits. A key given twice in one object is
/// refused (naming its path); malformed text fails with the parser's reason and, as the hint, the
/// path of the value it was reading. Numbers beyond a double fail likewise.
nlohmann::json ParseJson(const std::string& text, const std::string& file);

/// Reads `path` (a regular file of at most InputLimits::kJsonBytes; `what` names it in messages:
/// "script", "suggestion file") and parses it with ParseJson.
nlohmann::json ReadJsonFile(const std::string& path, const std::string& what);

/// A JSON value with its path in its file. Every accessor validates and throws
/// InputError(file, path, reason, hint) on a value of the wrong type or out of range.
class JsonNode {
 public:
  /// `file` must outlive the node and its children.
  JsonNode(const nlohmann::json* value, std::string path, const std::string* file)
      : value_(value), path_(std::move(path)), file_(file) {}

  /// The root ($) of a parsed document.
  static JsonNode Root(const nlohmann::json& document, const std::string& file) {
    return JsonNode(&document, "$", &file);
  }

  const nlohmann::json& value() const { return *value_; }
  const std::string& path() const { return path_; }
  const std::string& file() const { return *file_; }

  [[noreturn]] void Fail(const std::string& reason, const std::string& hint = {}) const;

  // Objects.

  void ExpectObject(const char* what = "an object") const;
  /// Fails on the first key not in `allowed`, suggesting the closest allowed one.
  void CheckKeys(const std::vector<std::string>& allowed) const;
  /// Whether this is an object with member `key`.
  bool Has(const std::string& key) const { return value_->contains(key); }
  std::optional<JsonNode> Find(const std::string& key) const;
  /// Member `key`; fails with "missing required key 'key'" when absent.
  JsonNode Get(const std::string& key) const;
  /// The one key of `keys` present; fails when none or several are.
  std::string OneOf(const std::vector<std::string>& keys, const std::string& what) const;

  // Arrays.

  /// The array's length; fails when this is not an array.
  std::size_t ArraySize(const char* what = "an array") const;
  /// The length of an array of at most `max` elements.
  std::size_t ArraySize(std::size_t max, const std::string& what) const;
  JsonNode At(std::size_t i) const;

  // Scalars.

  bool IsNull() const { return value_->is_null(); }
  /// A finite number.
  double Number() const;
  /// A finite number in [min, max].
  double Number(double min, double max) const;
  double Positive() const;
  double NonNegative() const;
  /// A whole number in [min, max].
  int Integer(int min, int max) const;
  std::string String() const;
  std::string NonEmptyString() const;
  /// A string equal to one of `values`; otherwise fails suggesting the closest.
  std::string Enum(const std::vector<std::string>& values) const;
  bool Bool() const;
  /// An array of exactly `n` finite numbers.
  Eigen::VectorXd Numbers(std::size_t n) const;
  /// "a number", "a string", "a boolean", "an array", "an object" or "null".
  std::string TypeName() const;

 private:
  const nlohmann::json* value_;
  std::string path_;
  const std::string* file_;
};

}  // namespace pandora
