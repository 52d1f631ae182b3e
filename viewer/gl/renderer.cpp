// The GPU projective-light renderer (viewer/gl/renderer.h). A frame is deferred:
//  1. G-buffer: the scene from the view; per pixel the surface point (relative to the scene's
//     centre, float), the normal turned towards the eye and the albedo.
//  2. Per enabled camera, in rig order: its distance map (one perspective map over the camera's
//     field, or a cube of six for wide lenses), then a full-screen pass that tests every pixel's
//     point as VisibilityTester does (range, lens projection, image bounds, facing, the map in
//     place of the occlusion segment) and adds the camera's term of the light rule into a float
//     accumulation target (additive blending, rig order) and ORs its bit into an RG32UI mask
//     (ping-pong between two mask textures: integer targets do not blend).
//  3. Compose: MaterialColor (or the light alone) and the background, then read back. Hidden-line
//     mode: the G-buffer pass also stores each fragment's coverage by its triangle's drawn edges
//     (render/frame.cpp's rule, from the screen derivatives of the barycentric coordinates), so
//     only edges of visible surface are drawn; contour mode: the compose pass finds object, depth
//     and crease discontinuities between neighbouring pixels of the G-buffer (Finish's rules).
#include "viewer/gl/renderer.h"

#include <epoxy/gl.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <list>
#include <map>
#include <optional>
#include <stdexcept>
#include <string>

#include "analysis/util/color.h"
#include "analysis/util/units.h"
#include "render/prepared_scene.h"
#include "render/render.h"

namespace pandora {
namespace {

// A camera whose field reaches this far off its axis gets a cube of maps: one perspective map
// would spend most of its texels at the edges (tan 75 deg = 3.7 times the centre's spacing).
constexpr double kMaxPerspectiveFieldAngle = 75.0 * kPi / 180.0;
// A camera's-eye view's cover G-buffer: texels per output pixel where the lens's rays are
// densest (each output ray then lands within a quarter of an output pixel of its cover texel's
// centre), and at most this many texels (52 bytes each).
constexpr double kCoverScale = 2.0;
constexpr double kMaxCoverTexels = 8e6;

// ------------------------------------------------------------------------------------------
// Shaders (GLSL 3.30 core): viewer/gl/shaders/, one file per stage of each pass, embedded at
// build time as the constants kGBufferVertex, kGBufferFragment, kShadowVertex, kShadowFragment,
// kFullScreenVertex, kLightRuleGlsl, kLightFragment, kComposeFragment, kLightWeightsFragment
// (viewer/CMakeLists.txt).
#include "viewer/gl/shaders.inc"

// `source` with the light rule's GLSL in place of its "// @LIGHT_RULE@" line.
std::string WithLightRule(const char* source) {
  std::string s = source;
  const std::string marker = "// @LIGHT_RULE@";
  s.replace(s.find(marker), marker.size(), kLightRuleGlsl);
  return s;
}

// ------------------------------------------------------------------------------------------
// GL helpers.

GLuint Compile(GLenum type, const char* source, const char* name) {
  const GLuint shader = glCreateShader(type);
  glShaderSource(shader, 1, &source, nullptr);
  glCompileShader(shader);
  GLint ok = 0;
  glGetShaderiv(shader, GL_COMPILE_STATUS, &ok);
  if (!ok) {
    char log[4096];
    glGetShaderInfoLog(shader, sizeof(log), nullptr, log);
    glDeleteShader(shader);
    throw std::runtime_error(std::string("GlRenderer: shader ") + name +
                             " does not compile: " + log);
  }
  return shader;
}

GLuint Link(const char* vertex, const char* fragment, const char* name) {
  const GLuint vs = Compile(GL_VERTEX_SHADER, vertex, name);
  const GLuint fs = Compile(GL_FRAGMENT_SHADER, fragment, name);
  const GLuint program = glCreateProgram();
  glAttachShader(program, vs);
  glAttachShader(program, fs);
  glLinkProgram(program);
  glDeleteShader(vs);
  glDeleteShader(fs);
  GLint ok = 0;
  glGetProgramiv(program, GL_LINK_STATUS, &ok);
  if (!ok) {
    char log[4096];
    glGetProgramInfoLog(program, sizeof(log), nullptr, log);
    glDeleteProgram(program);
    throw std::runtime_error(std::string("GlRenderer: program ") + name + " does not link: " + log);
  }
  return program;
}

// A program with a geometry shader between the two (the maps' layered pass).
GLuint Link(const char* vertex, const char* geometry, const char* fragment, const char* name) {
  const GLuint vs = Compile(GL_VERTEX_SHADER, vertex, name);
  const GLuint gs = Compile(GL_GEOMETRY_SHADER, geometry, name);
  const GLuint fs = Compile(GL_FRAGMENT_SHADER, fragment, name);
  const GLuint program = glCreateProgram();
  for (GLuint s : {vs, gs, fs}) glAttachShader(program, s);
  glLinkProgram(program);
  for (GLuint s : {vs, gs, fs}) glDeleteShader(s);
  GLint ok = 0;
  glGetProgramiv(program, GL_LINK_STATUS, &ok);
  if (!ok) {
    char log[4096];
    glGetProgramInfoLog(program, sizeof(log), nullptr, log);
    glDeleteProgram(program);
    throw std::runtime_error(std::string("GlRenderer: program ") + name + " does not link: " + log);
  }
  return program;
}

GLint Loc(GLuint program, const char* name) { return glGetUniformLocation(program, name); }

void SetMat3(GLuint program, const char* name, const Mat3& m) {
  float f[9];
  for (int c = 0; c < 3; ++c)
    for (int r = 0; r < 3; ++r) f[3 * c + r] = float(m(r, c));  // column-major
  glUniformMatrix3fv(Loc(program, name), 1, GL_FALSE, f);
}
void SetVec3(GLuint program, const char* name, const Vec3& v) {
  glUniform3f(Loc(program, name), float(v.x()), float(v.y()), float(v.z()));
}

GLuint MakeTexture(GLenum internal, int width, int height, GLenum format, GLenum type) {
  GLuint tex = 0;
  glGenTextures(1, &tex);
  glBindTexture(GL_TEXTURE_2D, tex);
  glTexImage2D(GL_TEXTURE_2D, 0, internal, width, height, 0, format, type, nullptr);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
  return tex;
}

void CheckFramebuffer(const char* what);

// A G-buffer of w x h: three RGBA32F targets (point, normal, albedo) and a depth buffer on one
// framebuffer (the view's, and a camera's-eye cover).
void MakeGBuffer(int w, int h, const char* what, GLuint* fbo, GLuint (&textures)[3],
                 GLuint* depth) {
  for (GLuint& t : textures) t = MakeTexture(GL_RGBA32F, w, h, GL_RGBA, GL_FLOAT);
  glGenRenderbuffers(1, depth);
  glBindRenderbuffer(GL_RENDERBUFFER, *depth);
  glRenderbufferStorage(GL_RENDERBUFFER, GL_DEPTH_COMPONENT32F, w, h);
  glGenFramebuffers(1, fbo);
  glBindFramebuffer(GL_FRAMEBUFFER, *fbo);
  for (int i = 0; i < 3; ++i)
    glFramebufferTexture2D(GL_FRAMEBUFFER, GLenum(GL_COLOR_ATTACHMENT0 + i), GL_TEXTURE_2D,
                           textures[i], 0);
  glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, *depth);
  CheckFramebuffer(what);
}

void CheckFramebuffer(const char* what) {
  const GLenum status = glCheckFramebufferStatus(GL_FRAMEBUFFER);
  if (status != GL_FRAMEBUFFER_COMPLETE)
    throw std::runtime_error(std::string("GlRenderer: framebuffer ") + what +
                             " incomplete (status " + std::to_string(status) + ")");
}

// Perspective clip coefficients A, B mapping z = near to -1 and z = far to +1.
Eigen::Vector2d DepthCoefficients(double near, double far) {
  return Eigen::Vector2d((far + near) / (far - near), -2.0 * far * near / (far - near));
}

// [near, far] for a depth buffer from the geometry's range: a margin of 1e-3 each way, near kept
// above 1e-5 of far (closer geometry is clipped: nothing a depth buffer could order anyway).
std::pair<double, double> PadRange(std::pair<double, double> r) {
  const double far = std::max(r.second * (1 + 1e-3), 1e-6);
  const double near = std::max(r.first * (1 - 1e-3), far * 1e-5);
  return {near, far};
}

// The six cube faces, in the shader's layer order +x, -x, +y, -y, +z, -z: each maps its axis
// onto +z.
std::array<Mat3, 6> CubeFaces() {
  std::array<Mat3, 6> f;
  auto frame = [](const Vec3& z, const Vec3& up) {
    const Vec3 x = up.cross(z).normalized();
    const Vec3 y = z.cross(x);
    Mat3 m;
    m.row(0) = x.transpose();
    m.row(1) = y.transpose();
    m.row(2) = z.transpose();
    return m;
  };
  f[0] = frame(Vec3::UnitX(), Vec3::UnitY());
  f[1] = frame(-Vec3::UnitX(), Vec3::UnitY());
  f[2] = frame(Vec3::UnitY(), Vec3::UnitZ());
  f[3] = frame(-Vec3::UnitY(), Vec3::UnitZ());
  f[4] = frame(Vec3::UnitZ(), Vec3::UnitY());
  f[5] = frame(-Vec3::UnitZ(), Vec3::UnitY());
  return f;
}

// Cameras per light pass: the uniform block holds kCameraVec4 vec4s per camera (16 KiB, the
// least GL 3.3 guarantees, fits 64 x 10 x 16 bytes).
constexpr int kCameraVec4 = 10;
constexpr int kMaxBatch = 64;

// Whether cube face `face` (CubeFaces) lies wholly outside `cam`'s field: its pyramid reaches
// 54.7 degrees around its axis.
bool FaceOutOfField(const Camera& cam, int face) {
  static const std::array<Mat3, 6> kCube = CubeFaces();
  const double axis_angle = std::acos(std::clamp(kCube[face].row(2).z(), -1.0, 1.0));
  return axis_angle - std::atan(std::sqrt(2.0)) >= cam.model.max_field_angle();
}

bool IsCube(const Camera& cam) { return cam.model.max_field_angle() >= kMaxPerspectiveFieldAngle; }

// Batches of enabled cameras in rig order, each within the map memory budget and the uniform
// block, and within one 64-camera word of the per-pixel camera sets (rig indices 64 w .. 64 w +
// 63, so one RG32UI mask holds a batch's bits); each batch is one light pass over the G-buffer
// with all its maps bound.
struct Batch {
  std::vector<int> cameras;
  int perspective = 0, cube = 0;
};

// The rig's enabled cameras in light batches (GlRenderer::Render).
std::vector<Batch> LightBatches(const Rig& rig, const GlRenderOptions& options, int max_layers) {
  const int camera_count = int(rig.cameras.size());
  std::vector<Batch> batches;
  const double map_bytes = 4.0 * options.shadow_map_size * options.shadow_map_size;
  const double budget = std::max(options.map_memory_mib, 1.0) * 1024.0 * 1024.0;
  double bytes = 0;
  for (int c = 0; c < camera_count; ++c) {
    const Camera& cam = rig.cameras[c];
    if (!cam.enabled) continue;
    const bool cube = IsCube(cam);
    const double need = cube ? 1.5 * map_bytes : map_bytes;
    // A new batch when this one is full: the uniform block, the map budget, or the layers a
    // texture array may have (GL_MAX_ARRAY_TEXTURE_LAYERS, at least 256 in GL 3.3).
    if (batches.empty() || int(batches.back().cameras.size()) == kMaxBatch ||
        batches.back().cameras.front() / 64 != c / 64 ||
        (bytes + need > budget && !batches.back().cameras.empty()) ||
        (cube ? 6 * (batches.back().cube + 1) : batches.back().perspective + 1) > max_layers) {
      batches.emplace_back();
      bytes = 0;
    }
    batches.back().cameras.push_back(c);
    (cube ? batches.back().cube : batches.back().perspective) += 1;
    bytes += need;
  }
  return batches;
}

// The eye of a frame as its passes take it (GlRenderer::Render).
struct FrameEye {
  int W = 0, H = 0;                                        // the image size
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();  // world_from_camera
  double f = 0;                                            // focal length, pixels
  Vec3 rel = Vec3::Zero();                                 // relative to the scene's centre
  bool table = false;  // a camera's-eye view: its rays from the lens's table, not a pinhole
};

// (sx, sy, ox, oy) with ndc = (sx x / z - ox, sy y / z - oy) mapping `bounds` onto [-1, 1]^2.
Eigen::Vector4d MapCoefficients(const Eigen::Vector4d& b) {
  return Eigen::Vector4d(2 / (b(1) - b(0)), 2 / (b(3) - b(2)), (b(0) + b(1)) / (b(1) - b(0)),
                         (b(2) + b(3)) / (b(3) - b(2)));
}

// Camera `index` of the rig as the light shader reads it (kLightFragment's c0 .. c9); its bit is
// index % 64 of the mask of word index / 64.
void PackCamera(const Camera& cam, int index, bool cube, int layer, const Vec3& origin,
                double brightness, float* out) {
  const Intrinsics& k = cam.model.intrinsics();
  const Eigen::Isometry3d cfw = cam.camera_from_world();
  const Mat3 R = cfw.linear();
  const Vec3 t = R * (origin - cam.center());
  const double max_radius = cam.model.max_radius();
  const int lens = k.model == LensModel::kPinhole ? 0 : k.model == LensModel::kBrownConrady ? 1 : 2;
  const Eigen::Vector4d map =
      cube ? Eigen::Vector4d(1, 1, 0, 0) : MapCoefficients(cam.model.normalized_bounds());
  const Vec3 light = brightness * cam.color;
  const double v[kCameraVec4][4] = {
      {R(0, 0), R(0, 1), R(0, 2), double(lens)},
      {R(1, 0), R(1, 1), R(1, 2), double(cube ? 6 * layer : layer)},
      {R(2, 0), R(2, 1), R(2, 2), cube ? 1.0 : 0.0},
      {t.x(), t.y(), t.z(), k.k3},
      {cam.center().x() - origin.x(), cam.center().y() - origin.y(), cam.center().z() - origin.z(),
       std::isfinite(max_radius) ? max_radius : 3e38},
      {k.fx, k.fy, k.cx, k.cy},
      {k.k1, k.k2, k.model == LensModel::kFisheye ? k.k3 : k.p1,
       k.model == LensModel::kFisheye ? k.k4 : k.p2},
      {double(k.width), double(k.height), cam.near, std::isfinite(cam.far) ? cam.far : 3e38},
      {light.x(), light.y(), light.z(), double(index % 64)},  // its bit in its word
      {map(0), map(1), map(2), map(3)},
  };
  for (int i = 0; i < kCameraVec4; ++i)
    for (int j = 0; j < 4; ++j) out[4 * i + j] = float(v[i][j]);
}

}  // namespace

