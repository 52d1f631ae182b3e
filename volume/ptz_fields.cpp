// PTZ fields: reach times, reachable shares and tour watch over the study region (docs/ptz.md).
#include "volume/ptz_fields.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <stdexcept>

#include "analysis/geometry/camera.h"
#include "volume/fields_vdb.h"
#include "volume/summary.h"

namespace pandora {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

std::string Percent(double share) {
  char b[32];
  std::snprintf(b, sizeof b, "%.1f%%", 100.0 * share);
  return b;
}

std::string Seconds(const std::optional<double>& s) {
  if (!s) return "-";
  char b[32];
  std::snprintf(b, sizeof b, "%.2g s", *s);
  return b;
}

}  // namespace

bool RigHasPtz(const Rig& rig) {
  for (const Camera& c : rig.cameras)
    if (c.enabled && c.ptz) return true;
  return false;
}

std::unique_ptr<SurfaceDistance> PtzSweptOccluders(const Scene& scene, const Rig& rig) {
  for (const Camera& c : rig.cameras)
    if (c.enabled && c.ptz && c.ptz->TourMovesCentre())
      return std::make_unique<SurfaceDistance>(scene.AllTriangles());
  return nullptr;
}

double PtzReachTime(const VisibilityTester& tester, int camera, const Vec3& X, double min_px_per_m,
                    double tolerance_s, std::int64_t* rays) {
  const Camera& base = tester.cameras()[camera];
  const PtzHead& head = *base.ptz;
  const PtzReach reach(base, head, head.current, min_px_per_m);
  PtzState pose;
  const double t = reach.ReachTime(X, nullptr, tolerance_s, &pose);
  if (!std::isfinite(t)) return kInf;
  Ray s;
  if (!PtzSees(base, head, pose, X, 0.0, nullptr, &s)) return kInf;
  if (!PtzSegmentOccluded(tester, camera, s, rays)) return t;
  // The pivot is the centre of every setting: blocked from one, blocked from all.
  if (head.offset.isZero(0.0)) return kInf;
  // The centre moves with the setting: try the best pose with no time limit, then bisect on the
  // whole test (reachable and unoccluded) between the first geometric reach and it.
  const double T = reach.MaxTime();
  auto seen = [&](double time) {
    Ray r;
    return reach.Reachable(X, time, nullptr, &r) && !PtzSegmentOccluded(tester, camera, r, rays);
  };
  if (!seen(T)) return kInf;
  double lo = t, hi = T;
  while (hi - lo > tolerance_s) {
    const double mid = 0.5 * (lo + hi);
    (seen(mid) ? hi : lo) = mid;
  }
  return hi;
}

PtzWatch PtzTourWatch(const VisibilityTester& tester, int camera,
                      const std::vector<PtzHead::TourLeg>& legs, const Vec3& X, double min_px_per_m,
                      std::int64_t* rays) {
  const Camera& base = tester.cameras()[camera];
  const PtzHead& head = *base.ptz;
  const bool fixed_centre = head.offset.isZero(0.0);
  int pivot_blocked = -1;  // with a zero offset: the one segment's answer, once cast
  auto sees = [&](const PtzState& s) {
    Ray r;
    if (!PtzSees(base, head, s, X, min_px_per_m, nullptr, &r)) return false;
    if (fixed_centre) {
      if (pivot_blocked < 0) pivot_blocked = PtzSegmentOccluded(tester, camera, r, rays) ? 1 : 0;
      return pivot_blocked == 0;
    }
    return !PtzSegmentOccluded(tester, camera, r, rays);
  };
  const PtzTarget target{X, min_px_per_m, nullptr, &tester, camera};
  return WatchTour(head, base, legs, sees, &target);
}

namespace {

// The enabled PTZ cameras of the rig, rig order.
std::vector<int> PtzCameras(const Rig& rig) {
  std::vector<int> ptz;
  for (int c = 0; c < static_cast<int>(rig.cameras.size()); ++c)
    if (rig.cameras[c].enabled && rig.cameras[c].ptz) ptz.push_back(c);
  return ptz;
}

// The parts' layout: counts [region voxels, rays, reachable by some PTZ, within each budget, then
// per PTZ camera: reachable, within each budget, within the trace, watched at some time, the
// watched fractions' exact sum (kFixedLimbs)]; lists per PTZ camera: the finite reach times and
// the gaps of the voxels watched at some time.
constexpr std::size_t kPtzCounts = 3;
std::size_t PerPtzCamera(std::size_t budgets) { return budgets + 3 + kFixedLimbs; }

}  // namespace

