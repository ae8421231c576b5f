#pragma once
// RGBA8 images, PNG I/O (libpng) and the image comparison used by golden tests.
#include <cstdint>
#include <string>
#include <vector>

#include "hysim/cutting/result.hpp"  // header only: Status / Result / Error

namespace hysim::render {

// 8-bit RGBA, rows top to bottom, no padding between rows.
struct Image {
  int width = 0;
  int height = 0;
  std::vector<std::uint8_t> rgba;  // width*height*4

  Image() = default;
  Image(int w, int h) : width(w), height(h), rgba(static_cast<std::size_t>(w) * h * 4, 0) {}
  bool valid() const {
    return width > 0 && height > 0 && rgba.size() == static_cast<std::size_t>(width) * height * 4;
  }
  // Pointer to the 4 bytes of pixel (x, y); (0, 0) is the top-left corner.
  const std::uint8_t* pixel(int x, int y) const {
    return rgba.data() + (static_cast<std::size_t>(y) * width + x) * 4;
  }
  std::uint8_t* pixel(int x, int y) {
    return rgba.data() + (static_cast<std::size_t>(y) * width + x) * 4;
  }
};

// Writes an 8-bit RGBA PNG. The error names the path and what went wrong.
hysim::Status writePng(const std::string& path, const Image& image);

// Reads any PNG (grey, palette, 16 bit, ...) converted to 8-bit RGBA.
hysim::Result<Image> readPng(const std::string& path);

// How far two images of the same size are apart, per channel (R, G, B; alpha ignored).
struct ImageDiff {
  double mean_abs_diff = 0.0;     // mean over pixels and the 3 colour channels, 0..255
  int max_abs_diff = 0;           // largest channel difference
  double fraction_over = 0.0;     // fraction of pixels with some channel differing > threshold
  Image diff;                     // |a-b| per channel, amplified x4, for people to look at
};

// Compares `a` and `b`; `threshold` is the per-channel difference counted in
// fraction_over. Images of different size give an error.
hysim::Result<ImageDiff> compareImages(const Image& a, const Image& b, int threshold);

}  // namespace hysim::render