// ------------------------------------------------------------------------------------------

namespace {

// This thread's CPU time, seconds: what preparing the maps costs the CPU, not the wall time (which
// counts llvmpipe's and the fields' threads taking the cores meanwhile).
double ThreadCpuSeconds() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return double(t.tv_sec) + 1e-9 * double(t.tv_nsec);
}

// Inward plane normals through the apex of the pyramid of `bounds`: x - x_min z >= 0,
// x_max z - x >= 0, ...
std::array<Vec3, 4> PyramidPlanes(const Eigen::Vector4d& bounds) {
  return {Vec3(1, 0, -bounds(0)), Vec3(-1, 0, bounds(1)), Vec3(0, 1, -bounds(2)),
          Vec3(0, -1, bounds(3))};
}

// Widens [*zmin, *zmax] by the depths of triangle (a, b, c) (camera frame) clipped to `planes`.
void ClipTriangleDepth(const Vec3& a, const Vec3& b, const Vec3& c,
                       const std::array<Vec3, 4>& planes, double* zmin, double* zmax) {
  std::array<Vec3, 16> poly, next;
  int count = 3;
  poly[0] = a;
  poly[1] = b;
  poly[2] = c;
  bool all_inside = true;
  for (const Vec3& p : planes) {
    int outside = 0;
    for (int k = 0; k < 3; ++k) outside += p.dot(poly[k]) < 0;
    if (outside == 3) return;
    all_inside &= outside == 0;
  }
  if (!all_inside) {
    // Sutherland-Hodgman against the four planes.
    for (const Vec3& p : planes) {
      int out = 0;
      for (int k = 0; k < count; ++k) {
        const Vec3& u = poly[k];
        const Vec3& v = poly[(k + 1) % count];
        const double du = p.dot(u), dv = p.dot(v);
        if (du >= 0) next[out++] = u;
        if ((du >= 0) != (dv >= 0)) next[out++] = u + (du / (du - dv)) * (v - u);
      }
      count = out;
      poly = next;
      if (count == 0) return;
    }
  }
  for (int k = 0; k < count; ++k) {
    *zmin = std::min(*zmin, poly[k].z());
    *zmax = std::max(*zmax, poly[k].z());
  }
}

}  // namespace

std::pair<double, double> DepthRangeInPyramid(const TriangleMesh& mesh,
                                              const Eigen::Isometry3d& camera_from_world,
                                              const Eigen::Vector4d& bounds) {
  const std::array<Vec3, 4> planes = PyramidPlanes(bounds);
  double zmin = std::numeric_limits<double>::infinity(), zmax = -zmin;
  std::vector<Vec3> camera_vertices(mesh.vertices.size());
  for (std::size_t i = 0; i < mesh.vertices.size(); ++i)
    camera_vertices[i] = camera_from_world * mesh.vertices[i];
  for (const Eigen::Vector3i& tri : mesh.triangles)
    ClipTriangleDepth(camera_vertices[tri[0]], camera_vertices[tri[1]], camera_vertices[tri[2]],
                      planes, &zmin, &zmax);
  return {zmin, zmax};
}

TriangleBoxTree BuildTriangleBoxTree(const TriangleMesh& mesh) {
  TriangleBoxTree tree;
  const int n = int(mesh.triangles.size());
  if (n == 0) return tree;
  std::vector<Aabb> boxes(static_cast<std::size_t>(n));
  std::vector<Vec3> centres(static_cast<std::size_t>(n));
  for (int t = 0; t < n; ++t) {
    for (int k = 0; k < 3; ++k) boxes[t].Extend(mesh.vertices[mesh.triangles[t][k]]);
    centres[t] = 0.5 * (boxes[t].min + boxes[t].max);
  }
  tree.order.resize(std::size_t(n));
  for (int t = 0; t < n; ++t) tree.order[t] = t;
  tree.nodes.reserve(std::size_t(n));  // about n / 2 for leaves of 3-4
  // Median split along the longest axis of the triangles' centres, leaves of at most 4.
  struct Pending {
    int node, first, count;
  };
  std::vector<Pending> stack{{0, 0, n}};
  tree.nodes.emplace_back();
  while (!stack.empty()) {
    const Pending job = stack.back();
    stack.pop_back();
    Aabb box, spread;
    for (int i = job.first; i < job.first + job.count; ++i) {
      box.Extend(boxes[tree.order[i]]);
      spread.Extend(centres[tree.order[i]]);
    }
    tree.nodes[job.node].box = box;
    if (job.count <= 4) {
      tree.nodes[job.node].first = job.first;
      tree.nodes[job.node].count = job.count;
      continue;
    }
    int axis = 0;
    (spread.max - spread.min).maxCoeff(&axis);
    const int half = job.count / 2;
    const auto begin = tree.order.begin() + job.first;
    std::nth_element(begin, begin + half, begin + job.count,
                     [&](int a, int b) { return centres[a](axis) < centres[b](axis); });
    const int left = int(tree.nodes.size());
    tree.nodes.emplace_back();
    tree.nodes.emplace_back();
    tree.nodes[job.node].left = left;
    tree.nodes[job.node].right = left + 1;
    stack.push_back({left, job.first, half});
    stack.push_back({left + 1, job.first + half, job.count - half});
  }
  return tree;
}

std::pair<double, double> DepthRangeInPyramid(const TriangleMesh& mesh, const TriangleBoxTree& tree,
                                              const Eigen::Isometry3d& camera_from_world,
                                              const Eigen::Vector4d& bounds,
                                              std::int64_t* visited) {
  const std::array<Vec3, 4> planes = PyramidPlanes(bounds);
  double zmin = std::numeric_limits<double>::infinity(), zmax = -zmin;
  std::int64_t clipped = 0;
  if (!tree.nodes.empty()) {
    const Mat3& R = camera_from_world.linear();
    const Mat3 abs_r = R.cwiseAbs();
    std::vector<int> stack{0};
    while (!stack.empty()) {
      const TriangleBoxTree::Node& node = tree.nodes[std::size_t(stack.back())];
      stack.pop_back();
      // The node's box in the camera frame (the box around the rotated box), widened by a margin
      // far above the rounding of these few products, so that a skipped triangle's own
      // transformed vertices lie inside it.
      const Vec3 centre = camera_from_world * (0.5 * (node.box.min + node.box.max));
      const Vec3 half = abs_r * (0.5 * (node.box.max - node.box.min));
      const Vec3 pad = Vec3::Constant(1e-9 * (centre.cwiseAbs().maxCoeff() + half.maxCoeff()));
      const Vec3 lo = centre - half - pad, hi = centre + half + pad;
      bool outside = false;
      for (const Vec3& p : planes) {
        double most = 0;  // the largest p . x over the box
        for (int k = 0; k < 3; ++k) most += std::max(p(k) * lo(k), p(k) * hi(k));
        outside |= most < 0;
      }
      if (outside) continue;
      // Inside the pyramid z >= 0: the node can only give depths in [max(lo.z, 0), hi.z].
      if (std::max(lo.z(), 0.0) >= zmin && hi.z() <= zmax) continue;
      if (node.left < 0) {
        for (int i = node.first; i < node.first + node.count; ++i) {
          const Eigen::Vector3i& tri = mesh.triangles[std::size_t(tree.order[i])];
          ClipTriangleDepth(camera_from_world * mesh.vertices[tri[0]],
                            camera_from_world * mesh.vertices[tri[1]],
                            camera_from_world * mesh.vertices[tri[2]], planes, &zmin, &zmax);
          ++clipped;
        }
        continue;
      }
      stack.push_back(node.right);
      stack.push_back(node.left);
    }
  }
  if (visited) *visited = clipped;
  return {zmin, zmax};
}

struct GlRenderer::Impl {
  TriangleMesh mesh;           // world, double: the depth ranges
  TriangleBoxTree boxes;       // over mesh: each map's range from the triangles that can widen it
  double map_cpu_seconds = 0;  // this frame's depth ranges of maps
  Vec3 origin = Vec3::Zero();
  double scene_scale = 1.0;
  GLsizei vertex_count = 0;
  GLuint vao = 0, vbo = 0;
  GLuint gbuffer_program = 0, shadow_program = 0, compose_program = 0, encode_program = 0;
  GLuint resample_program = 0;
  // The layered maps pass: up to kMaxMaps maps per instanced draw, their frames in map_ubo.
  static constexpr int kMaxMaps = 64;
  GLuint maps_program = 0, map_ubo = 0;
  // The triangles' corners (relative to the scene's centre, VBO order), 3 RGBA32F texels each,
  // as a texture buffer for the camera's-eye views' ray-triangle tests; 0 where the GL's texture
  // buffers cannot hold them.
  GLuint corner_buffer = 0, corner_texture = 0;
  Aabb mesh_box;  // the triangles' bounds: the ray caster's float frame (camera's-eye t_near)

