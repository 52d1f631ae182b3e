// The only translation unit that includes Embree.
#include <embree3/rtcore.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <chrono>
#include <limits>
#include <memory>
#include <mutex>
#include <stdexcept>
#include <string>

#include "analysis/geometry/ray_caster.h"

namespace pandora {
namespace {

// Embree's SoA packet types and entry points by width.
template <int W>
struct Packet;
template <>
struct Packet<4> {
  using Type = RTCRay4;
  static void Occluded(const int* valid, RTCScene s, RTCIntersectContext* c, Type* r) {
    rtcOccluded4(valid, s, c, r);
  }
};
template <>
struct Packet<8> {
  using Type = RTCRay8;
  static void Occluded(const int* valid, RTCScene s, RTCIntersectContext* c, Type* r) {
    rtcOccluded8(valid, s, c, r);
  }
};
template <>
struct Packet<16> {
  using Type = RTCRay16;
  static void Occluded(const int* valid, RTCScene s, RTCIntersectContext* c, Type* r) {
    rtcOccluded16(valid, s, c, r);
  }
};

template <int W>
struct HitPacket;
template <>
struct HitPacket<4> {
  using Type = RTCRayHit4;
  static void Intersect(const int* valid, RTCScene s, RTCIntersectContext* c, Type* r) {
    rtcIntersect4(valid, s, c, r);
  }
};
template <>
struct HitPacket<8> {
  using Type = RTCRayHit8;
  static void Intersect(const int* valid, RTCScene s, RTCIntersectContext* c, Type* r) {
    rtcIntersect8(valid, s, c, r);
  }
};
template <>
struct HitPacket<16> {
  using Type = RTCRayHit16;
  static void Intersect(const int* valid, RTCScene s, RTCIntersectContext* c, Type* r) {
    rtcIntersect16(valid, s, c, r);
  }
};

// Copies lane `lane` of a packet from a single RTCRay.
template <typename P>
void SetLane(P* p, int lane, const RTCRay& r) {
  p->org_x[lane] = r.org_x;
  p->org_y[lane] = r.org_y;
  p->org_z[lane] = r.org_z;
  p->tnear[lane] = r.tnear;
  p->dir_x[lane] = r.dir_x;
  p->dir_y[lane] = r.dir_y;
  p->dir_z[lane] = r.dir_z;
  p->time[lane] = 0.0f;
  p->tfar[lane] = r.tfar;
  p->mask[lane] = r.mask;
  p->id[lane] = 0;
  p->flags[lane] = 0;
}

// The parts of a RigidPartsRayCaster: one device, one bottom-level scene per part (vertices in the
// rest world frame minus `offset`), and each part's triangle indices in the caller's numbering.
// A deformable part's bottom-level scene whose vertices a sample replaces (refit).
struct DeformedBlas {
  RTCScene scene = nullptr;
  RTCGeometry geometry = nullptr;
};

struct EmbreeParts {
  RTCDevice device = nullptr;
  std::vector<RTCScene> scenes;          // null for an empty part
  std::vector<std::vector<int>> global;  // [part][primID] -> caller's triangle index
  std::vector<Aabb> bounds;              // rest bounds per part
  std::vector<int> bounds_vertices;      // vertices per part
  Vec3 offset = Vec3::Zero();
  std::size_t triangles = 0;
  // Deformable parts: their triangles, and the scenes no caster uses now (a caster takes one, or
  // builds one, for its sample and gives it back when it is destroyed, so a sequence of samples
  // refits one BVH while casters alive at once each keep their own).
  std::vector<std::vector<Eigen::Vector3i>> deformable;  // per part; empty: rigid
  mutable std::mutex pool_mutex;
  mutable std::vector<std::vector<DeformedBlas>> pool;  // per part
  ~EmbreeParts() {
    for (RTCScene s : scenes)
      if (s) rtcReleaseScene(s);
    for (auto& list : pool)
      for (DeformedBlas& b : list) {
        rtcReleaseGeometry(b.geometry);
        rtcReleaseScene(b.scene);
      }
    if (device) rtcReleaseDevice(device);
  }

