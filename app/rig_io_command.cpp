// `pandora export-rig` and `pandora import-rig` (issue 14, points 2 and 3; docs/tool-chain.md):
// the rig in reconstruction tools' formats, and a calibrated rig back into the scene file.
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <memory>

#include "analysis/rig/rig_check.h"
#include "analysis/rig/rig_formats.h"
#include "analysis/rig/rig_import.h"
#include "analysis/scene/scene.h"
#include "analysis/util/error.h"
#include "app/cli.h"
#include "app/commands.h"
#include "app/output.h"

namespace pandora::app {

int RunExportRig(const ExportRigArgs& args) {
  const auto t0 = std::chrono::steady_clock::now();
  const std::string& f = args.format;
  if (f != "opencv" && f != "colmap" && f != "gltf" && f != "sheet")
    throw InputError("--format", "", "unknown format '" + f + "'", "opencv, colmap, gltf or sheet");
  if (args.out.empty()) throw InputError("--out", "", "no output given");
  LoadOptions load;
  load.load_meshes = f == "gltf";
  const Scene scene = LoadScene(args.scene, load);
  const Rig& rig = FindRigOption(scene, args.rig);
  OutputTransaction output;
  AddSceneInputs(output, scene);
  std::vector<std::string> written;
  if (f == "colmap") {
    const ColmapText model = RigToColmap(rig);
    const std::filesystem::path dir(args.out);
    for (const auto& [name, text] :
         {std::pair<std::string, const std::string*>{"cameras.txt", &model.cameras},
          {"images.txt", &model.images},
          {"points3D.txt", &model.points3d}}) {
      output.Write((dir / name).string(), "--out", *text);
      written.push_back((dir / name).string());
    }
  } else {
    std::string bytes;
    if (f == "opencv") {
      try {
        bytes = RigToOpenCvYaml(rig);
      } catch (const InputError& e) {
        throw InputError(args.scene, "", e.reason(), e.hint());
      }
    } else if (f == "gltf") {
      // A .glb name gets binary glTF; any other name the .gltf JSON with the buffer embedded.
      const std::string ext = std::filesystem::path(args.out).extension().string();
      bytes = SceneToGltf(scene, rig, ext == ".glb" || ext == ".GLB");
    } else {
      bytes = RigToSheetCsv(rig);
    }
    output.Write(args.out, "--out", bytes);
    written.push_back(args.out);
  }
  output.Commit();
  // OpenCV's fisheye model and COLMAP's OPENCV_FISHEYE project through atan(r): rays 90 degrees or
  // more off the axis have no image there. A wider lens is written, but not all of it.
  std::vector<std::string> warnings;
  if (f == "opencv" || f == "colmap")
    for (const Camera& c : rig.cameras) {
      if (c.model.intrinsics().model != LensModel::kFisheye) continue;
      const LensCoverage lens = ComputeLensCoverage(c.model);
      const double widest = std::max(lens.hfov_deg, lens.vfov_deg);
      if (widest >= 180.0)
        warnings.push_back(args.scene + ": camera '" + c.id + "' sees " +
                           std::to_string(int(widest + 0.5)) + " degrees, but the " +
                           (f == "opencv" ? "OpenCV fisheye" : "COLMAP OPENCV_FISHEYE") +
                           " model written for it cannot hold rays 90 degrees or more off its "
                           "axis: that part of its view is lost");
    }
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  for (const std::string& w : warnings) std::fprintf(stderr, "pandora: warning: %s\n", w.c_str());
  if (!args.quiet) {
    std::printf("rig %s: %zu cameras as %s\n", rig.name.c_str(), rig.cameras.size(), f.c_str());
    for (const std::string& w : written) std::printf("wrote %s\n", w.c_str());
    std::printf("(%.3f s)\n", seconds);
  }
  return 0;
}

int RunImportRig(const ImportRigArgs& args) {
  if (args.format != "opencv" && args.format != "colmap")
    throw InputError("--from", "", "unknown format '" + args.format + "'",
                     "opencv or colmap, e.g. --from opencv rig.yml");
  RigImportOptions options;
  options.scene = args.scene;
  options.format = args.format;
  options.from = args.from;
  options.rig = args.rig;
  options.as = args.as;
  const RigImportResult r = ImportRig(options);
  if (!args.quiet) {
    std::printf("%s rig '%s' in %s (%zu cameras); backup %s\n", r.new_rig ? "added" : "updated",
                r.rig_written.c_str(), r.scene_path.c_str(), r.differences.size(),
                r.backup_path.c_str());
    bool any = false;
    for (const RigImportDifference& d : r.differences) any = any || d.in_design;
    if (any) {
      std::printf("against the design rig '%s':\n%-16s %12s %11s %12s %12s\n", args.rig.c_str(),
                  "camera", "moved_mm", "turned_deg", "fx_design", "fx_calib");
      for (const RigImportDifference& d : r.differences) {
        if (d.in_design)
          std::printf("%-16s %12.3f %11.4f %12.2f %12.2f\n", d.id.c_str(), d.moved_m * 1000.0,
                      d.turned_deg, d.fx_design, d.fx_imported);
        else
          std::printf("%-16s not in the design rig\n", d.id.c_str());
      }
    }
  }
  return 0;
}

// Registers `pandora export-rig` and its options.
Command AddExportRigCommand(CLI::App& app, CommonOptions& /*common*/) {
  auto args = std::make_shared<ExportRigArgs>();
  ExportRigArgs& export_rig = *args;
  CLI::App* er = app.add_subcommand("export-rig",
                                    "Write the rig as OpenCV YAML, a COLMAP text model, glTF "
                                    "(meshes + cameras) or an installation sheet (CSV)");
  er->add_option("scene", export_rig.scene, "Scene file (JSON)")->required();
  er->add_option("--rig", export_rig.rig, "Rig name (default: the first rig)");
  er->add_option("--format", export_rig.format, "opencv | colmap | gltf | sheet")->required();
  er->add_option("--out", export_rig.out, "Output file (a folder for colmap)")->required();
  er->add_flag("--quiet,-q", export_rig.quiet, "Print nothing but errors");
  return {er, [args] { return RunExportRig(*args); }};
}

// Registers `pandora import-rig` and its options (`import_from`: the two values of --from).
Command AddImportRigCommand(CLI::App& app, CommonOptions& /*common*/) {
  auto args = std::make_shared<ImportRigArgs>();
  ImportRigArgs& import_rig = *args;
  auto from = std::make_shared<std::vector<std::string>>();  // FORMAT PATH
  std::vector<std::string>& import_from = *from;
  CLI::App* ir =
      app.add_subcommand("import-rig",
                         "Write a calibrated rig (OpenCV YAML or COLMAP text model) into the scene "
                         "file (keeps a backup) and compare it with the design");
  ir->add_option("scene", import_rig.scene, "Scene file (JSON), rewritten")->required();
  ir->add_option("--from", import_from, "FORMAT PATH: opencv FILE.yml or colmap FOLDER")
      ->required()
      ->expected(2);
  ir->add_option("--rig", import_rig.rig,
                 "The design rig: replaced by id, or compared with when --as is given")
      ->required();
  ir->add_option("--as", import_rig.as, "Write a new rig of this name instead");
  ir->add_flag("--quiet,-q", import_rig.quiet, "Print nothing but errors");
  return {ir, [args, from] {
            args->format = from->at(0);
            args->from = from->at(1);
            return RunImportRig(*args);
          }};
}

}  // namespace pandora::app