  // Camera's-eye views: the lens's rays per output pixel (camera frame, RGBA32F, w = 1 inside
  // the domain) for the lens and size of eye_dirs_key, their normalized-coordinate bounds and
  // the smallest step between neighbouring pixels' rays; and the cover G-buffer.
  // The current one's textures, bounds and step; the last kEyeTables lenses' are kept (a window
  // draws up to four camera's-eye insets every frame).
  GLuint eye_dirs = 0, eye_dx = 0, eye_dy = 0;  // with the rays' derivatives per output pixel
  Eigen::Vector4d eye_dirs_bounds = Eigen::Vector4d::Zero();
  double eye_dirs_step = 0;
  struct EyeTable {
    std::string key;
    GLuint textures[3] = {0, 0, 0};  // directions, d/dx, d/dy
    Eigen::Vector4d bounds = Eigen::Vector4d::Zero();
    double step = 0;
  };
  static constexpr std::size_t kEyeTables = 8;
  std::list<EyeTable> eye_tables;  // most recently used first
  int cover_w = 0, cover_h = 0;
  GLuint cover_fbo = 0, cover_position = 0, cover_normal = 0, cover_albedo = 0, cover_depth = 0;
  struct Cover {
    GLuint fbo = 0, textures[3] = {0, 0, 0}, depth = 0;
  };
  static constexpr std::size_t kCovers = 4;
  std::list<std::pair<std::pair<int, int>, Cover>> covers;  // most recently used first, current too
  static void FreeCover(const Cover& c) {
    glDeleteTextures(3, c.textures);
    glDeleteRenderbuffers(1, &c.depth);
    glDeleteFramebuffers(1, &c.fbo);
  }
  double last_cover_scale = 0;           // cover texels per output pixel at the finest, last frame
  std::map<int, GLuint> light_programs;  // by variant bits: 1 grid, 2 fisheye, 4 distortion, 8 cube

  GLuint LightProgram(int variant) {
    auto it = light_programs.find(variant);
    if (it != light_programs.end()) return it->second;
    std::string source = WithLightRule(kLightFragment);
    const std::string defines = "#define GRID " + std::to_string(variant & 1) +
                                "\n#define FISHEYE " + std::to_string((variant >> 1) & 1) +
                                "\n#define DISTORTION " + std::to_string((variant >> 2) & 1) +
                                "\n#define CUBE " + std::to_string((variant >> 3) & 1) + "\n";
    source.insert(source.find('\n') + 1, defines);  // after #version
    const GLuint program = Link(kFullScreenVertex, source.c_str(), "light");
    glUniformBlockBinding(program, glGetUniformBlockIndex(program, "CameraBlock"), 0);
    light_programs[variant] = program;
    return program;
  }
  GLuint empty_vao = 0, camera_ubo = 0;
  // Triangles are uploaded grouped by texture: draw g covers vertices [first, first + count) with
  // texture texture_ids[g] (0: none).
  struct Draw {
    GLint first = 0;
    GLsizei count = 0;
    GLuint texture = 0;
  };
  std::vector<Draw> draws;
  std::vector<GLuint> texture_ids;

  // Per view size.
  int width = 0, height = 0;
  GLuint g_fbo = 0, g_position = 0, g_normal = 0, g_albedo = 0, g_depth = 0;
  GLuint light_fbo[2] = {0, 0}, light_accum = 0, mask[2] = {0, 0};
  GLuint compose_fbo = 0, compose_color = 0;
  GLuint encode_fbo = 0, encoded = 0;  // the composed frame as 8-bit sRGB (DrawToTexture)

  // Distance maps: perspective maps (one layer per camera) and cubes (six layers per camera),
  // with the camera each layer group was last drawn for (reused while it stays the same).
  int map_size = 0, cube_size = 0;
  int map_layers = 0, cube_layers = 0;
  GLuint shadow_fbo = 0, maps = 0, cubes = 0, map_depth = 0, cube_depth = 0;
  std::vector<std::optional<Camera>> map_camera, cube_camera;

  // The targets of one view size. A window draws its main view and camera's-eye insets of other
  // sizes every frame: the last kParkedSizes sizes' targets are kept (parked), so switching
  // between them allocates nothing, and each size's DrawToTexture texture stays valid while its
  // size is among them.
  struct ViewTargets {
    GLuint fbo[5], texture[8], depth;
  };
  static constexpr std::size_t kParkedSizes = 6;
  std::list<std::pair<std::pair<int, int>, ViewTargets>> parked;  // most recently used first

  ViewTargets CurrentTargets() const {
    return {{g_fbo, light_fbo[0], light_fbo[1], compose_fbo, encode_fbo},
            {g_position, g_normal, g_albedo, light_accum, mask[0], mask[1], compose_color, encoded},
            g_depth};
  }
  void UseTargets(const ViewTargets& t) {
    g_fbo = t.fbo[0], light_fbo[0] = t.fbo[1], light_fbo[1] = t.fbo[2], compose_fbo = t.fbo[3];
    encode_fbo = t.fbo[4];
    g_position = t.texture[0], g_normal = t.texture[1], g_albedo = t.texture[2];
    light_accum = t.texture[3], mask[0] = t.texture[4], mask[1] = t.texture[5];
    compose_color = t.texture[6], encoded = t.texture[7];
    g_depth = t.depth;
  }
  static void FreeTargets(const ViewTargets& t) {
    glDeleteTextures(8, t.texture);
    glDeleteRenderbuffers(1, &t.depth);
    glDeleteFramebuffers(5, t.fbo);
  }

  void EnsureViewTargets(int w, int h) {
    if (w == width && h == height) return;
    if (width > 0) parked.push_front({{width, height}, CurrentTargets()});
    width = height = 0;
    const auto it = std::find_if(parked.begin(), parked.end(), [&](const auto& p) {
      return p.first == std::pair{w, h};
    });
    if (it != parked.end()) {
      UseTargets(it->second);
      parked.erase(it);
      width = w;
      height = h;
    } else {
      AllocateViewTargets(w, h);
    }
    while (parked.size() > kParkedSizes) {
      FreeTargets(parked.back().second);
      parked.pop_back();
    }
  }

