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

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
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

// ------------------------------------------------------------------------------------------
// Shaders (GLSL 3.30 core).

const char* kGBufferVertex = R"(#version 330 core
layout(location = 0) in vec3 position;  // relative to the scene's centre
layout(location = 1) in vec3 normal;
layout(location = 2) in vec3 albedo;
layout(location = 3) in vec2 tag;  // object index, drawn-edge bits (bit i: edge opposite vertex i)
layout(location = 4) in vec2 uv;   // texture coordinate (v = 0: the texture's bottom row)
uniform mat3 view_R;   // camera_from_world rotation of the eye (OpenCV frame: y down, z forward)
uniform vec3 view_t;   // camera-frame position of the scene's centre, less (0, 0, view_d0)
uniform float view_d0; // the near plane's depth: z is kept relative to it (precision far away)
uniform vec4 proj;     // 2f/W, 2f/H, A, B': clip = (proj.x x, proj.y y, A z + B', z + d0)
out vec3 v_position;
out float v_z;         // depth beyond the near plane, m (the fragment's depth and the cut)
flat out vec3 v_normal;
flat out vec3 v_albedo;
flat out vec2 v_tag;
out vec3 v_bary;
out vec2 v_uv;
void main() {
  vec3 c = view_R * position + view_t;  // c.z: depth less view_d0
  v_uv = uv;
  v_z = c.z;
  gl_Position = vec4(proj.x * c.x, proj.y * c.y, proj.z * c.z + proj.w, c.z + view_d0);
  v_position = position;
  v_normal = normal;
  v_albedo = albedo;
  v_tag = tag;
  int corner = gl_VertexID % 3;  // non-indexed triangles: vertex i of its triangle
  v_bary = vec3(corner == 0 ? 1.0 : 0.0, corner == 1 ? 1.0 : 0.0, corner == 2 ? 1.0 : 0.0);
}
)";

const char* kGBufferFragment = R"(#version 330 core
in vec3 v_position;
flat in vec3 v_normal;
flat in vec3 v_albedo;
flat in vec2 v_tag;
in vec3 v_bary;
in vec2 v_uv;
in float v_z;
uniform vec2 depth_map;  // the cut's v_z (nothing nearer is drawn), 1 / (far - near)
uniform vec3 eye;
uniform int textured;         // 1: albedo times the texture (bilinear, repeat, filtered in linear)
uniform sampler2D albedo_tex; // sRGB8: decoded to linear before filtering, as the CPU's texels
uniform int edges;         // 1: hidden-line mode, the drawn edges' coverage into g_normal.w
uniform float line_width;  // output pixels
layout(location = 0) out vec4 g_position;  // xyz, 1 (-1: no surface)
layout(location = 1) out vec4 g_normal;    // turned towards the eye; w: edge coverage
layout(location = 2) out vec4 g_albedo;    // w: object index
void main() {
  // RenderView::clip_near, and the depth linear in v_z: an eye far away (plans) keeps the depth
  // test's precision, (far - near) / 2^24, instead of float's at the eye's distance.
  if (v_z < depth_map.x) discard;
  gl_FragDepth = clamp(v_z * depth_map.y, 0.0, 1.0);
  vec3 n = v_normal;
  if (dot(n, v_position - eye) > 0.0) n = -n;
  // Coverage by the drawn edges as render/frame.cpp: LineCoverage(|lambda_i| / |grad lambda_i|)
  // with the gradient in output pixels (here the screen derivatives of the barycentrics).
  float a = 0.0;
  int drawn = int(v_tag.y + 0.5);
  vec3 gx = dFdx(v_bary), gy = dFdy(v_bary);
  if (edges != 0) {
    for (int i = 0; i < 3; ++i) {
      if ((drawn & (1 << i)) == 0) continue;
      float g = length(vec2(gx[i], gy[i]));
      if (g > 0.0) a = max(a, clamp(0.5 * line_width + 0.5 - abs(v_bary[i]) / g, 0.0, 1.0));
    }
  }
  g_position = vec4(v_position, 1.0);
  g_normal = vec4(n, a);
  vec3 albedo = v_albedo;
  // The texture's row 0 is the image's top (uploaded as decoded), v = 0 its bottom: t = 1 - v.
  if (textured != 0) albedo *= texture(albedo_tex, vec2(v_uv.x, 1.0 - v_uv.y)).rgb;
  g_albedo = vec4(albedo, v_tag.x);
}
)";