SummaryParts PtzFieldsParts(const Scene& scene, const Rig& rig, const RayCaster& caster,
                            const Fields& fields, Fields* grids) {
  SummaryParts out;
  const Fields::Impl& g = fields.impl();
  if (!RigHasPtz(rig) || !g.coverage) return out;
  const auto t0 = std::chrono::steady_clock::now();
  const std::vector<double>& within_s = scene.study.ptz.within_s;
  const std::size_t budgets = within_s.size(), per = PerPtzCamera(budgets);
  std::vector<openvdb::Coord> voxels;
  ForEachActiveVoxel(*g.coverage, [&](const openvdb::Coord& c, int) { voxels.push_back(c); });
  const std::size_t n = voxels.size();
  const std::unique_ptr<SurfaceDistance> surfaces = PtzSweptOccluders(scene, rig);
  const VisibilityTester tester(rig.cameras, caster, scene.ContentBounds().diagonal(),
                                surfaces.get());
  const std::vector<int> ptz = PtzCameras(rig);
  out.counts.assign(kPtzCounts + budgets + per * ptz.size(), 0);
  out.lists.resize(2 * ptz.size());
  out.counts[0] = static_cast<std::int64_t>(n);
  std::vector<float> rig_min(n, std::numeric_limits<float>::infinity());
  std::atomic<std::int64_t> rays{0};
  const double px = scene.study.ptz.min_px_per_m;
  auto make_grid = [&](const std::string& name) {
    openvdb::FloatGrid::Ptr grid = openvdb::FloatGrid::create(0.0f);
    grid->setName(name);
    grid->setTransform(g.coverage->transformPtr()->copy());
    return grid;
  };
  for (std::size_t p = 0; p < ptz.size(); ++p) {
    const int c = ptz[p];
    const Camera& cam = rig.cameras[c];
    const PtzHead& head = *cam.ptz;
    const std::vector<PtzHead::TourLeg> legs = head.TourLegs();
    const bool tour = !legs.empty();
    const double period_s = tour ? legs.back().end() : 0.0;
    std::vector<float> reach(n), watched(tour ? n : 0), gap(tour ? n : 0);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 256), [&](const auto& r) {
      std::int64_t local = 0;
      for (std::size_t i = r.begin(); i != r.end(); ++i) {
        const openvdb::Vec3d w = g.coverage->indexToWorld(voxels[i]);
        const Vec3 X(w.x(), w.y(), w.z());
        reach[i] = static_cast<float>(PtzReachTime(tester, c, X, px, 1e-3, &local));
        if (tour) {
          const PtzWatch watch = PtzTourWatch(tester, c, legs, X, px, &local);
          watched[i] = static_cast<float>(period_s > 0 ? watch.watched_s() / period_s : 0.0);
          gap[i] = watch.intervals.empty() ? -1.0f : static_cast<float>(watch.longest_gap_s());
        }
      }
      rays += local;
    });
    std::int64_t* row = &out.counts[kPtzCounts + budgets + per * p];
    std::vector<float>& finite = out.lists[2 * p];
    for (std::size_t i = 0; i < n; ++i) {
      if (!std::isfinite(reach[i])) continue;
      finite.push_back(reach[i]);
      rig_min[i] = std::min(rig_min[i], reach[i]);
      for (std::size_t k = 0; k < budgets; ++k) row[1 + k] += reach[i] <= within_s[k];
      row[1 + budgets] += reach[i] <= head.trace_s;
    }
    row[0] = static_cast<std::int64_t>(finite.size());
    if (tour) {
      std::vector<float>& gaps = out.lists[2 * p + 1];
      for (std::size_t i = 0; i < n; ++i) {
        AddFixedLimbs(std::clamp(double(watched[i]), 0.0, 1.0), &row[3 + budgets]);
        if (gap[i] >= 0) gaps.push_back(gap[i]);
      }
      row[2 + budgets] = static_cast<std::int64_t>(gaps.size());
    }
    if (grids) {
      auto reach_grid = make_grid("ptz_reach_time/" + cam.id);
      auto acc = reach_grid->getAccessor();
      for (std::size_t i = 0; i < n; ++i)
        if (std::isfinite(reach[i])) acc.setValueOn(voxels[i], reach[i]);
      grids->impl().extra[reach_grid->getName()] = reach_grid;
      if (tour) {
        auto watched_grid = make_grid("ptz_watched/" + cam.id);
        auto gap_grid = make_grid("ptz_gap/" + cam.id);
        auto wa = watched_grid->getAccessor();
        auto ga = gap_grid->getAccessor();
        for (std::size_t i = 0; i < n; ++i) {
          wa.setValueOn(voxels[i], watched[i]);
          if (gap[i] >= 0) ga.setValueOn(voxels[i], gap[i]);
        }
        grids->impl().extra[watched_grid->getName()] = watched_grid;
        grids->impl().extra[gap_grid->getName()] = gap_grid;
      }
    }
  }
  for (std::size_t i = 0; i < n; ++i) {
    if (!std::isfinite(rig_min[i])) continue;
    ++out.counts[2];
    for (std::size_t k = 0; k < budgets; ++k)
      out.counts[kPtzCounts + k] += rig_min[i] <= within_s[k];
  }
  if (grids) {
    auto grid = make_grid("ptz_reach_time");
    auto acc = grid->getAccessor();
    for (std::size_t i = 0; i < n; ++i)
      if (std::isfinite(rig_min[i])) acc.setValueOn(voxels[i], rig_min[i]);
    grids->impl().extra["ptz_reach_time"] = grid;
  }
  out.counts[1] = rays.load();
  out.seconds = {std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count()};
  return out;
}

