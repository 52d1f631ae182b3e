#pragma once
/// \file scene_text.h
/// Rewriting a user's scene file text (`pandora accept`, the viewer's save): parse it keeping the
/// key order, write numbers as a person types them, re-serialise with the file's indentation.
/// Pulls in nlohmann/json. Every command that rewrites a scene file goes through
/// ReplaceSceneFileWithBackup (lock, hash re-check, backup, atomic rename).

#include <cstddef>
#include <nlohmann/json.hpp>
#include <string>
#include <utility>
#include <vector>

namespace pandora {
struct Intrinsics;
}

namespace pandora::scene_text {

using ordered_json = nlohmann::ordered_json;

/// A JSON input file's text within the input limits (InputError otherwise; `what` names it).
std::string ReadJsonText(const std::string& path, const std::string& what);
/// The text parsed with its key order (InputError "$" "malformed JSON: ..." otherwise).
ordered_json ParseOrdered(const std::string& text, const std::string& path);
/// Indentation of a JSON text: the whitespace run after its first newline (-1: compact).
std::pair<int, char> Indentation(const std::string& text);
/// `root` serialised with `original`'s indentation and final newline.
std::string DumpLike(const ordered_json& root, const std::string& original);
/// The rig called `rig_name` in `root` (its index in `index` when given); InputError (file = path,
/// "$.rigs") when the file has no rigs or none of that name, with `hint`.
ordered_json& FindRig(ordered_json& root, const std::string& path, const std::string& rig_name,
                      const std::string& hint, std::size_t* index = nullptr);
/// The file's metres per length unit ("units"; InputError "$.units" for an unknown one).
double MetresPerUnit(const ordered_json& root, const std::string& path);
/// A camera id as text (ids may be numbers).
std::string IdOf(const ordered_json& id);
/// The double nearest the 12-significant-digit decimal of v: what a person would have typed.
double Clean(double v);
/// A number as JSON: an integer when it is a whole number (as a person writes 4, not 4.0).
ordered_json Number(double v);
/// A lens's "distortion" in the scene format, "model" first (brown_conrady: k1 k2 p1 p2 k3;
/// fisheye: k1 k2 k3 k4); null for a pinhole.
ordered_json DistortionJson(const Intrinsics& k);

}  // namespace pandora::scene_text

namespace pandora {

/// Replaces the scene file `scene_path` (symbolic links followed) by `new_text`, keeping
/// `old_text` as a backup (`SCENE.bak`, or `SCENE.bak.N` with the first free N, with the scene
/// file's mode and owner); both appear together or neither does (OutputTransaction). `inputs` are
/// other files of the command (path, kind) that no output may name. A read-only scene file is
/// refused. Returns the backup's path. What `pandora accept` and a session's Save share.
std::string ReplaceSceneFileWithBackup(
    const std::string& scene_path, const std::string& old_text, const std::string& new_text,
    const std::vector<std::pair<std::string, std::string>>& inputs = {});

}  // namespace pandora
