// PNG files through libpng's simplified API (the only file that includes png.h).
#include <png.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <stdexcept>
#include <string>
#include <vector>

#include "analysis/util/atomic_file.h"
#include "analysis/util/error.h"
#include "analysis/util/input_file.h"
#include "render/colormap.h"
#include "render/render.h"

namespace pandora {

std::string EncodePngSrgb8(int width, int height, const std::vector<std::uint8_t>& rgb) {
  if (width <= 0 || height <= 0 || rgb.size() != 3 * std::size_t(width) * std::size_t(height))
    throw std::invalid_argument("EncodePngSrgb8: empty image or wrong buffer size");
  png_image png{};
  png.version = PNG_IMAGE_VERSION;
  png.width = png_uint_32(width);
  png.height = png_uint_32(height);
  png.format = PNG_FORMAT_RGB;
  // First the size, then the bytes (libpng's simplified API, in memory).
  png_alloc_size_t size = 0;
  if (!png_image_write_to_memory(&png, nullptr, &size, 0, rgb.data(), 0, nullptr)) {
    const std::string message = png.message;
    png_image_free(&png);
    throw std::runtime_error("cannot encode the PNG: " + message);
  }
  std::string bytes(size, '\0');
  if (!png_image_write_to_memory(&png, bytes.data(), &size, 0, rgb.data(), 0, nullptr)) {
    const std::string message = png.message;
    png_image_free(&png);
    throw std::runtime_error("cannot encode the PNG: " + message);
  }
  bytes.resize(size);
  return bytes;
}

std::string EncodePng(const Image& image) {
  const std::size_t pixels = std::size_t(image.width) * image.height;
  if (image.width <= 0 || image.height <= 0 || image.rgb.size() != 3 * pixels)
    throw std::invalid_argument("EncodePng: empty or inconsistent image");
  // sRGB encoding through a 65537-entry table of the transfer curve: the table's step (1/65536 in
  // linear light) moves the encoded value by at most 0.03 codes above 1/256, where it is used;
  // below, the curve is evaluated directly.
  static const std::vector<uint8_t> table = [] {
    std::vector<uint8_t> t(65537);
    for (int i = 0; i <= 65536; ++i)
      t[i] = uint8_t(std::lround(255.0 * SrgbFromLinear(i / 65536.0)));
    return t;
  }();
  std::vector<uint8_t> bytes(3 * pixels);
  for (std::size_t i = 0; i < bytes.size(); ++i) {
    const float v = image.rgb[i];
    if (!(v > 0.0f))
      bytes[i] = 0;  // also NaN
    else if (v >= 1.0f)
      bytes[i] = 255;
    else if (v < 1.0f / 256)
      bytes[i] = uint8_t(std::lround(255.0 * SrgbFromLinear(v)));
    else
      bytes[i] = table[std::size_t(std::lround(double(v) * 65536.0))];
  }
  return EncodePngSrgb8(image.width, image.height, bytes);
}

void WritePng(const Image& image, const std::string& path) {
  const std::string bytes = EncodePng(image);
  try {
    WriteFileAtomically(path, bytes);
  } catch (const InputError&) {
    throw;
  } catch (const std::exception& e) {
    throw InputError(path, "", std::string("cannot write the PNG file: ") + e.what(),
                     "check that the output folder exists and is writable");
  }
}

Image ReadPng(const std::string& path) {
  // A regular file of bounded size (a FIFO would block, /dev/zero never end).
  CheckInputFile(path, InputLimits::kImageBytes, "PNG file");
  png_image png{};
  png.version = PNG_IMAGE_VERSION;
  if (!png_image_begin_read_from_file(&png, path.c_str()))
    throw InputError(path, "", std::string("cannot read the PNG file: ") + png.message);
  // The header's size decides the allocation: a damaged or hostile header must not ask for
  // gigabytes.
  if (static_cast<std::uint64_t>(png.width) * png.height > (64ull << 20)) {
    png_image_free(&png);
    throw InputError(path, "",
                     "the PNG is " + std::to_string(png.width) + " x " +
                         std::to_string(png.height) + " pixels; at most 64 Mpx is read",
                     "scale the image down");
  }
  png.format = PNG_FORMAT_RGB;
  std::vector<uint8_t> bytes(PNG_IMAGE_SIZE(png));
  if (!png_image_finish_read(&png, nullptr, bytes.data(), 0, nullptr)) {
    const std::string message = png.message;
    png_image_free(&png);
    throw InputError(path, "", "cannot read the PNG file: " + message);
  }
  Image image;
  image.width = int(png.width);
  image.height = int(png.height);
  image.rgb.resize(bytes.size());
  for (std::size_t i = 0; i < bytes.size(); ++i)
    image.rgb[i] = float(LinearFromSrgb(bytes[i] / 255.0));
  return image;
}

}  // namespace pandora