const char* kShadowVertex = R"(#version 330 core
layout(location = 0) in vec3 position;
uniform mat3 face_R;  // face_from_world rotation
uniform vec3 face_t;  // face-frame position of the scene's centre (the camera at the origin)
uniform vec4 map;     // sx, sy, ox, oy: ndc = (sx x / z - ox, sy y / z - oy)
uniform vec2 depth;   // A, B
out vec3 v_face;
void main() {
  vec3 c = face_R * position + face_t;
  v_face = c;
  gl_Position = vec4(map.x * c.x - map.z * c.z, map.y * c.y - map.w * c.z,
                     depth.x * c.z + depth.y, c.z);
}
)";

const char* kShadowFragment = R"(#version 330 core
in vec3 v_face;
layout(location = 0) out float o_map;  // distance from the camera's centre
void main() { o_map = length(v_face); }
)";

// A triangle covering the screen, from gl_VertexID alone (no attributes).
const char* kFullScreenVertex = R"(#version 330 core
void main() {
  vec2 p = vec2(float((gl_VertexID << 1) & 2), float(gl_VertexID & 2));
  gl_Position = vec4(2.0 * p - 1.0, 0.0, 1.0);
}
)";

// The light rule of render/light.h in GLSL (shared by the light pass and GlCameraLightWeights).
const char* kLightRuleGlsl = R"(
// GridLineCoverage: one family of grid lines (camera pixel borders u = k n - 1/2) at camera
// coordinate u, g camera pixels per output pixel, lines `width` output pixels wide.
float GridLineCoverage(float u, float g, float n, float width) {
  if (!(g > 0.0) || isinf(g)) return 0.0;
  float f = (u + 0.5) / n;
  float du = abs(f - floor(f + 0.5)) * n;
  float spacing = n / g;
  float line = clamp(0.5 * width + 0.5 - du / g, 0.0, 1.0);
  float mean = min(1.0, width / spacing);
  float fade = clamp((3.0 - spacing) / 1.5, 0.0, 1.0);
  return (1.0 - fade) * line + fade * mean;
}
// CameraLightWeight of a camera that sees the point, grid pattern (n = max(1, grid_pixels)).
float GridLightWeight(bool projects, vec2 uv, vec2 duv, float n, float fill, float width) {
  float lu = projects ? GridLineCoverage(uv.x, duv.x, n, width) : 0.0;
  float lv = projects ? GridLineCoverage(uv.y, duv.y, n, width) : 0.0;
  return fill + (1.0 - fill) * (1.0 - (1.0 - lu) * (1.0 - lv));
}
)";

// The light of a batch of cameras over the G-buffer, in one pass: for each pixel, each camera of
// the batch in rig order. A camera's parameters are kCameraVec4 vec4s of the uniform block (see
// PackCamera); its distance map is layer `layer` of `maps` (one perspective map) or layers
// layer .. layer + 5 of `cubes` (a cube).
// Compiled in variants (Impl::LightProgram): GRID for the grid pattern, FISHEYE, DISTORTION
// (Brown-Conrady) and CUBE only when a camera of the batch needs them. Software GL (llvmpipe)
// runs every branch of a loop body under a mask whether or not a lane takes it, so code a batch
// cannot need would cost as much as code it runs.
const char* kLightFragment = R"(#version 330 core
#define CAMERA_VEC4 10
#define MAX_BATCH 64
layout(std140) uniform CameraBlock { vec4 cams[CAMERA_VEC4 * MAX_BATCH]; };
uniform int camera_count;
uniform sampler2D g_position_tex;
uniform sampler2D g_normal_tex;
uniform usampler2D mask_in;
uniform sampler2DArray maps;
uniform sampler2DArray cubes;
uniform int map_size;
uniform int cube_size;
uniform mat3 face_R[6];        // cube faces: face_from_camera
uniform float bias_scale;
uniform int shadow_mode;       // 0: distance + bias, 1: receiver plane, 2: either
uniform float lift;
uniform float grid_n;
uniform float grid_fill;
uniform float line_width;
uniform vec3 eye;
uniform mat3 view_Rt;          // world_from_camera rotation of the eye: columns x, y, z
uniform vec3 view_f;           // f, cx, cy of the eye
layout(location = 0) out vec4 o_light;
layout(location = 1) out uvec2 o_mask;

struct Lens {
  int model;      // 0 pinhole, 1 Brown-Conrady, 2 fisheye
  vec4 K;         // fx fy cx cy
  vec4 D0;        // Brown-Conrady k1 k2 p1 p2; fisheye k1 k2 k3 k4
  float D1;       // Brown-Conrady k3
  float max_radius;
};

