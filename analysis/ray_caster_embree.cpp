// The only translation unit that includes Embree.
#include <embree3/rtcore.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <chrono>
#include <limits>
#include <stdexcept>
#include <string>

#include "analysis/ray_caster.h"

namespace pandora {
namespace {

class EmbreeRayCaster final : public RayCaster {
 public:
  explicit EmbreeRayCaster(const TriangleMesh& mesh) : triangles_(mesh.triangles.size()) {
    const Aabb bounds = mesh.Bounds();
    offset_ = bounds.empty() ? Vec3::Zero() : bounds.center();

    device_ = rtcNewDevice(nullptr);
    if (!device_) throw std::runtime_error("Embree: cannot create a device");
    scene_ = rtcNewScene(device_);
    rtcSetSceneFlags(scene_, RTC_SCENE_FLAG_ROBUST);
    rtcSetSceneBuildQuality(scene_, RTC_BUILD_QUALITY_HIGH);

    if (!mesh.triangles.empty()) {
      RTCGeometry geom = rtcNewGeometry(device_, RTC_GEOMETRY_TYPE_TRIANGLE);
      auto* v = static_cast<float*>(rtcSetNewGeometryBuffer(
          geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float), mesh.vertices.size()));
      auto* idx = static_cast<unsigned*>(rtcSetNewGeometryBuffer(
          geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(unsigned), triangles_));
      if (!v || !idx) throw std::runtime_error("Embree: cannot allocate geometry buffers");
      for (std::size_t i = 0; i < mesh.vertices.size(); ++i) {
        const Vec3 p = mesh.vertices[i] - offset_;
        v[3 * i + 0] = static_cast<float>(p.x());
        v[3 * i + 1] = static_cast<float>(p.y());
        v[3 * i + 2] = static_cast<float>(p.z());
      }
      for (std::size_t i = 0; i < triangles_; ++i)
        for (int k = 0; k < 3; ++k) idx[3 * i + k] = static_cast<unsigned>(mesh.triangles[i][k]);
      rtcCommitGeometry(geom);
      rtcAttachGeometry(scene_, geom);
      rtcReleaseGeometry(geom);
    }
    rtcCommitScene(scene_);
    if (rtcGetDeviceError(device_) != RTC_ERROR_NONE)
      throw std::runtime_error("Embree: scene build failed");
  }

  ~EmbreeRayCaster() override {
    rtcReleaseScene(scene_);
    rtcReleaseDevice(device_);
  }

  bool Occluded(const Ray& ray) const override {
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    RTCRay r;
    Fill(ray, &r);
    rtcOccluded1(scene_, &context, &r);
    return r.tfar < 0.0f;
  }

  std::optional<RayHit> Intersect(const Ray& ray) const override {
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    RTCRayHit rh;
    Fill(ray, &rh.ray);
    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rh.hit.primID = RTC_INVALID_GEOMETRY_ID;
    rtcIntersect1(scene_, &context, &rh);
    if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return std::nullopt;
    RayHit hit;
    hit.t = rh.ray.tfar;
    hit.triangle = static_cast<int>(rh.hit.primID);
    hit.normal = Vec3(rh.hit.Ng_x, rh.hit.Ng_y, rh.hit.Ng_z).normalized();
    return hit;
  }

  const char* name() const override { return "embree"; }
  std::size_t triangle_count() const override { return triangles_; }

  RTCScene scene() const { return scene_; }
  const Vec3& offset() const { return offset_; }

  // Converts to Embree's single-precision ray in the recentred frame.
  void Fill(const Ray& ray, RTCRay* r) const {
    const Vec3 o = ray.origin - offset_;
    r->org_x = static_cast<float>(o.x());
    r->org_y = static_cast<float>(o.y());
    r->org_z = static_cast<float>(o.z());
    r->dir_x = static_cast<float>(ray.direction.x());
    r->dir_y = static_cast<float>(ray.direction.y());
    r->dir_z = static_cast<float>(ray.direction.z());
    r->tnear = static_cast<float>(ray.t_near);
    r->tfar = ray.t_far == std::numeric_limits<double>::infinity()
                  ? std::numeric_limits<float>::infinity()
                  : static_cast<float>(ray.t_far);
    r->time = 0.0f;
    r->mask = 0xFFFFFFFFu;
    r->id = 0;
    r->flags = 0;
  }

 private:
  std::size_t triangles_ = 0;
  Vec3 offset_ = Vec3::Zero();
  RTCDevice device_ = nullptr;
  RTCScene scene_ = nullptr;
};

}  // namespace

std::unique_ptr<RayCaster> MakeEmbreeRayCaster(const TriangleMesh& mesh) {
  return std::make_unique<EmbreeRayCaster>(mesh);
}

RawOcclusionResult RawEmbreeOcclusion(const RayCaster& caster, const std::vector<Ray>& rays) {
  const auto* embree = dynamic_cast<const EmbreeRayCaster*>(&caster);
  if (!embree) throw std::invalid_argument("RawEmbreeOcclusion needs an Embree ray caster");
  // Convert first so the timed loop is Embree alone.
  std::vector<RTCRay> converted(rays.size());
  for (std::size_t i = 0; i < rays.size(); ++i) embree->Fill(rays[i], &converted[i]);
  const RTCScene scene = embree->scene();

  const auto start = std::chrono::steady_clock::now();
  const std::size_t occluded = tbb::parallel_reduce(
      tbb::blocked_range<std::size_t>(0, converted.size(), 1024), std::size_t{0},
      [&](const tbb::blocked_range<std::size_t>& r, std::size_t count) {
        RTCIntersectContext context;
        rtcInitIntersectContext(&context);
        for (std::size_t i = r.begin(); i != r.end(); ++i) {
          RTCRay ray = converted[i];
          rtcOccluded1(scene, &context, &ray);
          count += ray.tfar < 0.0f ? 1 : 0;
        }
        return count;
      },
      [](std::size_t a, std::size_t b) { return a + b; });
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return RawOcclusionResult{seconds, rays.size(), occluded};
}

}  // namespace pandora