  void AllocateViewTargets(int w, int h) {
    width = w;
    height = h;
    GLuint g[3];
    MakeGBuffer(w, h, "G-buffer", &g_fbo, g, &g_depth);
    g_position = g[0], g_normal = g[1], g_albedo = g[2];

    light_accum = MakeTexture(GL_RGBA32F, w, h, GL_RGBA, GL_FLOAT);
    for (int k = 0; k < 2; ++k) {
      mask[k] = MakeTexture(GL_RG32UI, w, h, GL_RG_INTEGER, GL_UNSIGNED_INT);
      glGenFramebuffers(1, &light_fbo[k]);
      glBindFramebuffer(GL_FRAMEBUFFER, light_fbo[k]);
      glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, light_accum, 0);
      glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT1, GL_TEXTURE_2D, mask[k], 0);
      CheckFramebuffer("light");
    }
    compose_color = MakeTexture(GL_RGBA32F, w, h, GL_RGBA, GL_FLOAT);
    glGenFramebuffers(1, &compose_fbo);
    glBindFramebuffer(GL_FRAMEBUFFER, compose_fbo);
    glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, compose_color, 0);
    CheckFramebuffer("compose");
    encoded = MakeTexture(GL_RGBA8, w, h, GL_RGBA, GL_UNSIGNED_BYTE);
    glBindTexture(GL_TEXTURE_2D, encoded);  // shown scaled in the window
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
    glGenFramebuffers(1, &encode_fbo);
    glBindFramebuffer(GL_FRAMEBUFFER, encode_fbo);
    glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, encoded, 0);
    CheckFramebuffer("encode");
  }

  static GLuint MapArray(int size, int layers) {
    GLuint tex = 0;
    glGenTextures(1, &tex);
    glBindTexture(GL_TEXTURE_2D_ARRAY, tex);
    glTexImage3D(GL_TEXTURE_2D_ARRAY, 0, GL_R32F, size, size, layers, 0, GL_RED, GL_FLOAT, nullptr);
    glTexParameteri(GL_TEXTURE_2D_ARRAY, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
    glTexParameteri(GL_TEXTURE_2D_ARRAY, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
    glTexParameteri(GL_TEXTURE_2D_ARRAY, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
    glTexParameteri(GL_TEXTURE_2D_ARRAY, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
    return tex;
  }
  static GLuint DepthBuffer(int size) {
    GLuint rb = 0;
    glGenRenderbuffers(1, &rb);
    glBindRenderbuffer(GL_RENDERBUFFER, rb);
    glRenderbufferStorage(GL_RENDERBUFFER, GL_DEPTH_COMPONENT32F, size, size);
    return rb;
  }

  // At least `perspective` map layers and `cube` cubes of map size `size`; (re)allocating forgets
  // what the layers held.
  void EnsureMaps(int size, int perspective, int cube) {
    if (size != map_size) {
      glDeleteTextures(1, &maps);
      glDeleteTextures(1, &cubes);
      glDeleteRenderbuffers(1, &map_depth);
      glDeleteRenderbuffers(1, &cube_depth);
      maps = cubes = map_depth = cube_depth = 0;
      map_layers = cube_layers = 0;
      map_camera.clear();
      cube_camera.clear();
      map_size = size;
      cube_size = size / 2;
      map_depth = DepthBuffer(map_size);
      cube_depth = DepthBuffer(cube_size);
    }
    // Texture arrays need at least one layer to be complete, also when no camera uses them.
    perspective = std::max(perspective, 1);
    cube = std::max(cube, 1);
    if (perspective > map_layers) {
      glDeleteTextures(1, &maps);
      maps = MapArray(map_size, perspective);
      map_layers = perspective;
      map_camera.assign(perspective, std::nullopt);
    }
    if (6 * cube > cube_layers) {
      glDeleteTextures(1, &cubes);
      cubes = MapArray(cube_size, 6 * cube);
      cube_layers = 6 * cube;
      cube_camera.assign(cube, std::nullopt);
    }
    if (!shadow_fbo) glGenFramebuffers(1, &shadow_fbo);
  }

  ~Impl() {
    if (width > 0) FreeTargets(CurrentTargets());
    for (const auto& p : parked) FreeTargets(p.second);
    for (const EyeTable& t : eye_tables) glDeleteTextures(3, t.textures);
    for (const auto& c : covers) FreeCover(c.second);
    glDeleteTextures(1, &corner_texture);
    glDeleteBuffers(1, &corner_buffer);
    glDeleteTextures(1, &maps);
    glDeleteTextures(1, &cubes);
    glDeleteRenderbuffers(1, &map_depth);
    glDeleteRenderbuffers(1, &cube_depth);
    glDeleteFramebuffers(1, &shadow_fbo);
    glDeleteBuffers(1, &vbo);
    glDeleteBuffers(1, &camera_ubo);
    if (!texture_ids.empty()) glDeleteTextures(GLsizei(texture_ids.size()), texture_ids.data());
    glDeleteVertexArrays(1, &vao);
    glDeleteVertexArrays(1, &empty_vao);
    for (GLuint p : {gbuffer_program, shadow_program, compose_program, encode_program,
                     resample_program, maps_program})
      glDeleteProgram(p);
    glDeleteBuffers(1, &map_ubo);
    for (const auto& [variant, program] : light_programs) glDeleteProgram(program);
  }

  // Draws camera `cam`'s distance map(s): one perspective map into layer `layer` of `maps`, or a
  // cube into layers 6 layer .. 6 layer + 5 of `cubes`. Returns the maps drawn.
  int DrawMaps(const Camera& cam, bool cube, int layer) {
    const Eigen::Isometry3d cfw = cam.camera_from_world();
    static const std::array<Mat3, 6> kCube = CubeFaces();
    const int faces = cube ? 6 : 1;
    const int size = cube ? cube_size : map_size;
    glBindFramebuffer(GL_FRAMEBUFFER, shadow_fbo);
    glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER,
                              cube ? cube_depth : map_depth);
    glViewport(0, 0, size, size);
    glUseProgram(shadow_program);
    glBindVertexArray(vao);
    glEnable(GL_DEPTH_TEST);
    glDepthFunc(GL_LESS);
    glDisable(GL_BLEND);
    const GLenum buffer0 = GL_COLOR_ATTACHMENT0;
    glDrawBuffers(1, &buffer0);
    int drawn = 0;
    for (int i = 0; i < faces; ++i) {
      const Mat3 face_from_camera = cube ? kCube[i] : Mat3::Identity();
      const Eigen::Vector4d bounds =
          cube ? Eigen::Vector4d(-1, 1, -1, 1) : cam.model.normalized_bounds();
      glFramebufferTextureLayer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, cube ? cubes : maps, 0,
                                cube ? 6 * layer + i : layer);
      CheckFramebuffer("distance map");
      const float cleared[4] = {3e38f, 0, 0, 0};
      glClearBufferfv(GL_COLOR, 0, cleared);
      // A cube face whose pyramid (54.7 degrees around its axis) the field cannot reach stays
      // cleared.
      if (cube && FaceOutOfField(cam, i)) continue;
      Eigen::Isometry3d face_from_world = Eigen::Isometry3d::Identity();
      face_from_world.linear() = face_from_camera * cfw.linear();
      face_from_world.translation() = face_from_camera * cfw.translation();
      const double prepare = ThreadCpuSeconds();
      auto range = DepthRangeInPyramid(mesh, boxes, face_from_world, bounds);
      map_cpu_seconds += ThreadCpuSeconds() - prepare;
      range.second = std::min(range.second, cam.far);  // occluders lie nearer than the point
      if (!(range.first <= range.second)) continue;
      const auto [near, far] = PadRange(range);
      const Eigen::Vector2d ab = DepthCoefficients(near, far);
      glClear(GL_DEPTH_BUFFER_BIT);
      SetMat3(shadow_program, "face_R", face_from_world.linear());
      SetVec3(shadow_program, "face_t", face_from_world * origin);
      const Eigen::Vector4d m = MapCoefficients(bounds);
      glUniform4f(Loc(shadow_program, "map"), float(m(0)), float(m(1)), float(m(2)), float(m(3)));
      glUniform2f(Loc(shadow_program, "depth"), float(ab(0)), float(ab(1)));
      glDrawArrays(GL_TRIANGLES, 0, vertex_count);
      ++drawn;
    }
    return drawn;
  }

  // The G-buffer pass: surface point, normal and albedo of every pixel seen from the eye.
  void DrawGBuffer(const RenderView& view, const FrameEye& eye, const GlRenderOptions& options) {
    const int W = eye.W, H = eye.H;
    const double f = eye.f;
    const Mat3 eye_R = eye.pose.linear().transpose();  // camera_from_world
    const Eigen::Isometry3d cfw = eye.pose.inverse();
    const Eigen::Vector4d bounds(-0.5 * W / f, 0.5 * W / f, -0.5 * H / f, 0.5 * H / f);
    auto range = DepthRangeInPyramid(mesh, boxes, cfw, bounds);
    if (!(range.first <= range.second)) range = {1.0, 2.0};  // nothing in view: any range
    // The depth range spans the content in view (an eye 500 scene sizes away: far / near ~ 1.002).
    // Depths are taken relative to the near plane in the shaders and the depth test's value is
    // linear in them, so its resolution is (far - near) / 2^24 however far the eye stands. The
    // cut (RenderView::clip_near, a plan's) is a discard at that depth, as the CPU starts its rays
    // on the cut plane.
    const auto [near, far] = PadRange(range);
    const double cut_rel = view.clip_near > 0 ? view.clip_near - near : -1.0;
    const Eigen::Vector2d ab = DepthCoefficients(near, far);
    glBindFramebuffer(GL_FRAMEBUFFER, g_fbo);
    const GLenum buffers[3] = {GL_COLOR_ATTACHMENT0, GL_COLOR_ATTACHMENT1, GL_COLOR_ATTACHMENT2};
    glDrawBuffers(3, buffers);
    glViewport(0, 0, W, H);
    const float no_hit[4] = {0, 0, 0, -1}, zero[4] = {0, 0, 0, 0};
    glClearBufferfv(GL_COLOR, 0, no_hit);
    glClearBufferfv(GL_COLOR, 1, zero);
    glClearBufferfv(GL_COLOR, 2, zero);
    glClear(GL_DEPTH_BUFFER_BIT);
    glEnable(GL_DEPTH_TEST);
    glDepthFunc(GL_LESS);
    glDisable(GL_BLEND);
    glDisable(GL_CULL_FACE);
    glUseProgram(gbuffer_program);
    SetMat3(gbuffer_program, "view_R", eye_R);
    SetVec3(gbuffer_program, "view_t", eye_R * (origin - view.from) - Vec3(0, 0, near));
    glUniform1f(Loc(gbuffer_program, "view_d0"), float(near));
    glUniform4f(Loc(gbuffer_program, "proj"), float(2 * f / W), float(2 * f / H), float(ab(0)),
                float(ab(0) * near + ab(1)));
    glUniform2f(Loc(gbuffer_program, "depth_map"), float(cut_rel), float(1.0 / (far - near)));
    glUniform2f(Loc(gbuffer_program, "proj_offset"), 0.0f, 0.0f);  // the cover's, reset
    glUniform1f(Loc(gbuffer_program, "min_distance"), 0.0f);
    SetVec3(gbuffer_program, "eye", eye.rel);
    glUniform1i(Loc(gbuffer_program, "edges"), options.surface == Surface::kHiddenLine ? 1 : 0);
    glUniform1f(Loc(gbuffer_program, "line_width"), float(options.line_width_px));
    glUniform1i(Loc(gbuffer_program, "albedo_tex"), 0);
    glActiveTexture(GL_TEXTURE0);
    glBindVertexArray(vao);
    for (const Draw& d : draws) {
      glUniform1i(Loc(gbuffer_program, "textured"),
                  d.texture != 0 && options.surface == Surface::kMaterial ? 1 : 0);
      glUniform1i(Loc(gbuffer_program, "first_triangle"), d.first / 3);
      glBindTexture(GL_TEXTURE_2D, d.texture);
      glDrawArrays(GL_TRIANGLES, d.first, d.count);
    }
  }

  // The rays of camera `cam`'s image scaled to W x H (RenderView::camera), unprojected as the CPU's
  // ViewRays does (the same pixel mapping, CameraModel::Unproject and exact differentials
  // J^T (J J^T)^-1 per output pixel, rounded to float), into eye_dirs, eye_dx and eye_dy; with
  // their bounds in normalized coordinates and the smallest step between neighbouring pixels'
  // rays. Computed (in parallel) and uploaded only when the lens or the size
  // changes: the rays are in the camera's frame, so a camera that moves keeps them.
  void EnsureEyeTable(const Camera& cam, int W, int H) {
    const Intrinsics& k = cam.model.intrinsics();
    char key[400];
    std::snprintf(key, sizeof key,
                  "%d %d %d %d %d %.17g %.17g %.17g %.17g %.17g %.17g %.17g %.17g %.17g %.17g",
                  int(k.model), k.width, k.height, W, H, k.fx, k.fy, k.cx, k.cy, k.k1, k.k2, k.p1,
                  k.p2, k.k3, k.k4);
    const auto kept = std::find_if(eye_tables.begin(), eye_tables.end(),
                                   [&](const EyeTable& t) { return t.key == key; });
    if (kept != eye_tables.end()) {
      eye_tables.splice(eye_tables.begin(), eye_tables, kept);
    } else {
      eye_tables.push_front(ComputeEyeTable(cam, W, H, key));
      while (eye_tables.size() > kEyeTables) {
        glDeleteTextures(3, eye_tables.back().textures);
        eye_tables.pop_back();
      }
    }
    const EyeTable& t = eye_tables.front();
    eye_dirs = t.textures[0];
    eye_dx = t.textures[1];
    eye_dy = t.textures[2];
    eye_dirs_bounds = t.bounds;
    eye_dirs_step = t.step;
  }

  static EyeTable ComputeEyeTable(const Camera& cam, int W, int H, const std::string& key) {
    const double sx = double(cam.model.width()) / W, sy = double(cam.model.height()) / H;
    const std::size_t n = std::size_t(W) * std::size_t(H);
    std::vector<float> texels(4 * n, 0.0f), dx(4 * n, 0.0f), dy(4 * n, 0.0f);
    std::vector<Vec2> q(n, Vec2::Constant(std::numeric_limits<double>::quiet_NaN()));
    tbb::parallel_for(0, H, [&](int y) {
      for (int x = 0; x < W; ++x) {
        const auto dir = cam.model.Unproject(Vec2((x + 0.5) * sx - 0.5, (y + 0.5) * sy - 0.5));
        Mat23 J;
        if (!dir || !cam.model.Project(*dir, &J)) continue;
        const Eigen::Matrix2d JJt = J * J.transpose();
        if (!(std::abs(JJt.determinant()) > 0)) continue;  // as the CPU: no ray
        const Eigen::Matrix<double, 3, 2> M = J.transpose() * JJt.inverse();
        const std::size_t i = std::size_t(y) * W + std::size_t(x);
        for (int c = 0; c < 3; ++c) {
          texels[4 * i + std::size_t(c)] = float((*dir)(c));
          dx[4 * i + std::size_t(c)] = float(M(c, 0) * sx);
          dy[4 * i + std::size_t(c)] = float(M(c, 1) * sy);
        }
        texels[4 * i + 3] = 1.0f;
        if (dir->z() > 1e-9) q[i] = dir->head<2>() / dir->z();
      }
    });
    Eigen::Vector4d bounds(1e300, -1e300, 1e300, -1e300);
    double step = 1e300;
    for (int y = 0; y < H; ++y)
      for (int x = 0; x < W; ++x) {
        const Vec2& a = q[std::size_t(y) * W + std::size_t(x)];
        if (!a.allFinite()) continue;
        bounds = Eigen::Vector4d(std::min(bounds(0), a.x()), std::max(bounds(1), a.x()),
                                 std::min(bounds(2), a.y()), std::max(bounds(3), a.y()));
        if (x + 1 < W && q[std::size_t(y) * W + std::size_t(x) + 1].allFinite())
          step = std::min(step, (q[std::size_t(y) * W + std::size_t(x) + 1] - a).norm());
        if (y + 1 < H && q[std::size_t(y + 1) * W + std::size_t(x)].allFinite())
          step = std::min(step, (q[std::size_t(y + 1) * W + std::size_t(x)] - a).norm());
      }
    EyeTable table;
    table.key = key;
    table.bounds = bounds;
    table.step = step;
    const std::vector<float>* data[3] = {&texels, &dx, &dy};
    for (int i = 0; i < 3; ++i) {
      table.textures[i] = MakeTexture(GL_RGBA32F, W, H, GL_RGBA, GL_FLOAT);
      glPixelStorei(GL_UNPACK_ALIGNMENT, 4);
      glTexImage2D(GL_TEXTURE_2D, 0, GL_RGBA32F, W, H, 0, GL_RGBA, GL_FLOAT, data[i]->data());
    }
    return table;
  }

  // The cover G-buffer's targets at w x h (the last kCovers sizes' kept).
  void EnsureCover(int w, int h) {
    if (w == cover_w && h == cover_h) return;
    cover_w = w;
    cover_h = h;
    const auto kept = std::find_if(covers.begin(), covers.end(), [&](const auto& c) {
      return c.first == std::pair{w, h};
    });
    if (kept != covers.end()) {
      covers.splice(covers.begin(), covers, kept);
    } else {
      Cover c;
      MakeGBuffer(w, h, "camera's-eye cover", &c.fbo, c.textures, &c.depth);
      covers.push_front({{w, h}, c});
      while (covers.size() > kCovers) {
        FreeCover(covers.back().second);
        covers.pop_back();
      }
    }
    const Cover& c = covers.front().second;
    cover_fbo = c.fbo;
    cover_position = c.textures[0], cover_normal = c.textures[1], cover_albedo = c.textures[2];
    cover_depth = c.depth;
  }

  // A camera's-eye view's G-buffer (view.camera): the camera's pinhole G-buffer over its lens's
  // whole field at kCoverScale times the output's finest ray spacing (the cover), then per output
  // pixel the lens's own ray resampled from it (shaders/resample.frag). Primary rays start where
  // the CPU's do, VisibilityTester::Tolerance(camera, 0) from the centre (a camera on a wall's
  // face does not see the wall), here from the triangles' bounds as the ray caster's frame.
  void DrawCameraGBuffer(const Camera& cam, const FrameEye& eye, const GlRenderOptions& options) {
    const int W = eye.W, H = eye.H;
    EnsureEyeTable(cam, W, H);
    Eigen::Vector4d b = eye_dirs_bounds;
    const bool empty =
        !(b(0) <= b(1) && b(2) <= b(3)) || !(eye_dirs_step > 0) || !std::isfinite(eye_dirs_step);
    if (empty) b = Eigen::Vector4d(-1, 1, -1, 1);
    GLint max_size = 0;
    glGetIntegerv(GL_MAX_TEXTURE_SIZE, &max_size);
    // Cover texels per unit of normalized coordinates: kCoverScale per output step at the finest,
    // within the GL's texture size and kMaxCoverTexels.
    double density = empty ? 1.0 : kCoverScale / eye_dirs_step;
    const double span_x = b(1) - b(0), span_y = b(3) - b(2);
    density = std::min({density, (max_size - 2) / std::max(span_x, 1e-12),
                        (max_size - 2) / std::max(span_y, 1e-12),
                        std::sqrt(kMaxCoverTexels / std::max(span_x * span_y, 1e-24))});
    const int cw = std::max(2, int(std::ceil(density * span_x)) + 2);
    const int ch = std::max(2, int(std::ceil(density * span_y)) + 2);
    last_cover_scale = empty ? 0.0 : density * eye_dirs_step;
    // One texel of margin on each side.
    b += Eigen::Vector4d(-1.0 / density, 1.0 / density, -1.0 / density, 1.0 / density);
    EnsureCover(cw, ch);

    const Eigen::Isometry3d cfw = cam.camera_from_world();
    auto range = DepthRangeInPyramid(mesh, boxes, cfw, b);
    if (!(range.first <= range.second)) range = {1.0, 2.0};
    const auto [near, far] = PadRange(range);
    const Eigen::Vector2d ab = DepthCoefficients(near, far);
    const Eigen::Vector4d m = MapCoefficients(b);
    const Mat3 R = cfw.linear();
    const double t_near = std::max(
        1e-5 * scene_scale,
        4.0 * 0x1p-24 * (0.5 * mesh_box.diagonal() + (cam.center() - mesh_box.center()).norm()));

    glBindFramebuffer(GL_FRAMEBUFFER, cover_fbo);
    const GLenum buffers[3] = {GL_COLOR_ATTACHMENT0, GL_COLOR_ATTACHMENT1, GL_COLOR_ATTACHMENT2};
    glDrawBuffers(3, buffers);
    glViewport(0, 0, cw, ch);
    const float no_hit[4] = {0, 0, 0, -1}, zero[4] = {0, 0, 0, 0};
    glClearBufferfv(GL_COLOR, 0, no_hit);
    glClearBufferfv(GL_COLOR, 1, zero);
    glClearBufferfv(GL_COLOR, 2, zero);
    glClear(GL_DEPTH_BUFFER_BIT);
    glEnable(GL_DEPTH_TEST);
    glDepthFunc(GL_LESS);
    glDisable(GL_BLEND);
    glDisable(GL_CULL_FACE);
    const GLuint p = gbuffer_program;
    glUseProgram(p);
    SetMat3(p, "view_R", R);
    SetVec3(p, "view_t", R * (origin - cam.center()) - Vec3(0, 0, near));
    glUniform1f(Loc(p, "view_d0"), float(near));
    glUniform4f(Loc(p, "proj"), float(m(0)), float(m(1)), float(ab(0)),
                float(ab(0) * near + ab(1)));
    glUniform2f(Loc(p, "proj_offset"), float(m(2)), float(m(3)));
    glUniform2f(Loc(p, "depth_map"), -1.0f, float(1.0 / (far - near)));
    glUniform1f(Loc(p, "min_distance"), float(t_near));
    SetVec3(p, "eye", eye.rel);
    glUniform1i(Loc(p, "edges"), options.surface == Surface::kHiddenLine ? 1 : 0);
    // Lines are drawn in cover texels: kCoverScale (at the finest) per output pixel.
    glUniform1f(Loc(p, "line_width"),
                float(options.line_width_px * std::max(1.0, last_cover_scale)));
    glUniform1i(Loc(p, "albedo_tex"), 0);
    glActiveTexture(GL_TEXTURE0);
    glBindVertexArray(vao);
    for (const Draw& d : draws) {
      glUniform1i(Loc(p, "textured"),
                  d.texture != 0 && options.surface == Surface::kMaterial ? 1 : 0);
      glUniform1i(Loc(p, "first_triangle"), d.first / 3);
      glBindTexture(GL_TEXTURE_2D, d.texture);
      glDrawArrays(GL_TRIANGLES, d.first, d.count);
    }

    // Resample into the output's G-buffer.
    glBindFramebuffer(GL_FRAMEBUFFER, g_fbo);
    glDrawBuffers(3, buffers);
    glViewport(0, 0, W, H);
    glDisable(GL_DEPTH_TEST);
    const GLuint r = resample_program;
    glUseProgram(r);
    const GLuint inputs[4] = {eye_dirs, cover_position, cover_normal, cover_albedo};
    const char* names[4] = {"eye_dirs", "cover_position", "cover_normal", "cover_albedo"};
    for (int i = 0; i < 4; ++i) {
      glActiveTexture(GLenum(GL_TEXTURE0 + i));
      glBindTexture(GL_TEXTURE_2D, inputs[i]);
      glUniform1i(Loc(r, names[i]), i);
    }
    glActiveTexture(GL_TEXTURE4);
    glBindTexture(GL_TEXTURE_BUFFER, corner_texture);
    glUniform1i(Loc(r, "triangles"), 4);
    glUniform1i(Loc(r, "use_triangles"), corner_texture != 0 ? 1 : 0);
    glUniform1f(Loc(r, "min_distance"), float(t_near));
    glUniform4f(Loc(r, "cover_map"), float(m(0)), float(m(1)), float(m(2)), float(m(3)));
    glUniform2i(Loc(r, "cover_size"), cw, ch);
    SetMat3(r, "eye_R", cam.world_from_camera.linear());
    SetVec3(r, "eye", eye.rel);
    glBindVertexArray(empty_vao);
    glDrawArrays(GL_TRIANGLES, 0, 3);
    glActiveTexture(GL_TEXTURE0);
  }

  // One distance map of a layered pass: its frame, its pyramid's bounds and its layer.
  struct MapInstance {
    Eigen::Isometry3d face_from_world;
    Eigen::Vector4d bounds;
    int layer = 0;
  };

  // The layered pass's part of camera `cam` (GlRenderOptions::one_pass_maps): its map, or its cube
  // faces, as instances, and the layers to clear (a cube's faces its field cannot reach, 54.7
  // degrees around their axes, stay cleared).
  struct LayeredMaps {
    std::vector<MapInstance> flat, faces;
    std::vector<int> clear_flat, clear_faces;
  };
  static void AddLayered(const Camera& cam, bool cube, int layer, LayeredMaps* out) {
    static const std::array<Mat3, 6> kCube = CubeFaces();
    const Eigen::Isometry3d cfw = cam.camera_from_world();
    if (!cube) {
      out->clear_flat.push_back(layer);
      out->flat.push_back({cfw, cam.model.normalized_bounds(), layer});
      return;
    }
    for (int f = 0; f < 6; ++f) {
      out->clear_faces.push_back(6 * layer + f);
      if (FaceOutOfField(cam, f)) continue;
      Eigen::Isometry3d face_from_world = Eigen::Isometry3d::Identity();
      face_from_world.linear() = kCube[f] * cfw.linear();
      face_from_world.translation() = kCube[f] * cfw.translation();
      out->faces.push_back({face_from_world, Eigen::Vector4d(-1, 1, -1, 1), 6 * layer + f});
    }
  }

  // Clears the layers `clear` of `array` (size x size) and draws `maps_to_draw` into their layers
  // in instanced draws of kMaxMaps, keeping the nearest distance by MIN blending.
  void DrawLayered(GLuint array, int size, const std::vector<int>& clear,
                   const std::vector<MapInstance>& maps_to_draw) {
    if (clear.empty()) return;
    glBindFramebuffer(GL_FRAMEBUFFER, shadow_fbo);
    glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, 0);
    const GLenum buffer0 = GL_COLOR_ATTACHMENT0;
    glDrawBuffers(1, &buffer0);
    const float cleared[4] = {3e38f, 0, 0, 0};
    for (int l : clear) {
      glFramebufferTextureLayer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, array, 0, l);
      glClearBufferfv(GL_COLOR, 0, cleared);
    }
    if (maps_to_draw.empty()) return;
    glFramebufferTexture(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, array, 0);
    CheckFramebuffer("distance maps (layered)");
    glViewport(0, 0, size, size);
    glDisable(GL_DEPTH_TEST);
    glEnable(GL_BLEND);
    glBlendEquation(GL_MIN);
    glBlendFunc(GL_ONE, GL_ONE);
    glUseProgram(maps_program);
    glBindVertexArray(vao);
    // What lies nearer the map's plane than the CPU's smallest occlusion tolerance is clipped.
    const double near = 1e-5 * scene_scale;
    std::vector<float> block(std::size_t(20 * kMaxMaps), 0.0f);
    for (std::size_t first = 0; first < maps_to_draw.size(); first += kMaxMaps) {
      const std::size_t n = std::min<std::size_t>(kMaxMaps, maps_to_draw.size() - first);
      for (std::size_t k = 0; k < n; ++k) {
        const MapInstance& m = maps_to_draw[first + k];
        const Mat3 R = m.face_from_world.linear();
        const Vec3 t = m.face_from_world * origin;
        const Eigen::Vector4d c = MapCoefficients(m.bounds);
        float* out = &block[20 * k];
        for (int r = 0; r < 3; ++r) {
          for (int j = 0; j < 3; ++j) out[4 * r + j] = float(R(r, j));
          out[4 * r + 3] = float(t(r));
        }
        for (int j = 0; j < 4; ++j) out[12 + j] = float(c(j));
        out[16] = float(m.layer);
        out[17] = float(near);
      }
      glBindBuffer(GL_UNIFORM_BUFFER, map_ubo);
      glBufferSubData(GL_UNIFORM_BUFFER, 0, GLsizeiptr(20 * n * sizeof(float)), block.data());
      glBindBufferBase(GL_UNIFORM_BUFFER, 1, map_ubo);
      glDrawArraysInstanced(GL_TRIANGLES, 0, vertex_count, GLsizei(n));
    }
    glBlendEquation(GL_FUNC_ADD);
    glDisable(GL_BLEND);
  }

  // Draws the distance maps of a batch's cameras not kept from the last frame (in one layered
  // pass with GlRenderOptions::one_pass_maps, else one draw per map) and sets each
  // camera's layer. Returns the maps drawn.
  int DrawBatchMaps(const Rig& rig, const Batch& batch, bool keep, const GlRenderOptions& options,
                    std::vector<int>& layer) {
    int maps_drawn = 0;
    int next_map = 0, next_cube = 0;
    LayeredMaps layered;  // one_pass_maps: every map drawn after the loop, in one pass
    for (std::size_t i = 0; i < batch.cameras.size(); ++i) {
      const Camera& cam = rig.cameras[batch.cameras[i]];
      const bool cube = IsCube(cam);
      layer[i] = cube ? next_cube++ : next_map++;
      std::optional<Camera>& held = cube ? cube_camera[layer[i]] : map_camera[layer[i]];
      if (held && SameCameraGeometry(*held, cam)) continue;
      if (options.one_pass_maps)
        AddLayered(cam, cube, layer[i], &layered);
      else
        maps_drawn += DrawMaps(cam, cube, layer[i]);
      if (keep && options.reuse_maps)
        held = cam;
      else
        held.reset();
    }
    if (options.one_pass_maps) {
      DrawLayered(maps, map_size, layered.clear_flat, layered.flat);
      DrawLayered(cubes, cube_size, layered.clear_faces, layered.faces);
      maps_drawn = int(layered.flat.size() + layered.faces.size());
    }
    return maps_drawn;
  }

  // A batch's light pass over the G-buffer: adds its cameras' light into the accumulation target
  // and their bits from mask `src` into the other mask. Returns that mask.
  int DrawBatchLight(const Rig& rig, const Batch& batch, const std::vector<int>& layer,
                     const FrameEye& eye, const GlRenderOptions& options, double brightness,
                     int src, std::vector<float>& block) {
    const double lift = 0.1 * 1e-5 * scene_scale;  // as the CPU renderer: a tenth of epsilon
    for (std::size_t i = 0; i < batch.cameras.size(); ++i) {
      const int c = batch.cameras[i];
      PackCamera(rig.cameras[c], c, IsCube(rig.cameras[c]), layer[i], origin, brightness,
                 &block[4 * kCameraVec4 * i]);
    }
    glBindBuffer(GL_UNIFORM_BUFFER, camera_ubo);
    glBufferSubData(GL_UNIFORM_BUFFER, 0,
                    GLsizeiptr(4 * kCameraVec4 * batch.cameras.size() * sizeof(float)),
                    block.data());
    glBindBufferBase(GL_UNIFORM_BUFFER, 0, camera_ubo);
    const int dst = 1 - src;
    glBindFramebuffer(GL_FRAMEBUFFER, light_fbo[dst]);
    const GLenum buffers[2] = {GL_COLOR_ATTACHMENT0, GL_COLOR_ATTACHMENT1};
    glDrawBuffers(2, buffers);
    glViewport(0, 0, eye.W, eye.H);
    glDisable(GL_DEPTH_TEST);
    glEnablei(GL_BLEND, 0);
    glDisablei(GL_BLEND, 1);  // integer: the shader ORs the previous mask in
    glBlendEquation(GL_FUNC_ADD);
    glBlendFunc(GL_ONE, GL_ONE);
    int variant = options.pattern == Pattern::kGrid ? 1 : 0;
    for (int c : batch.cameras) {
      const LensModel lens = rig.cameras[c].model.intrinsics().model;
      variant |= lens == LensModel::kFisheye ? 2 : lens == LensModel::kBrownConrady ? 4 : 0;
      variant |= IsCube(rig.cameras[c]) ? 8 : 0;
    }
    const GLuint p = LightProgram(variant);
    glUseProgram(p);
    glActiveTexture(GL_TEXTURE0);
    glBindTexture(GL_TEXTURE_2D, g_position);
    glActiveTexture(GL_TEXTURE1);
    glBindTexture(GL_TEXTURE_2D, g_normal);
    glActiveTexture(GL_TEXTURE2);
    glBindTexture(GL_TEXTURE_2D, mask[src]);
    glActiveTexture(GL_TEXTURE3);
    glBindTexture(GL_TEXTURE_2D_ARRAY, maps);
    glActiveTexture(GL_TEXTURE4);
    glBindTexture(GL_TEXTURE_2D_ARRAY, cubes);
    glUniform1i(Loc(p, "g_position_tex"), 0);
    glUniform1i(Loc(p, "g_normal_tex"), 1);
    glUniform1i(Loc(p, "mask_in"), 2);
    glUniform1i(Loc(p, "maps"), 3);
    glUniform1i(Loc(p, "cubes"), 4);
    glUniform1i(Loc(p, "camera_count"), int(batch.cameras.size()));
    glUniform1i(Loc(p, "map_size"), map_size);
    glUniform1i(Loc(p, "cube_size"), cube_size);
    static const std::array<Mat3, 6> kCube = CubeFaces();
    for (int i = 0; i < 6; ++i) SetMat3(p, ("face_R[" + std::to_string(i) + "]").c_str(), kCube[i]);
    glUniform1f(Loc(p, "bias_scale"), float(options.shadow_bias_scale));
    glUniform1i(Loc(p, "shadow_mode"), int(options.shadow_test));
    glUniform1f(Loc(p, "lift"), float(lift));
    glUniform1f(Loc(p, "grid_n"), float(std::max(1, options.grid_pixels)));
    glUniform1f(Loc(p, "grid_fill"), float(options.grid_fill));
    glUniform1f(Loc(p, "line_width"), float(options.line_width_px));
    SetVec3(p, "eye", eye.rel);
    SetMat3(p, "view_Rt", eye.pose.linear());
    glUniform3f(Loc(p, "view_f"), float(eye.f), float(0.5 * eye.W - 0.5), float(0.5 * eye.H - 0.5));
    glUniform1i(Loc(p, "eye_table"), eye.table ? 1 : 0);
    const GLuint table[3] = {eye_dirs, eye_dx, eye_dy};
    const char* table_names[3] = {"eye_dirs", "eye_dx", "eye_dy"};
    for (int i = 0; i < 3; ++i) {
      glActiveTexture(GLenum(GL_TEXTURE5 + i));
      glBindTexture(GL_TEXTURE_2D, eye.table ? table[i] : 0);
      glUniform1i(Loc(p, table_names[i]), 5 + i);
    }
    glActiveTexture(GL_TEXTURE0);
    glBindVertexArray(empty_vao);
    glDrawArrays(GL_TRIANGLES, 0, 3);
    glDisablei(GL_BLEND, 0);
    return dst;
  }

  // The compose pass: material colour (or the light alone) and the background.
  void Compose(const FrameEye& eye, const GlRenderOptions& options) {
    glBindFramebuffer(GL_FRAMEBUFFER, compose_fbo);
    const GLenum buffer0 = GL_COLOR_ATTACHMENT0;
    glDrawBuffers(1, &buffer0);
    glViewport(0, 0, eye.W, eye.H);
    glDisable(GL_DEPTH_TEST);
    glDisable(GL_BLEND);
    const GLuint p = compose_program;
    glUseProgram(p);
    glActiveTexture(GL_TEXTURE0);
    glBindTexture(GL_TEXTURE_2D, g_position);
    glActiveTexture(GL_TEXTURE1);
    glBindTexture(GL_TEXTURE_2D, g_normal);
    glActiveTexture(GL_TEXTURE2);
    glBindTexture(GL_TEXTURE_2D, g_albedo);
    glActiveTexture(GL_TEXTURE3);
    glBindTexture(GL_TEXTURE_2D, light_accum);
    glUniform1i(Loc(p, "g_position_tex"), 0);
    glUniform1i(Loc(p, "g_normal_tex"), 1);
    glUniform1i(Loc(p, "g_albedo_tex"), 2);
    glUniform1i(Loc(p, "light_tex"), 3);
    const int surface = options.surface == Surface::kMaterial     ? 0
                        : options.surface == Surface::kHiddenLine ? 2
                        : options.surface == Surface::kContours   ? 3
                                                                  : 1;
    glUniform1i(Loc(p, "surface"), surface);
    glUniform1f(Loc(p, "line_grey"), float(options.line_grey));
    glUniform1f(Loc(p, "ambient"), float(options.ambient));
    SetVec3(p, "background", options.background);
    SetVec3(p, "eye", eye.rel);
    glBindVertexArray(empty_vao);
    glDrawArrays(GL_TRIANGLES, 0, 3);
  }

  // Camera sets of rigs over 64 cameras: word w's RG32UI mask texels, read back when the light
  // passes move on to word w + 1 (empty: no enabled camera in the word, or not read).
  std::vector<std::vector<GLuint>> word_bits;

  // Mask `src` (word `word` of the camera sets) read back into word_bits[word].
  void ReadMaskWord(int W, int H, int src, int word) {
    word_bits[std::size_t(word)].resize(2 * std::size_t(W) * H);
    glBindFramebuffer(GL_FRAMEBUFFER, light_fbo[src]);
    glReadBuffer(GL_COLOR_ATTACHMENT1);
    glPixelStorei(GL_PACK_ALIGNMENT, 1);
    glReadPixels(0, 0, W, H, GL_RG_INTEGER, GL_UNSIGNED_INT, word_bits[std::size_t(word)].data());
  }
  // Mask `src` set to no camera (the light beside it kept).
  void ClearMask(int src) {
    glBindFramebuffer(GL_FRAMEBUFFER, light_fbo[src]);
    const GLenum buffers[2] = {GL_NONE, GL_COLOR_ATTACHMENT1};
    glDrawBuffers(2, buffers);
    const GLuint zero_u[4] = {0, 0, 0, 0};
    glClearBufferuiv(GL_COLOR, 1, zero_u);
  }

  // What DrawFrame drew: the frame's size, the mask holding its camera sets (of word mask_word;
  // earlier words in word_bits), and its costs.
  struct Frame {
    int W = 0, H = 0, src = 0, camera_count = 0, maps_drawn = 0, light_passes = 0;
    int mask_word = 0, words_read = 0;
    double shadow_seconds = 0, light_seconds = 0, total_seconds = 0, map_cpu_seconds = 0;
  };
  // Steps 1-4 of a frame (G-buffer, maps, light, compose); `timed` waits for the GPU after each
  // part. Nothing is read back but, with `sets` and a rig of over 64 cameras, each finished word
  // of the camera sets (into word_bits) before the next word's light passes.
  Frame DrawFrame(const Rig& rig, const RenderView& view, const GlRenderOptions& options,
                  bool timed, bool sets);
  Frame LightAndCompose(const Rig& rig, const FrameEye& eye, const GlRenderOptions& options,
                        const std::vector<Batch>& batches, bool keep, bool timed, bool sets,
                        std::chrono::steady_clock::time_point start);
  static void FinishFrame(const Frame& f, std::chrono::steady_clock::time_point read,
                          std::int64_t readback_bytes, GlFrameStats* stats);

  // The composed colour as 8-bit sRGB into `encoded`, on the GPU.
  void Encode(int W, int H) {
    glBindFramebuffer(GL_FRAMEBUFFER, encode_fbo);
    const GLenum buffer0 = GL_COLOR_ATTACHMENT0;
    glDrawBuffers(1, &buffer0);
    glViewport(0, 0, W, H);
    glDisable(GL_DEPTH_TEST);
    glDisable(GL_BLEND);
    glUseProgram(encode_program);
    glActiveTexture(GL_TEXTURE0);
    glBindTexture(GL_TEXTURE_2D, compose_color);
    glUniform1i(Loc(encode_program, "color_tex"), 0);
    glBindVertexArray(empty_vao);
    glDrawArrays(GL_TRIANGLES, 0, 3);
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
  }

  // Bytes Render reads from the GPU for a frame: two RGBA float images (colour, surface hits) and
  // 8 per pixel for each word of the camera sets that has an enabled camera.
  static std::int64_t ReadBackBytes(const Frame& f) {
    return std::int64_t(f.W) * f.H * (2 * 16 + 8 * std::int64_t(f.words_read));
  }

  // Reads the composed colour, the surface hits and the camera sets back (the last word from
  // mask f.src, the earlier ones from word_bits).
  GlImage ReadBack(const Frame& f) {
    const int W = f.W, H = f.H;
    const std::size_t pixels = std::size_t(W) * H;
    // GL's row r is the image's row r: no flip.
    GlImage image;
    image.width = W;
    image.height = H;
    glPixelStorei(GL_PACK_ALIGNMENT, 1);
    std::vector<float> rgba(4 * pixels);
    glReadBuffer(GL_COLOR_ATTACHMENT0);
    glReadPixels(0, 0, W, H, GL_RGBA, GL_FLOAT, rgba.data());
    image.rgb.resize(3 * pixels);
    for (std::size_t i = 0; i < pixels; ++i)
      for (int ch = 0; ch < 3; ++ch) image.rgb[3 * i + ch] = rgba[4 * i + ch];
    glBindFramebuffer(GL_FRAMEBUFFER, g_fbo);
    glReadBuffer(GL_COLOR_ATTACHMENT0);
    glReadPixels(0, 0, W, H, GL_RGBA, GL_FLOAT, rgba.data());
    image.hit.resize(pixels);
    for (std::size_t i = 0; i < pixels; ++i) image.hit[i] = rgba[4 * i + 3] >= 0;
    ReadMaskWord(W, H, f.src, f.mask_word);
    const std::size_t words = word_bits.size();
    image.camera_words = int(words);
    image.cameras.assign(pixels * words, 0);
    for (std::size_t w = 0; w < words; ++w) {
      const std::vector<GLuint>& bits = word_bits[w];
      if (bits.empty()) continue;  // no enabled camera in this word
      for (std::size_t i = 0; i < pixels; ++i)
        image.cameras[i * words + w] = uint64_t(bits[2 * i]) | (uint64_t(bits[2 * i + 1]) << 32);
    }
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    return image;
  }
};

