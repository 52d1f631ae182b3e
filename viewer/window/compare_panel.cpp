// The compare panel: the edited rig beside the scene's other rigs (ViewerApp::Impl).
#include "viewer/window/viewer_app_impl.h"

namespace pandora::viewer {

void ViewerApp::Impl::ComparePanel() {
  ImGui::SetNextWindowPos(ImVec2(266, 34), ImGuiCond_FirstUseEver);
  ImGui::SetNextWindowSize(ImVec2(400, 330), ImGuiCond_FirstUseEver);
  ImGui::SetNextWindowCollapsed(true, ImGuiCond_FirstUseEver);
  ImGui::Begin("Compare");
  std::vector<std::string> rigs = {"(none)"};
  for (const Rig& r : model.scene().rigs)
    if (r.name != model.rig().name) rigs.push_back(r.name);
  compare_other = std::clamp(compare_other, 0, int(rigs.size()) - 1);
  if (ImGui::BeginCombo("other rig", rigs[compare_other].c_str())) {
    for (int i = 0; i < int(rigs.size()); ++i)
      if (ImGui::Selectable(rigs[i].c_str(), i == compare_other)) compare_other = i;
    ImGui::EndCombo();
  }
  if (ImGui::Button("Compare with saved")) {
    Action a = Make(Action::Kind::kCompare, {"saved"});
    if (compare_other > 0) a.cameras.push_back(rigs[compare_other]);
    Do(a);
  }
  const std::optional<RigComparison>& cmp = model.comparison;
  if (cmp) {
    if (model.comparison_rig_version != model.session().rig().version()) {
      ImGui::SameLine();
      ImGui::TextColored(ImVec4(1.0f, 0.75f, 0.3f, 1.0f), "rig edited since");
    }
    const int n = int(cmp->rigs.size());
    if (ImGui::BeginTable("comparison", n + 1, ImGuiTableFlags_Borders | ImGuiTableFlags_RowBg)) {
      // Short headers: "edited", "saved", the other rig's name.
      ImGui::TableSetupColumn("", ImGuiTableColumnFlags_WidthFixed, 170.0f);
      for (const std::string& r : cmp->rigs) {
        const auto open = r.rfind(" (");
        const std::string head = open != std::string::npos && r.back() == ')'
                                     ? r.substr(open + 2, r.size() - open - 3)
                                     : r;
        ImGui::TableSetupColumn(head.c_str(), ImGuiTableColumnFlags_WidthStretch);
      }
      ImGui::TableHeadersRow();
      ImGui::TableNextRow();
      ImGui::TableSetColumnIndex(0);
      ImGui::TextUnformatted("Cameras on");
      for (int i = 0; i < n; ++i) {
        ImGui::TableSetColumnIndex(i + 1);
        ImGui::Text("%d", cmp->enabled_cameras[i]);
      }
      for (const ComparisonRow& row : cmp->rows) {
        if (std::none_of(row.values.begin(), row.values.end(),
                         [](const std::optional<double>& v) { return v.has_value(); }))
          continue;  // a row no rig has (a field that is not live)
        ImGui::TableNextRow();
        ImGui::TableSetColumnIndex(0);
        ImGui::TextUnformatted(row.label.c_str());
        for (int i = 0; i < n; ++i) {
          ImGui::TableSetColumnIndex(i + 1);
          const std::string text = row.Text(i);
          if (row.best[i])
            ImGui::TextColored(ImVec4(0.4f, 0.95f, 0.45f, 1.0f), "%s", text.c_str());
          else
            ImGui::TextUnformatted(text.c_str());
        }
      }
      ImGui::EndTable();
    }
  } else {
    ImGui::TextDisabled(
        "the edited rig's live fields against the rig as saved\n(evaluated once on the button)");
  }
  ImGui::End();
}

}  // namespace pandora::viewer
