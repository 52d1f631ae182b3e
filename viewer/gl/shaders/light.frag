#version 330 core
// The light of a batch of cameras over the G-buffer, in one pass: for each pixel, each camera of
// the batch in rig order. A camera's parameters are kCameraVec4 vec4s of the uniform block (see
// PackCamera); its distance map is layer `layer` of `maps` (one perspective map) or layers
// layer .. layer + 5 of `cubes` (a cube).
// Compiled in variants (Impl::LightProgram): GRID for the grid pattern, FISHEYE, DISTORTION
// (Brown-Conrady) and CUBE only when a camera of the batch needs them. Software GL (llvmpipe)
// runs every branch of a loop body under a mask whether or not a lane takes it, so code a batch
// cannot need would cost as much as code it runs.
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
uniform int eye_table;         // 1: a camera's-eye view, its rays in eye_dirs (camera frame)
uniform sampler2D eye_dirs;    // unit direction per output pixel; w: 1 inside the lens's domain
uniform sampler2D eye_dx;      // its derivatives per output pixel (the CPU's exact ones)
uniform sampler2D eye_dy;

// The eye ray's unit direction through output pixel `ip` and its derivatives per output pixel.
void EyeRay(ivec2 ip, out vec3 d, out vec3 ddx, out vec3 ddy) {
  if (eye_table == 0) {
    vec2 pp = vec2(ip);
    vec3 D = view_Rt[2] + ((pp.x - view_f.y) / view_f.x) * view_Rt[0] +
             ((pp.y - view_f.z) / view_f.x) * view_Rt[1];
    float len = length(D);
    d = D / len;
    vec3 Dx = view_Rt[0] / view_f.x, Dy = view_Rt[1] / view_f.x;
    ddx = (Dx - d * dot(d, Dx)) / len;
    ddy = (Dy - d * dot(d, Dy)) / len;
    return;
  }
  // The lens's rays and their exact differentials (camera frame), computed on the CPU.
  d = view_Rt * texelFetch(eye_dirs, ip, 0).xyz;
  ddx = view_Rt * texelFetch(eye_dx, ip, 0).xyz;
  ddy = view_Rt * texelFetch(eye_dy, ip, 0).xyz;
}
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
      vec3 d, ddx, ddy;
      EyeRay(ip, d, ddx, ddy);
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
