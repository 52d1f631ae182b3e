#include "app/options.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <sstream>

#include "analysis/util/error.h"

namespace pandora::app {

std::vector<std::string> SplitList(const std::string& text) {
  std::vector<std::string> out;
  std::string item;
  std::istringstream in(text);
  while (std::getline(in, item, ',')) {
    const auto b = item.find_first_not_of(" \t");
    const auto e = item.find_last_not_of(" \t");
    out.push_back(b == std::string::npos ? "" : item.substr(b, e - b + 1));
  }
  return out;
}

std::vector<double> ParseNumbers(const std::string& option, const std::string& text,
                                 std::size_t count) {
  std::vector<double> out;
  for (const std::string& s : SplitList(text)) {
    char* end = nullptr;
    const double v = std::strtod(s.c_str(), &end);
    if (s.empty() || !end || *end != '\0' || !std::isfinite(v))
      throw InputError(option, "",
                       "'" + text + "' is not a list of " + std::to_string(count) + " numbers",
                       "separate the numbers with commas");
    out.push_back(v);
  }
  if (out.size() != count)
    throw InputError(option, "",
                     "expected " + std::to_string(count) + " comma-separated numbers, got " +
                         std::to_string(out.size()));
  return out;
}

Vec3 ParseVec3(const std::string& option, const std::string& text) {
  try {
    const std::vector<double> v = ParseNumbers(option, text, 3);
    return Vec3(v[0], v[1], v[2]);
  } catch (const InputError&) {
    throw InputError(option, "", "expected three numbers X,Y,Z, got '" + text + "'",
                     "e.g. " + option + " 1.5,-2,1.8");
  }
}

Aabb ParseBox(const Scene& scene, const std::string& option, const std::string& text) {
  const std::vector<double> v = ParseNumbers(option, text, 6);
  Aabb b;
  b.min = Vec3(v[0], v[1], v[2]);
  b.max = Vec3(v[3], v[4], v[5]);
  CheckBox(scene, option, b);
  return b;
}

void CheckBox(const Scene& scene, const std::string& option, const Aabb& b) {
  if (!b.min.allFinite() || !b.max.allFinite())
    throw InputError(option, "", "the box's corners must be finite numbers");
  scene.CheckReach(b.min, option, "the box's min corner");
  scene.CheckReach(b.max, option, "the box's max corner");
  if ((b.min.array() > b.max.array()).any())
    throw InputError(option, "", "the box's min exceeds its max",
                     "give XMIN,YMIN,ZMIN,XMAX,YMAX,ZMAX");
}

int CameraOption(const Rig& rig, const std::string& option, const std::string& id) {
  const int index = rig.FindCamera(id);
  if (index < 0)
    throw InputError(option, "", "no camera '" + id + "' in rig '" + rig.name + "'",
                     "cameras: " + rig.CameraIds());
  return index;
}

RenderView NamedView(const Scene& scene, const std::string& option, const std::string& name,
                     int width, int height) {
  const auto it = scene.views.find(name);
  if (it == scene.views.end()) {
    std::string names;
    for (const auto& [view_name, view] : scene.views)
      names += (names.empty() ? "" : ", ") + view_name;
    throw InputError(option, "", "no view '" + name + "' in " + scene.path,
                     names.empty() ? "the scene defines no views; use --from X,Y,Z --at X,Y,Z"
                                   : "views: " + names);
  }
  return ViewFromScene(it->second, width, height);
}

std::string Lower(std::string text) {
  std::transform(text.begin(), text.end(), text.begin(),
                 [](unsigned char c) { return std::tolower(c); });
  return text;
}

}  // namespace pandora::app
