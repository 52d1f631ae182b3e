// OpenEXR files (the only file that includes OpenEXR): RGB plus the per-pixel layers.
#include <OpenEXR/ImfChannelList.h>
#include <OpenEXR/ImfFrameBuffer.h>
#include <OpenEXR/ImfHeader.h>
#include <OpenEXR/ImfInputFile.h>
#include <OpenEXR/ImfOutputFile.h>
#include <OpenEXR/ImfStringAttribute.h>

#include <cstdio>
#include <string>
#include <vector>

#include "analysis/util/atomic_file.h"
#include "analysis/util/error.h"
#include "render/render.h"

namespace pandora {

void WriteExr(const Image& image, const std::string& path, int rig_cameras) {
  const int W = image.width, H = image.height;
  const std::size_t pixels = std::size_t(W) * H;
  const bool mask = !image.cameras.empty();
  bool consistent =
      W > 0 && H > 0 && image.rgb.size() == 3 * pixels && (!mask || image.cameras.size() == pixels);
  for (const ImageLayer& layer : ImageFloatLayers())
    consistent = consistent && (image.*layer.values).size() == pixels;
  if (!consistent)
    throw std::invalid_argument(
        "WriteExr: empty or inconsistent image (every layer needs a value per pixel)");
  if (mask != (rig_cameras <= Image::kMaxMaskCameras))
    throw std::invalid_argument(
        mask ? "WriteExr: a cameras layer for a rig of more than 64 cameras"
             : "WriteExr: the image has no cameras layer, but the rig has at most 64 cameras");
  // The camera set: a bitmask for rigs of at most 64 cameras; larger rigs have none (coverage
  // still counts them all).
  std::vector<uint32_t> lo, hi;
  const bool want_hi = mask && rig_cameras > 32;
  if (mask) {
    lo.resize(pixels);
    for (std::size_t i = 0; i < pixels; ++i) lo[i] = uint32_t(image.cameras[i] & 0xffffffffu);
  }
  if (want_hi) {
    hi.resize(pixels);
    for (std::size_t i = 0; i < pixels; ++i) hi[i] = uint32_t(image.cameras[i] >> 32);
  }
  Imf::Header header(W, H);
  header.compression() = Imf::ZIP_COMPRESSION;
  const std::string cameras_meaning =
      mask ? "cameras: bitmask (bit c = rig camera c, bits 32-63 in cameras_hi)"
           : "cameras: not written, the rig has " + std::to_string(rig_cameras) +
                 " cameras (a bitmask holds 64; coverage counts them all)";
  std::string layers = "R,G,B: linear light";
  for (const ImageLayer& layer : ImageFloatLayers()) {
    layers += std::string("; ") + layer.name + ": " + layer.meaning;
    if (layer.values == &Image::coverage) layers += "; " + cameras_meaning;
  }
  header.insert("pandora_layers", Imf::StringAttribute(layers));
  Imf::FrameBuffer fb;
  const std::size_t fs = sizeof(float), us = sizeof(uint32_t);
  auto add_float = [&](const char* name, const float* data, std::size_t x_stride) {
    header.channels().insert(name, Imf::Channel(Imf::FLOAT));
    fb.insert(name, Imf::Slice(Imf::FLOAT, (char*)data, x_stride * fs, x_stride * fs * W));
  };
  add_float("R", image.rgb.data() + 0, 3);
  add_float("G", image.rgb.data() + 1, 3);
  add_float("B", image.rgb.data() + 2, 3);
  for (const ImageLayer& layer : ImageFloatLayers())
    add_float(layer.name, (image.*layer.values).data(), 1);
  if (mask) {
    header.channels().insert("cameras", Imf::Channel(Imf::UINT));
    fb.insert("cameras", Imf::Slice(Imf::UINT, (char*)lo.data(), us, us * W));
  }
  if (want_hi) {
    header.channels().insert("cameras_hi", Imf::Channel(Imf::UINT));
    fb.insert("cameras_hi", Imf::Slice(Imf::UINT, (char*)hi.data(), us, us * W));
  }
  const std::string tmp = TemporaryPath(path);
  try {
    Imf::OutputFile file(tmp.c_str(), header);
    file.setFrameBuffer(fb);
    file.writePixels(H);
  } catch (const std::exception& e) {
    std::remove(tmp.c_str());
    throw InputError(path, "", std::string("cannot write the EXR file: ") + e.what(),
                     "check that the output folder exists and is writable");
  }
  CommitTemporary(path);
}

Image ReadExr(const std::string& path) {
  try {
    Imf::InputFile file(path.c_str());
    const Imath::Box2i dw = file.header().dataWindow();
    Image image;
    const int W = dw.max.x - dw.min.x + 1, H = dw.max.y - dw.min.y + 1;
    image.width = W;
    image.height = H;
    const std::size_t pixels = std::size_t(W) * H;
    image.rgb.assign(3 * pixels, 0.0f);
    for (const ImageLayer& layer : ImageFloatLayers()) (image.*layer.values).assign(pixels, 0.0f);
    std::vector<uint32_t> lo(pixels, 0), hi(pixels, 0);
    const std::size_t fs = sizeof(float), us = sizeof(uint32_t);
    // Slices are addressed from the data window's origin.
    const std::ptrdiff_t origin = std::ptrdiff_t(dw.min.x) + std::ptrdiff_t(dw.min.y) * W;
    Imf::FrameBuffer fb;
    auto add_float = [&](const char* name, float* data, std::size_t x_stride) {
      fb.insert(name, Imf::Slice(Imf::FLOAT, (char*)(data - origin * x_stride), x_stride * fs,
                                 x_stride * fs * W, 1, 1, 0.0));
    };
    add_float("R", image.rgb.data() + 0, 3);
    add_float("G", image.rgb.data() + 1, 3);
    add_float("B", image.rgb.data() + 2, 3);
    for (const ImageLayer& layer : ImageFloatLayers())
      add_float(layer.name, (image.*layer.values).data(), 1);
    fb.insert("cameras", Imf::Slice(Imf::UINT, (char*)(lo.data() - origin), us, us * W));
    fb.insert("cameras_hi", Imf::Slice(Imf::UINT, (char*)(hi.data() - origin), us, us * W));
    file.setFrameBuffer(fb);
    file.readPixels(dw.min.y, dw.max.y);
    // Files of rigs over 64 cameras have no camera set: `cameras` stays empty.
    if (file.header().channels().findChannel("cameras")) {
      image.cameras.resize(pixels);
      for (std::size_t i = 0; i < pixels; ++i) image.cameras[i] = (uint64_t(hi[i]) << 32) | lo[i];
    }
    image.object.assign(pixels, -1);
    return image;
  } catch (const std::exception& e) {
    throw InputError(path, "", std::string("cannot read the EXR file: ") + e.what());
  }
}

}  // namespace pandora