// CameraModel::Project (analysis/geometry/camera.cpp) in float: camera-frame point to distorted pixel.
bool Project(Lens L, vec3 p, out vec2 px) {
  px = vec2(0.0);
#if FISHEYE
  if (L.model == 2) {
    float r = length(p.xy);
    if (r == 0.0 && p.z == 0.0) return false;
    float theta = atan(r, p.z);
    if (!(theta < L.max_radius)) return false;
    float t = theta * theta;
    float poly = 1.0 + t * (L.D0.x + t * (L.D0.y + t * (L.D0.z + t * L.D0.w)));
    vec2 q = r > 0.0 ? p.xy * (theta * poly / r) : vec2(0.0);
    px = L.K.xy * q + L.K.zw;
    return true;
  }
#endif
  if (!(p.z > 0.0)) return false;
  vec2 n = p.xy / p.z;
  vec2 d = n;
#if DISTORTION
  if (L.model == 1) {
    if (!(length(n) < L.max_radius)) return false;
    vec4 D = L.D0;
    float x = n.x, y = n.y, s = x * x + y * y;
    float radial = 1.0 + s * (D.x + s * (D.y + s * L.D1));
    float dr = 2.0 * (D.x + s * (2.0 * D.y + s * 3.0 * L.D1));
    d = vec2(x * radial + 2.0 * D.z * x * y + D.w * (s + 2.0 * x * x),
             y * radial + D.z * (s + 2.0 * y * y) + 2.0 * D.w * x * y);
    float c = dr * x * y + 2.0 * D.z * x + 2.0 * D.w * y;
    float j00 = radial + dr * x * x + 2.0 * D.z * y + 6.0 * D.w * x;
    float j11 = radial + dr * y * y + 6.0 * D.z * y + 2.0 * D.w * x;
    if (!(j00 * j11 - c * c > 0.0)) return false;
  }
#endif
  px = L.K.xy * d + L.K.zw;
  return true;
}

// @LIGHT_RULE@

