// Suggestions for a PTZ camera's controller: a preset's setting, a tour's order (docs/ptz.md).
#include "suggest/ptz_suggest.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <limits>
#include <nlohmann/json.hpp>
#include <numeric>

#include "analysis/geometry/camera.h"
#include "analysis/scene/scene_text.h"
#include "analysis/util/error.h"
#include "analysis/util/json_reader.h"
#include "analysis/util/sha256.h"
#include "analysis/util/units.h"
#include "suggest/suggestion_file.h"

namespace pandora {
namespace {

using json = nlohmann::json;
using ordered_json = nlohmann::ordered_json;

double Seconds(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

// The setting within the head's ranges (pan wrapped when continuous).
PtzState Clamp(const PtzHead& h, PtzState s) {
  s.pan_deg = h.ContinuousPan() ? h.WrapPan(s.pan_deg)
                                : std::clamp(s.pan_deg, h.pan_min_deg, h.pan_max_deg);
  s.tilt_deg = std::clamp(s.tilt_deg, h.tilt_min_deg, h.tilt_max_deg);
  s.focal = std::clamp(s.focal, h.focal_min, h.focal_max);
  return s;
}

struct Candidate {
  PtzState s;
  int seen = -1;
  double move = 0;
};

// More points; then the wider zoom; then the shorter move from the preset as it was.
bool Better(const Candidate& a, const Candidate& b) {
  if (a.seen != b.seen) return a.seen > b.seen;
  if (std::abs(a.s.focal - b.s.focal) > 1e-9 * b.s.focal) return a.s.focal < b.s.focal;
  return a.move < b.move - 1e-12;
}

// The merged intervals' longest gap around a period (PtzWatch::longest_gap_s).
double LongestGap(std::vector<std::pair<double, double>>& v, double period) {
  PtzWatch w;
  w.period = period;
  for (const auto& [a, b] : v) {
    if (!(b > a)) continue;
    if (!w.intervals.empty() && a <= w.intervals.back().second + 1e-12)
      w.intervals.back().second = std::max(w.intervals.back().second, b);
    else
      w.intervals.emplace_back(a, b);
  }
  return w.longest_gap_s();
}

json StateJson(const PtzHead& h, const Camera& c, const PtzState& s) {
  const Intrinsics& k = c.model.intrinsics();
  return {{"pan_deg", s.pan_deg},
          {"tilt_deg", s.tilt_deg},
          {"hfov_deg", Deg(HfovFromFocal(s.focal, k.width, k.model))},
          {"focal_px", s.focal},
          {"zooms", h.focal_max > h.focal_min}};
}

json Header(const std::string& kind, const Scene& scene, const Rig& rig, bool improved) {
  return {{"pandora_suggestion", 1},
          {"kind", kind},
          {"scene",
           {{"path", std::filesystem::absolute(scene.path).lexically_normal().string()},
            {"sha256", scene.sha256}}},
          {"rig", rig.name},
          {"improved", improved},
          {"cameras", json::array()}};
}

// The rig, camera and its ptz block in an ordered scene file; InputError when not there.
ordered_json& FindPtzBlock(ordered_json& root, const std::string& path, const std::string& rig_name,
                           const std::string& camera, std::string* where) {
  const std::string hint = "the scene file no longer matches the suggestion";
  std::size_t r = 0;
  ordered_json& rig = scene_text::FindRig(root, path, rig_name, hint, &r);
  const std::string cameras = "$.rigs[" + std::to_string(r) + "].cameras";
  if (!rig.contains("cameras") || !rig["cameras"].is_array())
    throw InputError(path, cameras, "no cameras", hint);
  for (std::size_t c = 0; c < rig["cameras"].size(); ++c) {
    ordered_json& cam = rig["cameras"][c];
    if (!cam.is_object() || !cam.contains("id") || scene_text::IdOf(cam["id"]) != camera) continue;
    *where = cameras + "[" + std::to_string(c) + "].ptz";
    if (!cam.contains("ptz") || !cam["ptz"].is_object())
      throw InputError(path, *where, "camera '" + camera + "' has no ptz block", hint);
    return cam["ptz"];
  }
  throw InputError(path, cameras, "no camera '" + camera + "' in rig '" + rig_name + "'", hint);
}

}  // namespace

PtzPointJudge::PtzPointJudge(const VisibilityTester& tester, int camera,
                             const std::vector<Vec3>& points, double min_px_per_m)
    : tester_(tester),
      camera_(camera),
      points_(points),
      min_px_per_m_(min_px_per_m),
      pivot_clear_(points.size(), -1) {}

bool PtzPointJudge::Sees(std::size_t i, const PtzState& s) const {
  Ray r;
  if (!PtzSees(camera(), head(), s, points_[i], min_px_per_m_, nullptr, &r)) return false;
  const bool fixed_centre = head().offset.isZero(0.0);
  if (fixed_centre && pivot_clear_[i] >= 0) return pivot_clear_[i] == 1;
  const bool clear = !PtzSegmentOccluded(tester_, camera_, r, &rays_);
  if (fixed_centre) pivot_clear_[i] = clear ? 1 : 0;
  return clear;
}

int PtzPointJudge::Count(const PtzState& s) const {
  int n = 0;
  for (std::size_t i = 0; i < points_.size(); ++i) n += Sees(i, s);
  return n;
}

PtzPresetSuggestion SuggestPtzPreset(const VisibilityTester& tester, int camera, int preset,
                                     const std::vector<Vec3>& points, double min_px_per_m) {
  const auto t0 = std::chrono::steady_clock::now();
  const PtzPointJudge judge(tester, camera, points, min_px_per_m);
  const Camera& cam = judge.camera();
  const PtzHead& h = judge.head();
  PtzPresetSuggestion out;
  out.camera = cam.id;
  out.preset = h.presets[preset].name;
  out.before = h.presets[preset].state;
  out.points = static_cast<int>(points.size());
  auto judge_state = [&](const PtzState& s) {
    Candidate c;
    c.s = Clamp(h, s);
    c.seen = judge.Count(c.s);
    c.move = h.MoveTime(out.before, c.s);
    ++out.evaluations;
    return c;
  };
  const Candidate start = judge_state(out.before);
  out.seen_before = start.seen;
  // Zooms: 12 from the widest to the narrowest, evenly in log focal (one without a zoom range).
  std::vector<double> focals{h.focal_min};
  if (h.focal_max > h.focal_min)
    for (int k = 1; k < 12; ++k)
      focals.push_back(h.focal_min * std::pow(h.focal_max / h.focal_min, k / 11.0));
  // Centres: the centring setting of up to 64 target points (evenly through the list) and of
  // their mean.
  const PtzReach reach(cam, h, h.current);
  std::vector<Vec3> aims;
  const std::size_t stride = std::max<std::size_t>(1, points.size() / 64);
  for (std::size_t i = 0; i < points.size(); i += stride) aims.push_back(points[i]);
  if (!points.empty())
    aims.push_back(std::accumulate(points.begin(), points.end(), Vec3(Vec3::Zero())) /
                   double(points.size()));
  std::vector<Candidate> best{start};
  for (const Vec3& X : aims) {
    const std::optional<PtzState> centre = reach.BestPose(X, 1e9);
    if (!centre) continue;
    for (double f : focals) {
      const Candidate c = judge_state({centre->pan_deg, centre->tilt_deg, f});
      best.push_back(c);
    }
  }
  std::sort(best.begin(), best.end(), Better);
  if (best.size() > 4) best.resize(4);
  // Pattern search from the best few: pan, tilt, log focal; halve the steps when nothing improves.
  Candidate winner = best.front();
  const double log_span = h.focal_max > h.focal_min ? std::log(h.focal_max / h.focal_min) : 0.0;
  for (Candidate c : best) {
    const Intrinsics& k = cam.model.intrinsics();
    double angle = 0.25 * Deg(HfovFromFocal(c.s.focal, k.width, k.model));
    double zoom = log_span / 24.0;
    while (angle > 0.01) {
      bool moved = false;
      for (int axis = 0; axis < 3; ++axis) {
        for (double sign : {-1.0, 1.0}) {
          PtzState s = c.s;
          if (axis == 0) s.pan_deg += sign * angle;
          if (axis == 1) s.tilt_deg += sign * angle;
          if (axis == 2) {
            if (!(zoom > 0)) continue;
            s.focal *= std::exp(sign * zoom);
          }
          const Candidate n = judge_state(s);
          if (Better(n, c)) {
            c = n;
            moved = true;
          }
        }
      }
      if (!moved) {
        angle *= 0.5;
        zoom *= 0.5;
      }
    }
    if (Better(c, winner)) winner = c;
  }
  out.after = winner.s;
  out.seen_after = winner.seen;
  if (!out.improved()) {
    out.after = out.before;
    out.seen_after = out.seen_before;
  }
  out.seconds = Seconds(t0);
  return out;
}

std::vector<double> PtzTourGaps(const PtzPointJudge& judge, const std::vector<int>& order) {
  const std::vector<PtzHead::TourLeg> legs = judge.head().TourLegs(order);
  std::vector<double> gaps;
  for (std::size_t i = 0; i < judge.size(); ++i) {
    const PtzTarget target = judge.target(i);
    const PtzWatch w = WatchTour(
        judge.head(), judge.camera(), legs, [&](const PtzState& s) { return judge.Sees(i, s); },
        &target);
    gaps.push_back(w.longest_gap_s());
  }
  return gaps;
}

PtzTourSuggestion SuggestPtzTour(const VisibilityTester& tester, int camera,
                                 const std::vector<Vec3>& points, double min_px_per_m,
                                 TourObjective objective) {
  const auto t0 = std::chrono::steady_clock::now();
  const PtzPointJudge judge(tester, camera, points, min_px_per_m);
  const PtzHead& h = judge.head();
  const Camera& cam = judge.camera();
  const int n = static_cast<int>(h.tour.size());
  const std::size_t P = points.size();
  PtzTourSuggestion out;
  out.camera = cam.id;
  out.objective = objective;
  out.points = static_cast<int>(P);
  for (int i = 0; i < n; ++i) out.before.push_back(i);
  auto state = [&](int stop) { return h.presets[h.tour[stop].preset].state; };
  // Per point: the dwell at each stop, the move between every ordered pair of stops (relative to
  // the move's start), exactly as WatchTour finds a leg's.
  std::vector<std::vector<char>> dwell(P, std::vector<char>(n, 0));
  std::vector<std::vector<std::vector<std::pair<double, double>>>> moves(
      P, std::vector<std::vector<std::pair<double, double>>>(n * n));
  std::vector<double> move_s(n * n, 0.0);
  std::vector<char> watchable(P, 0);
  for (int a = 0; a < n; ++a)
    for (int b = 0; b < n; ++b) move_s[a * n + b] = h.MoveTime(state(a), state(b));
  for (std::size_t i = 0; i < P; ++i) {
    auto sees = [&](const PtzState& s) { return judge.Sees(i, s); };
    const PtzTarget target = judge.target(i);
    for (int a = 0; a < n; ++a) {
      dwell[i][a] = h.tour[a].dwell_s > 0 && sees(state(a));
      watchable[i] |= dwell[i][a];
      for (int b = 0; b < n; ++b) {
        if (a == b || !(move_s[a * n + b] > 0)) continue;
        PtzHead::TourLeg leg;
        leg.from = state(a);
        leg.to = state(b);
        leg.move_s = move_s[a * n + b];
        const PtzWatch w = WatchTour(h, cam, {leg}, sees, &target);
        moves[i][a * n + b] = w.intervals;
      }
    }
  }
  out.watchable = static_cast<int>(std::count(watchable.begin(), watchable.end(), 1));
  // An order's gaps: its legs' intervals laid end to end (the same sums as TourLegs and WatchTour).
  std::vector<std::pair<double, double>> v;
  auto judge_order = [&](const std::vector<int>& order, double* gap_max, double* gap_mean,
                         double* period) {
    ++out.orders;
    std::vector<double> start(n);
    double t = 0;
    for (int k = 0; k < n; ++k) {
      const int from = order[(k + n - 1) % n], to = order[k];
      start[k] = t;
      t = t + move_s[from * n + to] + h.tour[to].dwell_s;
    }
    *period = t;
    double worst = 0, sum = 0;
    for (std::size_t i = 0; i < P; ++i) {
      if (!watchable[i]) continue;
      v.clear();
      for (int k = 0; k < n; ++k) {
        const int from = order[(k + n - 1) % n], to = order[k];
        const double m = move_s[from * n + to];
        if (m > 0)
          for (const auto& [a, b] : moves[i][from * n + to])
            v.emplace_back(start[k] + a, start[k] + b);
        if (dwell[i][to]) v.emplace_back(start[k] + m, start[k] + m + h.tour[to].dwell_s);
      }
      const double g = LongestGap(v, t);
      worst = std::max(worst, g);
      sum += g;
    }
    *gap_max = worst;
    *gap_mean = out.watchable ? sum / out.watchable : 0.0;
  };
  judge_order(out.before, &out.gap_max_before, &out.gap_mean_before, &out.period_before);
  std::vector<int> best = out.before;
  double best_max = out.gap_max_before, best_mean = out.gap_mean_before,
         best_period = out.period_before;
  auto consider = [&](const std::vector<int>& order) {
    double gmax, gmean, period;
    judge_order(order, &gmax, &gmean, &period);
    if (out.Better(gmax, gmean, best_max, best_mean)) {
      best = order;
      best_max = gmax;
      best_mean = gmean;
      best_period = period;
      return true;
    }
    return false;
  };
  if (n <= 8) {
    out.exhaustive = true;
    std::vector<int> order = out.before;
    while (std::next_permutation(order.begin() + 1, order.end())) consider(order);
  } else {
    // 2-opt: reverse a stretch of the cycle (the first stop stays first) while it helps.
    bool improved = true;
    while (improved) {
      improved = false;
      for (int a = 1; a < n - 1 && !improved; ++a)
        for (int b = a + 1; b < n && !improved; ++b) {
          std::vector<int> order = best;
          std::reverse(order.begin() + a, order.begin() + b + 1);
          improved = consider(order);
        }
    }
  }
  out.after = best;
  out.gap_max_after = best_max;
  out.gap_mean_after = best_mean;
  out.period_after = best_period;
  out.seconds = Seconds(t0);
  return out;
}

std::string PtzPresetSuggestionToJson(const PtzPresetSuggestion& s, const Scene& scene,
                                      const Rig& rig) {
  const Camera* cam = &rig.cameras.at(static_cast<std::size_t>(rig.FindCamera(s.camera)));
  json j = Header("ptz_preset", scene, rig, s.improved());
  j["ptz"] = {{"camera", s.camera},
              {"preset", s.preset},
              {"before", StateJson(*cam->ptz, *cam, s.before)},
              {"after", StateJson(*cam->ptz, *cam, s.after)},
              {"points", s.points},
              {"seen_before", s.seen_before},
              {"seen_after", s.seen_after},
              {"evaluations", s.evaluations},
              {"seconds", s.seconds}};
  return j.dump(2) + "\n";
}

std::string PtzTourSuggestionToJson(const PtzTourSuggestion& s, const Scene& scene,
                                    const Rig& rig) {
  const Camera* cam = &rig.cameras.at(static_cast<std::size_t>(rig.FindCamera(s.camera)));
  auto names = [&](const std::vector<int>& order) {
    json a = json::array();
    for (int stop : order) a.push_back(cam->ptz->presets[cam->ptz->tour[stop].preset].name);
    return a;
  };
  json j = Header("ptz_tour", scene, rig, s.improved());
  j["ptz"] = {{"camera", s.camera},
              {"objective", TourObjectiveName(s.objective)},
              {"tour_before", s.before},
              {"tour_after", s.after},
              {"presets_before", names(s.before)},
              {"presets_after", names(s.after)},
              {"points", s.points},
              {"watchable", s.watchable},
              {"gap_max_before_s", s.gap_max_before},
              {"gap_max_after_s", s.gap_max_after},
              {"gap_mean_before_s", s.gap_mean_before},
              {"gap_mean_after_s", s.gap_mean_after},
              {"period_before_s", s.period_before},
              {"period_after_s", s.period_after},
              {"orders", s.orders},
              {"exhaustive", s.exhaustive},
              {"seconds", s.seconds}};
  return j.dump(2) + "\n";
}

std::string ReplacePtzPreset(const std::string& text, const std::string& path,
                             const std::string& rig, const std::string& camera,
                             const std::string& preset, const PtzState& state, double hfov_deg) {
  ordered_json root = scene_text::ParseOrdered(text, path);
  std::string where;
  ordered_json& ptz = FindPtzBlock(root, path, rig, camera, &where);
  if (ptz.contains("presets") && ptz["presets"].is_array())
    for (ordered_json& p : ptz["presets"]) {
      if (!p.is_object() || !p.contains("name") || p["name"] != preset) continue;
      p["pan_deg"] = scene_text::Number(scene_text::Clean(state.pan_deg));
      p["tilt_deg"] = scene_text::Number(scene_text::Clean(state.tilt_deg));
      if (hfov_deg > 0) p["hfov_deg"] = scene_text::Number(scene_text::Clean(hfov_deg));
      return scene_text::DumpLike(root, text);
    }
  throw InputError(path, where + ".presets", "no preset '" + preset + "'",
                   "the scene file no longer matches the suggestion");
}

std::string ReplacePtzTour(const std::string& text, const std::string& path, const std::string& rig,
                           const std::string& camera, const std::vector<int>& order) {
  ordered_json root = scene_text::ParseOrdered(text, path);
  std::string where;
  ordered_json& ptz = FindPtzBlock(root, path, rig, camera, &where);
  if (!ptz.contains("tour") || !ptz["tour"].is_array() || ptz["tour"].size() != order.size())
    throw InputError(path, where + ".tour",
                     "the tour does not have " + std::to_string(order.size()) + " stops",
                     "the scene file no longer matches the suggestion");
  const ordered_json old = ptz["tour"];
  ordered_json tour = ordered_json::array();
  for (int stop : order) tour.push_back(old.at(static_cast<std::size_t>(stop)));
  ptz["tour"] = std::move(tour);
  return scene_text::DumpLike(root, text);
}

std::string AcceptPtzSuggestion(const JsonNode& root, bool force, std::string* scene_path,
                                std::string* what) {
  const std::string& suggestion_path = root.file();
  root.ExpectObject();
  const std::string kind = root.Get("kind").Enum({"ptz_preset", "ptz_tour"});
  const JsonNode scene = root.Get("scene");
  scene.ExpectObject("a scene {\"path\", \"sha256\"}");
  *scene_path = scene.Get("path").String();
  const std::string sha256 = scene.Get("sha256").String();
  const std::string rig = root.Get("rig").String();
  const bool improved = root.Get("improved").Bool();
  const JsonNode p = root.Get("ptz");
  p.ExpectObject();
  const std::string camera = p.Get("camera").String();
  if (!improved)
    throw InputError(suggestion_path, "$.improved",
                     "the suggestion offers no improvement; nothing to accept",
                     "run pandora suggest with another target");
  const std::string scene_text = scene_text::ReadJsonText(*scene_path, "scene file");
  if (Sha256Hex(scene_text) != sha256 && !force)
    throw InputError(*scene_path, "",
                     "the scene file changed since the suggestion was made (SHA-256 differs)",
                     "run pandora suggest again, or accept with {force}");
  LoadOptions lo;
  lo.load_meshes = false;
  const Scene before = ParseScene(scene_text, *scene_path, lo);
  const Rig* r = nullptr;
  for (const Rig& candidate : before.rigs)
    if (candidate.name == rig) r = &candidate;
  const int index = r ? r->FindCamera(camera) : -1;
  const Camera* cam = index >= 0 ? &r->cameras[index] : nullptr;
  if (!cam || !cam->ptz)
    throw InputError(*scene_path, "$.rigs", "no PTZ camera '" + camera + "' in rig '" + rig + "'",
                     "the scene file no longer matches the suggestion");
  const PtzHead& head = *cam->ptz;
  std::string new_text;
  PtzState expected_state;
  int preset_index = -1;
  std::vector<int> order;
  if (kind == "ptz_preset") {
    const std::string preset = p.Get("preset").String();
    for (std::size_t i = 0; i < head.presets.size(); ++i)
      if (head.presets[i].name == preset) preset_index = static_cast<int>(i);
    if (preset_index < 0)
      throw InputError(*scene_path, "", "camera '" + camera + "' has no preset '" + preset + "'",
                       "the scene file no longer matches the suggestion");
    const JsonNode after = p.Get("after");
    const double pan = after.Get("pan_deg").Number(), tilt = after.Get("tilt_deg").Number(),
                 hfov = after.Get("hfov_deg").Number();
    const Intrinsics& k = cam->model.intrinsics();
    const bool zooms = head.focal_max > head.focal_min;
    expected_state = {pan, tilt,
                      zooms ? FocalFromHfov(hfov * kPi / 180.0, k.width, k.model)
                            : head.presets[preset_index].state.focal};
    new_text = ReplacePtzPreset(scene_text, *scene_path, rig, camera, preset, expected_state,
                                zooms ? hfov : 0.0);
    *what = camera + " preset " + preset;
  } else {
    const JsonNode tour_after = p.Get("tour_after");
    const std::size_t n = tour_after.ArraySize("an array of the tour's stops");
    std::vector<char> used(head.tour.size(), 0);
    for (std::size_t i = 0; i < n; ++i) {
      const int stop = tour_after.At(i).Integer(0, static_cast<int>(head.tour.size()) - 1);
      if (used[static_cast<std::size_t>(stop)]) tour_after.At(i).Fail("a stop is named twice");
      used[static_cast<std::size_t>(stop)] = 1;
      order.push_back(stop);
    }
    if (order.size() != head.tour.size())
      tour_after.Fail("not an order of the tour's " + std::to_string(head.tour.size()) + " stops");
    new_text = ReplacePtzTour(scene_text, *scene_path, rig, camera, order);
    *what = camera + " tour";
  }
  // Read it back: that preset or tour changed as intended, every camera of every rig unchanged.
  const Scene after = ParseScene(new_text, *scene_path, lo);
  auto bad = [&](const std::string& at) {
    throw InputError(
        *scene_path, at,
        "internal check failed: the rewritten PTZ block does not read back as intended",
        "the scene file was not changed");
  };
  for (std::size_t ri = 0; ri < before.rigs.size(); ++ri)
    for (std::size_t c = 0; c < before.rigs[ri].cameras.size(); ++c) {
      const Camera& a = before.rigs[ri].cameras[c];
      const Camera& b = after.rigs[ri].cameras[c];
      const std::string at =
          "$.rigs[" + std::to_string(ri) + "].cameras[" + std::to_string(c) + "]";
      if (!(a.world_from_camera.matrix() - b.world_from_camera.matrix()).isZero(1e-12) ||
          bool(a.ptz) != bool(b.ptz))
        bad(at);
      if (!a.ptz) continue;
      const PtzHead& ha = *a.ptz;
      const PtzHead& hb = *b.ptz;
      const bool target = before.rigs[ri].name == rig && a.id == camera;
      if (ha.presets.size() != hb.presets.size() || ha.tour.size() != hb.tour.size())
        bad(at + ".ptz");
      for (std::size_t k = 0; k < ha.presets.size(); ++k) {
        PtzState want = ha.presets[k].state;
        if (target && static_cast<int>(k) == preset_index) want = expected_state;
        const PtzState got = hb.presets[k].state;
        if (std::abs(got.pan_deg - want.pan_deg) > 1e-9 ||
            std::abs(got.tilt_deg - want.tilt_deg) > 1e-9 ||
            std::abs(got.focal - want.focal) > 1e-9 * want.focal)
          bad(at + ".ptz.presets[" + std::to_string(k) + "]");
      }
      for (std::size_t k = 0; k < ha.tour.size(); ++k) {
        const PtzTourStop want = target && !order.empty() ? ha.tour[order[k]] : ha.tour[k];
        if (hb.tour[k].preset != want.preset || hb.tour[k].dwell_s != want.dwell_s)
          bad(at + ".ptz.tour[" + std::to_string(k) + "]");
      }
    }
  return ReplaceSceneFileWithBackup(*scene_path, scene_text, new_text,
                                    {{suggestion_path, "suggestion file"}});
}

}  // namespace pandora
