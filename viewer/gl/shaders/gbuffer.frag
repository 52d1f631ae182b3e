#version 330 core
in vec3 v_position;
flat in vec3 v_normal;
flat in vec3 v_albedo;
flat in vec2 v_tag;
in vec3 v_bary;
in vec2 v_uv;
in float v_z;
uniform vec2 depth_map;  // the cut's v_z (nothing nearer is drawn), 1 / (far - near)
uniform float min_distance;  // a camera's-eye view: nothing nearer the camera's centre is drawn
uniform vec3 eye;
uniform int textured;         // 1: albedo times the texture (bilinear, repeat, filtered in linear)
uniform sampler2D albedo_tex; // sRGB8: decoded to linear before filtering, as the CPU's texels
uniform int edges;         // 1: hidden-line mode, the drawn edges' coverage into g_normal.w
uniform float line_width;  // output pixels
uniform int first_triangle;  // the draw's first triangle: g_position.w is its index + 1 + this
layout(location = 0) out vec4 g_position;  // xyz, triangle index + 1 (-1: no surface)
layout(location = 1) out vec4 g_normal;    // turned towards the eye; w: edge coverage
layout(location = 2) out vec4 g_albedo;    // w: object index
void main() {
  // RenderView::clip_near, and the depth linear in v_z: an eye far away (plans) keeps the depth
  // test's precision, (far - near) / 2^24, instead of float's at the eye's distance.
  if (v_z < depth_map.x) discard;
  if (min_distance > 0.0 && length(v_position - eye) < min_distance) discard;
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
  g_position = vec4(v_position, float(first_triangle + gl_PrimitiveID + 1));
  g_normal = vec4(n, a);
  vec3 albedo = v_albedo;
  // The texture's row 0 is the image's top (uploaded as decoded), v = 0 its bottom: t = 1 - v.
  if (textured != 0) albedo *= texture(albedo_tex, vec2(v_uv.x, 1.0 - v_uv.y)).rgb;
  g_albedo = vec4(albedo, v_tag.x);
}