  // A scene of part k with `vertices` (world frame before the part's transform): a free one of
  // the pool refitted, else a new one built.
  DeformedBlas Take(std::size_t k, const std::vector<Vec3>& vertices) const {
    DeformedBlas b;
    {
      std::lock_guard<std::mutex> lock(pool_mutex);
      if (!pool[k].empty()) {
        b = pool[k].back();
        pool[k].pop_back();
      }
    }
    const std::vector<Eigen::Vector3i>& tris = deformable[k];
    if (!b.scene) {
      b.geometry = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
      rtcSetGeometryBuildQuality(b.geometry, RTC_BUILD_QUALITY_REFIT);
      rtcSetNewGeometryBuffer(b.geometry, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                              3 * sizeof(float), vertices.size());
      auto* idx = static_cast<unsigned*>(
          rtcSetNewGeometryBuffer(b.geometry, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                  3 * sizeof(unsigned), tris.size()));
      if (!idx) throw std::runtime_error("Embree: cannot allocate geometry buffers");
      for (std::size_t i = 0; i < tris.size(); ++i)
        for (int c = 0; c < 3; ++c) idx[3 * i + c] = static_cast<unsigned>(tris[i][c]);
      b.scene = rtcNewScene(device);
      rtcSetSceneFlags(b.scene, RTC_SCENE_FLAG_ROBUST | RTC_SCENE_FLAG_DYNAMIC);
      rtcSetSceneBuildQuality(
          b.scene,
          RTC_BUILD_QUALITY_LOW);  // Embree refits only under LOW (MEDIUM: 5 ms rebuilds, measured)
      rtcAttachGeometry(b.scene, b.geometry);
    }
    auto* v = static_cast<float*>(rtcGetGeometryBufferData(b.geometry, RTC_BUFFER_TYPE_VERTEX, 0));
    if (!v) throw std::runtime_error("Embree: no vertex buffer");
    for (std::size_t i = 0; i < vertices.size(); ++i) {
      const Vec3 p = vertices[i] - offset;
      v[3 * i + 0] = static_cast<float>(p.x());
      v[3 * i + 1] = static_cast<float>(p.y());
      v[3 * i + 2] = static_cast<float>(p.z());
    }
    rtcUpdateGeometryBuffer(b.geometry, RTC_BUFFER_TYPE_VERTEX, 0);
    rtcCommitGeometry(b.geometry);
    rtcCommitScene(b.scene);
    return b;
  }
  void Give(std::size_t k, DeformedBlas b) const {
    std::lock_guard<std::mutex> lock(pool_mutex);
    pool[k].push_back(b);
  }
};

// Triangles of `mesh` into a new geometry of `scene` (vertices minus `offset`, in float).
void AttachTriangles(RTCDevice device, RTCScene scene, const TriangleMesh& mesh,
                     const Vec3& offset) {
  RTCGeometry geom = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
  auto* v = static_cast<float*>(rtcSetNewGeometryBuffer(
      geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float), mesh.vertices.size()));
  auto* idx = static_cast<unsigned*>(rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_INDEX, 0,
                                                             RTC_FORMAT_UINT3, 3 * sizeof(unsigned),
                                                             mesh.triangles.size()));
  if (!v || !idx) throw std::runtime_error("Embree: cannot allocate geometry buffers");
  for (std::size_t i = 0; i < mesh.vertices.size(); ++i) {
    const Vec3 p = mesh.vertices[i] - offset;
    v[3 * i + 0] = static_cast<float>(p.x());
    v[3 * i + 1] = static_cast<float>(p.y());
    v[3 * i + 2] = static_cast<float>(p.z());
  }
  for (std::size_t i = 0; i < mesh.triangles.size(); ++i)
    for (int k = 0; k < 3; ++k) idx[3 * i + k] = static_cast<unsigned>(mesh.triangles[i][k]);
  rtcCommitGeometry(geom);
  rtcAttachGeometry(scene, geom);
  rtcReleaseGeometry(geom);
}

int NativePacketWidth(RTCDevice device) {
  if (rtcGetDeviceProperty(device, RTC_DEVICE_PROPERTY_NATIVE_RAY16_SUPPORTED)) return 16;
  if (rtcGetDeviceProperty(device, RTC_DEVICE_PROPERTY_NATIVE_RAY8_SUPPORTED)) return 8;
  if (rtcGetDeviceProperty(device, RTC_DEVICE_PROPERTY_NATIVE_RAY4_SUPPORTED)) return 4;
  return 1;
}