void main() {
  ivec2 ip = ivec2(gl_FragCoord.xy);
  uvec2 mask = texelFetch(mask_in, ip, 0).xy;
  o_light = vec4(0.0);
  o_mask = mask;
  vec4 g = texelFetch(g_position_tex, ip, 0);
  if (g.w < 0.0) return;
  vec3 n = texelFetch(g_normal_tex, ip, 0).xyz;
  vec3 X = g.xyz + lift * n;
  vec3 sum = vec3(0.0);
  for (int i = 0; i < camera_count; ++i) {
    int b = CAMERA_VEC4 * i;
    vec4 c0 = cams[b], c1 = cams[b + 1], c2 = cams[b + 2], c3 = cams[b + 3], c4 = cams[b + 4];
    vec4 c7 = cams[b + 7];
    // c0..c2: rows of camera_from_world and (lens, first map layer, cube); c3: translation of
    // the scene's centre, k3; c4: centre, monotonic radius; c5: K; c6: D0; c7: image size, range;
    // c8: light, bit index; c9: perspective map's (sx, sy, ox, oy).
    vec3 to_point = X - c4.xyz;
    float dist = length(to_point);
    if (dist < c7.z || dist > c7.w) continue;
    mat3 R = transpose(mat3(c0.xyz, c1.xyz, c2.xyz));  // rows -> camera_from_world
    vec3 pc = R * X + c3.xyz;
    Lens L = Lens(int(c0.w), cams[b + 5], cams[b + 6], c3.w, c4.w);
    vec2 px;
    if (!Project(L, pc, px)) continue;
    if (!(px.x >= -0.5 && px.y >= -0.5 && px.x <= c7.x - 0.5 && px.y <= c7.y - 0.5)) continue;
    float facing = -dot(n, to_point);
    if (!(facing > 0.0)) continue;

    // Shadow: the texel of the camera's distance map that holds the point's direction.
    bool cube = c2.w > 0.5;
    int layer = int(c1.w);
    mat3 F = mat3(1.0);
    vec4 fm = cams[b + 9];
    int size = map_size;
#if CUBE
    if (cube) {
      vec3 a = abs(pc);
      int face = a.x >= a.y && a.x >= a.z ? (pc.x > 0.0 ? 0 : 1)
               : a.y >= a.z              ? (pc.y > 0.0 ? 2 : 3)
                                         : (pc.z > 0.0 ? 4 : 5);
      F = face_R[face];
      layer += face;
      fm = vec4(1.0, 1.0, 0.0, 0.0);
      size = cube_size;
    }
#endif
    vec3 pf = F * pc;
    vec2 q = pf.xy / pf.z;
    vec2 uv = 0.5 * vec2(fm.x * q.x - fm.z, fm.y * q.y - fm.w) + 0.5;
    ivec2 tc = clamp(ivec2(floor(uv * float(size))), ivec2(0), ivec2(size - 1));
#if CUBE
    float stored = cube ? texelFetch(cubes, ivec3(tc, layer), 0).x
                        : texelFetch(maps, ivec3(tc, layer), 0).x;
#else
    float stored = texelFetch(maps, ivec3(tc, layer), 0).x;
#endif
    bool lit = false;
    if (shadow_mode != 1) {
      // Distance within how much it can change between the point and its texel's centre on the
      // point's own plane: the texel's size there times the tangent of the incidence.
      float texel = 2.0 / (min(fm.x, fm.y) * float(size));
      float cos_i = facing / dist;
      float tan_i = sqrt(max(1.0 - cos_i * cos_i, 0.0)) / max(cos_i, 1e-6);
      float w = texel * dist * sqrt(1.0 + dot(q, q));
      float bias = bias_scale * (w * (0.5 + 0.75 * min(tan_i, 10.0)) + 1e-5 * dist);
      lit = dist <= stored + bias;
    }
    if (!lit && shadow_mode != 0) {
      // Receiver plane: where the texel's centre ray meets the point's own plane. A planar
      // receiver compares with itself exactly there, at any incidence (no acne).
      vec2 qc = (((vec2(tc) + 0.5) / float(size)) * 2.0 - 1.0 + fm.zw) / fm.xy;
      vec3 rc = transpose(R) * (transpose(F) * vec3(qc, 1.0));
      float nr = dot(n, rc);
      float plane = nr < 0.0 ? dot(n, to_point) / nr * length(rc) : 3e38;
      lit = stored >= plane - bias_scale * 1e-4 * dist;
    }
    if (!lit) continue;

    float weight = 1.0;
#if GRID
    {
      // Ray differentials of the hit point on its plane, then the camera pixel's change per
      // output pixel by central differences of the projection along them.
      vec2 pp = gl_FragCoord.xy - 0.5;
      vec3 D = view_Rt[2] + ((pp.x - view_f.y) / view_f.x) * view_Rt[0] +
               ((pp.y - view_f.z) / view_f.x) * view_Rt[1];
      float len = length(D);
      vec3 d = D / len;
      vec3 Dx = view_Rt[0] / view_f.x, Dy = view_Rt[1] / view_f.x;
      vec3 ddx = (Dx - d * dot(d, Dx)) / len, ddy = (Dy - d * dot(d, Dy)) / len;
      float t = length(g.xyz - eye);
      float nd = dot(n, d);
      vec3 dXdx = t * (ddx - (dot(n, ddx) / nd) * d);
      vec3 dXdy = t * (ddy - (dot(n, ddy) / nd) * d);
      vec2 pa, pb, pc2, pd;
      float du = 0.0, dv = 0.0;
      if (Project(L, R * (X + 0.5 * dXdx) + c3.xyz, pa) &&
          Project(L, R * (X - 0.5 * dXdx) + c3.xyz, pb) &&
          Project(L, R * (X + 0.5 * dXdy) + c3.xyz, pc2) &&
          Project(L, R * (X - 0.5 * dXdy) + c3.xyz, pd)) {
        vec2 jx = pa - pb, jy = pc2 - pd;
        du = length(vec2(jx.x, jy.x));
        dv = length(vec2(jx.y, jy.y));
      }
      weight = GridLightWeight(true, px, vec2(du, dv), grid_n, grid_fill, line_width);
    }
#endif
    vec4 c8 = cams[b + 8];
    sum += weight * c8.xyz;
    int bit = int(c8.w);
    if (bit < 32) mask.x |= 1u << uint(bit);
    else if (bit < 64) mask.y |= 1u << uint(bit - 32);
  }
  o_light = vec4(sum, 0.0);
  o_mask = mask;
}
)";

