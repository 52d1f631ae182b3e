#include "suggest/propose.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <set>

#include "analysis/geometry/ray_caster.h"
#include "analysis/geometry/surface_distance.h"
#include "analysis/geometry/visibility.h"
#include "analysis/rig/calibration.h"
#include "analysis/util/error.h"
#include "analysis/util/palette.h"
#include "analysis/util/seeded.h"
#include "analysis/util/units.h"
#include "volume/pixel_targets.h"

namespace pandora {
namespace {

using Clock = std::chrono::steady_clock;
double Since(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

// The triangles of the objects no motion moves and no skin animates.
TriangleMesh StaticMesh(const Scene& scene) {
  std::vector<char> moving(scene.objects.size(), 0);
  for (const ObjectMotion& m : scene.motions)
    for (int o : m.objects) moving[o] = 1;
  TriangleMesh mesh;
  for (std::size_t o = 0; o < scene.objects.size(); ++o)
    if (!moving[o] && scene.objects[o].skin < 0) mesh.Append(scene.objects[o].mesh);
  return mesh;
}

// The mount `clearance` off a surface a ray hit, on the ray's side.
Vec3 OffSurface(const Ray& ray, const RayHit& hit, double clearance) {
  Vec3 n = hit.normal;
  if (n.dot(ray.direction) > 0) n = -n;
  return ray.origin + hit.t * ray.direction + clearance * n;
}

// Seeded k-means (k-means++ start, 20 rounds) of the target points' positions.
std::vector<Vec3> AimPoints(const std::vector<TargetPoint>& targets, int k, std::uint64_t seed) {
  std::vector<Vec3> p;
  const std::size_t step = std::max<std::size_t>(1, targets.size() / 4000);
  for (std::size_t i = 0; i < targets.size(); i += step) p.push_back(targets[i].p);
  Vec3 centroid = Vec3::Zero();
  for (const Vec3& v : p) centroid += v;
  centroid /= double(p.size());
  std::vector<Vec3> centres;
  if (k > 0 && int(p.size()) > k) {
    centres.push_back(p[std::size_t(SeededUniform(seed, 0) * p.size()) % p.size()]);
    std::vector<double> d2(p.size());
    while (int(centres.size()) < k) {
      double total = 0;
      for (std::size_t i = 0; i < p.size(); ++i) {
        d2[i] = 1e300;
        for (const Vec3& c : centres) d2[i] = std::min(d2[i], (p[i] - c).squaredNorm());
        total += d2[i];
      }
      double pick = SeededUniform(seed, centres.size()) * total;
      std::size_t i = 0;
      while (i + 1 < p.size() && pick > d2[i]) pick -= d2[i++];
      centres.push_back(p[i]);
    }
    for (int round = 0; round < 20; ++round) {
      std::vector<Vec3> sum(centres.size(), Vec3::Zero());
      std::vector<int> count(centres.size(), 0);
      for (const Vec3& v : p) {
        std::size_t best = 0;
        for (std::size_t c = 1; c < centres.size(); ++c)
          if ((v - centres[c]).squaredNorm() < (v - centres[best]).squaredNorm()) best = c;
        sum[best] += v;
        ++count[best];
      }
      for (std::size_t c = 0; c < centres.size(); ++c)
        if (count[c] > 0) centres[c] = sum[c] / count[c];
    }
  }
  centres.insert(centres.begin(), centroid);
  return centres;
}

using BitMatrix = std::vector<std::vector<std::uint64_t>>;

// One objective term's state: counts of the selected cameras per point (at the term's density).
struct TermState {
  const BitMatrix* vis;  ///< Per candidate: the points (coverage) or poses (calibration) it sees.
  int k;
  bool n1;
  double weight;
  std::vector<int> counts;
  int ge_k = 0;
  long soft = 0;
  int min_shared = 0;  ///< > 0: a calibration term over pose bits.
};

// The weakest edge of the maximum spanning tree of the cameras' shared pose counts (Prim's), 0
// when they do not all connect; over min_shared, at most 1.
double CalibrationStrength(const BitMatrix& poses, const std::vector<int>& cameras,
                           int min_shared) {
  const std::size_t n = cameras.size();
  if (n < 2) return 0;
  std::vector<std::vector<int>> shared(n, std::vector<int>(n, 0));
  for (std::size_t a = 0; a < n; ++a)
    for (std::size_t b = a + 1; b < n; ++b) {
      const std::vector<std::uint64_t>&x = poses[std::size_t(cameras[a])],
            &y = poses[std::size_t(cameras[b])];
      int c = 0;
      for (std::size_t w = 0; w < x.size(); ++w) c += __builtin_popcountll(x[w] & y[w]);
      shared[a][b] = shared[b][a] = c;
    }
  std::vector<char> in(n, 0);
  std::vector<int> best(n, -1);
  in[0] = 1;
  for (std::size_t v = 1; v < n; ++v) best[v] = shared[0][v];
  int weakest = 1 << 30;
  for (std::size_t step = 1; step < n; ++step) {
    std::size_t pick = n;
    for (std::size_t v = 0; v < n; ++v)
      if (!in[v] && (pick == n || best[v] > best[pick])) pick = v;
    weakest = std::min(weakest, best[pick]);
    in[pick] = 1;
    for (std::size_t v = 0; v < n; ++v)
      if (!in[v]) best[v] = std::max(best[v], shared[pick][v]);
  }
  return std::min(1.0, double(weakest) / std::max(1, min_shared));
}

// The search state over the visibility bit matrices, one per term.
struct Search {
  std::vector<TermState> terms;
  const std::vector<double>& price;
  const std::vector<int>& mount_of;
  int points;
  double budget;
  std::vector<int> selected;

  int candidates() const { return int(terms.front().vis->size()); }
  void Reset() {
    for (TermState& t : terms) {
      t.counts.assign(std::size_t(points), 0);
      t.ge_k = 0, t.soft = 0;
    }
    selected.clear();
  }
  void Add(int c, int sign) {
    for (TermState& t : terms) {
      if (t.min_shared > 0) continue;  // calibration: judged from the selection itself
      const std::vector<std::uint64_t>& bits = (*t.vis)[std::size_t(c)];
      for (std::size_t w = 0; w < bits.size(); ++w)
        for (std::uint64_t b = bits[w]; b; b &= b - 1) {
          int& n = t.counts[w * 64 + std::size_t(__builtin_ctzll(b))];
          if (sign > 0) {
            t.soft += n < t.k;
            ++n;
            t.ge_k += n == t.k;
          } else {
            t.ge_k -= n == t.k;
            --n;
            t.soft -= n < t.k;
          }
        }
    }
  }
  // A term's share seen by >= k after the worst single failure among the selected cameras.
  double N1Share(const TermState& t) const {
    std::vector<std::uint64_t> at_k((std::size_t(points) + 63) / 64, 0);
    for (int i = 0; i < points; ++i)
      if (t.counts[std::size_t(i)] == t.k) at_k[std::size_t(i) / 64] |= 1ull << (i % 64);
    int worst = 0;
    for (int c : selected) {
      int lost = 0;
      const std::vector<std::uint64_t>& bits = (*t.vis)[std::size_t(c)];
      for (std::size_t w = 0; w < bits.size(); ++w) lost += __builtin_popcountll(bits[w] & at_k[w]);
      worst = std::max(worst, lost);
    }
    return double(t.ge_k - worst) / points;
  }
  double Share(const TermState& t) const { return double(t.ge_k) / points; }
  double TermValue(const TermState& t) const {
    if (t.min_shared > 0) return CalibrationStrength(*t.vis, selected, t.min_shared);
    return t.n1 ? N1Share(t) : Share(t);
  }
  double Exact() const {
    double v = 0;
    for (const TermState& t : terms) v += t.weight * TermValue(t);
    return v;
  }
  // What the search maximises: the exact objective, the soft one as a tie-break, less the
  // diversity penalty.
  double Score(const std::vector<char>& taken_mounts, double diversity) const {
    double s = Exact();
    for (const TermState& t : terms)
      if (t.min_shared == 0) s += 1e-3 * t.weight * double(t.soft) / (double(points) * t.k);
    for (int c : selected) s -= taken_mounts[std::size_t(mount_of[std::size_t(c)])] ? diversity : 0;
    return s;
  }
  // The soft objective's gain of adding candidate c.
  double Gain(int c) {
    double g = 0;
    for (const TermState& t : terms) {
      if (t.min_shared > 0) {  // the strength's change with c added
        const double before = TermValue(t);
        selected.push_back(c);
        g += t.weight * (TermValue(t) - before);
        selected.pop_back();
        continue;
      }
      long n = 0;
      const std::vector<std::uint64_t>& bits = (*t.vis)[std::size_t(c)];
      for (std::size_t w = 0; w < bits.size(); ++w)
        for (std::uint64_t b = bits[w]; b; b &= b - 1)
          n += t.counts[w * 64 + std::size_t(__builtin_ctzll(b))] < t.k;
      g += t.weight * double(n) / (double(points) * t.k);
    }
    return g;
  }
  double Price() const {
    double p = 0;
    for (int c : selected) p += price[std::size_t(c)];
    return p;
  }
};

// Greedy on the soft objective, then simulated annealing of swaps for `seconds`.
void Optimise(Search* s, int n, const std::vector<char>& taken_mounts, double diversity,
              double seconds, std::int64_t iterations, std::uint64_t seed) {
  const int candidates = s->candidates();
  s->Reset();
  std::vector<char> in(std::size_t(candidates), 0);
  for (int step = 0; step < n; ++step) {
    int best = -1;
    double best_gain = -1e300;
    const double left = s->budget > 0 ? s->budget - s->Price() : 1e300;
    for (int c = 0; c < candidates; ++c) {
      if (in[std::size_t(c)] || s->price[std::size_t(c)] > left) continue;
      // With a budget, value for money: the gain per unit of price.
      const double per_price =
          s->budget > 0 ? 1.0 / std::max(s->price[std::size_t(c)], 1e-9 * s->budget) : 1.0;
      const double g = s->Gain(c) * per_price -
                       (taken_mounts[std::size_t(s->mount_of[std::size_t(c)])] ? diversity : 0);
      if (g > best_gain) best_gain = g, best = c;
    }
    if (best < 0) break;
    s->Add(best, +1);
    s->selected.push_back(best);
    in[std::size_t(best)] = 1;
  }
  if (s->selected.empty()) return;
  const Clock::time_point t0 = Clock::now();
  double score = s->Score(taken_mounts, diversity), best_score = score;
  std::vector<int> best = s->selected;
  const double t_hot = 0.01, t_cold = 1e-4;
  for (std::uint64_t it = 0;; ++it) {
    const double done =
        iterations > 0 ? double(it) / double(iterations) : Since(t0) / std::max(seconds, 1e-9);
    if (done >= 1) break;
    const double temperature = t_hot * std::pow(t_cold / t_hot, done);
    const std::size_t i = std::size_t(SeededUniform(seed, it, 0) * s->selected.size());
    const int out = s->selected[i];
    int j = int(SeededUniform(seed, it, 1) * candidates) % candidates;
    if (in[std::size_t(j)]) continue;
    // Under a budget with room for more cameras, an added one is tried first.
    if (s->budget > 0 && int(s->selected.size()) < n &&
        s->Price() + s->price[std::size_t(j)] <= s->budget + 1e-9) {
      s->Add(j, +1);
      s->selected.push_back(j);
      const double next = s->Score(taken_mounts, diversity);
      if (next >= score) {
        score = next;
        in[std::size_t(j)] = 1;
        if (score > best_score) best_score = score, best = s->selected;
        continue;
      }
      s->Add(j, -1);
      s->selected.pop_back();
    }
    if (s->budget > 0 &&
        s->Price() - s->price[std::size_t(out)] + s->price[std::size_t(j)] > s->budget + 1e-9)
      continue;
    s->Add(out, -1);
    s->Add(j, +1);
    s->selected[i] = j;
    const double next = s->Score(taken_mounts, diversity);
    if (next >= score || SeededUniform(seed, it, 2) < std::exp((next - score) / temperature)) {
      score = next;
      in[std::size_t(out)] = 0, in[std::size_t(j)] = 1;
      if (score > best_score) best_score = score, best = s->selected;
    } else {
      s->Add(j, -1);
      s->Add(out, +1);
      s->selected[i] = out;
    }
  }
  s->Reset();
  for (int c : best) {
    s->Add(c, +1);
    s->selected.push_back(c);
  }
}

// Candidate cameras: every mount looking at every aim point through every lens.
void MakeCandidates(const ProposeOptions& options, const std::vector<Vec3>& aims,
                    ProposeResult* result, std::vector<int>* mount_of) {
  for (std::size_t m = 0; m < options.mounts.size(); ++m)
    for (const Vec3& aim : aims)
      for (std::size_t l = 0; l < options.lenses.size(); ++l) {
        const Vec3& at = options.mounts[m].position;
        std::optional<Eigen::Isometry3d> pose = LookAt(at, aim, Vec3::UnitZ());
        if (!pose) pose = LookAt(at, aim, Vec3::UnitY());
        if (!pose) continue;
        const ProposeLens& lens = options.lenses[l];
        Camera c;
        c.id = "candidate_" + std::to_string(result->candidates.size() + 1);
        c.world_from_camera = *pose;
        c.model = CameraModel(lens.intrinsics);
        c.near = lens.near;
        c.far = lens.far;
        result->candidates.push_back(c);
        result->candidate_lens.push_back(int(l));
        result->candidate_surface.push_back(options.mounts[m].surface);
        mount_of->push_back(int(m));
      }
}

// vis[d][c]: bit i set when candidate c sees target point i at densities[d] px/m or more (exact
// tests, the point's own sample; density 0: seen at all).
std::vector<BitMatrix> Visibility(const Scene& scene, const RayCaster& caster,
                                  const std::vector<const RayCaster*>& sample_casters,
                                  const std::vector<TargetPoint>& targets,
                                  const std::vector<Camera>& candidates,
                                  const std::vector<double>& densities,
                                  const ProposeOptions& options) {
  const std::size_t words = (targets.size() + 63) / 64;
  std::vector<BitMatrix> vis(densities.size(),
                             BitMatrix(candidates.size(), std::vector<std::uint64_t>(words, 0)));
  const double scale = scene.ContentBounds().diagonal();
  std::vector<std::unique_ptr<VisibilityTester>> testers;
  const std::size_t samples = std::max<std::size_t>(1, sample_casters.size());
  for (std::size_t s = 0; s < samples; ++s)
    testers.push_back(std::make_unique<VisibilityTester>(
        candidates, sample_casters.empty() ? caster : *sample_casters[s], scale));
  std::atomic<std::size_t> done{0};
  tbb::parallel_for(std::size_t(0), candidates.size(), [&](std::size_t c) {
    for (std::size_t i = 0; i < targets.size(); ++i) {
      const TargetPoint& t = targets[i];
      const VisibilityTester& tester = *testers[sample_casters.empty() ? 0 : std::size_t(t.sample)];
      const Vec3* normal = t.normal ? &*t.normal : nullptr;
      Mat23 J;
      if (tester.Test(int(c), t.p, normal, &J) != ViewResult::kSeen) continue;
      const double density = PixelDensity(J);
      for (std::size_t d = 0; d < densities.size(); ++d)
        if (density >= densities[d]) vis[d][c][i / 64] |= 1ull << (i % 64);
    }
    const std::size_t n = ++done;
    if (options.progress && n % 64 == 0)
      options.progress("visibility", double(n) / double(candidates.size()));
  });
  return vis;
}

// The distinct densities of the terms, and the search's term states over their matrices.
std::vector<double> TermDensities(const std::vector<ProposeTerm>& terms) {
  std::vector<double> d = {0.0};  // seen at all: the candidates' check
  for (const ProposeTerm& t : terms)
    if (!t.calibration && std::find(d.begin(), d.end(), t.min_px_per_m) == d.end())
      d.push_back(t.min_px_per_m);
  return d;
}

// Per camera, the calibration poses it observes (the study's board or wand through the region,
// the static scene as placed occluding; poses sampled with the cameras given, as
// SimulateCalibration does for a rig). Empty without a calibration term.
BitMatrix CalibrationPoses(const Scene& scene, const RayCaster& caster,
                           const std::vector<Camera>& cameras,
                           const std::vector<ProposeTerm>& terms) {
  if (std::none_of(terms.begin(), terms.end(), [](const ProposeTerm& t) { return t.calibration; }))
    return {};
  if (!scene.study.calibration)
    throw InputError("{objective}", "", "a calibration term needs the study's \"calibration\"",
                     "add \"calibration\": {\"target\": \"board\", ...} to the study "
                     "(docs/calibration.md)");
  const CalibrationSpec& spec = *scene.study.calibration;
  const VisibilityTester tester(cameras, caster, scene.ContentBounds().diagonal());
  const std::vector<CalibrationPose> poses = SampleCalibrationPoses(scene, tester, spec);
  const std::size_t words = (poses.size() + 63) / 64;
  BitMatrix out(cameras.size(), std::vector<std::uint64_t>(words, 0));
  tbb::parallel_for(std::size_t(0), cameras.size(), [&](std::size_t c) {
    for (std::size_t p = 0; p < poses.size(); ++p)
      if (ObservesPose(tester, int(c), spec, poses[p])) out[c][p / 64] |= 1ull << (p % 64);
  });
  return out;
}

int MinShared(const Scene& scene) {
  return scene.study.calibration ? scene.study.calibration->min_shared : 0;
}
std::vector<TermState> TermStates(const std::vector<ProposeTerm>& terms,
                                  const std::vector<double>& densities,
                                  const std::vector<BitMatrix>& vis, const BitMatrix* poses,
                                  int min_shared) {
  std::vector<TermState> out;
  for (const ProposeTerm& t : terms) {
    if (t.calibration) {
      out.push_back({poses, 1, false, t.weight, {}, 0, 0, min_shared});
      continue;
    }
    const std::size_t d = std::size_t(
        std::find(densities.begin(), densities.end(), t.min_px_per_m) - densities.begin());
    out.push_back({&vis[d], t.k, t.n1, t.weight, {}, 0, 0, 0});
  }
  return out;
}

// The proposal's numbers from the search's state.
Proposal Measure(const Search& search) {
  Proposal p;
  p.candidates = search.selected;
  p.objective = search.Exact();
  for (const TermState& t : search.terms) p.terms.push_back(search.TermValue(t));
  for (const TermState& t : search.terms)
    if (t.min_shared == 0) {  // the first coverage term
      p.coverage_k = search.Share(t);
      p.n1 = search.N1Share(t);
      break;
    }
  p.price = search.Price();
  return p;
}

}  // namespace

std::vector<ProposeTerm> ParseProposeObjective(const std::string& text, const Scene& scene) {
  auto fail = [&text](const std::string& why) -> std::vector<ProposeTerm> {
    throw InputError("{objective}", "", "'" + text + "': " + why,
                     "terms [W*]coverageK[-n1][@DENSITY] or [W*]calibration joined by '+', DENSITY "
                     "px/m, detection, observation, recognition, identification or a pixel "
                     "target, e.g. 0.7*coverage3+0.3*coverage1@identification");
  };
  std::vector<ProposeTerm> terms;
  std::size_t at = 0;
  while (at <= text.size()) {
    const std::size_t plus = text.find('+', at);
    std::string term = text.substr(at, plus == std::string::npos ? std::string::npos : plus - at);
    at = plus == std::string::npos ? text.size() + 1 : plus + 1;
    ProposeTerm t;
    t.name = term;
    const std::size_t star = term.find('*');
    if (star != std::string::npos) {
      char* end = nullptr;
      const std::string w = term.substr(0, star);
      t.weight = std::strtod(w.c_str(), &end);
      if (w.empty() || *end != '\0' || !(t.weight > 0 && t.weight <= 1e6))
        return fail("a weight must be a positive number");
      term = term.substr(star + 1);
      t.name = term;
    }
    if (term == "calibration") {
      t.calibration = true;
      terms.push_back(t);
      continue;
    }
    const std::size_t sign = term.find('@');
    if (sign != std::string::npos) {
      const std::string d = term.substr(sign + 1);
      term = term.substr(0, sign);
      const std::vector<std::string> dori = {"detection", "observation", "recognition",
                                             "identification"};
      bool found = false;
      for (std::size_t i = 0; i < dori.size(); ++i)
        if (d == dori[i]) t.min_px_per_m = kDoriPxPerM[i], found = true;
      for (const PixelTarget& p : scene.study.pixel_targets)
        if (!found && d == p.name) t.min_px_per_m = p.px_per_m(), found = true;
      if (!found) {
        char* end = nullptr;
        t.min_px_per_m = std::strtod(d.c_str(), &end);
        if (d.empty() || *end != '\0' || !(t.min_px_per_m > 0 && t.min_px_per_m < 1e9))
          return fail("unknown density '" + d + "'");
      }
    }
    if (term.size() > 3 && term.compare(term.size() - 3, 3, "-n1") == 0) {
      t.n1 = true;
      term.resize(term.size() - 3);
    }
    if (term.rfind("coverage", 0) != 0) return fail("a term is coverageK, not '" + term + "'");
    const std::string k = term.substr(8);
    if (k.empty()) {
      t.k = 1;
    } else {
      char* end = nullptr;
      const long v = std::strtol(k.c_str(), &end, 10);
      if (*end != '\0' || v < 1 || v > 64) return fail("K must be 1 to 64");
      t.k = int(v);
    }
    terms.push_back(t);
    if (terms.size() > 8) return fail("at most 8 terms");
  }
  return terms;
}

std::vector<MountPoint> WallMounts(const Scene& scene, const std::vector<double>& heights,
                                   double spacing, double clearance) {
  const TriangleMesh mesh = StaticMesh(scene);
  std::vector<MountPoint> out;
  if (mesh.triangles.empty()) return out;
  const auto caster = MakeEmbreeRayCaster(mesh);
  const Vec3 centre = scene.study.region.box.center();
  constexpr int kRays = 1440;
  for (double h : heights) {
    std::vector<Vec3> hits;
    for (int r = 0; r < kRays; ++r) {
      const double a = 2 * kPi * r / kRays;
      const Ray ray{Vec3(centre.x(), centre.y(), h), Vec3(std::cos(a), std::sin(a), 0), 0, 1e4};
      const auto hit = caster->Intersect(ray);
      hits.push_back(hit ? OffSurface(ray, *hit, clearance) : Vec3::Constant(1e300));
    }
    // One mount per `spacing` metres along the chain of hits (gaps: doors, open sides, restart).
    double run = spacing;
    for (int r = 0; r < kRays; ++r) {
      const Vec3& p = hits[std::size_t(r)];
      if (p.x() > 1e299) continue;
      const Vec3& q = hits[std::size_t((r + kRays - 1) % kRays)];
      if (q.x() < 1e299) run += (p - q).norm();
      if (run >= spacing) {
        out.push_back({p, "wall"});
        run = 0;
      }
    }
  }
  return out;
}

std::vector<MountPoint> CeilingMounts(const Scene& scene, double spacing, double clearance) {
  const TriangleMesh mesh = StaticMesh(scene);
  std::vector<MountPoint> out;
  if (mesh.triangles.empty()) return out;
  const auto caster = MakeEmbreeRayCaster(mesh);
  // Over the whole static scene's plan (inset by the clearance), from the region's top up: a hit on
  // a downward face is a ceiling (an upward one is the inside of a closed solid: skipped).
  Aabb region = mesh.Bounds();
  region.min += Vec3::Constant(clearance), region.max -= Vec3::Constant(clearance);
  region.max.z() = scene.study.region.box.max.z();
  const int nx = std::max(1, int(std::round((region.max.x() - region.min.x()) / spacing))),
            ny = std::max(1, int(std::round((region.max.y() - region.min.y()) / spacing)));
  for (int i = 0; i < nx; ++i)
    for (int j = 0; j < ny; ++j) {
      const Vec3 o(region.min.x() + (i + 0.5) * (region.max.x() - region.min.x()) / nx,
                   region.min.y() + (j + 0.5) * (region.max.y() - region.min.y()) / ny,
                   region.max.z());
      const Ray ray{o, Vec3::UnitZ(), 0, 1e4};
      const auto hit = caster->Intersect(ray);
      if (hit && hit->normal.z() < 0) out.push_back({OffSurface(ray, *hit, clearance), "ceiling"});
    }
  return out;
}

std::vector<MountPoint> ObjectMounts(const Scene& scene, const std::vector<std::string>& names,
                                     double spacing, double clearance) {
  std::vector<MountPoint> out;
  for (const std::string& name : names) {
    Aabb b;
    for (const SceneObject& o : scene.objects)
      if (o.InGroup(name)) b.Extend(o.mesh.Bounds());
    if (b.empty())
      throw InputError(scene.path, "", "no object or group named '" + name + "' to mount on");
    const int nx = std::max(1, int(std::round((b.max.x() - b.min.x()) / spacing))),
              ny = std::max(1, int(std::round((b.max.y() - b.min.y()) / spacing)));
    for (int i = 0; i < nx; ++i)
      for (int j = 0; j < ny; ++j)
        out.push_back(
            {Vec3(b.min.x() + (i + 0.5) * (b.max.x() - b.min.x()) / nx,
                  b.min.y() + (j + 0.5) * (b.max.y() - b.min.y()) / ny, b.min.z() - clearance),
             name});
  }
  return out;
}

std::vector<MountPoint> BoxMounts(const Scene& scene, const Aabb& box, double spacing,
                                  double clearance) {
  const TriangleMesh mesh = scene.AllTriangles();
  const SurfaceDistance distance(mesh);
  std::vector<MountPoint> out;
  int n[3];
  for (int a = 0; a < 3; ++a)
    n[a] = std::max(1, int(std::round((box.max[a] - box.min[a]) / spacing)) + 1);
  for (int i = 0; i < n[0]; ++i)
    for (int j = 0; j < n[1]; ++j)
      for (int k = 0; k < n[2]; ++k) {
        Vec3 p;
        const int at[3] = {i, j, k};
        for (int a = 0; a < 3; ++a)
          p[a] = n[a] == 1 ? 0.5 * (box.min[a] + box.max[a])
                           : box.min[a] + (box.max[a] - box.min[a]) * at[a] / (n[a] - 1);
        if (mesh.triangles.empty() || distance.Distance(p, 2 * clearance) >= clearance)
          out.push_back({p, "box"});
      }
  return out;
}

ProposeResult Propose(const Scene& scene, const RayCaster& caster,
                      const std::vector<const RayCaster*>& sample_casters,
                      const std::vector<TargetPoint>& targets, const ProposeOptions& options,
                      int curve_from, int curve_to) {
  if (options.mounts.empty())
    throw InputError(scene.path, "", "no mount points", "give walls, ceiling, objects or points");
  if (options.lenses.empty()) throw InputError(scene.path, "", "no camera models");
  if (targets.empty()) throw InputError(scene.path, "", "no target points");
  ProposeResult result;
  result.points = int(targets.size());
  const Clock::time_point t0 = Clock::now();
  std::vector<int> mount_of;
  MakeCandidates(options, AimPoints(targets, options.aims, options.seed), &result, &mount_of);
  const std::vector<double> densities = TermDensities(options.terms);
  const std::vector<BitMatrix> vis =
      Visibility(scene, caster, sample_casters, targets, result.candidates, densities, options);
  const BitMatrix poses = CalibrationPoses(scene, caster, result.candidates, options.terms);
  result.visibility_seconds = Since(t0);
  std::vector<double> price;
  for (int l : result.candidate_lens) price.push_back(options.lenses[std::size_t(l)].price);
  bool any = false;
  for (const auto& v : vis.front())
    for (std::uint64_t w : v) any |= w != 0;
  if (!any)
    throw InputError(scene.path, "", "no candidate camera sees any target point",
                     "check the mounts (walls, ceiling) and the lenses' range");
  const Clock::time_point t1 = Clock::now();
  Search search{TermStates(options.terms, densities, vis, &poses, MinShared(scene)),
                price,
                mount_of,
                result.points,
                options.budget,
                {}};
  const int curve_n = curve_to >= curve_from && curve_from > 0 ? curve_to - curve_from + 1 : 0;
  const double per = options.seconds /
                     std::max(1, options.proposals + curve_n + int(options.curve_budgets.size()));
  std::vector<char> taken(options.mounts.size(), 0);
  for (int p = 0; p < options.proposals; ++p) {
    if (options.progress) options.progress("search", double(p) / options.proposals);
    Optimise(&search, options.cameras, taken, p == 0 ? 0.0 : options.diversity, per,
             options.iterations, options.seed + std::uint64_t(p) * 7919);
    for (int c : search.selected) taken[std::size_t(mount_of[std::size_t(c)])] = 1;
    result.proposals.push_back(Measure(search));
  }
  const std::vector<char> none(options.mounts.size(), 0);
  for (int n = curve_from; curve_n > 0 && n <= curve_to; ++n) {
    if (options.progress) options.progress("curve", double(n - curve_from) / curve_n);
    Optimise(&search, n, none, 0.0, per, options.iterations,
             options.seed + 104729 * std::uint64_t(n));
    result.curve.emplace_back(n, search.Exact());
  }
  for (std::size_t b = 0; b < options.curve_budgets.size(); ++b) {
    if (options.progress) options.progress("budgets", double(b) / options.curve_budgets.size());
    search.budget = options.curve_budgets[b];
    Optimise(&search, options.cameras, none, 0.0, per, options.iterations,
             options.seed + 15485863 * std::uint64_t(b + 1));
    result.budget_curve.push_back(
        {search.budget, search.Price(), search.Exact(), int(search.selected.size())});
  }
  std::sort(result.proposals.begin(), result.proposals.end(),
            [](const Proposal& a, const Proposal& b) { return a.objective > b.objective; });
  result.search_seconds = Since(t1);
  return result;
}

Proposal ScoreCameras(const Scene& scene, const RayCaster& caster,
                      const std::vector<const RayCaster*>& sample_casters,
                      const std::vector<TargetPoint>& targets, const std::vector<Camera>& cameras,
                      const std::vector<ProposeTerm>& terms) {
  std::vector<Camera> enabled;
  for (const Camera& c : cameras)
    if (c.enabled) enabled.push_back(c);
  const ProposeOptions options;
  const std::vector<double> densities = TermDensities(terms);
  const std::vector<BitMatrix> vis =
      Visibility(scene, caster, sample_casters, targets, enabled, densities, options);
  const BitMatrix poses = CalibrationPoses(scene, caster, enabled, terms);
  const std::vector<double> price(enabled.size(), 0.0);
  const std::vector<int> mount_of(enabled.size(), 0);
  Search search{TermStates(terms, densities, vis, &poses, MinShared(scene)),
                price,
                mount_of,
                int(targets.size()),
                0,
                {}};
  search.Reset();
  for (std::size_t c = 0; c < enabled.size(); ++c) {
    search.Add(int(c), +1);
    search.selected.push_back(int(c));
  }
  return Measure(search);
}

Rig ProposalRig(const ProposeResult& result, const Proposal& proposal, const std::string& name) {
  Rig rig;
  rig.name = name;
  for (std::size_t i = 0; i < proposal.candidates.size(); ++i) {
    Camera c = result.candidates[std::size_t(proposal.candidates[i])];
    c.id = name + "_" + std::to_string(i + 1);
    c.name = c.id;
    c.color = CameraPaletteColor(int(i));
    rig.cameras.push_back(c);
  }
  return rig;
}

}  // namespace pandora
