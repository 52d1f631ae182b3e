#include "app/report_images.h"

#include <png.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace pandora::app {

Raster SliceRaster(const FieldSlice& slice, double min, double max, int scale) {
  scale = std::max(1, scale);
  Raster r;
  r.width = slice.width * scale;
  r.height = slice.height * scale;
  r.rgb.assign(3 * static_cast<std::size_t>(r.width) * r.height, 0);
  const double span = max > min ? max - min : 1.0;
  for (int row = 0; row < slice.height; ++row)
    for (int col = 0; col < slice.width; ++col) {
      const std::size_t o = static_cast<std::size_t>(row) * slice.width + col;
      Rgb8 c = kOutsideRegionColor;
      if (slice.inside[o]) c = slice.has_value[o] ? Viridis((slice.values[o] - min) / span) : kNoValueColor;
      for (int dy = 0; dy < scale; ++dy)
        for (int dx = 0; dx < scale; ++dx) r.Set(col * scale + dx, row * scale + dy, c);
    }
  return r;
}

std::string EncodePng(const Raster& raster) {
  if (raster.width <= 0 || raster.height <= 0 ||
      raster.rgb.size() != 3 * static_cast<std::size_t>(raster.width) * raster.height)
    throw std::invalid_argument("EncodePng: empty raster or wrong buffer size");
  png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, nullptr, nullptr, nullptr);
  if (!png) throw std::runtime_error("libpng: cannot create a write struct");
  png_infop info = png_create_info_struct(png);
  std::string out;
  if (!info || setjmp(png_jmpbuf(png))) {
    png_destroy_write_struct(&png, info ? &info : nullptr);
    throw std::runtime_error("libpng: encoding failed");
  }
  png_set_write_fn(
      png, &out,
      [](png_structp p, png_bytep data, png_size_t size) {
        static_cast<std::string*>(png_get_io_ptr(p))->append(reinterpret_cast<const char*>(data), size);
      },
      [](png_structp) {});
  png_set_IHDR(png, info, raster.width, raster.height, 8, PNG_COLOR_TYPE_RGB, PNG_INTERLACE_NONE,
               PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
  png_set_sRGB(png, info, PNG_sRGB_INTENT_PERCEPTUAL);
  png_write_info(png, info);
  for (int y = 0; y < raster.height; ++y)
    png_write_row(png, const_cast<png_bytep>(raster.rgb.data() + 3 * static_cast<std::size_t>(y) * raster.width));
  png_write_end(png, nullptr);
  png_destroy_write_struct(&png, &info);
  return out;
}

std::string Base64(const std::string& bytes) {
  static constexpr char kAlphabet[] =
      "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  out.reserve((bytes.size() + 2) / 3 * 4);
  std::size_t i = 0;
  for (; i + 2 < bytes.size(); i += 3) {
    const unsigned v = (static_cast<unsigned char>(bytes[i]) << 16) |
                       (static_cast<unsigned char>(bytes[i + 1]) << 8) |
                       static_cast<unsigned char>(bytes[i + 2]);
    out += kAlphabet[v >> 18];
    out += kAlphabet[(v >> 12) & 63];
    out += kAlphabet[(v >> 6) & 63];
    out += kAlphabet[v & 63];
  }
  if (i < bytes.size()) {
    unsigned v = static_cast<unsigned char>(bytes[i]) << 16;
    if (i + 1 < bytes.size()) v |= static_cast<unsigned char>(bytes[i + 1]) << 8;
    out += kAlphabet[v >> 18];
    out += kAlphabet[(v >> 12) & 63];
    out += i + 1 < bytes.size() ? kAlphabet[(v >> 6) & 63] : '=';
    out += '=';
  }
  return out;
}

std::string DataUri(const std::string& mime, const std::string& bytes) {
  return "data:" + mime + ";base64," + Base64(bytes);
}

}  // namespace pandora::app
