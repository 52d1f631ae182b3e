// The fields panel: the live fields, their slice and isosurface, the summary (ViewerApp::Impl).
#include "viewer/window/viewer_app_impl.h"

namespace pandora::viewer {

void ViewerApp::Impl::FieldsPanel() {
  ImGui::SetNextWindowPos(ImVec2(266, float(std::max(40, model.height - 230))),
                          ImGuiCond_FirstUseEver);
  ImGui::SetNextWindowSize(ImVec2(250, 195), ImGuiCond_FirstUseEver);
  ImGui::Begin("Fields");
  // The numbers of the fields' latest version, worked out once per version (the median copies
  // and partially sorts every sigma); while an update holds the fields, the last ones stay.
  model.session().TryReadFields([&](const Fields& f, std::int64_t version) {
    if (version == fields_numbers_version) return;
    fields_numbers_version = version;
    fields_lattice = f.lattice;
    fields_numbers.clear();
    const std::vector<double> shares = CoverageAtLeast(f.stats.coverage_histogram);
    for (std::size_t k = 1; k <= shares.size() && k <= 3; ++k) {
      char cell[48];
      std::snprintf(cell, sizeof cell, ">=%zu %.1f%%  ", k, 100.0 * shares[k - 1]);
      fields_numbers += cell;
    }
    const auto p50 = NearestRankPercentile(f.stats.sigma_max_mm, 50);
    if (p50) fields_numbers += "\nsigma_max p50 " + std::to_string(*p50).substr(0, 5) + " mm";
  });
  const VoxelLattice& lattice = fields_lattice;
  const std::string numbers =
      fields_numbers +
      (fields_numbers_version == model.session().rig().version() ? "" : "\n(updating)");
  ImGui::TextUnformatted(fields_numbers_version == -2 ? "evaluating..." : numbers.c_str());
  // With people (time samples): the live fields above are the empty volume's; these are the
  // numbers with the people at every sample, as `pandora analyze` reports them.
  if (const auto time = model.session().TimeNumbers()) {
    const TimeSummary& t = time->first;
    const double worst = t.samples.empty() ? 0.0 : t.samples[t.worst_sample].ge_k;
    ImGui::Text("with people, %zu samples, >=%d:\nalways %.1f%%  worst sample %.1f%%%s",
                t.samples.size(), t.min_cameras, 100.0 * t.always, 100.0 * worst,
                time->second == model.session().rig().version() ? "" : " (updating)");
    if (ImGui::IsItemHovered())
      ImGui::SetTooltip(
          "The fields above are the static scene's (the volume without the moving objects).\n"
          "These are over the time samples with them: the share of voxels covered by >= %d\n"
          "cameras at every sample where they are free, and in the worst sample.",
          t.min_cameras);
  }
  const char* fields[] = {"", "coverage", "resolution", "sigma_max"};
  const OverlayOptions& ov = model.display.overlays;
  int current = 0;
  for (int i = 1; i < 4; ++i)
    if (ov.slice_field == fields[i]) current = i;
  int axis = ov.slice_axis;
  float at = std::isnan(ov.slice_position)
                 ? float(lattice.origin[axis] + 0.5 * lattice.voxel_size * (lattice.dims[axis] - 1))
                 : float(ov.slice_position);
  bool changed = ImGui::Combo("slice", &current, "off\0coverage\0resolution\0sigma_max\0");
  changed |= ImGui::RadioButton("x", &axis, 0);
  ImGui::SameLine();
  changed |= ImGui::RadioButton("y", &axis, 1);
  ImGui::SameLine();
  changed |= ImGui::RadioButton("z", &axis, 2);
  const float lo = float(lattice.origin[axis]),
              hi = float(lattice.origin[axis] +
                         lattice.voxel_size * std::max(0, lattice.dims[axis] - 1));
  changed |= ImGui::SliderFloat("at m", &at, lo, std::max(hi, lo + 1e-3f), "%.3f");
  if (changed) {
    Action a = Make(Action::Kind::kSlice);
    a.text = fields[current];
    a.flag = a.text.empty();
    a.text2 = axis == 0 ? "x" : axis == 1 ? "y" : "z";
    a.number = at;
    Do(a);
  }
  // The isosurface: field and value.
  int iso_current = 0;
  for (int i = 1; i < 4; ++i)
    if (ov.iso_field == fields[i]) iso_current = i;
  float iso_value = float(ov.iso_value);
  bool iso_changed = ImGui::Combo("iso", &iso_current, "off\0coverage\0resolution\0sigma_max\0");
  iso_changed |= ImGui::DragFloat("iso value", &iso_value, 0.05f, -1e6f, 1e6f, "%.2f");
  if (iso_changed) {
    Action a = Make(Action::Kind::kIso);
    a.text = fields[iso_current];
    a.flag = a.text.empty();
    a.number = iso_value;
    Do(a);
  }
  ImGui::End();
}

}  // namespace pandora::viewer
