// Rewriting a user's scene file text: ordered parse, numbers as typed, the file's indentation.
#include "analysis/scene/scene_text.h"

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>

#include "analysis/geometry/camera.h"
#include "analysis/util/atomic_file.h"
#include "analysis/util/error.h"
#include "analysis/util/input_file.h"
#include "analysis/util/output_transaction.h"
#include "analysis/util/sha256.h"
#include "analysis/util/units.h"

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

ordered_json DistortionJson(const Intrinsics& k) {
  if (k.model == LensModel::kPinhole) return nullptr;
  ordered_json d = {{"model", LensModelName(k.model)}, {"k1", k.k1}, {"k2", k.k2}};
  if (k.model == LensModel::kFisheye)
    d["k3"] = k.k3, d["k4"] = k.k4;
  else
    d["p1"] = k.p1, d["p2"] = k.p2, d["k3"] = k.k3;
  return d;
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
  if (u.is_string())
    if (const double metres = MetresPerUnitNamed(u.get<std::string>()); metres > 0) return metres;
  throw InputError(path, "$.units", "unknown unit", "use m, cm, mm, in or ft");
}

std::string DumpLike(const ordered_json& root, const std::string& original) {
  const auto [indent, ch] = Indentation(original);
  std::string out = root.dump(indent, ch);
  if (!original.empty() && original.back() == '\n') out += "\n";
  return out;
}

}  // namespace pandora::scene_text

namespace pandora {

using scene_text::ReadJsonText;

std::string ReplaceSceneFileWithBackup(
    const std::string& scene_path, const std::string& old_text, const std::string& new_text,
    const std::vector<std::pair<std::string, std::string>>& inputs) {
  // The backup and the new scene file appear together (OutputTransaction), the backup with the
  // scene file's mode and owner, the scene file keeping its own. Through a symbolic link to the
  // file it names; a read-only scene file is refused.
  namespace fs = std::filesystem;
  std::error_code ec;
  const fs::path target = fs::canonical(scene_path, ec);
  if (ec) throw InputError(scene_path, "", "cannot resolve the scene file: " + ec.message());
  const fs::perms perms = fs::status(target, ec).permissions();
  if (ec || (perms & fs::perms::owner_write) == fs::perms::none)
    throw InputError(scene_path, "", "the scene file is read-only",
                     "make it writable, then accept again");
  const std::string path = target.string();
  // Under the folder's lock, the file must still be what the caller read: a second writer that
  // read the same text before the first one wrote is refused here, never applied over it.
  FolderLock lock(path);
  std::string on_disk;
  try {
    on_disk = ReadJsonText(path, "scene file");
  } catch (const InputError&) {
    throw InputError(scene_path, "",
                     "the scene file vanished or became unreadable while it was being replaced",
                     "check the file, then try again");
  }
  if (Sha256Hex(on_disk) != Sha256Hex(old_text))
    throw InputError(
        scene_path, "",
        "the scene file was changed by another program while this one worked (SHA-256 differs); "
        "nothing was written",
        "look at the file, then run the command again");
  std::string backup = path + ".bak";
  for (int n = 1; fs::exists(backup, ec); ++n) backup = path + ".bak." + std::to_string(n);
  OutputTransaction output;
  for (const auto& [input, kind] : inputs) output.AddInput(input, kind);
  output.AddInput(path, "scene file");
  output.Write(backup, "", old_text, path);  // with the scene file's mode and owner
  WriteFileAtomically(output.StageReplacement(path, ""), new_text);
  output.Commit();
  return backup;
}

}  // namespace pandora
