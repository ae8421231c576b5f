// PNG I/O through libpng's simplified API (png_image): it reports errors in a message
// buffer instead of longjmp, which is the safe way to use libpng from C++.
#include "hysim/render/image.hpp"

#include <png.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>

namespace hysim::render {

hysim::Status writePng(const std::string& path, const Image& image) {
  if (!image.valid()) {
    return hysim::Error{path + ": cannot write PNG: image is empty or its pixel buffer (" +
                        std::to_string(image.rgba.size()) + " bytes) does not match " +
                        std::to_string(image.width) + "x" + std::to_string(image.height) +
                        " RGBA"};
  }
  png_image png{};
  png.version = PNG_IMAGE_VERSION;
  png.width = static_cast<png_uint_32>(image.width);
  png.height = static_cast<png_uint_32>(image.height);
  png.format = PNG_FORMAT_RGBA;
  png.flags = PNG_IMAGE_FLAG_FAST;  // frames are written every k steps: favour speed over size
  // Through a temporary file and a rename: a run killed mid-write leaves no truncated frame.
  const std::string tmp = path + ".tmp";
  const int ok = png_image_write_to_file(&png, tmp.c_str(), 0, image.rgba.data(), image.width * 4, nullptr);
  if (!ok) {
    std::string message = path + ": cannot write PNG: " + png.message;
    png_image_free(&png);
    std::remove(tmp.c_str());
    return hysim::Error{message};
  }
  if (std::rename(tmp.c_str(), path.c_str()) != 0) {
    std::remove(tmp.c_str());
    return hysim::Error{path + ": cannot write PNG: cannot move it from '" + tmp + "'"};
  }
  return hysim::Status::Ok();
}

hysim::Result<Image> readPng(const std::string& path) {
  png_image png{};
  png.version = PNG_IMAGE_VERSION;
  if (!png_image_begin_read_from_file(&png, path.c_str())) {
    std::string message = path + ": cannot read PNG: " + png.message;
    png_image_free(&png);
    return hysim::Error{message};
  }
  png.format = PNG_FORMAT_RGBA;  // libpng converts grey, palette, 16-bit, ... to RGBA8
  Image image(static_cast<int>(png.width), static_cast<int>(png.height));
  if (!png_image_finish_read(&png, nullptr, image.rgba.data(), image.width * 4, nullptr)) {
    std::string message = path + ": cannot read PNG: " + png.message;
    png_image_free(&png);
    return hysim::Error{message};
  }
  return image;
}

hysim::Result<ImageDiff> compareImages(const Image& a, const Image& b, int threshold) {
  if (!a.valid() || !b.valid()) return hysim::Error{"compareImages: empty or malformed image"};
  if (a.width != b.width || a.height != b.height) {
    return hysim::Error{"compareImages: size differs: " + std::to_string(a.width) + "x" +
                        std::to_string(a.height) + " vs " + std::to_string(b.width) + "x" +
                        std::to_string(b.height)};
  }
  ImageDiff result;
  result.diff = Image(a.width, a.height);
  const std::size_t pixels = static_cast<std::size_t>(a.width) * a.height;
  std::uint64_t sum = 0;
  std::size_t over = 0;
  for (std::size_t p = 0; p < pixels; ++p) {
    int worst = 0;
    for (int c = 0; c < 3; ++c) {
      const int d = std::abs(int(a.rgba[p * 4 + c]) - int(b.rgba[p * 4 + c]));
      sum += static_cast<std::uint64_t>(d);
      worst = std::max(worst, d);
      result.diff.rgba[p * 4 + c] = static_cast<std::uint8_t>(std::min(255, d * 4));
    }
    result.diff.rgba[p * 4 + 3] = 255;
    result.max_abs_diff = std::max(result.max_abs_diff, worst);
    if (worst > threshold) ++over;
  }
  result.mean_abs_diff = static_cast<double>(sum) / (static_cast<double>(pixels) * 3.0);
  result.fraction_over = static_cast<double>(over) / static_cast<double>(pixels);
  return result;
}

}  // namespace hysim::render