GlRenderer::GlRenderer(const Scene& scene, const PreparedScene* prepared)
    : impl_(std::make_unique<Impl>()) {
  Impl& m = *impl_;
  std::vector<int> triangle_object;
  m.mesh = scene.AllTriangles(&triangle_object);
  m.boxes = BuildTriangleBoxTree(m.mesh);
  const Aabb content = scene.ContentBounds();
  m.origin = content.empty() ? Vec3::Zero() : content.center();
  m.scene_scale = std::max(content.diagonal(), 1e-9);

  std::vector<Vec3> object_color(scene.objects.size(), Material().color);
  for (std::size_t o = 0; o < scene.objects.size(); ++o) {
    const int mat = scene.objects[o].material;
    if (mat >= 0 && mat < int(scene.materials.size())) object_color[o] = scene.materials[mat].color;
  }
  const std::vector<uint8_t> drawn = ComputeDrawnEdges(m.mesh);
  // Textures: each decoded image once, as sRGB8 (the PNG's own 8-bit values; GL decodes them to
  // linear before filtering, as the CPU filters its decoded texels), bilinear with repeat, no mip
  // maps (the CPU samples the base level). Triangles are grouped by texture for one draw each.
  std::vector<int> object_texture(scene.objects.size(), -1);
  if (prepared) {
    const std::vector<Image>& images = prepared->Textures();
    const std::vector<int>& of_object = prepared->ObjectTextures();
    GLint max_size = 0;
    glGetIntegerv(GL_MAX_TEXTURE_SIZE, &max_size);
    m.texture_ids.assign(images.size(), 0);
    for (std::size_t i = 0; i < images.size(); ++i) {
      const Image& im = images[i];
      if (im.width <= 0 || im.height <= 0 || im.width > max_size || im.height > max_size) continue;
      std::vector<unsigned char> texels(std::size_t(3) * im.width * im.height);
      for (std::size_t k = 0; k < texels.size(); ++k)
        texels[k] = static_cast<unsigned char>(std::lround(
            255.0 * std::clamp(SrgbFromLinear(std::clamp(double(im.rgb[k]), 0.0, 1.0)), 0.0, 1.0)));
      glGenTextures(1, &m.texture_ids[i]);
      glBindTexture(GL_TEXTURE_2D, m.texture_ids[i]);
      glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
      glTexImage2D(GL_TEXTURE_2D, 0, GL_SRGB8, im.width, im.height, 0, GL_RGB, GL_UNSIGNED_BYTE,
                   texels.data());
      glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
      glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
      glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_REPEAT);
      glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_REPEAT);
      glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAX_LEVEL, 0);
    }
    for (std::size_t o = 0; o < object_texture.size() && o < of_object.size(); ++o)
      if (of_object[o] >= 0 && of_object[o] < int(m.texture_ids.size()) &&
          m.texture_ids[of_object[o]] != 0 && m.mesh.corner_uvs.size() == m.mesh.triangles.size())
        object_texture[o] = of_object[o];
  }
  std::vector<int> order(m.mesh.triangles.size());
  for (std::size_t t = 0; t < order.size(); ++t) order[t] = int(t);
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) {
    return object_texture[triangle_object[a]] < object_texture[triangle_object[b]];
  });
  std::vector<float> data;
  data.reserve(m.mesh.triangles.size() * 39);
  for (std::size_t i = 0; i < order.size(); ++i) {
    const int t = order[i];
    const int texture = object_texture[triangle_object[t]];
    const GLuint id = texture >= 0 ? m.texture_ids[texture] : 0u;
    if (m.draws.empty() || m.draws.back().texture != id) m.draws.push_back({GLint(3 * i), 0, id});
    m.draws.back().count += 3;
    const Eigen::Vector3i& tri = m.mesh.triangles[t];
    const Vec3 a = m.mesh.vertices[tri[0]], b = m.mesh.vertices[tri[1]],
               c = m.mesh.vertices[tri[2]];
    Vec3 n = (b - a).cross(c - a);
    n = n.norm() > 0 ? Vec3(n.normalized()) : Vec3::UnitZ();
    const Vec3& albedo = object_color[triangle_object[t]];
    for (int corner = 0; corner < 3; ++corner) {
      const Vec3 r = (corner == 0 ? a : corner == 1 ? b : c) - m.origin;
      for (const Vec3* v : std::array<const Vec3*, 3>{&r, &n, &albedo})
        for (int k = 0; k < 3; ++k) data.push_back(float((*v)(k)));
      data.push_back(float(triangle_object[t]));
      data.push_back(float(drawn[t]));
      const Eigen::Vector2d uv =
          texture >= 0 ? m.mesh.corner_uvs[t][corner] : Eigen::Vector2d::Zero();
      data.push_back(float(uv.x()));
      data.push_back(float(uv.y()));
    }
  }
  m.vertex_count = GLsizei(3 * m.mesh.triangles.size());
  GLint max_buffer_texels = 0;
  glGetIntegerv(GL_MAX_TEXTURE_BUFFER_SIZE, &max_buffer_texels);
  if (!order.empty() && double(max_buffer_texels) >= 3.0 * double(order.size())) {
    std::vector<float> corners;
    corners.reserve(12 * order.size());
    for (const std::size_t t : std::vector<std::size_t>(order.begin(), order.end()))
      for (int corner = 0; corner < 3; ++corner) {
        const Vec3 r = m.mesh.vertices[std::size_t(m.mesh.triangles[t][corner])] - m.origin;
        corners.insert(corners.end(), {float(r.x()), float(r.y()), float(r.z()), 0.0f});
      }
    glGenBuffers(1, &m.corner_buffer);
    glBindBuffer(GL_TEXTURE_BUFFER, m.corner_buffer);
    glBufferData(GL_TEXTURE_BUFFER, GLsizeiptr(corners.size() * sizeof(float)), corners.data(),
                 GL_STATIC_DRAW);
    glGenTextures(1, &m.corner_texture);
    glBindTexture(GL_TEXTURE_BUFFER, m.corner_texture);
    glTexBuffer(GL_TEXTURE_BUFFER, GL_RGBA32F, m.corner_buffer);
    glBindTexture(GL_TEXTURE_BUFFER, 0);
  }
  glGenVertexArrays(1, &m.vao);
  glBindVertexArray(m.vao);
  glGenBuffers(1, &m.vbo);
  glBindBuffer(GL_ARRAY_BUFFER, m.vbo);
  glBufferData(GL_ARRAY_BUFFER, GLsizeiptr(data.size() * sizeof(float)), data.data(),
               GL_STATIC_DRAW);
  const GLsizei stride = 13 * sizeof(float);
  for (int k = 0; k < 5; ++k) {
    glEnableVertexAttribArray(k);
    glVertexAttribPointer(
        k, k < 3 ? 3 : 2, GL_FLOAT, GL_FALSE, stride,
        reinterpret_cast<const void*>(std::size_t(k < 4 ? 3 * k : 11) * sizeof(float)));
  }
  glGenVertexArrays(1, &m.empty_vao);
  m.gbuffer_program = Link(kGBufferVertex, kGBufferFragment, "gbuffer");
  m.shadow_program = Link(kShadowVertex, kShadowFragment, "shadow");
  m.compose_program = Link(kFullScreenVertex, kComposeFragment, "compose");
  m.encode_program = Link(kFullScreenVertex, kEncodeFragment, "encode");
  m.resample_program = Link(kFullScreenVertex, kResampleFragment, "resample");
  {
    std::string geometry = kMapsGeometry;
    geometry.insert(geometry.find('\n') + 1,
                    "#define MAX_MAPS " + std::to_string(Impl::kMaxMaps) + "\n");
    m.maps_program = Link(kMapsVertex, geometry.c_str(), kMapsFragment, "maps");
    glUniformBlockBinding(m.maps_program, glGetUniformBlockIndex(m.maps_program, "MapBlock"), 1);
    glGenBuffers(1, &m.map_ubo);
    glBindBuffer(GL_UNIFORM_BUFFER, m.map_ubo);
    glBufferData(GL_UNIFORM_BUFFER, GLsizeiptr(20 * Impl::kMaxMaps * sizeof(float)), nullptr,
                 GL_DYNAMIC_DRAW);
  }
  for (const Vec3& v : m.mesh.vertices) m.mesh_box.Extend(v);
  m.LightProgram(15);  // every branch compiled once now: a shader error shows at construction
  glGenBuffers(1, &m.camera_ubo);
  glBindBuffer(GL_UNIFORM_BUFFER, m.camera_ubo);
  glBufferData(GL_UNIFORM_BUFFER, GLsizeiptr(kCameraVec4 * kMaxBatch * 4 * sizeof(float)), nullptr,
               GL_DYNAMIC_DRAW);
}