class EmbreeRayCaster final : public RayCaster {
 public:
  // One time sample of rigid parts: a top-level scene of one instance per part with its transform
  // (world_from_rest), over the parts' shared bottom-level scenes. Only this small top-level BVH is
  // built.
  EmbreeRayCaster(std::shared_ptr<const EmbreeParts> parts,
                  const std::vector<Eigen::Isometry3d>& transforms,
                  const std::vector<std::vector<Vec3>>& vertices = {})
      : triangles_(parts->triangles), offset_(parts->offset), parts_(std::move(parts)) {
    device_ = parts_->device;
    rtcRetainDevice(device_);
    scene_ = rtcNewScene(device_);
    rtcSetSceneFlags(scene_, RTC_SCENE_FLAG_ROBUST);
    rtcSetSceneBuildQuality(scene_, RTC_BUILD_QUALITY_HIGH);
    part_rotation_.resize(parts_->scenes.size(), Mat3::Identity());
    for (std::size_t k = 0; k < parts_->scenes.size(); ++k) {
      const Eigen::Isometry3d T =
          k < transforms.size() ? transforms[k] : Eigen::Isometry3d::Identity();
      part_rotation_[k] = T.linear();
      RTCScene blas = parts_->scenes[k];
      const bool deformed = k < vertices.size() && !parts_->deformable[k].empty() &&
                            vertices[k].size() == std::size_t(parts_->bounds_vertices[k]);
      if (deformed) {
        for (const Vec3& v : vertices[k]) bounds_.Extend(T * v);
        const DeformedBlas d = parts_->Take(k, vertices[k]);
        borrowed_.emplace_back(k, d);
        blas = d.scene;
      } else {
        // Part bounds at the sample: the rest box's corners moved.
        const Aabb& b = parts_->bounds[k];
        if (!b.empty())
          for (int c = 0; c < 8; ++c)
            bounds_.Extend(T * Vec3(c & 1 ? b.max.x() : b.min.x(), c & 2 ? b.max.y() : b.min.y(),
                                    c & 4 ? b.max.z() : b.min.z()));
      }
      if (!blas) continue;
      // In the recentred frame: x' = R x + (R o + t - o), o the offset.
      const Mat3 R = T.linear();
      const Vec3 t = R * offset_ + T.translation() - offset_;
      float xfm[12];
      for (int col = 0; col < 3; ++col)
        for (int row = 0; row < 3; ++row) xfm[3 * col + row] = static_cast<float>(R(row, col));
      for (int row = 0; row < 3; ++row) xfm[9 + row] = static_cast<float>(t[row]);
      RTCGeometry inst = rtcNewGeometry(device_, RTC_GEOMETRY_TYPE_INSTANCE);
      rtcSetGeometryInstancedScene(inst, blas);
      rtcSetGeometryTransform(inst, 0, RTC_FORMAT_FLOAT3X4_COLUMN_MAJOR, xfm);
      rtcCommitGeometry(inst);
      rtcAttachGeometryByID(scene_, inst, static_cast<unsigned>(k));
      rtcReleaseGeometry(inst);
    }
    rtcCommitScene(scene_);
    if (rtcGetDeviceError(device_) != RTC_ERROR_NONE)
      throw std::runtime_error("Embree: instance scene build failed");
    packet_width_ = NativePacketWidth(device_);
  }

  explicit EmbreeRayCaster(const TriangleMesh& mesh) : triangles_(mesh.triangles.size()) {
    bounds_ = mesh.Bounds();
    offset_ = bounds_.empty() ? Vec3::Zero() : bounds_.center();

    device_ = rtcNewDevice(nullptr);
    if (!device_) throw std::runtime_error("Embree: cannot create a device");
    scene_ = rtcNewScene(device_);
    rtcSetSceneFlags(scene_, RTC_SCENE_FLAG_ROBUST);
    rtcSetSceneBuildQuality(scene_, RTC_BUILD_QUALITY_HIGH);

    if (!mesh.triangles.empty()) AttachTriangles(device_, scene_, mesh, offset_);
    rtcCommitScene(scene_);
    if (rtcGetDeviceError(device_) != RTC_ERROR_NONE)
      throw std::runtime_error("Embree: scene build failed");
    packet_width_ = NativePacketWidth(device_);
  }

