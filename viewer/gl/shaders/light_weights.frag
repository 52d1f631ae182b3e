#version 330 core
// GlCameraLightWeights: the light rule of one camera at each input point, one fragment per point:
// (u, v, du, dv) and (sees, projects) from two float textures, the weight into a float target.
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