GlRenderer::~GlRenderer() = default;

std::size_t GlRenderer::triangle_count() const { return impl_->mesh.triangles.size(); }

GlRenderer::Impl::Frame GlRenderer::Impl::DrawFrame(const Rig& rig, const RenderView& view,
                                                    const GlRenderOptions& options, bool timed,
                                                    bool sets) {
  using Clock = std::chrono::steady_clock;
  const auto start = Clock::now();
  Impl& m = *this;
  m.map_cpu_seconds = 0;
  const bool camera_eye = view.camera >= 0;
  if (camera_eye && view.camera >= int(rig.cameras.size()))
    throw std::invalid_argument("GlRenderer: no camera " + std::to_string(view.camera) +
                                " in the rig (RenderView::camera)");
  if (camera_eye && IsCube(rig.cameras[std::size_t(view.camera)]))
    throw std::invalid_argument(
        "GlRenderer: camera's-eye views of lenses reaching 75 degrees off their axis (wide "
        "fisheyes) are drawn by the CPU renderer (render/render.h)");
  GLint max_size = 0;
  glGetIntegerv(GL_MAX_TEXTURE_SIZE, &max_size);
  if (view.width <= 0 || view.height <= 0 || view.width > max_size || view.height > max_size)
    throw std::invalid_argument("GlRenderer: the image size must be 1 .. " +
                                std::to_string(max_size) + " pixels per side");
  if (!camera_eye && !(view.fov_deg > 0 && view.fov_deg < 180))
    throw std::invalid_argument("GlRenderer: fov must be in (0, 180) degrees");
  const auto pose = camera_eye
                        ? std::optional(rig.cameras[std::size_t(view.camera)].world_from_camera)
                        : LookAt(view.from, view.at, view.up);
  if (!pose)
    throw std::invalid_argument(
        "GlRenderer: 'at' equals 'from', or 'up' is parallel to the viewing direction");
  if (options.shadow_map_size < 256 || options.shadow_map_size > 4096)
    throw std::invalid_argument("GlRenderer: shadow_map_size must be 256 .. 4096 (is " +
                                std::to_string(options.shadow_map_size) + ")");
  if (options.shadow_map_size > max_size)
    throw std::invalid_argument("GlRenderer: this GL's textures are at most " +
                                std::to_string(max_size) + " texels per side; shadow_map_size is " +
                                std::to_string(options.shadow_map_size));
  GLint max_layers = 0;
  glGetIntegerv(GL_MAX_ARRAY_TEXTURE_LAYERS, &max_layers);
  const int W = view.width, H = view.height;

  const std::vector<Batch> batches = LightBatches(rig, options, max_layers);
  int perspective_layers = 0, cube_count = 0;
  for (const Batch& b : batches) {
    perspective_layers = std::max(perspective_layers, b.perspective);
    cube_count = std::max(cube_count, b.cube);
  }
  m.EnsureViewTargets(W, H);
  m.EnsureMaps(options.shadow_map_size, perspective_layers, cube_count);
  // Maps are kept for the next frame only when every camera has its own layers.
  const bool keep = batches.size() <= 1;
  if (!keep || !options.reuse_maps) {
    std::fill(m.map_camera.begin(), m.map_camera.end(), std::nullopt);
    std::fill(m.cube_camera.begin(), m.cube_camera.end(), std::nullopt);
  }

  // 1. G-buffer. The eye: OpenCV frame (x right, y down, z forward); GL's window row r is the
  // image's row r.
  if (camera_eye) {
    const Camera& cam = rig.cameras[std::size_t(view.camera)];
    const FrameEye eye{W, H, *pose, 0.0, cam.center() - m.origin, true};
    m.DrawCameraGBuffer(cam, eye, options);
    return m.LightAndCompose(rig, eye, options, batches, keep, timed, sets, start);
  }
  const double f = 0.5 * W / std::tan(0.5 * view.fov_deg * kPi / 180.0);
  const Vec3 eye_rel = view.from - m.origin;
  const FrameEye eye{W, H, *pose, f, eye_rel, false};
  m.DrawGBuffer(view, eye, options);
  return m.LightAndCompose(rig, eye, options, batches, keep, timed, sets, start);
}