  // The caller's triangle index and the world normal of a hit (instances report their part's
  // local primitive and normal).
  void MapHit(unsigned inst, unsigned prim, const Vec3& ng, int* triangle, Vec3* normal) const {
    if (!parts_ || inst == RTC_INVALID_GEOMETRY_ID) {
      *triangle = static_cast<int>(prim);
      *normal = ng.normalized();
      return;
    }
    *triangle = parts_->global[inst][prim];
    *normal = (part_rotation_[inst] * ng).normalized();
  }

  // Packets are traced in Embree's coherent mode over one mesh (a fan of rays from one camera
  // centre: 1.5x faster than incoherent, measured on the trauma room), but never over the
  // instances of a moving scene: there Embree 3.13's coherent packet traversal can loop for ever
  // (rtcOccluded16 never returned on the mocap lab's people with sigma_max asked for; test
  // cli.motion_uncertainty_finishes keeps the smallest such scene under a timeout).
  RTCIntersectContextFlags PacketFlags() const {
    return parts_ ? RTC_INTERSECT_CONTEXT_FLAG_INCOHERENT : RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
  }

  ~EmbreeRayCaster() override {
    rtcReleaseScene(scene_);
    for (const auto& [k, b] : borrowed_) parts_->Give(k, b);
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
    rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
    rtcIntersect1(scene_, &context, &rh);
    if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return std::nullopt;
    RayHit hit;
    hit.t = rh.ray.tfar;
    MapHit(rh.hit.instID[0], rh.hit.primID, Vec3(rh.hit.Ng_x, rh.hit.Ng_y, rh.hit.Ng_z),
           &hit.triangle, &hit.normal);
    return hit;
  }

  void OccludedPacket(const Ray* rays, std::size_t count, uint8_t* occluded) const override {
    switch (packet_width_) {
      case 16:
        return TracePackets<16>(rays, count, occluded);
      case 8:
        return TracePackets<8>(rays, count, occluded);
      case 4:
        return TracePackets<4>(rays, count, occluded);
      default:
        RayCaster::OccludedPacket(rays, count, occluded);
    }
  }

  void OccludedFan(const Fan& fan, std::size_t count, uint8_t* occluded) const override {
    switch (packet_width_) {
      case 16:
        return TraceFan<16>(fan, count, occluded);
      case 8:
        return TraceFan<8>(fan, count, occluded);
      case 4:
        return TraceFan<4>(fan, count, occluded);
      default:
        RayCaster::OccludedFan(fan, count, occluded);
    }
  }

  // Packets of W filled from the fan's arrays, converted as Fill() converts a Ray (so the same
  // floats as OccludedPacket on the same rays); the origin and constant fields once.
  template <int W>
  void TraceFan(const Fan& fan, std::size_t count, uint8_t* occluded) const {
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    context.flags = PacketFlags();
    alignas(64) typename Packet<W>::Type packet;
    alignas(64) int valid[W];
    const Vec3 o = fan.origin - offset_;
    for (int lane = 0; lane < W; ++lane) {
      packet.org_x[lane] = static_cast<float>(o.x());
      packet.org_y[lane] = static_cast<float>(o.y());
      packet.org_z[lane] = static_cast<float>(o.z());
      packet.time[lane] = 0.0f;
      packet.mask[lane] = 0xFFFFFFFFu;
      packet.id[lane] = 0;
      packet.flags[lane] = 0;
    }
    constexpr double kInf = std::numeric_limits<double>::infinity();
    for (std::size_t start = 0; start < count; start += W) {
      const int n = static_cast<int>(std::min<std::size_t>(W, count - start));
      for (int lane = 0; lane < W; ++lane) {
        const std::size_t k = fan.at(start + std::min(lane, n - 1));
        valid[lane] = lane < n ? -1 : 0;
        packet.dir_x[lane] = static_cast<float>(fan.dx[k]);
        packet.dir_y[lane] = static_cast<float>(fan.dy[k]);
        packet.dir_z[lane] = static_cast<float>(fan.dz[k]);
        packet.tnear[lane] = static_cast<float>(fan.t_near[k]);
        packet.tfar[lane] = fan.t_far[k] == kInf ? std::numeric_limits<float>::infinity()
                                                 : static_cast<float>(fan.t_far[k]);
      }
      Packet<W>::Occluded(valid, scene_, &context, &packet);
      for (int lane = 0; lane < n; ++lane) occluded[start + lane] = packet.tfar[lane] < 0.0f;
    }
  }

