#include "volume/surface.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <cmath>
#include <cstring>
#include <fstream>
#include <sstream>

#include "analysis/geometry/uncertainty.h"
#include "analysis/geometry/visibility.h"
#include "analysis/util/atomic_file.h"
#include "analysis/util/color.h"
#include "analysis/util/error.h"
#include "analysis/util/seeded.h"

namespace pandora {
namespace {

double TriangleArea(const TriangleMesh& mesh, const Eigen::Vector3i& t, Vec3* normal) {
  const Vec3& a = mesh.vertices[t[0]];
  const Vec3 cross = (mesh.vertices[t[1]] - a).cross(mesh.vertices[t[2]] - a);
  const double twice = cross.norm();
  if (normal && twice > 0) *normal = cross / twice;
  return 0.5 * twice;
}

std::string Number(double v) {
  std::ostringstream s;
  s.precision(6);
  s << v;
  return s.str();
}

// The points whose extremes bound the region (the box's corners, or a mesh region's vertices) and
// the viewpoints.
std::vector<Vec3> Extremes(const Region& region, const std::vector<Vec3>& viewpoints) {
  std::vector<Vec3> corners = viewpoints;
  if (region.kind == Region::Kind::kMesh && !region.mesh.vertices.empty()) {
    corners.insert(corners.end(), region.mesh.vertices.begin(), region.mesh.vertices.end());
    return corners;
  }
  if (region.box.empty()) return corners;
  for (int i = 0; i < 8; ++i)
    corners.emplace_back(i & 1 ? region.box.max.x() : region.box.min.x(),
                         i & 2 ? region.box.max.y() : region.box.min.y(),
                         i & 4 ? region.box.max.z() : region.box.min.z());
  return corners;
}

bool Faces(const std::vector<Vec3>& extremes, const Vec3& a, const Vec3& b, const Vec3& c) {
  const Vec3 cross = (b - a).cross(c - a);
  const double twice = cross.norm();
  if (!(twice > 0)) return false;
  const Vec3 n = cross / twice;
  for (const Vec3& x : extremes)
    if (n.dot(x - a) > 0) return true;
  return false;
}

bool Selected(SurfaceSelection selection, const std::vector<Vec3>& extremes,
              const TriangleMesh& mesh, const Eigen::Vector3i& t) {
  return selection == SurfaceSelection::kAll ||
         Faces(extremes, mesh.vertices[t[0]], mesh.vertices[t[1]], mesh.vertices[t[2]]);
}

std::vector<Vec3> EnabledCentres(const Rig* rig) {
  std::vector<Vec3> out;
  if (rig)
    for (const Camera& c : rig->cameras)
      if (c.enabled) out.push_back(c.center());
  return out;
}

}  // namespace

bool FacesRegionOrViewpoints(const Region& region, const std::vector<Vec3>& viewpoints,
                             const Vec3& a, const Vec3& b, const Vec3& c) {
  return Faces(Extremes(region, viewpoints), a, b, c);
}

double SurfaceArea(const Scene& scene, SurfaceSelection selection, const Rig* rig) {
  const std::vector<Vec3> extremes = Extremes(scene.study.region, EnabledCentres(rig));
  double area = 0;
  for (const SceneObject& o : scene.objects)
    for (const Eigen::Vector3i& t : o.mesh.triangles)
      if (Selected(selection, extremes, o.mesh, t)) area += TriangleArea(o.mesh, t, nullptr);
  return area;
}

std::vector<SurfaceSample> SampleSurfaces(const Scene& scene, double spacing, std::uint64_t seed,
                                          const std::string& option, SurfaceSelection selection,
                                          const Rig* rig) {
  if (!(spacing > 0) || !std::isfinite(spacing))
    throw InputError(option, "", "must be a positive number of metres", "e.g. 0.02");
  const std::vector<Vec3> extremes = Extremes(scene.study.region, EnabledCentres(rig));
  const double area = SurfaceArea(scene, selection, rig);
  const double expected = area / (spacing * spacing);
  if (expected > kMaxSurfaceSamples)
    throw InputError(
        option, "",
        "spacing " + Number(spacing) + " m gives about " + Number(expected) + " samples over " +
            Number(area) + " m^2 of surface, over the limit of " + Number(kMaxSurfaceSamples),
        "use a spacing of at least " + Number(std::sqrt(area / kMaxSurfaceSamples) * 1.01) + " m");

  // Counts first (per object, per triangle), then the points: the output order is object, triangle,
  // sample, whatever the thread count.
  std::vector<SurfaceSample> out;
  out.reserve(static_cast<std::size_t>(expected * 1.01) + 16);
  const double inv_cell = 1.0 / (spacing * spacing);
  for (std::size_t oi = 0; oi < scene.objects.size(); ++oi) {
    const TriangleMesh& mesh = scene.objects[oi].mesh;
    for (std::size_t ti = 0; ti < mesh.triangles.size(); ++ti) {
      const Eigen::Vector3i& t = mesh.triangles[ti];
      if (!Selected(selection, extremes, mesh, t)) continue;
      Vec3 normal;
      const double a = TriangleArea(mesh, t, &normal);
      if (!(a > 0)) continue;
      const double e = a * inv_cell;
      const double whole = std::floor(e);
      std::uint64_t n = static_cast<std::uint64_t>(whole);
      // The extra point uses sample index 2^63 so it never shares random numbers with the others.
      if (SeededUniform(seed, oi, ti, std::uint64_t{1} << 63) < e - whole) ++n;
      const Vec3& p0 = mesh.vertices[t[0]];
      const Vec3& p1 = mesh.vertices[t[1]];
      const Vec3& p2 = mesh.vertices[t[2]];
      for (std::uint64_t s = 0; s < n; ++s) {
        // Uniform on the triangle: with r1, r2 uniform, (1 - sqrt r1, sqrt r1 (1 - r2), sqrt r1 r2)
        // are barycentric coordinates of uniform density (Osada et al. 2002).
        const double r1 = std::sqrt(SeededUniform(seed, oi, ti, 2 * s));
        const double r2 = SeededUniform(seed, oi, ti, 2 * s + 1);
        SurfaceSample sample;
        sample.position = (1 - r1) * p0 + r1 * (1 - r2) * p1 + r1 * r2 * p2;
        sample.normal = normal;
        sample.object = static_cast<int>(oi);
        out.push_back(sample);
      }
    }
  }
  return out;
}

struct PointEvaluator::Impl {
  Impl(const Scene& scene, const Rig& rig, const RayCaster& caster)
      : tester(rig.cameras, caster, scene.ContentBounds().diagonal()) {
    for (const Camera& c : rig.cameras)
      sigma.push_back(c.pixel_sigma > 0 ? c.pixel_sigma : scene.study.pixel_sigma);
  }
  VisibilityTester tester;
  std::vector<double> sigma;  // pixel noise per camera, pixels
};

PointEvaluator::PointEvaluator(const Scene& scene, const Rig& rig, const RayCaster& caster)
    : impl_(new Impl(scene, rig, caster)) {}

PointEvaluator::~PointEvaluator() { delete impl_; }

PointValues PointEvaluator::Evaluate(const Vec3& point, const Vec3* normal) const {
  PointValues v;
  const VisibilityTester& tester = impl_->tester;
  // J's upper triangle (xx xy xz yy yz zz), summed camera by camera with EvaluateFields' own
  // AddCameraInformation; the camera-frame Jacobian Jc gives the pixel density.
  double I[6] = {0, 0, 0, 0, 0, 0};
  const int cameras = static_cast<int>(tester.cameras().size());
  float best_density = 0;  // the grids store float
  for (int c = 0; c < cameras; ++c) {
    Ray segment;
    Mat23 Jc;
    if (tester.TestGeometryCameraFrame(c, point, normal, &segment, &Jc) != ViewResult::kSeen)
      continue;
    if (segment.t_far > segment.t_near && tester.caster().Occluded(segment)) continue;
    ++v.coverage;
    v.cameras.push_back(c);
    best_density = std::max(best_density, static_cast<float>(PixelDensity(Jc)));
    double Rw[9];
    WhitenedRotation(tester.camera_rotation(c), impl_->sigma[c], Rw);
    // Each camera's contribution on its own, then summed in rig order: the fields' arithmetic.
    double contribution[6] = {0, 0, 0, 0, 0, 0};
    AddCameraInformation(Jc, Rw, contribution);
    for (int k = 0; k < 6; ++k) I[k] = v.coverage == 1 ? contribution[k] : I[k] + contribution[k];
  }
  v.resolution = best_density;
  if (v.coverage < 2) return v;
  // Eigenvalues as the fields compute them (SymmetricEigenvalues3, the general solver where it did
  // not converge), clipped at 0, with the same observability rule.
  const double* upper[6] = {&I[0], &I[1], &I[2], &I[3], &I[4], &I[5]};
  double e[3];
  double* values[3] = {&e[0], &e[1], &e[2]};
  unsigned char converged = 0;
  SymmetricEigenvalues3(upper, values, &converged, 1);
  const Vec3 eigenvalues = Vec3(e[0], e[1], e[2]).cwiseMax(0.0);
  const double largest = eigenvalues[2];
  if (!(largest > 0 && std::isfinite(largest) && eigenvalues[0] > kRelativeObservability * largest))
    return v;
  v.triangulable = true;
  v.sigma_max_mm = 1e3 * std::sqrt(1.0 / eigenvalues[0]);
  return v;
}

std::vector<PointValues> PointEvaluator::EvaluateSamples(
    const std::vector<SurfaceSample>& samples) const {
  std::vector<PointValues> values(samples.size());
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, samples.size(), 1024),
                    [&](const tbb::blocked_range<std::size_t>& r) {
                      for (std::size_t i = r.begin(); i != r.end(); ++i)
                        values[i] = Evaluate(samples[i].position, &samples[i].normal);
                    });
  return values;
}

