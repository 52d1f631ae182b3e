#include "app/session/ptz_edit.h"

#include <algorithm>
#include <memory>
#include <stdexcept>

#include "analysis/util/error.h"
#include "analysis/util/units.h"

namespace pandora::session {
namespace {

bool SameState(const PtzState& a, const PtzState& b) {
  return a.pan_deg == b.pan_deg && a.tilt_deg == b.tilt_deg && a.focal == b.focal;
}

std::string Num(double v) {
  char s[32];
  std::snprintf(s, sizeof s, "%.6g", v);
  return s;
}

}  // namespace

bool SamePtzHead(const PtzHead* a, const PtzHead* b) {
  if (!a || !b) return a == b;
  if (a == b) return true;
  if (a->presets.size() != b->presets.size() || a->tour.size() != b->tour.size()) return false;
  for (std::size_t i = 0; i < a->presets.size(); ++i)
    if (a->presets[i].name != b->presets[i].name ||
        !SameState(a->presets[i].state, b->presets[i].state))
      return false;
  for (std::size_t i = 0; i < a->tour.size(); ++i)
    if (a->tour[i].preset != b->tour[i].preset || a->tour[i].dwell_s != b->tour[i].dwell_s)
      return false;
  return a->home.matrix() == b->home.matrix() && a->pan_axis == b->pan_axis &&
         a->offset == b->offset && a->pan_min_deg == b->pan_min_deg &&
         a->pan_max_deg == b->pan_max_deg && a->tilt_min_deg == b->tilt_min_deg &&
         a->tilt_max_deg == b->tilt_max_deg && a->focal_min == b->focal_min &&
         a->focal_max == b->focal_max && a->pan_speed_deg_s == b->pan_speed_deg_s &&
         a->tilt_speed_deg_s == b->tilt_speed_deg_s && a->zoom_speed == b->zoom_speed &&
         a->home_focal == b->home_focal && a->trace_s == b->trace_s &&
         SameState(a->current, b->current);
}

PtzState ClampPtzState(const PtzHead& h, PtzState s) {
  s.pan_deg = h.ContinuousPan() ? h.WrapPan(s.pan_deg)
                                : std::clamp(s.pan_deg, h.pan_min_deg, h.pan_max_deg);
  s.tilt_deg = std::clamp(s.tilt_deg, h.tilt_min_deg, h.tilt_max_deg);
  s.focal = std::clamp(s.focal, h.focal_min, h.focal_max);
  return s;
}

Camera WithPtzState(const Camera& camera, const PtzState& s) {
  if (!camera.ptz)
    throw std::logic_error("WithPtzState: camera '" + camera.id + "' has no PTZ head");
  auto head = std::make_shared<PtzHead>(*camera.ptz);
  head->current = ClampPtzState(*head, s);
  Camera out = head->CameraAt(camera, head->current);
  out.ptz = std::move(head);
  return out;
}

PtzState PtzStateFacing(const PtzHead& h, const Mat3& R, double keep_pan) {
  // Forward at (pan, tilt) = Rot(a, pan) (cos(e + tilt) b + sin(e + tilt) a), with a the pan axis,
  // e home's elevation and b = a x (home's image x axis) home's horizontal direction.
  const Vec3 a = h.pan_axis;
  const Vec3 b = a.cross(h.home.linear().col(0)).normalized();
  const Vec3 f = R.col(2);
  const double up = std::clamp(f.dot(a), -1.0, 1.0);
  PtzState s = h.current;
  s.tilt_deg = Deg(std::asin(up)) - h.HomeElevationDeg();
  const Vec3 horizontal = f - up * a;
  s.pan_deg = horizontal.norm() > 1e-12
                  ? Deg(std::atan2(a.dot(b.cross(horizontal)), b.dot(horizontal)))
                  : keep_pan;
  if (!h.ContinuousPan()) {
    // The turn within the range nearest the azimuth (a range may reach beyond +-180).
    double best = s.pan_deg, distance = std::numeric_limits<double>::infinity();
    for (double k : {-360.0, 0.0, 360.0}) {
      const double p = s.pan_deg + k;
      const double d = p < h.pan_min_deg   ? h.pan_min_deg - p
                       : p > h.pan_max_deg ? p - h.pan_max_deg
                                           : 0.0;
      if (d < distance) distance = d, best = p;
    }
    s.pan_deg = best;
  }
  return s;
}

Camera PtzFollow(const Camera& before, const Camera& requested, bool* clamped) {
  if (!before.ptz) throw std::logic_error("PtzFollow: camera '" + before.id + "' has no PTZ head");
  const PtzHead& h = *before.ptz;
  auto head = std::make_shared<PtzHead>(h);
  head->home.translation() += requested.center() - before.center();
  PtzState want = h.current;
  if (requested.world_from_camera.linear() != before.world_from_camera.linear())
    want = PtzStateFacing(h, requested.world_from_camera.linear(), h.current.pan_deg);
  want.focal = requested.model.intrinsics().fx;
  if (want.focal == before.model.intrinsics().fx) want.focal = h.current.focal;
  head->current = ClampPtzState(*head, want);
  if (clamped) {
    const double dpan = h.ContinuousPan()
                            ? std::abs(head->current.pan_deg - h.WrapPan(want.pan_deg))
                            : std::abs(head->current.pan_deg - want.pan_deg);
    *clamped = dpan > 1e-9 || std::abs(head->current.tilt_deg - want.tilt_deg) > 1e-9 ||
               std::abs(head->current.focal - want.focal) > 1e-9 * want.focal;
  }
  Camera out = head->CameraAt(requested, head->current);
  out.ptz = std::move(head);
  return out;
}

Camera RecentredPtz(const Camera& camera, const std::string& file, const std::string& where) {
  if (!camera.ptz)
    throw InputError(file, where,
                     "camera '" + camera.id + "' has no pan-tilt-zoom head to re-centre",
                     "re-centre applies to a camera with a \"ptz\" block (docs/ptz.md)");
  const PtzHead& h = *camera.ptz;
  auto head = std::make_shared<PtzHead>(h);
  PtzHead& n = *head;
  const double pan = h.current.pan_deg, tilt = h.current.tilt_deg;
  n.home.linear() = Eigen::AngleAxisd(Rad(pan), h.pan_axis).toRotationMatrix() * h.home.linear() *
                    Eigen::AngleAxisd(Rad(tilt), Vec3::UnitX()).toRotationMatrix();
  n.current.pan_deg = 0;
  n.current.tilt_deg = 0;
  n.pan_min_deg = h.pan_min_deg - pan;
  n.pan_max_deg = h.pan_max_deg - pan;
  n.tilt_min_deg = h.tilt_min_deg - tilt;
  n.tilt_max_deg = h.tilt_max_deg - tilt;
  for (PtzPreset& p : n.presets) {
    p.state.pan_deg -= pan;
    p.state.tilt_deg -= tilt;
  }
  // The scene reader's checks (analysis/scene/scene.cpp ReadPtz), on the new home: a level head,
  // the ranges holding home, the tilt range within the optical axis's straight down .. straight up.
  const double el = n.HomeElevationDeg();
  // Along the pan axis (within 1e-6 deg) the elevation's asin has lost the digits the check needs.
  if (std::abs(el) >= 90 - 1e-6)
    throw InputError(file, where + ".ptz.tilt_range_deg",
                     "re-centring '" + camera.id + "' at tilt " + Num(tilt) +
                         " deg would make its home look straight " + (el > 0 ? "up" : "down") +
                         ", along the pan axis, past which the tilt range cannot reach",
                     "tilt the head less far before re-centring");
  if (!(n.tilt_min_deg >= -90 - el - 1e-9 && n.tilt_max_deg <= 90 - el + 1e-9) ||
      std::abs(n.pan_axis.dot(n.home.linear().col(0))) > 1e-6)
    throw InputError(
        file, where + ".ptz.tilt_range_deg",
        "re-centring '" + camera.id + "' at tilt " + Num(tilt) +
            " deg would make its tilt range [" + Num(n.tilt_min_deg) + ", " + Num(n.tilt_max_deg) +
            "] reach past straight up or down from the new home (elevation " + Num(el) + " deg)",
        "tilt the head less far before re-centring, or narrow its tilt_range_deg");
  if (n.pan_min_deg < -360 - 1e-9 || n.pan_max_deg > 360 + 1e-9)
    throw InputError(
        file, where + ".ptz.pan_range_deg",
        "re-centring '" + camera.id + "' would shift its pan range beyond one turn either way");
  Camera out = n.CameraAt(camera, n.current);
  out.ptz = std::move(head);
  return out;
}

Rig PtzTracedRig(const Rig& rig, const std::string& mode, double budget_s,
                 std::vector<RenderOptions::PtzTrace>* all, bool* any) {
  if (mode != "single" && mode != "path" && mode != "all")
    throw std::invalid_argument("unknown PTZ trace mode '" + mode + "' (single, path or all)");
  bool found = false;
  for (const Camera& cam : rig.cameras) found = found || (cam.ptz && cam.enabled);
  if (any) *any = found;
  if (mode == "single") return rig;
  Rig traced = rig;
  traced.cameras.clear();
  for (const Camera& cam : rig.cameras) {
    if (!cam.ptz || !cam.enabled) {
      traced.cameras.push_back(cam);
      continue;
    }
    if (mode == "all") {
      traced.cameras.push_back(cam.ptz->CameraAt(cam, cam.ptz->Home()));
      if (all)
        all->push_back(
            {int(traced.cameras.size()) - 1, std::isnan(budget_s) ? cam.ptz->trace_s : budget_s});
      continue;
    }
    const std::vector<PtzState> path = cam.ptz->Path(cam.ptz->Home(), cam.ptz->current);
    for (std::size_t k = 0; k < path.size(); ++k) {
      Camera step = cam.ptz->CameraAt(cam, path[k]);
      step.id = cam.id + "@" + std::to_string(k) + (k + 1 == path.size() && k > 0 ? "-end" : "");
      step.color =
          (1.0 - 0.6 * double(k) / double(std::max<std::size_t>(1, path.size() - 1))) * cam.color;
      traced.cameras.push_back(step);
    }
  }
  return traced;
}

}  // namespace pandora::session