  // Traces already converted rays in packets of W (the last one partly valid).
  template <int W>
  void TraceConverted(const RTCRay* rays, std::size_t count, uint8_t* occluded) const {
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    context.flags = PacketFlags();
    alignas(64) typename Packet<W>::Type packet;
    alignas(64) int valid[W];
    for (std::size_t start = 0; start < count; start += W) {
      const int n = static_cast<int>(std::min<std::size_t>(W, count - start));
      for (int lane = 0; lane < W; ++lane) {
        valid[lane] = lane < n ? -1 : 0;
        SetLane(&packet, lane, rays[start + std::min(lane, n - 1)]);
      }
      Packet<W>::Occluded(valid, scene_, &context, &packet);
      for (int lane = 0; lane < n; ++lane) occluded[start + lane] = packet.tfar[lane] < 0.0f;
    }
  }

  void IntersectPacket(const Ray* rays, std::size_t count,
                       std::optional<RayHit>* hits) const override {
    switch (packet_width_) {
      case 16:
        return IntersectPackets<16>(rays, count, hits);
      case 8:
        return IntersectPackets<8>(rays, count, hits);
      case 4:
        return IntersectPackets<4>(rays, count, hits);
      default:
        RayCaster::IntersectPacket(rays, count, hits);
    }
  }

  // First hits of already converted rays in packets of W; calls out(index, packet, lane) per ray.
  template <int W, typename Out>
  void IntersectConverted(const RTCRay* rays, std::size_t count, Out&& out) const {
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    context.flags = PacketFlags();
    alignas(64) typename HitPacket<W>::Type packet;
    alignas(64) int valid[W];
    for (std::size_t start = 0; start < count; start += W) {
      const int n = static_cast<int>(std::min<std::size_t>(W, count - start));
      for (int lane = 0; lane < W; ++lane) {
        valid[lane] = lane < n ? -1 : 0;
        SetLane(&packet.ray, lane, rays[start + std::min(lane, n - 1)]);
        packet.hit.geomID[lane] = RTC_INVALID_GEOMETRY_ID;
        packet.hit.primID[lane] = RTC_INVALID_GEOMETRY_ID;
        packet.hit.instID[0][lane] = RTC_INVALID_GEOMETRY_ID;
      }
      HitPacket<W>::Intersect(valid, scene_, &context, &packet);
      for (int lane = 0; lane < n; ++lane) out(start + lane, packet, lane);
    }
  }

  template <int W>
  void IntersectPackets(const Ray* rays, std::size_t count, std::optional<RayHit>* hits) const {
    constexpr std::size_t kChunk = 256;
    RTCRay converted[kChunk];
    for (std::size_t start = 0; start < count; start += kChunk) {
      const std::size_t n = std::min(kChunk, count - start);
      for (std::size_t i = 0; i < n; ++i) Fill(rays[start + i], &converted[i]);
      IntersectConverted<W>(converted, n, [&](std::size_t i, const auto& p, int lane) {
        std::optional<RayHit>& h = hits[start + i];
        if (p.hit.geomID[lane] == RTC_INVALID_GEOMETRY_ID) {
          h.reset();
          return;
        }
        RayHit hit;
        hit.t = p.ray.tfar[lane];
        MapHit(p.hit.instID[0][lane], p.hit.primID[lane],
               Vec3(p.hit.Ng_x[lane], p.hit.Ng_y[lane], p.hit.Ng_z[lane]), &hit.triangle,
               &hit.normal);
        h = hit;
      });
    }
  }

  int packet_width() const { return packet_width_; }
  const char* name() const override { return "embree"; }
  std::size_t triangle_count() const override { return triangles_; }

  RTCScene scene() const { return scene_; }

