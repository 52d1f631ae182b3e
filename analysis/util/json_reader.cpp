#include "analysis/util/json_reader.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <set>
#include <sstream>
#include <utility>

#include "analysis/util/error.h"
#include "analysis/util/input_file.h"
#include "analysis/util/text.h"

namespace pandora {
namespace {

using json = nlohmann::json;

// Twelve significant digits: the number as the user wrote it, in messages.
std::string FormatNumber(double v) {
  std::ostringstream s;
  s.precision(12);
  s << v;
  return s.str();
}

bool IsIdentifier(const std::string& key) {
  if (key.empty() || std::isdigit(static_cast<unsigned char>(key[0]))) return false;
  return std::all_of(key.begin(), key.end(), [](char c) {
    return std::isalnum(static_cast<unsigned char>(c)) || c == '_';
  });
}

// The parser's text after "[json.exception.parse_error.101] ".
std::string ParserReason(const std::string& what) {
  const std::size_t bracket = what.find("] ");
  if (what.rfind("[json.exception", 0) == 0 && bracket != std::string::npos)
    return what.substr(bracket + 2);
  return what;
}

// Follows the parser's position as a JSON path, and rejects duplicate keys.
class PathTracker {
 public:
  explicit PathTracker(const std::string& file) : file_(file) {}

  // The path of the value the parser is reading now.
  std::string CurrentPath() const {
    if (stack_.empty()) return "$";
    const Frame& top = stack_.back();
    if (top.is_array) return JsonElementPath(top.path, top.count);
    return top.key.empty() && top.keys.empty() ? top.path : JsonMemberPath(top.path, top.key);
  }

  bool OnEvent(json::parse_event_t event, const json& parsed) {
    switch (event) {
      case json::parse_event_t::object_start:
      case json::parse_event_t::array_start: {
        Frame frame;
        frame.is_array = event == json::parse_event_t::array_start;
        frame.path = CurrentPath();
        stack_.push_back(std::move(frame));
        break;
      }
      case json::parse_event_t::key: {
        Frame& top = stack_.back();
        top.key = parsed.get<std::string>();
        if (!top.keys.insert(top.key).second) {
          throw InputError(file_, JsonMemberPath(top.path, top.key),
                           "duplicate key " + Quoted(top.key),
                           "a key may appear once per object; the later value would replace the "
                           "earlier one");
        }
        break;
      }
      case json::parse_event_t::object_end:
      case json::parse_event_t::array_end:
        stack_.pop_back();
        EndValue();
        break;
      case json::parse_event_t::value:
        EndValue();
        break;
    }
    return true;
  }

 private:
  struct Frame {
    bool is_array = false;
    std::size_t count = 0;  // Elements read so far (arrays).
    std::string key;        // The current key (objects).
    std::set<std::string> keys;
    std::string path;
  };

  void EndValue() {
    if (!stack_.empty() && stack_.back().is_array) ++stack_.back().count;
  }