const char* kComposeFragment = R"(#version 330 core
uniform sampler2D g_position_tex;
uniform sampler2D g_normal_tex;
uniform sampler2D g_albedo_tex;
uniform sampler2D light_tex;
uniform int surface;  // 0 material, 1 black, 2 hidden line, 3 contours
uniform float ambient;
uniform vec3 background;
uniform vec3 eye;
uniform float line_grey;
layout(location = 0) out vec4 o_color;
// Contours as render/frame.cpp's Finish: for the pair (p, q), q right of or below p, the line
// weight it gives `self` (p when first, q otherwise). Missing surface on one side: the surface
// pixel; another object, or q's depth more than 5 % of p's from where q's ray meets p's plane: the
// nearer pixel; normals more than 30 degrees apart: both, at half weight.
float PairContour(ivec2 p, ivec2 q, bool first) {
  ivec2 size = textureSize(g_position_tex, 0);
  if (q.x >= size.x || q.y >= size.y || p.x < 0 || p.y < 0) return 0.0;
  vec4 gp = texelFetch(g_position_tex, p, 0), gq = texelFetch(g_position_tex, q, 0);
  bool hp = gp.w >= 0.0, hq = gq.w >= 0.0;
  if (!hp && !hq) return 0.0;
  if (hp != hq) return (first ? hp : hq) ? 1.0 : 0.0;
  vec3 np = texelFetch(g_normal_tex, p, 0).xyz, nq = texelFetch(g_normal_tex, q, 0).xyz;
  float tp = length(gp.xyz - eye), tq = length(gq.xyz - eye);
  bool jump = texelFetch(g_albedo_tex, p, 0).w != texelFetch(g_albedo_tex, q, 0).w;
  if (!jump) {
    vec3 dp = (gp.xyz - eye) / tp, dq = (gq.xyz - eye) / tq;
    float denom = dot(np, dq);
    if (denom != 0.0) {
      float predicted = tp * dot(np, dp) / denom;
      jump = !(predicted > 0.0) || abs(predicted - tq) > 0.05 * tp;
    } else {
      jump = true;
    }
  }
  if (jump) return (first == (tp <= tq)) ? 1.0 : 0.0;
  return dot(np, nq) < 0.8660254037844387 ? 0.5 : 0.0;
}
void main() {
  ivec2 ip = ivec2(gl_FragCoord.xy);
  vec4 g = texelFetch(g_position_tex, ip, 0);
  if (g.w < 0.0) {
    o_color = vec4(background, 1.0);
    return;
  }
  vec3 L = texelFetch(light_tex, ip, 0).xyz;
  if (surface == 2) {
    float a = texelFetch(g_normal_tex, ip, 0).w;
    o_color = vec4(mix(L, vec3(line_grey), a), 1.0);
    return;
  }
  if (surface == 3) {
    float a = max(max(PairContour(ip, ip + ivec2(1, 0), true),
                      PairContour(ip - ivec2(1, 0), ip, false)),
                  max(PairContour(ip, ip + ivec2(0, 1), true),
                      PairContour(ip - ivec2(0, 1), ip, false)));
    o_color = vec4(mix(L, vec3(line_grey), a), 1.0);
    return;
  }
  if (surface != 0) {
    o_color = vec4(L, 1.0);
    return;
  }
  vec3 n = texelFetch(g_normal_tex, ip, 0).xyz;
  vec3 albedo = texelFetch(g_albedo_tex, ip, 0).xyz;
  float cos_eye = dot(n, normalize(g.xyz - eye));
  o_color = vec4(albedo * L + ambient * (0.4 + 0.6 * abs(cos_eye)) * albedo, 1.0);
}
)";

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

bool IsCube(const Camera& cam) { return cam.model.max_field_angle() >= kMaxPerspectiveFieldAngle; }

// Batches of enabled cameras in rig order, each within the map memory budget and the uniform
// block; each batch is one light pass over the G-buffer with all its maps bound.
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
};

// (sx, sy, ox, oy) with ndc = (sx x / z - ox, sy y / z - oy) mapping `bounds` onto [-1, 1]^2.
Eigen::Vector4d MapCoefficients(const Eigen::Vector4d& b) {
  return Eigen::Vector4d(2 / (b(1) - b(0)), 2 / (b(3) - b(2)), (b(0) + b(1)) / (b(1) - b(0)),
                         (b(2) + b(3)) / (b(3) - b(2)));
}

// Camera `index` of the rig as the light shader reads it (kLightFragment's c0 .. c9).
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
      {light.x(), light.y(), light.z(), double(std::min(index, 64))},
      {map(0), map(1), map(2), map(3)},
  };
  for (int i = 0; i < kCameraVec4; ++i)
    for (int j = 0; j < 4; ++j) out[4 * i + j] = float(v[i][j]);
}

}  // namespace

