// `pandora accuracy` (e): coarse-to-fine evaluation against the full one (app/session/accuracy.h).
// The only file of the studies that reads grids (OpenVDB), to compare voxel by voxel.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <optional>
#include <vector>

#include "app/session/accuracy.h"
#include "volume/active_set.h"
#include "volume/fields.h"
#include "volume/fields_vdb.h"

namespace pandora {
namespace {

using Clock = std::chrono::steady_clock;

double Seconds(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

// A field over a lattice, dense: coverage (-1 where inactive) and sigma_max (mm; NaN where not
// triangulable).
struct Dense {
  Eigen::Vector3i dims = Eigen::Vector3i::Zero();
  std::vector<std::int32_t> coverage;
  std::vector<float> sigma;
  std::size_t At(int i, int j, int k) const {
    return (std::size_t(i) * dims.y() + j) * dims.z() + k;
  }
  bool Inside(int i, int j, int k) const {
    return i >= 0 && j >= 0 && k >= 0 && i < dims.x() && j < dims.y() && k < dims.z();
  }
};

Dense Densify(const Fields& fields) {
  Dense d;
  d.dims = fields.lattice.dims;
  const std::size_t n = std::size_t(d.dims.x()) * d.dims.y() * d.dims.z();
  d.coverage.assign(n, -1);
  d.sigma.assign(n, std::numeric_limits<float>::quiet_NaN());
  const Fields::Impl& g = fields.impl();
  ForEachActiveVoxel(*g.coverage, [&](const openvdb::Coord& c, std::int32_t v) {
    if (d.Inside(c.x(), c.y(), c.z())) d.coverage[d.At(c.x(), c.y(), c.z())] = v;
  });
  if (auto sigma = g.Float("sigma_max"))
    ForEachActiveVoxel(*sigma, [&](const openvdb::Coord& c, float v) {
      if (d.Inside(c.x(), c.y(), c.z())) d.sigma[d.At(c.x(), c.y(), c.z())] = v;
    });
  return d;
}

// Whether two cells' values differ enough to refine between them.
bool Differ(std::int32_t ca, float sa, std::int32_t cb, float sb, double tolerance) {
  if ((ca < 0) != (cb < 0)) return true;  // region or solid boundary
  if (ca < 0) return false;
  if (std::min(ca, 3) != std::min(cb, 3))
    return true;  // the classes >= 1, 2, 3 the summaries count
  if (std::isnan(sa) != std::isnan(sb)) return true;
  if (std::isnan(sa)) return false;
  return std::fabs(double(sa) - double(sb)) > tolerance * std::max(double(sa), double(sb));
}

double Percentile(std::vector<double> v, double q) {
  if (v.empty()) return 0.0;
  const std::size_t k = std::min(v.size() - 1, std::size_t(q * double(v.size() - 1) + 0.5));
  std::nth_element(v.begin(), v.begin() + k, v.end());
  return v[k];
}

}  // namespace

RefineStudy RunRefineStudy(const Scene& scene, const Rig& rig, const RayCaster& caster,
                           const SolidTrees* solid_trees) {
  RefineStudy study;
  const double h = scene.study.voxel_size;
  study.voxel_size = h;
  FieldOptions options;
  options.fields = {"coverage", "sigma_max"};
  options.scene_path = scene.path;
  options.memory_budget_bytes = scene.study.memory_budget_bytes;
  options.solid_trees = solid_trees;  // built once for the nine evaluations

  // The reference: the full evaluation at the study's size (best of up to 3 within ~1 s).
  std::optional<Fields> reference;
  study.reference_seconds = std::numeric_limits<double>::infinity();
  double total = 0;
  for (int r = 0; r < 3 && (r == 0 || total < 1.0); ++r) {
    const Clock::time_point t0 = Clock::now();
    Fields f = EvaluateFields(scene, rig, caster, options);
    const double t = Seconds(t0);
    total += t;
    study.reference_seconds = std::min(study.reference_seconds, t);
    reference = std::move(f);
  }
  const Dense ref = Densify(*reference);
  reference.reset();
  for (std::size_t v = 0; v < ref.coverage.size(); ++v) {
    study.reference_voxels += ref.coverage[v] >= 0 ? 1 : 0;
    study.reference_triangulable += std::isnan(ref.sigma[v]) ? 0 : 1;
  }

  for (int factor : {2, 4}) {
    Scene coarse_scene = scene;
    coarse_scene.study.voxel_size = factor * h;
    const Clock::time_point t0 = Clock::now();
    const Fields coarse_fields = EvaluateFields(coarse_scene, rig, caster, options);
    const double coarse_seconds = Seconds(t0);
    const Dense coarse = Densify(coarse_fields);
    for (double tolerance : {0.02, 0.1}) {
      RefineRow row;
      row.factor = factor;
      row.tolerance = tolerance;
      row.coarse_seconds = coarse_seconds;
      // Coarse cells to refine: any of the 26 neighbours differs (outside the lattice counts as
      // inactive, so the region's edge refines too).
      std::vector<std::uint8_t> refine(coarse.coverage.size(), 0);
      const Eigen::Vector3i& cd = coarse.dims;
      for (int i = 0; i < cd.x(); ++i)
        for (int j = 0; j < cd.y(); ++j)
          for (int k = 0; k < cd.z(); ++k) {
            const std::size_t a = coarse.At(i, j, k);
            bool differs = false;
            for (int di = -1; di <= 1 && !differs; ++di)
              for (int dj = -1; dj <= 1 && !differs; ++dj)
                for (int dk = -1; dk <= 1 && !differs; ++dk) {
                  if (!di && !dj && !dk) continue;
                  const bool in = coarse.Inside(i + di, j + dj, k + dk);
                  const std::size_t b = in ? coarse.At(i + di, j + dj, k + dk) : a;
                  differs = Differ(
                      coarse.coverage[a], coarse.sigma[a], in ? coarse.coverage[b] : -1,
                      in ? coarse.sigma[b] : std::numeric_limits<float>::quiet_NaN(), tolerance);
                }
            refine[a] = differs ? 1 : 0;
          }
      const auto cell = [&](int i, int j, int k) {
        return coarse.At(std::min(i / factor, cd.x() - 1), std::min(j / factor, cd.y() - 1),
                         std::min(k / factor, cd.z() - 1));
      };
      FieldOptions fine = options;
      fine.voxel_filter = [&](int i, int j, int k) { return refine[cell(i, j, k)] != 0; };
      const Clock::time_point t1 = Clock::now();
      const Fields refined_fields = EvaluateFields(scene, rig, caster, fine);
      row.refine_seconds = Seconds(t1);
      const Dense refined = Densify(refined_fields);
      row.refined_voxels = refined_fields.stats.active_set.region_voxels;

      // The composed result against the reference, over the reference's region voxels.
      std::int64_t wrong = 0, wrong_class = 0;
      std::vector<double> errors;
      for (int i = 0; i < ref.dims.x(); ++i)
        for (int j = 0; j < ref.dims.y(); ++j)
          for (int k = 0; k < ref.dims.z(); ++k) {
            const std::size_t v = ref.At(i, j, k);
            if (ref.coverage[v] < 0) continue;
            const std::size_t c = cell(i, j, k);
            const bool exact = refine[c] != 0;
            const std::int32_t cov = exact ? refined.coverage[v] : coarse.coverage[c];
            const float sigma = exact ? refined.sigma[v] : coarse.sigma[c];
            if (cov != ref.coverage[v]) ++wrong;
            if (std::min(cov, 3) != std::min(ref.coverage[v], 3)) ++wrong_class;
            if (std::isnan(sigma) != std::isnan(ref.sigma[v])) {
              ++row.triangulable_mismatch;
            } else if (!std::isnan(sigma)) {
              errors.push_back(std::fabs(double(sigma) / double(ref.sigma[v]) - 1.0));
            }
          }
      const double voxels = double(std::max<std::int64_t>(1, study.reference_voxels));
      row.coverage_wrong_pct = 100.0 * double(wrong) / voxels;
      row.class_wrong_pct = 100.0 * double(wrong_class) / voxels;
      row.sigma_p50_pct = 100 * Percentile(errors, 0.5);
      row.sigma_p99_pct = 100 * Percentile(errors, 0.99);
      row.sigma_max_pct =
          errors.empty() ? 0.0 : 100 * *std::max_element(errors.begin(), errors.end());
      study.rows.push_back(row);
    }
  }
  study.notes.push_back(
      "refined where a neighbour's coverage class (0, 1, 2, >= 3 cameras) or triangulability "
      "differs, or its sigma_max by more than the tolerance; the refined voxels hold exactly the "
      "full "
      "evaluation's values, the others their coarse cell's, so every error comes from cells whose "
      "26 "
      "neighbours agreed");
  return study;
}

}  // namespace pandora
