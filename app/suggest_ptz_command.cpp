// `pandora suggest --ptz-preset ID:PRESET | --ptz-tour ID`: a PTZ controller's preset setting or
// tour order for the target points, written as a suggestion file for `pandora accept`
// (docs/ptz.md).
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "analysis/geometry/camera.h"
#include "analysis/geometry/visibility.h"
#include "analysis/util/atomic_file.h"
#include "analysis/util/error.h"
#include "analysis/util/units.h"
#include "app/commands.h"
#include "app/options.h"
#include "app/output.h"
#include "app/session/session.h"
#include "app/suggest_options.h"
#include "suggest/ptz_suggest.h"
#include "suggest/suggest.h"
#include "volume/ptz_fields.h"

namespace pandora::app {
namespace {

std::string Names(const std::vector<std::string>& names) {
  std::string out;
  for (const std::string& n : names) out += (out.empty() ? "" : ", ") + n;
  return out.empty() ? "none" : out;
}

std::string AtDensity(double px) {
  if (!(px > 0)) return "";
  char b[64];
  std::snprintf(b, sizeof b, " at %g px/m", px);
  return b;
}

}  // namespace

int RunSuggestPtz(const SuggestArgs& args) {
  if (!args.ptz_preset.empty() && !args.ptz_tour.empty())
    throw InputError("--ptz-tour", "", "give --ptz-preset or --ptz-tour, not both");
  if (!args.cameras.empty())
    throw InputError("--cameras", "",
                     "moves cameras; --ptz-preset and --ptz-tour change a PTZ controller",
                     "give one of them");
  if (args.over_time)
    throw InputError("--over-time", "", "is not available with --ptz-preset or --ptz-tour");
  const std::optional<TourObjective> tour = TourObjectiveFromName(args.tour_objective);
  if (!tour)
    throw InputError("--tour-objective", "", "unknown objective '" + args.tour_objective + "'",
                     "use mean or max");
  const TourObjective objective = *tour;
  session::Session session(session::Study::Load(args.scene), SuggestSessionOptions(args));
  const Scene& scene = session.study().scene();
  const Rig& rig = session.rig().rig();
  const bool preset_mode = !args.ptz_preset.empty();
  const std::string option = preset_mode ? "--ptz-preset" : "--ptz-tour";
  std::string id = preset_mode ? args.ptz_preset : args.ptz_tour, preset_name;
  if (preset_mode) {
    const std::size_t colon = id.rfind(':');
    if (colon == std::string::npos || colon == 0 || colon + 1 == id.size())
      throw InputError(option, "", "expected ID:PRESET, got '" + id + "'");
    preset_name = id.substr(colon + 1);
    id = id.substr(0, colon);
  }
  const int camera = PtzCameraOption(rig, option, id);
  const PtzHead& head = *rig.cameras[camera].ptz;
  int preset = -1;
  if (preset_mode) {
    std::vector<std::string> names;
    for (std::size_t i = 0; i < head.presets.size(); ++i) {
      names.push_back(head.presets[i].name);
      if (head.presets[i].name == preset_name) preset = static_cast<int>(i);
    }
    if (preset < 0)
      throw InputError(option, "", "camera '" + id + "' has no preset '" + preset_name + "'",
                       "its presets: " + Names(names));
  } else if (head.tour.size() < 3) {
    throw InputError(option, "",
                     "camera '" + id + "' has " + std::to_string(head.tour.size()) +
                         " tour stops: with fewer than 3 every order is the same cycle");
  }
  // The target points: the study region's (or a named region's), or surfaces.
  const std::vector<TargetPoint> targets =
      SampleTargetsInRegion(scene, "--target-region", args.target_region, args.points,
                            args.target_surfaces, args.with_region, args.seed);
  std::vector<Vec3> points;
  for (const TargetPoint& t : targets) points.push_back(t.p);
  const std::unique_ptr<SurfaceDistance> surfaces = PtzSweptOccluders(scene, rig);
  const VisibilityTester tester(rig.cameras, session.study().caster(),
                                scene.ContentBounds().diagonal(), surfaces.get());
  const double px = scene.study.ptz.min_px_per_m;

  OutputTransaction output;
  AddSceneInputs(output, scene);
  const std::string path = output.Stage(args.out, "--out");
  std::string text, summary;
  bool improved = false;
  char line[512];
  if (preset_mode) {
    const PtzPresetSuggestion s = SuggestPtzPreset(tester, camera, preset, points, px);
    improved = s.improved();
    const Intrinsics& k = rig.cameras[camera].model.intrinsics();
    auto hfov = [&](double f) { return HfovFromFocal(f, k.width, k.model) * 180 / kPi; };
    std::snprintf(line, sizeof line,
                  "%s preset %s: sees %d -> %d of %d target points%s\n"
                  "  pan %.2f -> %.2f deg, tilt %.2f -> %.2f deg, hfov %.2f -> %.2f deg (%d "
                  "settings judged, %.2f s)\n",
                  id.c_str(), preset_name.c_str(), s.seen_before, s.seen_after, s.points,
                  px > 0 ? AtDensity(px).c_str() : "", s.before.pan_deg, s.after.pan_deg,
                  s.before.tilt_deg, s.after.tilt_deg, hfov(s.before.focal), hfov(s.after.focal),
                  s.evaluations, s.seconds);
    summary = line;
    text = PtzPresetSuggestionToJson(s, scene, rig);
  } else {
    const PtzTourSuggestion s = SuggestPtzTour(tester, camera, points, px, objective);
    improved = s.improved();
    auto names = [&](const std::vector<int>& order) {
      std::string out;
      for (int stop : order)
        out += (out.empty() ? "" : " > ") + head.presets[head.tour[stop].preset].name;
      return out;
    };
    std::snprintf(line, sizeof line,
                  "%s tour (objective %s) over the %d of %d target points a stop watches%s: "
                  "longest unwatched %.2f -> %.2f s, mean %.2f -> %.2f s, "
                  "period %.2f -> %.2f s\n  %s\n  -> %s\n  (%lld orders judged%s, %.2f s)\n",
                  id.c_str(), args.tour_objective.c_str(), s.watchable, s.points,
                  px > 0 ? AtDensity(px).c_str() : "", s.gap_max_before, s.gap_max_after,
                  s.gap_mean_before, s.gap_mean_after, s.period_before, s.period_after,
                  names(s.before).c_str(), names(s.after).c_str(), static_cast<long long>(s.orders),
                  s.exhaustive ? ", every order" : ", 2-opt", s.seconds);
    summary = line;
    text = PtzTourSuggestionToJson(s, scene, rig);
  }
  WriteFileAtomically(path, text);
  output.Commit();
  if (!args.quiet) {
    std::fputs(summary.c_str(), stdout);
    std::printf("wrote %s%s\n", args.out.c_str(),
                improved ? "" : " (no improvement: nothing to accept)");
  }
  return 0;
}

}  // namespace pandora::app
