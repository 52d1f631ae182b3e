#version 330 core
// The composed linear RGB as 8-bit sRGB for the window (GlRenderer::DrawToTexture): what the CPU
// path's ToRgba8 does per channel (analysis/util/color.cpp SrgbFromLinear, clamped to [0, 1]),
// the conversion to the RGBA8 target rounding to the nearest of the 256 levels.
uniform sampler2D color_tex;
layout(location = 0) out vec4 o_color;
float Srgb(float v) {
  v = clamp(v, 0.0, 1.0);
  return v <= 0.0031308 ? 12.92 * v : 1.055 * pow(v, 1.0 / 2.4) - 0.055;
}
void main() {
  vec3 c = texelFetch(color_tex, ivec2(gl_FragCoord.xy), 0).rgb;
  o_color = vec4(Srgb(c.r), Srgb(c.g), Srgb(c.b), 1.0);
}
