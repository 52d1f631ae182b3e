#version 330 core
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