// Steps 2-4 of a frame over the G-buffer drawn (maps, light, compose).
GlRenderer::Impl::Frame GlRenderer::Impl::LightAndCompose(
    const Rig& rig, const FrameEye& eye, const GlRenderOptions& options,
    const std::vector<Batch>& batches, bool keep, bool timed, bool sets,
    std::chrono::steady_clock::time_point start) {
  using Clock = std::chrono::steady_clock;
  Impl& m = *this;
  const int W = eye.W, H = eye.H;
  const int camera_count = int(rig.cameras.size());

  // Clear the light and the first mask.
  glBindFramebuffer(GL_FRAMEBUFFER, m.light_fbo[0]);
  {
    const GLenum buffers[2] = {GL_COLOR_ATTACHMENT0, GL_COLOR_ATTACHMENT1};
    glDrawBuffers(2, buffers);
    const float zero[4] = {0, 0, 0, 0};
    const GLuint zero_u[4] = {0, 0, 0, 0};
    glClearBufferfv(GL_COLOR, 0, zero);
    glClearBufferuiv(GL_COLOR, 1, zero_u);
  }

  const double brightness =
      std::isnan(options.brightness) ? DefaultBrightness(rig.enabled_count()) : options.brightness;
  int src = 0;
  double shadow_seconds = 0, light_seconds = 0;
  int maps_drawn = 0;
  std::vector<float> block(4 * kCameraVec4 * kMaxBatch, 0.0f);
  // The camera sets' words: batches never straddle one (LightBatches); the mask starts each word
  // from no camera, the finished word read back first when the sets are wanted.
  m.word_bits.assign(std::size_t(std::max(1, (camera_count + 63) / 64)), {});
  int mask_word = batches.empty() ? 0 : batches.front().cameras.front() / 64, words_read = 1;
  for (const Batch& batch : batches) {
    if (const int word = batch.cameras.front() / 64; word != mask_word) {
      if (sets) m.ReadMaskWord(W, H, src, mask_word);
      ++words_read;
      m.ClearMask(src);
      mask_word = word;
    }
    // 2. The batch's distance maps (those not kept from the last frame).
    if (timed) glFinish();
    const auto shadow_start = Clock::now();
    std::vector<int> layer(batch.cameras.size());
    maps_drawn += m.DrawBatchMaps(rig, batch, keep, options, layer);
    if (timed) {
      glFinish();
      shadow_seconds += std::chrono::duration<double>(Clock::now() - shadow_start).count();
    }

    // 3. The batch's light over the G-buffer, in one pass.
    const auto light_start = Clock::now();
    src = m.DrawBatchLight(rig, batch, layer, eye, options, brightness, src, block);
    if (timed) {
      glFinish();
      light_seconds += std::chrono::duration<double>(Clock::now() - light_start).count();
    }
  }

  // 4. Compose.
  m.Compose(eye, options);
  if (timed) glFinish();
  const auto drawn = Clock::now();

  Frame frame;
  frame.W = W;
  frame.H = H;
  frame.src = src;
  frame.mask_word = mask_word;
  frame.words_read = words_read;
  frame.camera_count = camera_count;
  frame.maps_drawn = maps_drawn;
  frame.light_passes = int(batches.size());
  frame.shadow_seconds = shadow_seconds;
  frame.light_seconds = light_seconds;
  frame.total_seconds = std::chrono::duration<double>(drawn - start).count();
  frame.map_cpu_seconds = m.map_cpu_seconds;
  return frame;
}

