#pragma once
/// \file test_options.h
/// Render options the render tests share: only the cameras' light on black surfaces and a black
/// background, without camera bodies, key or layers (so a pixel is lit exactly where a camera
/// sees).

#include "render/render.h"

namespace pandora {

inline RenderOptions LightOnlyOptions() {
  RenderOptions o;
  o.surface = Surface::kBlack;
  o.background = Vec3::Zero();
  o.overlays.cameras = false;
  o.overlays.key = false;
  o.layers = false;
  return o;
}

}  // namespace pandora