PtzFieldsSummary FinishPtzFields(const Scene& scene, const Rig& rig,
                                 const std::vector<std::int64_t>& counts,
                                 const std::vector<double>& seconds, PercentileSource& lists) {
  PtzFieldsSummary out;
  out.min_px_per_m = scene.study.ptz.min_px_per_m;
  out.pixel_target = scene.study.ptz.pixel_target;
  out.within_s = scene.study.ptz.within_s;
  if (counts.empty()) return out;  // no PTZ camera, or no coverage field
  const std::vector<int> ptz = PtzCameras(rig);
  const std::size_t budgets = out.within_s.size(), per = PerPtzCamera(budgets);
  if (counts.size() != kPtzCounts + budgets + per * ptz.size())
    throw std::invalid_argument("FinishPtzFields: the parts are of another rig");
  const std::int64_t n = counts[0];
  out.region_voxels = n;
  const auto share = [n](std::int64_t count) {
    return n ? static_cast<double>(count) / static_cast<double>(n) : 0.0;
  };
  for (std::size_t p = 0; p < ptz.size(); ++p) {
    const Camera& cam = rig.cameras[ptz[p]];
    const PtzHead& head = *cam.ptz;
    const std::int64_t* row = &counts[kPtzCounts + budgets + per * p];
    PtzCameraFields f;
    f.id = cam.id;
    f.camera = ptz[p];
    f.max_time_s = PtzReach(cam, head, head.current, out.min_px_per_m).MaxTime();
    f.trace_s = head.trace_s;
    const std::vector<PtzHead::TourLeg> legs = head.TourLegs();
    f.tour = !legs.empty();
    f.stops = static_cast<int>(legs.size());
    f.period_s = f.tour ? legs.back().end() : 0.0;
    f.reachable_voxels = row[0];
    f.reachable_share = share(row[0]);
    for (std::size_t k = 0; k < budgets; ++k) f.within.push_back(share(row[1 + k]));
    f.within_trace = share(row[1 + budgets]);
    const ListPercentiles reach = lists.Percentiles(2 * p, {50, 90});
    f.reach_p50_s = reach.values[0];
    f.reach_p90_s = reach.values[1];
    const ListPercentiles gaps = lists.Percentiles(2 * p + 1, {50, 90, 100});
    if (f.tour) {
      f.watched_mean = n ? FixedLimbsToDouble(&row[3 + budgets]) / static_cast<double>(n) : 0.0;
      f.watched_share = share(row[2 + budgets]);
      f.gap_p50_s = gaps.values[0];
      f.gap_p90_s = gaps.values[1];
      f.gap_max_s = gaps.values[2];
    }
    out.cameras.push_back(std::move(f));
  }
  out.reachable_share = share(counts[2]);
  for (std::size_t k = 0; k < budgets; ++k) out.within.push_back(share(counts[kPtzCounts + k]));
  out.rays = counts[1];
  out.seconds = seconds.empty() ? 0.0 : seconds[0];
  return out;
}