  template <int W>
  void TracePackets(const Ray* rays, std::size_t count, uint8_t* occluded) const {
    constexpr std::size_t kChunk = 256;
    RTCRay converted[kChunk];
    for (std::size_t start = 0; start < count; start += kChunk) {
      const std::size_t n = std::min(kChunk, count - start);
      for (std::size_t i = 0; i < n; ++i) Fill(rays[start + i], &converted[i]);
      TraceConverted<W>(converted, n, occluded + start);
    }
  }
  const Vec3& offset() const { return offset_; }
  const Aabb& bounds() const override { return bounds_; }

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
  int packet_width_ = 1;
  Vec3 offset_ = Vec3::Zero();
  Aabb bounds_;
  RTCDevice device_ = nullptr;
  RTCScene scene_ = nullptr;
  std::shared_ptr<const EmbreeParts> parts_;  // set for a sample of rigid parts
  std::vector<Mat3> part_rotation_;           // per part: world_from_rest rotation (normals)
  std::vector<std::pair<std::size_t, DeformedBlas>>
      borrowed_;  // deformed parts' scenes, given back
};

class EmbreeRigidParts final : public RigidPartsRayCaster {
 public:
  EmbreeRigidParts(const std::vector<TriangleMesh>& parts,
                   const std::vector<std::vector<int>>& triangle_index,
                   const std::vector<bool>& deformable) {
    auto data = std::make_shared<EmbreeParts>();
    data->deformable.resize(parts.size());
    data->pool.resize(parts.size());
    for (std::size_t k = 0; k < parts.size(); ++k) {
      data->bounds_vertices.push_back(int(parts[k].vertices.size()));
      if (k < deformable.size() && deformable[k]) data->deformable[k] = parts[k].triangles;
    }
    Aabb all;
    for (const TriangleMesh& m : parts) all.Extend(m.Bounds());
    data->offset = all.empty() ? Vec3::Zero() : all.center();
    data->device = rtcNewDevice(nullptr);
    if (!data->device) throw std::runtime_error("Embree: cannot create a device");
    int next = 0;
    for (std::size_t k = 0; k < parts.size(); ++k) {
      const TriangleMesh& mesh = parts[k];
      data->bounds.push_back(mesh.Bounds());
      std::vector<int> global(mesh.triangles.size());
      for (std::size_t i = 0; i < global.size(); ++i)
        global[i] = k < triangle_index.size() && triangle_index[k].size() == global.size()
                        ? triangle_index[k][i]
                        : next + int(i);
      next += int(global.size());
      data->triangles += global.size();
      data->global.push_back(std::move(global));
      if (mesh.triangles.empty()) {
        data->scenes.push_back(nullptr);
        continue;
      }
      RTCScene scene = rtcNewScene(data->device);
      rtcSetSceneFlags(scene, RTC_SCENE_FLAG_ROBUST);
      rtcSetSceneBuildQuality(scene, RTC_BUILD_QUALITY_HIGH);
      AttachTriangles(data->device, scene, mesh, data->offset);
      rtcCommitScene(scene);
      data->scenes.push_back(scene);
    }
    if (rtcGetDeviceError(data->device) != RTC_ERROR_NONE)
      throw std::runtime_error("Embree: part build failed");
    data_ = std::move(data);
  }
  std::unique_ptr<RayCaster> At(const std::vector<Eigen::Isometry3d>& transforms,
                                const std::vector<std::vector<Vec3>>& vertices) const override {
    return std::make_unique<EmbreeRayCaster>(data_, transforms, vertices);
  }
  std::size_t part_count() const override { return data_->scenes.size(); }

 private:
  std::shared_ptr<const EmbreeParts> data_;
};

}  // namespace

std::unique_ptr<RayCaster> MakeEmbreeRayCaster(const TriangleMesh& mesh) {
  return std::make_unique<EmbreeRayCaster>(mesh);
}

std::unique_ptr<RigidPartsRayCaster> MakeEmbreeRigidParts(
    const std::vector<TriangleMesh>& parts, const std::vector<std::vector<int>>& triangle_index,
    const std::vector<bool>& deformable) {
  return std::make_unique<EmbreeRigidParts>(parts, triangle_index, deformable);
}

int EmbreePacketWidth(const RayCaster& caster) {
  const auto* embree = dynamic_cast<const EmbreeRayCaster*>(&caster);
  return embree ? embree->packet_width() : 1;
}

