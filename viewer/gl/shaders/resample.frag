#version 330 core
// A camera's-eye view's G-buffer (GlRenderer, RenderView::camera): per output pixel, the camera's
// own ray through it (the CPU's unprojection, distortion included, in `eye_dirs`) is looked up in
// the cover G-buffer, a pinhole G-buffer of the same camera drawn finer than the output over the
// lens's whole field. Of the triangles its 3 x 3 nearest cover texels show, the nearest one the
// ray itself hits (an exact ray-triangle test on the triangle's corners) gives the point, normal,
// material and object: exact but where a triangle smaller than a cover texel hides between them.
// Where none is hit, the ray meets the plane of the nearest texel's triangle.
uniform sampler2D eye_dirs;        // camera-frame unit direction; w: 1 inside the lens's domain
uniform sampler2D cover_position;  // as g_position (xyz relative to the scene's centre, w < 0: none)
uniform sampler2D cover_normal;
uniform sampler2D cover_albedo;
uniform vec4 cover_map;    // (sx, sy, ox, oy): ndc = (sx x / z - ox, sy y / z - oy)
uniform ivec2 cover_size;
uniform mat3 eye_R;        // world_from_camera rotation
uniform vec3 eye;          // the camera's centre relative to the scene's centre
uniform samplerBuffer triangles;  // 3 texels per triangle (VBO order): corners, relative
uniform int use_triangles;        // 0: the GL's texture buffers are too small for the scene
uniform float min_distance;       // primary rays start this far from the centre (the CPU's)

// The ray eye + t d against triangle `tri` (Moller-Trumbore, barycentric tolerance 1e-5).
bool Hit(int tri, vec3 d, out float t) {
  vec3 a = texelFetch(triangles, 3 * tri).xyz;
  vec3 e1 = texelFetch(triangles, 3 * tri + 1).xyz - a, e2 = texelFetch(triangles, 3 * tri + 2).xyz - a;
  vec3 p = cross(d, e2);
  float det = dot(e1, p);
  t = 0.0;
  if (abs(det) < 1e-30) return false;
  float inv = 1.0 / det;
  vec3 s = eye - a;
  float u = dot(s, p) * inv;
  vec3 q = cross(s, e1);
  float v = dot(d, q) * inv;
  if (u < -1e-5 || v < -1e-5 || u + v > 1.0 + 1e-5) return false;
  t = dot(e2, q) * inv;
  return t > min_distance;
}
layout(location = 0) out vec4 g_position;
layout(location = 1) out vec4 g_normal;
layout(location = 2) out vec4 g_albedo;
void main() {
  ivec2 ip = ivec2(gl_FragCoord.xy);
  vec4 e = texelFetch(eye_dirs, ip, 0);
  g_position = vec4(0.0, 0.0, 0.0, -1.0);
  g_normal = vec4(0.0);
  g_albedo = vec4(0.0);
  if (e.w < 0.5 || !(e.z > 0.0)) return;
  vec2 q = e.xy / e.z;
  vec2 uv = 0.5 * vec2(cover_map.x * q.x - cover_map.z, cover_map.y * q.y - cover_map.w) + 0.5;
  ivec2 tc = ivec2(floor(uv * vec2(cover_size)));
  if (any(lessThan(tc, ivec2(0))) || any(greaterThanEqual(tc, cover_size))) return;
  vec3 d = eye_R * e.xyz;
  // The nearest triangle the ray hits among those of the 3 x 3 texels around.
  ivec2 best = ivec2(-1);
  float best_t = 3e38;
  int seen[9];
  int count = 0;
  for (int k = 0; k < 9 && use_triangles != 0; ++k) {
    ivec2 c = tc + ivec2(k % 3 - 1, k / 3 - 1);
    if (any(lessThan(c, ivec2(0))) || any(greaterThanEqual(c, cover_size))) continue;
    float w = texelFetch(cover_position, c, 0).w;
    if (w < 0.5) continue;
    int tri = int(w + 0.5) - 1;
    bool again = false;
    for (int i = 0; i < count; ++i) again = again || seen[i] == tri;
    if (again) continue;
    seen[count++] = tri;
    float t;
    if (Hit(tri, d, t) && t < best_t) {
      best_t = t;
      best = c;
    }
  }
  if (best.x >= 0) {
    g_position = vec4(eye + best_t * d, 1.0);
    g_normal = texelFetch(cover_normal, best, 0);
    g_albedo = texelFetch(cover_albedo, best, 0);
    return;
  }
  vec4 p = texelFetch(cover_position, tc, 0);
  if (p.w < 0.0) return;
  vec4 n = texelFetch(cover_normal, tc, 0);  // turned towards the camera
  float nd = dot(n.xyz, d);
  vec3 x = p.xyz;
  if (nd < 0.0) {
    float t = dot(n.xyz, p.xyz - eye) / nd;
    if (t > 0.0) x = eye + t * d;
  }
  g_position = vec4(x, 1.0);
  g_normal = n;
  g_albedo = texelFetch(cover_albedo, tc, 0);
}