PtzFieldsSummary EvaluatePtzFields(const Scene& scene, const Rig& rig, const RayCaster& caster,
                                   const Fields& fields, Fields* grids) {
  const auto t0 = std::chrono::steady_clock::now();
  const SummaryParts parts = PtzFieldsParts(scene, rig, caster, fields, grids);
  InMemoryPercentiles lists(parts.lists);
  PtzFieldsSummary out = FinishPtzFields(scene, rig, parts.counts, parts.seconds, lists);
  out.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return out;
}

void to_json(nlohmann::json& j, const PtzFieldsSummary& s) {
  const auto value = [](const std::optional<double>& v) {
    return v ? nlohmann::json(*v) : nlohmann::json();
  };
  nlohmann::json cameras = nlohmann::json::array();
  for (const PtzCameraFields& f : s.cameras) {
    nlohmann::json tour;
    if (f.tour)
      tour = {{"stops", f.stops},
              {"period_s", f.period_s},
              {"watched_mean", f.watched_mean},
              {"watched_share", f.watched_share},
              {"gap_p50_s", value(f.gap_p50_s)},
              {"gap_p90_s", value(f.gap_p90_s)},
              {"gap_max_s", value(f.gap_max_s)}};
    cameras.push_back({{"id", f.id},
                       {"max_time_s", f.max_time_s},
                       {"reachable_share", f.reachable_share},
                       {"within", f.within},
                       {"trace_s", f.trace_s},
                       {"within_trace", f.within_trace},
                       {"reach_p50_s", value(f.reach_p50_s)},
                       {"reach_p90_s", value(f.reach_p90_s)},
                       {"tour", tour}});
  }
  j = {{"min_px_per_m", s.min_px_per_m},
       {"pixel_target", s.pixel_target.empty() ? nlohmann::json() : nlohmann::json(s.pixel_target)},
       {"within_s", s.within_s},
       {"region_voxels", s.region_voxels},
       {"cameras", cameras},
       {"rig", {{"reachable_share", s.reachable_share}, {"within", s.within}}},
       {"rays", s.rays},
       {"seconds", s.seconds}};
}

std::string FormatPtzFields(const PtzFieldsSummary& s) {
  if (s.cameras.empty()) return "";
  std::string budgets, out;
  for (std::size_t k = 0; k < s.within_s.size(); ++k) {
    char b[32];
    std::snprintf(b, sizeof b, "%s%g", k ? "/" : "", s.within_s[k]);
    budgets += b;
  }
  auto shares = [](const std::vector<double>& v) {
    std::string t;
    for (std::size_t k = 0; k < v.size(); ++k) t += (k ? "/" : "") + Percent(v[k]);
    return t;
  };
  char line[512];
  std::string density = "any zoom";
  if (s.min_px_per_m > 0) {
    std::snprintf(line, sizeof line, "zoom meeting %g px/m%s%s", s.min_px_per_m,
                  s.pixel_target.empty() ? "" : ", pixel target ", s.pixel_target.c_str());
    density = line;
  }
  out += "PTZ reach (" + density + "), within " + budgets + " s:\n";
  for (const PtzCameraFields& f : s.cameras) {
    std::snprintf(line, sizeof line,
                  "  %-10s reaches %s of the region (longest move %.2g s), within: %s; median %s\n",
                  f.id.c_str(), Percent(f.reachable_share).c_str(), f.max_time_s,
                  shares(f.within).c_str(), Seconds(f.reach_p50_s).c_str());
    out += line;
    if (f.tour) {
      std::snprintf(
          line, sizeof line,
          "  %-10s tour %.3g s (%d stops): watched %s of the time on average, %s at some time; "
          "longest unwatched p50 %s, max %s\n",
          "", f.period_s, f.stops, Percent(f.watched_mean).c_str(),
          Percent(f.watched_share).c_str(), Seconds(f.gap_p50_s).c_str(),
          Seconds(f.gap_max_s).c_str());
      out += line;
    }
  }
  if (s.cameras.size() > 1) {
    std::snprintf(line, sizeof line, "  %-10s reaches %s, within: %s\n", "any PTZ",
                  Percent(s.reachable_share).c_str(), shares(s.within).c_str());
    out += line;
  }
  return out;
}

}  // namespace pandora