RawOcclusionResult RawEmbreeOcclusion(const RayCaster& caster, const std::vector<Ray>& rays,
                                      RawMode mode) {
  const auto* embree = dynamic_cast<const EmbreeRayCaster*>(&caster);
  if (!embree) throw std::invalid_argument("RawEmbreeOcclusion needs an Embree ray caster");
  // Convert first so the timed loop is Embree alone.
  std::vector<RTCRay> converted(rays.size());
  for (std::size_t i = 0; i < rays.size(); ++i) embree->Fill(rays[i], &converted[i]);
  const RTCScene scene = embree->scene();
  const int width = mode == RawMode::kPacket ? embree->packet_width() : 1;
  // Packets are formed from consecutive rays within each chunk, as the field evaluation forms them
  // from consecutive voxels of one block and camera.
  const std::size_t grain = 1024;

  const auto start = std::chrono::steady_clock::now();
  const std::size_t occluded = tbb::parallel_reduce(
      tbb::blocked_range<std::size_t>(0, converted.size(), grain), std::size_t{0},
      [&](const tbb::blocked_range<std::size_t>& r, std::size_t count) {
        if (width == 1) {
          RTCIntersectContext context;
          rtcInitIntersectContext(&context);
          for (std::size_t i = r.begin(); i != r.end(); ++i) {
            RTCRay ray = converted[i];
            rtcOccluded1(scene, &context, &ray);
            count += ray.tfar < 0.0f ? 1 : 0;
          }
          return count;
        }
        uint8_t hits[grain];
        const std::size_t n = r.size();
        for (std::size_t done = 0; done < n; done += grain) {
          const std::size_t m = std::min(grain, n - done);
          const RTCRay* first = converted.data() + r.begin() + done;
          switch (width) {
            case 16:
              embree->TraceConverted<16>(first, m, hits);
              break;
            case 8:
              embree->TraceConverted<8>(first, m, hits);
              break;
            default:
              embree->TraceConverted<4>(first, m, hits);
              break;
          }
          for (std::size_t i = 0; i < m; ++i) count += hits[i];
        }
        return count;
      },
      [](std::size_t a, std::size_t b) { return a + b; });
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return RawOcclusionResult{seconds, rays.size(), occluded};
}

RawOcclusionResult RawEmbreeIntersection(const RayCaster& caster, const std::vector<Ray>& rays,
                                         RawMode mode) {
  const auto* embree = dynamic_cast<const EmbreeRayCaster*>(&caster);
  if (!embree) throw std::invalid_argument("RawEmbreeIntersection needs an Embree ray caster");
  std::vector<RTCRay> converted(rays.size());
  for (std::size_t i = 0; i < rays.size(); ++i) embree->Fill(rays[i], &converted[i]);
  const RTCScene scene = embree->scene();
  const int width = mode == RawMode::kPacket ? embree->packet_width() : 1;
  const auto start = std::chrono::steady_clock::now();
  const std::size_t hits = tbb::parallel_reduce(
      tbb::blocked_range<std::size_t>(0, converted.size(), 1024), std::size_t{0},
      [&](const tbb::blocked_range<std::size_t>& r, std::size_t count) {
        if (width > 1) {
          const RTCRay* first = converted.data() + r.begin();
          auto tally = [&](std::size_t, const auto& p, int lane) {
            count += p.hit.geomID[lane] != RTC_INVALID_GEOMETRY_ID ? 1 : 0;
          };
          switch (width) {
            case 16:
              embree->IntersectConverted<16>(first, r.size(), tally);
              break;
            case 8:
              embree->IntersectConverted<8>(first, r.size(), tally);
              break;
            default:
              embree->IntersectConverted<4>(first, r.size(), tally);
              break;
          }
          return count;
        }
        RTCIntersectContext context;
        rtcInitIntersectContext(&context);
        RTCRayHit rh;
        for (std::size_t i = r.begin(); i != r.end(); ++i) {
          rh.ray = converted[i];
          rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
          rh.hit.primID = RTC_INVALID_GEOMETRY_ID;
          rtcIntersect1(scene, &context, &rh);
          count += rh.hit.geomID != RTC_INVALID_GEOMETRY_ID ? 1 : 0;
        }
        return count;
      },
      [](std::size_t a, std::size_t b) { return a + b; });
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return RawOcclusionResult{seconds, rays.size(), hits};
}

}  // namespace pandora
