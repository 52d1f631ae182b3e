// The display panel: the projected pattern, brightness, surface mode and shadow maps
// (ViewerApp::Impl).
#include "viewer/window/viewer_app_impl.h"

namespace pandora::viewer {

void ViewerApp::Impl::DisplayPanel() {
  ImGui::SetNextWindowPos(ImVec2(266, 8), ImGuiCond_FirstUseEver);
  ImGui::SetNextWindowSize(ImVec2(230, 130), ImGuiCond_FirstUseEver);
  ImGui::SetNextWindowCollapsed(true, ImGuiCond_FirstUseEver);
  ImGui::Begin("Display");
  int pattern = model.display.pattern == Pattern::kGrid ? 1 : 0;
  bool changed = ImGui::Combo("light", &pattern, "uniform\0grid\0");
  int grid = model.display.grid_pixels;
  changed |= ImGui::DragInt("grid px", &grid, 1, 1, 1000, "%d", ImGuiSliderFlags_AlwaysClamp);
  // The paper's display modes: material colours, black, hidden-line edges, contours.
  int surface = int(model.display.surface);
  changed |= ImGui::Combo("surfaces", &surface, "material\0black\0hidden-line\0contours\0");
  bool automatic = std::isnan(model.display.brightness);
  float brightness = automatic ? float(DefaultBrightness(model.rig().enabled_count()))
                               : float(model.display.brightness);
  changed |= ImGui::Checkbox("auto brightness", &automatic);
  if (!automatic)
    changed |= ImGui::DragFloat("brightness", &brightness, 0.01f, 0.01f, 10.0f, "%.2f",
                                ImGuiSliderFlags_AlwaysClamp);
  if (ImGui::Combo("shadow map", &map_index,
                   "512\0"
                   "1024\0"
                   "2048\0"
                   "4096\0"))
    shadow_map_size = 512 << map_index;
  if (changed) {
    Action a = Make(Action::Kind::kLight);
    a.text = PatternName(pattern ? Pattern::kGrid : Pattern::kUniform);
    a.number = grid;
    a.number2 = automatic ? NAN : brightness;
    a.text2 = SurfaceName(static_cast<Surface>(std::clamp(surface, 0, 3)));
    Do(a);
  }
  ImGui::End();
}

}  // namespace pandora::viewer