void WriteSurfacePly(const std::string& path, const std::vector<SurfaceSample>& samples,
                     const std::vector<PointValues>& values, int enabled_cameras,
                     const std::vector<std::string>& comments) {
  if (samples.size() != values.size())
    throw std::invalid_argument("WriteSurfacePly: one value per sample expected");
  std::string header = "ply\nformat binary_little_endian 1.0\n";
  for (std::string c : comments) {
    for (char& ch : c)
      if (ch == '\n' || ch == '\r') ch = ' ';
    header += "comment " + c + "\n";
  }
  header += "element vertex " + std::to_string(samples.size()) + "\n";
  for (const char* p : {"x", "y", "z", "nx", "ny", "nz"})
    header += std::string("property float ") + p + "\n";
  header +=
      "property uchar red\nproperty uchar green\nproperty uchar blue\n"
      "property float coverage\nproperty float resolution\nproperty float sigma_max\n"
      "property uchar triangulable\nproperty int object\nend_header\n";

  constexpr std::size_t kRecord = 6 * 4 + 3 + 3 * 4 + 1 + 4;
  std::string data(header.size() + kRecord * samples.size(), '\0');
  std::memcpy(data.data(), header.data(), header.size());
  char* p = data.data() + header.size();
  // PLY binary_little_endian: the host is little-endian (x86-64, ARM64 Linux).
  static_assert(sizeof(float) == 4 && sizeof(std::int32_t) == 4);
  auto put_float = [&p](double v) {
    const float f = static_cast<float>(v);
    std::memcpy(p, &f, 4);
    p += 4;
  };
  for (std::size_t i = 0; i < samples.size(); ++i) {
    const SurfaceSample& s = samples[i];
    const PointValues& v = values[i];
    for (int k = 0; k < 3; ++k) put_float(s.position[k]);
    for (int k = 0; k < 3; ++k) put_float(s.normal[k]);
    Rgb8 color{128, 128, 128};
    if (v.coverage > 0) color = Viridis(double(v.coverage) / std::max(1, enabled_cameras));
    *p++ = static_cast<char>(color.r);
    *p++ = static_cast<char>(color.g);
    *p++ = static_cast<char>(color.b);
    put_float(v.coverage);
    put_float(v.resolution);
    put_float(v.triangulable ? v.sigma_max_mm : 0.0);
    *p++ = v.triangulable ? 1 : 0;
    const std::int32_t object = s.object;
    std::memcpy(p, &object, 4);
    p += 4;
  }
  WriteFileAtomically(path, data);
}

}  // namespace pandora
