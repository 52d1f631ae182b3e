// The light rule of render/light.h in GLSL (shared by the light pass and GlCameraLightWeights).
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