// The frame's statistics, the read-back's time and bytes with them; throws on a GL error.
void GlRenderer::Impl::FinishFrame(const Frame& f, std::chrono::steady_clock::time_point read,
                                   std::int64_t readback_bytes, GlFrameStats* stats) {
  const GLenum error = glGetError();
  if (error != GL_NO_ERROR)
    throw std::runtime_error("GlRenderer: GL error " + std::to_string(error) + " in a frame");
  if (!stats) return;
  stats->shadow_seconds = f.shadow_seconds;
  stats->map_cpu_seconds = f.map_cpu_seconds;
  stats->light_seconds = f.light_seconds;
  stats->total_seconds = f.total_seconds;
  stats->readback_seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - read).count();
  stats->readback_bytes = readback_bytes;
  stats->shadow_maps = f.maps_drawn;
  stats->light_passes = f.light_passes;
}

GlImage GlRenderer::Render(const Rig& rig, const RenderView& view, const GlRenderOptions& options,
                           GlFrameStats* stats) {
  const Impl::Frame f = impl_->DrawFrame(rig, view, options, stats && stats->per_part, true);
  const auto read = std::chrono::steady_clock::now();
  GlImage image = impl_->ReadBack(f);
  Impl::FinishFrame(f, read, Impl::ReadBackBytes(f), stats);
  return image;
}

unsigned GlRenderer::DrawToTexture(const Rig& rig, const RenderView& view,
                                   const GlRenderOptions& options, GlFrameStats* stats) {
  const Impl::Frame f = impl_->DrawFrame(rig, view, options, stats && stats->per_part, false);
  const auto read = std::chrono::steady_clock::now();
  impl_->Encode(f.W, f.H);
  if (stats && stats->per_part) glFinish();
  Impl::FinishFrame(f, read, 0, stats);
  return impl_->encoded;
}

std::vector<unsigned char> GlReadRgba8(unsigned texture, int width, int height) {
  std::vector<unsigned char> rgba(4 * std::size_t(width) * std::size_t(height));
  glBindTexture(GL_TEXTURE_2D, texture);
  glPixelStorei(GL_PACK_ALIGNMENT, 1);
  glGetTexImage(GL_TEXTURE_2D, 0, GL_RGBA, GL_UNSIGNED_BYTE, rgba.data());
  return rgba;
}

void GlCopyTexture(unsigned from, unsigned to, int width, int height) {
  GLuint fbo[2] = {0, 0};
  glGenFramebuffers(2, fbo);
  glBindFramebuffer(GL_READ_FRAMEBUFFER, fbo[0]);
  glFramebufferTexture2D(GL_READ_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, from, 0);
  glBindFramebuffer(GL_DRAW_FRAMEBUFFER, fbo[1]);
  glFramebufferTexture2D(GL_DRAW_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, to, 0);
  glReadBuffer(GL_COLOR_ATTACHMENT0);
  const GLenum buffer0 = GL_COLOR_ATTACHMENT0;
  glDrawBuffers(1, &buffer0);
  glBlitFramebuffer(0, 0, width, height, 0, 0, width, height, GL_COLOR_BUFFER_BIT, GL_NEAREST);
  glBindFramebuffer(GL_FRAMEBUFFER, 0);
  glDeleteFramebuffers(2, fbo);
}

bool GlDrawsCameraEye(const Camera& cam) { return !IsCube(cam); }

std::vector<double> GlCameraLightWeights(const LightRule& rule,
                                         const std::vector<CameraAtPoint>& points) {
  // One fragment per input (shaders/light_weights.frag).
  const int count = int(points.size());
  if (count == 0) return {};
  std::vector<float> coords(4 * points.size()), flags(4 * points.size(), 0.0f);
  for (int i = 0; i < count; ++i) {
    const CameraAtPoint& p = points[i];
    coords[4 * i] = float(p.u);
    coords[4 * i + 1] = float(p.v);
    coords[4 * i + 2] = float(p.du);
    coords[4 * i + 3] = float(p.dv);
    flags[4 * i] = p.sees ? 1.0f : 0.0f;
    flags[4 * i + 1] = p.projects ? 1.0f : 0.0f;
  }
  const GLuint program =
      Link(kFullScreenVertex, WithLightRule(kLightWeightsFragment).c_str(), "light rule");
  const GLuint coord_tex = MakeTexture(GL_RGBA32F, count, 1, GL_RGBA, GL_FLOAT);
  glTexSubImage2D(GL_TEXTURE_2D, 0, 0, 0, count, 1, GL_RGBA, GL_FLOAT, coords.data());
  const GLuint flag_tex = MakeTexture(GL_RGBA32F, count, 1, GL_RGBA, GL_FLOAT);
  glTexSubImage2D(GL_TEXTURE_2D, 0, 0, 0, count, 1, GL_RGBA, GL_FLOAT, flags.data());
  const GLuint out_tex = MakeTexture(GL_RGBA32F, count, 1, GL_RGBA, GL_FLOAT);
  GLuint fbo = 0, vao = 0;
  glGenFramebuffers(1, &fbo);
  glBindFramebuffer(GL_FRAMEBUFFER, fbo);
  glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, out_tex, 0);
  CheckFramebuffer("light rule");
  const GLenum buffer0 = GL_COLOR_ATTACHMENT0;
  glDrawBuffers(1, &buffer0);
  glViewport(0, 0, count, 1);
  glDisable(GL_DEPTH_TEST);
  glDisable(GL_BLEND);
  glUseProgram(program);
  glActiveTexture(GL_TEXTURE0);
  glBindTexture(GL_TEXTURE_2D, coord_tex);
  glActiveTexture(GL_TEXTURE1);
  glBindTexture(GL_TEXTURE_2D, flag_tex);
  glUniform1i(Loc(program, "coords"), 0);
  glUniform1i(Loc(program, "flags"), 1);
  glUniform1i(Loc(program, "grid"), rule.pattern == Pattern::kGrid ? 1 : 0);
  glUniform1f(Loc(program, "n"), float(std::max(1, rule.grid_pixels)));
  glUniform1f(Loc(program, "fill"), float(rule.grid_fill));
  glUniform1f(Loc(program, "width"), float(rule.line_width_px));
  glGenVertexArrays(1, &vao);
  glBindVertexArray(vao);
  glDrawArrays(GL_TRIANGLES, 0, 3);
  std::vector<float> rgba(4 * points.size());
  glReadBuffer(GL_COLOR_ATTACHMENT0);
  glPixelStorei(GL_PACK_ALIGNMENT, 1);
  glReadPixels(0, 0, count, 1, GL_RGBA, GL_FLOAT, rgba.data());
  glBindFramebuffer(GL_FRAMEBUFFER, 0);
  glDeleteVertexArrays(1, &vao);
  glDeleteFramebuffers(1, &fbo);
  const GLuint textures[3] = {coord_tex, flag_tex, out_tex};
  glDeleteTextures(3, textures);
  glDeleteProgram(program);
  std::vector<double> weights(points.size());
  for (int i = 0; i < count; ++i) weights[i] = rgba[4 * i];
  return weights;
}

}  // namespace pandora