// ------------------------------------------------------------------------------------------

std::pair<double, double> DepthRangeInPyramid(const TriangleMesh& mesh,
                                              const Eigen::Isometry3d& camera_from_world,
                                              const Eigen::Vector4d& bounds) {
  // Inward plane normals through the apex: x - x_min z >= 0, x_max z - x >= 0, ...
  const std::array<Vec3, 4> planes = {Vec3(1, 0, -bounds(0)), Vec3(-1, 0, bounds(1)),
                                      Vec3(0, 1, -bounds(2)), Vec3(0, -1, bounds(3))};
  double zmin = std::numeric_limits<double>::infinity(), zmax = -zmin;
  std::vector<Vec3> camera_vertices(mesh.vertices.size());
  for (std::size_t i = 0; i < mesh.vertices.size(); ++i)
    camera_vertices[i] = camera_from_world * mesh.vertices[i];
  std::array<Vec3, 16> poly, next;
  for (const Eigen::Vector3i& tri : mesh.triangles) {
    int count = 3;
    for (int k = 0; k < 3; ++k) poly[k] = camera_vertices[tri[k]];
    bool all_inside = true;
    for (const Vec3& p : planes) {
      int outside = 0;
      for (int k = 0; k < 3; ++k) outside += p.dot(poly[k]) < 0;
      if (outside == 3) {
        count = 0;
        break;
      }
      all_inside &= outside == 0;
    }
    if (count == 0) continue;
    if (!all_inside) {
      // Sutherland-Hodgman against the four planes.
      for (const Vec3& p : planes) {
        int out = 0;
        for (int k = 0; k < count; ++k) {
          const Vec3& a = poly[k];
          const Vec3& b = poly[(k + 1) % count];
          const double da = p.dot(a), db = p.dot(b);
          if (da >= 0) next[out++] = a;
          if ((da >= 0) != (db >= 0)) next[out++] = a + (da / (da - db)) * (b - a);
        }
        count = out;
        poly = next;
        if (count == 0) break;
      }
    }
    for (int k = 0; k < count; ++k) {
      zmin = std::min(zmin, poly[k].z());
      zmax = std::max(zmax, poly[k].z());
    }
  }
  return {zmin, zmax};
}

struct GlRenderer::Impl {
  TriangleMesh mesh;  // world, double: the depth ranges
  Vec3 origin = Vec3::Zero();
  double scene_scale = 1.0;
  GLsizei vertex_count = 0;
  GLuint vao = 0, vbo = 0;
  GLuint gbuffer_program = 0, shadow_program = 0, compose_program = 0;
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

  // Distance maps: perspective maps (one layer per camera) and cubes (six layers per camera),
  // with the camera each layer group was last drawn for (reused while it stays the same).
  int map_size = 0, cube_size = 0;
  int map_layers = 0, cube_layers = 0;
  GLuint shadow_fbo = 0, maps = 0, cubes = 0, map_depth = 0, cube_depth = 0;
  std::vector<std::optional<Camera>> map_camera, cube_camera;

  void FreeViewTargets() {
    GLuint textures[] = {g_position, g_normal, g_albedo,     light_accum,
                         mask[0],    mask[1],  compose_color};
    glDeleteTextures(7, textures);
    glDeleteRenderbuffers(1, &g_depth);
    GLuint fbos[] = {g_fbo, light_fbo[0], light_fbo[1], compose_fbo};
    glDeleteFramebuffers(4, fbos);
    width = height = 0;
  }

