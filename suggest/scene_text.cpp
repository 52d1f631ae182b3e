// Rewriting a user's scene file text: ordered parse, numbers as typed, the file's indentation.
#include "suggest/scene_text.h"

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <map>

#include "analysis/error.h"
#include "analysis/input_file.h"

namespace pandora::scene_text {

std::string ReadJsonText(const std::string& path, const std::string& what) {
  std::string text = ReadInputFile(path, InputLimits::kJsonBytes, what);
  CheckJsonLimits(text, path);
  return text;
}

std::string IdOf(const ordered_json& id) {
  if (id.is_string()) return id.get<std::string>();
  if (id.is_number_integer()) return std::to_string(id.get<int64_t>());
  return id.dump();
}

// Indentation of a JSON text: the whitespace run after its first newline (-1: compact).
std::pair<int, char> Indentation(const std::string& text) {
  const std::size_t nl = text.find('\n');
  if (nl == std::string::npos || nl + 1 >= text.size()) return {-1, ' '};
  const char ch = text[nl + 1] == '\t' ? '\t' : ' ';
  int n = 0;
  for (std::size_t i = nl + 1; i < text.size() && text[i] == ch; ++i) ++n;
  return {n, ch};
}

// The double nearest the 12-significant-digit decimal of v: what a person would have typed.
double Clean(double v) {
  if (!std::isfinite(v)) return v;
  char b[40];
  std::snprintf(b, sizeof b, "%.12g", v);
  const double c = std::strtod(b, nullptr);
  return c == 0 ? 0.0 : c;  // no -0
}

// A number as JSON: an integer when it is a whole number (as a person writes 4, not 4.0).
ordered_json Number(double v) {
  if (std::isfinite(v) && v == std::round(v) && std::abs(v) < 1e15)
    return ordered_json(static_cast<std::int64_t>(v));
  return ordered_json(v);
}

ordered_json ParseOrdered(const std::string& text, const std::string& scene_path) {
  try {
    return ordered_json::parse(text);
  } catch (const std::exception& e) {
    throw InputError(scene_path, "$", std::string("malformed JSON: ") + e.what());
  }
}

ordered_json& FindRig(ordered_json& root, const std::string& path, const std::string& rig_name,
                      const std::string& hint, std::size_t* index) {
  if (!root.is_object() || !root.contains("rigs") || !root["rigs"].is_array())
    throw InputError(path, "$.rigs", "no rigs");
  ordered_json* rig = nullptr;
  for (std::size_t r = 0; r < root["rigs"].size(); ++r) {
    ordered_json& candidate = root["rigs"][r];
    if (candidate.is_object() && candidate.contains("name") && candidate["name"] == rig_name) {
      rig = &candidate;
      if (index) *index = r;
    }
  }
  if (!rig) throw InputError(path, "$.rigs", "no rig called '" + rig_name + "'", hint);
  return *rig;
}

double MetresPerUnit(const ordered_json& root, const std::string& path) {
  if (!root.contains("units")) return 1.0;
  const ordered_json& u = root["units"];
  static const std::map<std::string, double> units{
      {"m", 1.0}, {"cm", 0.01}, {"mm", 0.001}, {"in", 0.0254}, {"ft", 0.3048}};
  if (u.is_string()) {
    auto it = units.find(u.get<std::string>());
    if (it != units.end()) return it->second;
  }
  throw InputError(path, "$.units", "unknown unit", "use m, cm, mm, in or ft");
}

std::string DumpLike(const ordered_json& root, const std::string& original) {
  const auto [indent, ch] = Indentation(original);
  std::string out = root.dump(indent, ch);
  if (!original.empty() && original.back() == '\n') out += "\n";
  return out;
}

}  // namespace pandora::scene_text
