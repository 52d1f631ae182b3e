// The suggest panel: objective, limits, mounts and targets; the suggestion and its accept
// (ViewerApp::Impl).
#include "viewer/window/viewer_app_impl.h"

namespace pandora::viewer {

void ViewerApp::Impl::SuggestPanel() {
  ImGui::SetNextWindowPos(ImVec2(float(model.width - 290), float(model.height - 290)),
                          ImGuiCond_FirstUseEver);
  ImGui::SetNextWindowSize(ImVec2(280, 250), ImGuiCond_FirstUseEver);
  ImGui::Begin("Suggest");
  const char* objectives[] = {"coverage2",  "coverage3",    "sigma-p90",   "sigma-mean",
                              "resolution", "coverage3-n1", "calibration", "mix"};
  if (model.suggestion) {  // the panel shows what the suggestion on screen was asked for
    for (int i = 0; i < IM_ARRAYSIZE(objectives); ++i)
      if (ObjectiveName(model.suggestion->objective) == objectives[i]) objective = i;
    over_time = model.suggestion_over_time;
  }
  ImGui::Combo("objective", &objective, objectives, IM_ARRAYSIZE(objectives));
  if (std::string(objectives[objective]) == "mix")
    ImGui::DragFloat3("weights c s r", weights, 0.05f, 0.0f, 100.0f, "%.2f");
  // The points the objective is evaluated on, as `pandora suggest`: the study region, named
  // surfaces (--target-surface, with --with-region), or the study's targets over time
  // (--over-time).
  const bool has_targets = model.scene().study.targets.has_value();
  if (!has_targets) over_time = false;
  if (has_targets) ImGui::Checkbox("over time (the study's targets)", &over_time);
  if (!over_time) {
    ImGui::InputText("target surfaces", surfaces, sizeof surfaces);
    if (surfaces[0]) ImGui::Checkbox("and region points", &with_region);
  }
  ImGui::DragFloat("max move m", &max_move, 0.01f, 0.0f, 10.0f, "%.2f");
  ImGui::DragFloat("max turn deg", &max_rotate, 0.5f, 0.0f, 179.0f, "%.1f");
  ImGui::DragInt("points", &points, 10, 50, 20000);
  // Mount of the selected cameras: free, on a rail (a line), on a plane (a wall), or in a box.
  ImGui::Combo("mount", &mount, "free\0rail\0plane\0box\0");
  if (mount == 1 || mount == 2)
    ImGui::DragFloat3(mount == 1 ? "rail direction" : "plane normal", mount_axis, 0.05f);
  if (mount == 3) {
    ImGui::DragFloat3("box min m", mount_box, 0.01f);
    ImGui::DragFloat3("box max m", mount_box + 3, 0.01f);
  }
  // Keep-out boxes (drawn in red in the view): no suggested camera centre inside any of them.
  for (std::size_t i = 0; i < keep_outs.size(); ++i) {
    ImGui::PushID(int(i));
    ImGui::DragFloat3("keep-out min m", keep_outs[i].data(), 0.01f);
    ImGui::DragFloat3("keep-out max m", keep_outs[i].data() + 3, 0.01f);
    const bool remove = ImGui::SmallButton("remove keep-out box");
    ImGui::PopID();
    if (remove) {
      keep_outs.erase(keep_outs.begin() + long(i));
      break;
    }
  }
  if (ImGui::Button("add keep-out box")) {
    // Around the view's target, half a metre each way, floor to 2 m.
    const Vec3 t = model.view.target;
    keep_outs.push_back({float(t.x() - 0.5), float(t.y() - 0.5), 0.0f, float(t.x() + 0.5),
                         float(t.y() + 0.5), 2.0f});
  }
  ImGui::DragFloat("clearance m", &clearance, 0.005f, 0.0f, 2.0f, "%.3f");
  ImGui::Checkbox("zoom", &zoom_on);
  if (zoom_on) ImGui::DragFloat2("hfov range deg", zoom, 0.5f, 1.0f, 179.0f, "%.1f");
  const session::JobStatus s = model.session().jobs().Status("suggest");
  const bool running =
      s.state == session::JobState::kRunning || s.state == session::JobState::kQueued;
  if (model.selection.empty()) {
    ImGui::TextDisabled("select the cameras that may move");
  } else if (running) {
    ImGui::Text("suggesting... %.0f %%", 100 * s.progress);
    ImGui::SameLine();
    // Stops the search where it is (SuggestOptions::cancel); nothing is offered.
    if (ImGui::Button("Cancel")) model.session().jobs().Cancel("suggest");
  } else if (ImGui::Button(
                 ("Suggest for " + std::to_string(model.selection.size()) + " cameras").c_str())) {
    Action a = Make(Action::Kind::kSuggest, SelectedIds());
    a.text = objectives[objective];
    a.number = max_move;
    a.number2 = max_rotate;
    a.number3 = points;
    a.clearance = clearance;
    if (mount == 1 || mount == 2) {
      a.mount = mount == 1 ? "rail" : "plane";
      a.a = Vec3(mount_axis[0], mount_axis[1], mount_axis[2]);
    } else if (mount == 3) {
      a.mount = "box";
      a.mount_box.min = Vec3(mount_box[0], mount_box[1], mount_box[2]);
      a.mount_box.max = Vec3(mount_box[3], mount_box[4], mount_box[5]);
    }
    for (const auto& k : keep_outs) {
      Aabb b;
      b.min = Vec3(k[0], k[1], k[2]);
      b.max = Vec3(k[3], k[4], k[5]);
      a.keep_out.push_back(b);
    }
    if (zoom_on) {
      a.min_hfov = zoom[0];
      a.max_hfov = zoom[1];
    }
    if (std::string(objectives[objective]) == "mix")
      a.weights = Vec3(weights[0], weights[1], weights[2]);
    a.over_time = over_time;
    if (!over_time) {
      std::string list = surfaces, item;
      for (char ch : list + ",")
        if (ch == ',') {
          if (!item.empty()) a.target_surfaces.push_back(item);
          item.clear();
        } else if (ch != ' ') {
          item += ch;
        }
      a.with_region = with_region && !a.target_surfaces.empty();
    }
    Do(a);
    waiting_for_suggestion = true;
  }
  if (waiting_for_suggestion && !running) {
    waiting_for_suggestion = false;
    Action a = Make(Action::Kind::kWait);
    a.text = "suggest";
    Do(a);
  }
  if (model.suggestion) {
    const Suggestion& g = *model.suggestion;
    ImGui::Separator();
    ImGui::Text("%s: %.4g -> %.4g%s", ObjectiveName(g.objective).c_str(), g.before.objective,
                g.after.objective, g.improved ? "" : " (no improvement)");
    ImGui::TextDisabled("over %s", model.suggestion_targets.c_str());
    if (!g.improved) {  // as `pandora accept`: nothing to accept
      if (ImGui::Button("Reject")) Do(Make(Action::Kind::kReject));
      ImGui::End();
      return;
    }
    for (const CameraChange& ch : g.cameras) {
      ImGui::PushID(ch.index);
      ImGui::Text("%s: %.3f m, %.1f deg", ch.id.c_str(), ch.move_m, ch.rotate_deg);
      ImGui::SameLine();
      if (ImGui::SmallButton("accept")) {
        Do(Make(Action::Kind::kAccept, {ch.id}));
        ImGui::PopID();
        break;
      }
      ImGui::PopID();
    }
    if (model.suggestion && ImGui::Button("Accept all")) Do(Make(Action::Kind::kAccept));
    ImGui::SameLine();
    if (model.suggestion && ImGui::Button("Reject")) Do(Make(Action::Kind::kReject));
  }
  ImGui::End();
}

}  // namespace pandora::viewer
