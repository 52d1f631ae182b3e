#include "app/session/autosave.h"

#include <filesystem>
#include <nlohmann/json.hpp>
#include <system_error>

#include "analysis/util/atomic_file.h"
#include "analysis/util/error.h"
#include "analysis/util/input_file.h"
#include "analysis/util/json_reader.h"

namespace pandora::session {

using nlohmann::json;

std::string AutosavePath(const std::string& scene_path) { return scene_path + ".autosave.json"; }

void WriteAutosave(const Session& session, const std::string& path) {
  const EditableRig& rig = session.rig();
  const std::vector<int> unsaved = rig.Unsaved();
  if (unsaved.empty()) {
    std::error_code ec;
    std::filesystem::remove(path, ec);
    return;
  }
  Rig changed;
  changed.name = rig.rig().name;
  for (int c : unsaved) changed.cameras.push_back(rig.rig().cameras[c]);
  const json j = {{"pandora_autosave", 1},
                  {"scene", session.study().scene().path},
                  {"scene_sha256", session.study().scene().sha256},
                  {"rig", changed.name},
                  {"cameras", RigToJson(changed)["cameras"]}};
  WriteFileAtomically(path, j.dump(1) + "\n");
}

std::optional<Autosave> ReadAutosave(const std::string& path, const Study& study) {
  std::error_code ec;
  if (!std::filesystem::exists(path, ec)) return std::nullopt;
  const json j = ReadJsonFile(path, "autosave file");
  const JsonNode root = JsonNode::Root(j, path);
  root.ExpectObject();
  if (!j.contains("pandora_autosave") || j["pandora_autosave"] != 1)
    throw InputError(path, "$.pandora_autosave", "not a Pandora autosave file (version 1)",
                     "delete the autosave file to start from the scene file");
  Autosave a;
  const std::string sha256 = root.Get("scene_sha256").String();
  a.rig = root.Get("rig").String();
  root.Get("cameras").ArraySize("an array of cameras");
  a.stale = sha256 != study.scene().sha256;
  const Rig* found = nullptr;
  for (const Rig& r : study.scene().rigs)
    if (r.name == a.rig) found = &r;
  if (!found) throw InputError(path, "$.rig", "the scene has no rig '" + a.rig + "'");
  const Rig& rig = *found;
  // The cameras, through the scene file's own checks (a rig needs a name and >= 1 camera).
  if (j["cameras"].empty())
    throw InputError(path, "$.cameras", "an autosave lists at least one camera");
  const json as_rig = {{"name", a.rig}, {"cameras", j["cameras"]}};
  a.cameras = ParseRigJson(as_rig, path, "$").cameras;
  for (std::size_t i = 0; i < a.cameras.size(); ++i)
    if (rig.FindCamera(a.cameras[i].id) < 0)
      throw InputError(path, "$.cameras[" + std::to_string(i) + "].id",
                       "rig '" + rig.name + "' has no camera '" + a.cameras[i].id + "'",
                       "cameras: " + rig.CameraIds());
  return a;
}

std::vector<std::string> RecoverAutosave(Session& session, const Autosave& autosave,
                                         const std::string& path) {
  if (autosave.stale)
    throw InputError(path, "$.scene_sha256",
                     "the scene file changed since this autosave was written",
                     "delete the autosave file, or restore the scene file it was made for");
  EditableRig& rig = session.rig();
  if (autosave.rig != rig.rig().name)
    throw InputError(path, "$.rig",
                     "the autosave is of rig '" + autosave.rig + "', the session edits '" +
                         rig.rig().name + "'");
  Edit edit;
  std::vector<std::string> ids;
  for (const Camera& camera : autosave.cameras) {
    const int index = rig.Find(camera.id);
    edit.changes.push_back({index, rig.rig().cameras[index], camera});
    ids.push_back(camera.id);
  }
  edit.label = "recover autosave (" + std::to_string(ids.size()) + " cameras)";
  rig.Apply(std::move(edit));
  return ids;
}

}  // namespace pandora::session