  void EnsureViewTargets(int w, int h) {
    if (w == width && h == height) return;
    FreeViewTargets();
    width = w;
    height = h;
    g_position = MakeTexture(GL_RGBA32F, w, h, GL_RGBA, GL_FLOAT);
    g_normal = MakeTexture(GL_RGBA32F, w, h, GL_RGBA, GL_FLOAT);
    g_albedo = MakeTexture(GL_RGBA32F, w, h, GL_RGBA, GL_FLOAT);
    glGenRenderbuffers(1, &g_depth);
    glBindRenderbuffer(GL_RENDERBUFFER, g_depth);
    glRenderbufferStorage(GL_RENDERBUFFER, GL_DEPTH_COMPONENT32F, w, h);
    glGenFramebuffers(1, &g_fbo);
    glBindFramebuffer(GL_FRAMEBUFFER, g_fbo);
    glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, g_position, 0);
    glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT1, GL_TEXTURE_2D, g_normal, 0);
    glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT2, GL_TEXTURE_2D, g_albedo, 0);
    glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, g_depth);
    CheckFramebuffer("G-buffer");

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
    FreeViewTargets();
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
    for (GLuint p : {gbuffer_program, shadow_program, compose_program}) glDeleteProgram(p);
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
      if (cube) {
        const double axis_angle = std::acos(std::clamp(kCube[i].row(2).z(), -1.0, 1.0));
        if (axis_angle - std::atan(std::sqrt(2.0)) >= cam.model.max_field_angle()) continue;
      }
      Eigen::Isometry3d face_from_world = Eigen::Isometry3d::Identity();
      face_from_world.linear() = face_from_camera * cfw.linear();
      face_from_world.translation() = face_from_camera * cfw.translation();
      auto range = DepthRangeInPyramid(mesh, face_from_world, bounds);
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
    auto range = DepthRangeInPyramid(mesh, cfw, bounds);
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
    SetVec3(gbuffer_program, "eye", eye.rel);
    glUniform1i(Loc(gbuffer_program, "edges"), options.surface == Surface::kHiddenLine ? 1 : 0);
    glUniform1f(Loc(gbuffer_program, "line_width"), float(options.line_width_px));
    glUniform1i(Loc(gbuffer_program, "albedo_tex"), 0);
    glActiveTexture(GL_TEXTURE0);
    glBindVertexArray(vao);
    for (const Draw& d : draws) {
      glUniform1i(Loc(gbuffer_program, "textured"),
                  d.texture != 0 && options.surface == Surface::kMaterial ? 1 : 0);
      glBindTexture(GL_TEXTURE_2D, d.texture);
      glDrawArrays(GL_TRIANGLES, d.first, d.count);
    }
  }

  // Draws the distance maps of a batch's cameras not kept from the last frame and sets each
  // camera's layer. Returns the maps drawn.
  int DrawBatchMaps(const Rig& rig, const Batch& batch, bool keep, const GlRenderOptions& options,
                    std::vector<int>& layer) {
    int maps_drawn = 0;
    int next_map = 0, next_cube = 0;
    for (std::size_t i = 0; i < batch.cameras.size(); ++i) {
      const Camera& cam = rig.cameras[batch.cameras[i]];
      const bool cube = IsCube(cam);
      layer[i] = cube ? next_cube++ : next_map++;
      std::optional<Camera>& held = cube ? cube_camera[layer[i]] : map_camera[layer[i]];
      if (held && SameCameraGeometry(*held, cam)) continue;
      maps_drawn += DrawMaps(cam, cube, layer[i]);
      if (keep && options.reuse_maps)
        held = cam;
      else
        held.reset();
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

  // Reads the composed colour, the surface hits and (up to 64 cameras) mask `src` back.
  GlImage ReadBack(int W, int H, int src, int camera_count) {
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
    if (camera_count <= 64) {
      std::vector<GLuint> bits(2 * pixels);
      glBindFramebuffer(GL_FRAMEBUFFER, light_fbo[src]);
      glReadBuffer(GL_COLOR_ATTACHMENT1);
      glReadPixels(0, 0, W, H, GL_RG_INTEGER, GL_UNSIGNED_INT, bits.data());
      image.cameras.resize(pixels);
      for (std::size_t i = 0; i < pixels; ++i)
        image.cameras[i] = uint64_t(bits[2 * i]) | (uint64_t(bits[2 * i + 1]) << 32);
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
  m.LightProgram(15);  // every branch compiled once now: a shader error shows at construction
  glGenBuffers(1, &m.camera_ubo);
  glBindBuffer(GL_UNIFORM_BUFFER, m.camera_ubo);
  glBufferData(GL_UNIFORM_BUFFER, GLsizeiptr(kCameraVec4 * kMaxBatch * 4 * sizeof(float)), nullptr,
               GL_DYNAMIC_DRAW);
}

GlRenderer::~GlRenderer() = default;

std::size_t GlRenderer::triangle_count() const { return impl_->mesh.triangles.size(); }

GlImage GlRenderer::Render(const Rig& rig, const RenderView& view, const GlRenderOptions& options,
                           GlFrameStats* stats) {
  using Clock = std::chrono::steady_clock;
  const auto start = Clock::now();
  Impl& m = *impl_;
  if (view.camera >= 0)
    throw std::invalid_argument(
        "GlRenderer: camera's-eye views (RenderView::camera) are not drawn on the GPU yet; use "
        "the CPU renderer (render/render.h)");
  GLint max_size = 0;
  glGetIntegerv(GL_MAX_TEXTURE_SIZE, &max_size);
  if (view.width <= 0 || view.height <= 0 || view.width > max_size || view.height > max_size)
    throw std::invalid_argument("GlRenderer: the image size must be 1 .. " +
                                std::to_string(max_size) + " pixels per side");
  if (!(view.fov_deg > 0 && view.fov_deg < 180))
    throw std::invalid_argument("GlRenderer: fov must be in (0, 180) degrees");
  const auto pose = LookAt(view.from, view.at, view.up);
  if (!pose)
    throw std::invalid_argument(
        "GlRenderer: 'at' equals 'from', or 'up' is parallel to the viewing direction");
  if (options.shadow_map_size < 512 || options.shadow_map_size > 4096)
    throw std::invalid_argument("GlRenderer: shadow_map_size must be 512 .. 4096 (is " +
                                std::to_string(options.shadow_map_size) + ")");
  if (options.shadow_map_size > max_size)
    throw std::invalid_argument("GlRenderer: this GL's textures are at most " +
                                std::to_string(max_size) + " texels per side; shadow_map_size is " +
                                std::to_string(options.shadow_map_size));
  GLint max_layers = 0;
  glGetIntegerv(GL_MAX_ARRAY_TEXTURE_LAYERS, &max_layers);
  const int W = view.width, H = view.height;
  const int camera_count = int(rig.cameras.size());

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
  const double f = 0.5 * W / std::tan(0.5 * view.fov_deg * kPi / 180.0);
  const Vec3 eye_rel = view.from - m.origin;
  const FrameEye eye{W, H, *pose, f, eye_rel};
  m.DrawGBuffer(view, eye, options);

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
  for (const Batch& batch : batches) {
    // 2. The batch's distance maps (those not kept from the last frame).
    if (stats) glFinish();
    const auto shadow_start = Clock::now();
    std::vector<int> layer(batch.cameras.size());
    maps_drawn += m.DrawBatchMaps(rig, batch, keep, options, layer);
    if (stats) {
      glFinish();
      shadow_seconds += std::chrono::duration<double>(Clock::now() - shadow_start).count();
    }

    // 3. The batch's light over the G-buffer, in one pass.
    const auto light_start = Clock::now();
    src = m.DrawBatchLight(rig, batch, layer, eye, options, brightness, src, block);
    if (stats) {
      glFinish();
      light_seconds += std::chrono::duration<double>(Clock::now() - light_start).count();
    }
  }

  // 4. Compose.
  m.Compose(eye, options);
  if (stats) glFinish();
  const auto drawn = Clock::now();

  // 5. Read back.
  GlImage image = m.ReadBack(W, H, src, camera_count);
  const GLenum error = glGetError();
  if (error != GL_NO_ERROR)
    throw std::runtime_error("GlRenderer: GL error " + std::to_string(error) + " in a frame");
  if (stats) {
    stats->shadow_seconds = shadow_seconds;
    stats->light_seconds = light_seconds;
    stats->total_seconds = std::chrono::duration<double>(drawn - start).count();
    stats->readback_seconds = std::chrono::duration<double>(Clock::now() - drawn).count();
    stats->shadow_maps = maps_drawn;
    stats->light_passes = int(batches.size());
  }
  return image;
}

std::vector<double> GlCameraLightWeights(const LightRule& rule,
                                         const std::vector<CameraAtPoint>& points) {
  // One fragment per input: (u, v, du, dv) and (sees, projects) from two float textures, the
  // weight into a float target.
  static const char* kFragment = R"(#version 330 core
uniform sampler2D coords;
uniform sampler2D flags;
uniform int grid;
uniform float n;
uniform float fill;
uniform float width;
layout(location = 0) out vec4 o_weight;
// @LIGHT_RULE@
void main() {
  ivec2 ip = ivec2(gl_FragCoord.xy);
  vec4 c = texelFetch(coords, ip, 0);
  vec4 f = texelFetch(flags, ip, 0);
  float w = 0.0;
  if (f.x > 0.5) w = grid == 1 ? GridLightWeight(f.y > 0.5, c.xy, c.zw, n, fill, width) : 1.0;
  o_weight = vec4(w, 0.0, 0.0, 1.0);
}
)";
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
  const GLuint program = Link(kFullScreenVertex, WithLightRule(kFragment).c_str(), "light rule");
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
