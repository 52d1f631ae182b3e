// The libraries' option fields as the command line's flags (app/flags.h).
#include "app/flags.h"

namespace pandora::app {

const std::vector<std::pair<std::string, std::string>>& CommandLineFlags() {
  static const std::vector<std::pair<std::string, std::string>> kFlags{
      // Suggest (SuggestArgs, SuggestOptions, CameraLimits) and accept.
      {"cameras", "--cameras"},
      {"max_move", "--max-move"},
      {"max_rotate_deg", "--max-rotate"},
      {"hfov_range", "--hfov-range"},
      {"rail", "--rail"},
      {"plane", "--plane"},
      {"mount_box", "--mount-box"},
      {"keep_out", "--keep-out"},
      {"clearance", "--clearance"},
      {"snap_move", "--snap-move"},
      {"snap_rotate_deg", "--snap-rotate"},
      {"objective", "--objective"},
      {"weights", "--weights"},
      {"outer_iterations", "--outer"},
      {"over_time", "--over-time"},
      {"target_surfaces", "--target-surface"},
      {"points", "--points"},
      {"perturb", "--perturb"},
      {"ptz_preset", "--ptz-preset"},
      {"ptz_tour", "--ptz-tour"},
      {"force", "--force"},
      // The study and its rig (SessionOptions, FieldOptions, ReportOptions).
      {"rig", "--rig"},
      {"rigs", "--rig"},
      {"disable", "--disable"},
      {"voxel_size", "--voxel-size"},
      {"memory_budget_mb", "--memory-budget"},
      {"spacing", "--spacing"},
      // Pictures (RenderView, overlays, ReportOptions).
      {"fields", "--fields"},
      {"size", "--size"},
      {"camera", "--camera"},
      {"fov_deg", "--fov"},
      {"at", "--at"},
      {"slice_field", "--slice"},
      {"slice_axis", "--slice-axis"},
      {"iso_field", "--iso"},
      {"view_width", "--width"},
      {"camera_width", "--camera-width"},
      {"brightness", "--brightness"},
      {"grid_pixels", "--grid"},
      {"samples", "--samples"},
      {"pattern", "--pattern"},
      {"surface", "--surface"},
      {"budget_s", "--ptz-time"},
      // Rig import (ImportRigOptions).
      {"from", "--from"},
      {"as", "--as"},
      // Floor plans (PlanOptions, ReadDxfPlan).
      {"units", "--units"},
      {"walls", "--walls"},
  };
  return kFlags;
}

const std::vector<std::string>& FieldsWithoutFlag() {
  // The typed camera edits' values (app/session/camera_edits.h): Python and the viewer set them.
  static const std::vector<std::string> kFields{
      "position", "look_at", "rotation", "ypr_deg", "hfov_deg", "resolution", "k1", "k2", "p1",
      "p2", "k3", "k4", "near", "far", "color", "preset", "pan_deg", "tilt_deg",
      // Set by `pandora analyze --mpi` from the MPI world, never by hand.
      "partition_count",
      // The render options no command sets (RenderOptions::Check).
      "ambient", "grid_fill", "line_width_px", "line_grey", "background", "pixel_sigma"};
  return kFields;
}

std::string CommandLineFlag(const std::string& field) {
  for (const auto& [name, flag] : CommandLineFlags())
    if (name == field) return flag;
  return {};
}

InputError ForCommandLine(const InputError& e) {
  return RenameOptions(e, [](const std::string& field) {
    const std::string flag = CommandLineFlag(field);
    if (!flag.empty()) return flag;
    for (const std::string& f : FieldsWithoutFlag())
      if (f == field) return field;
    return std::string();
  });
}

}  // namespace pandora::app