  std::string file_;
  std::vector<Frame> stack_;
};

}  // namespace

std::string JsonMemberPath(const std::string& path, const std::string& key) {
  return IsIdentifier(key) ? path + "." + key : path + "[" + json(key).dump() + "]";
}

std::string JsonElementPath(const std::string& path, std::size_t index) {
  return path + "[" + std::to_string(index) + "]";
}

json ParseJson(const std::string& text, const std::string& file) {
  CheckJsonLimits(text, file);
  PathTracker tracker(file);
  try {
    return json::parse(text, [&tracker](int, json::parse_event_t event, json& parsed) {
      return tracker.OnEvent(event, parsed);
    });
  } catch (const json::parse_error& e) {
    const std::string where = tracker.CurrentPath();
    throw InputError(file, "$", "malformed JSON: " + ParserReason(e.what()),
                     where == "$" ? "check the brackets, commas and quotes there"
                                  : "the error is inside " + where +
                                        "; check the brackets, commas and quotes there");
  } catch (const json::exception& e) {
    // Numbers too large for a double (1e400) end up here.
    std::string message = e.what();
    const std::size_t bracket = message.find("] ");
    if (bracket != std::string::npos) message = message.substr(bracket + 2);
    throw InputError(file, tracker.CurrentPath(), message,
                     "numbers must be finite and within the range of a double");
  }
}

json ReadJsonFile(const std::string& path, const std::string& what) {
  return ParseJson(ReadInputFile(path, InputLimits::kJsonBytes, what), path);
}

void JsonNode::Fail(const std::string& reason, const std::string& hint) const {
  throw InputError(*file_, path_, reason, hint);
}

void JsonNode::ExpectObject(const char* what) const {
  if (!value_->is_object()) Fail(std::string("expected ") + what + ", got " + TypeName());
}

void JsonNode::CheckKeys(const std::vector<std::string>& allowed) const {
  ExpectObject();
  for (const auto& item : value_->items()) {
    if (std::find(allowed.begin(), allowed.end(), item.key()) != allowed.end()) continue;
    throw InputError(*file_, JsonMemberPath(path_, item.key()), "unknown key " + Quoted(item.key()),
                     DidYouMean(item.key(), allowed, "allowed keys here"));
  }
}

std::optional<JsonNode> JsonNode::Find(const std::string& key) const {
  if (!value_->is_object()) return std::nullopt;
  const auto it = value_->find(key);
  if (it == value_->end()) return std::nullopt;
  return JsonNode(&*it, JsonMemberPath(path_, key), file_);
}

JsonNode JsonNode::Get(const std::string& key) const {
  std::optional<JsonNode> child = Find(key);
  if (!child) Fail("missing required key " + Quoted(key));
  return *child;
}

std::string JsonNode::OneOf(const std::vector<std::string>& keys, const std::string& what) const {
  std::string found;
  for (const std::string& key : keys) {
    if (!Has(key)) continue;
    if (!found.empty()) {
      throw InputError(*file_, JsonMemberPath(path_, key),
                       "both " + Quoted(found) + " and " + Quoted(key) + " are given",
                       "give exactly one " + what + ": " + JoinQuoted(keys));
    }
    found = key;
  }
  if (found.empty()) Fail("missing " + what, "give exactly one of " + JoinQuoted(keys));
  return found;
}

std::size_t JsonNode::ArraySize(const char* what) const {
  if (!value_->is_array()) Fail(std::string("expected ") + what + ", got " + TypeName());
  return value_->size();
}

std::size_t JsonNode::ArraySize(std::size_t max, const std::string& what) const {
  const std::size_t n = ArraySize(("an array of " + what).c_str());
  if (n > max) Fail("more than " + std::to_string(max) + " " + what);
  return n;
}

JsonNode JsonNode::At(std::size_t i) const {
  return JsonNode(&(*value_)[i], JsonElementPath(path_, i), file_);
}

double JsonNode::Number() const {
  if (!value_->is_number()) Fail("expected a number, got " + TypeName());
  const double v = value_->get<double>();
  if (!std::isfinite(v)) Fail("number is not finite");
  return v;
}

double JsonNode::Number(double min, double max) const {
  const double v = Number();
  if (v < min || v > max)
    Fail("must be between " + FormatNumber(min) + " and " + FormatNumber(max) + ", got " +
         FormatNumber(v));
  return v;
}

double JsonNode::Positive() const {
  const double v = Number();
  if (!(v > 0)) Fail("must be positive, got " + FormatNumber(v));
  return v;
}

double JsonNode::NonNegative() const {
  const double v = Number();
  if (!(v >= 0)) Fail("must be zero or positive, got " + FormatNumber(v));
  return v;
}

int JsonNode::Integer(int min, int max) const {
  const double v = Number();
  if (v != std::floor(v)) Fail("expected an integer, got " + FormatNumber(v));
  if (v < min || v > max) {
    Fail("must be between " + std::to_string(min) + " and " + std::to_string(max) + ", got " +
         FormatNumber(v));
  }
  return static_cast<int>(v);
}

std::string JsonNode::String() const {
  if (!value_->is_string()) Fail("expected a string, got " + TypeName());
  return value_->get<std::string>();
}

std::string JsonNode::NonEmptyString() const {
  std::string s = String();
  if (s.empty()) Fail("must not be empty");
  return s;
}

std::string JsonNode::Enum(const std::vector<std::string>& values) const {
  const std::string s = String();
  if (std::find(values.begin(), values.end(), s) == values.end())
    Fail("unknown value " + Quoted(s), DidYouMean(s, values, "known values"));
  return s;
}

bool JsonNode::Bool() const {
  if (!value_->is_boolean()) Fail("expected true or false, got " + TypeName());
  return value_->get<bool>();
}

Eigen::VectorXd JsonNode::Numbers(std::size_t n) const {
  const std::string expected = "expected an array of " + std::to_string(n) + " numbers";
  if (!value_->is_array()) Fail(expected + ", got " + TypeName());
  if (value_->size() != n) Fail(expected + ", got an array of " + std::to_string(value_->size()));
  Eigen::VectorXd v(n);
  for (std::size_t i = 0; i < n; ++i) v[i] = At(i).Number();
  return v;
}

std::string JsonNode::TypeName() const {
  if (value_->is_number()) return "a number";
  if (value_->is_string()) return "a string";
  if (value_->is_boolean()) return "a boolean";
  if (value_->is_array()) return "an array";
  if (value_->is_object()) return "an object";
  return "null";
}

}  // namespace pandora
