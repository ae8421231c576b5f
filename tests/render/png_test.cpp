// PNG I/O and image comparison: no GL needed.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "hysim/render/image.hpp"

namespace hr = hysim::render;
namespace fs = std::filesystem;

namespace {

fs::path outputDir() {
  fs::path dir = fs::path(HYSIM_TEST_OUTPUT_DIR) / "render";
  fs::create_directories(dir);
  return dir;
}

hr::Image gradient(int w, int h) {
  hr::Image image(w, h);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      std::uint8_t* p = image.pixel(x, y);
      p[0] = static_cast<std::uint8_t>(x * 255 / (w - 1));
      p[1] = static_cast<std::uint8_t>(y * 255 / (h - 1));
      p[2] = static_cast<std::uint8_t>((x * 7 + y * 13) & 0xff);
      p[3] = static_cast<std::uint8_t>(255 - ((x + y) & 0x7f));
    }
  }
  return image;
}

}  // namespace

TEST(Png, RoundTripIsExact) {
  const hr::Image image = gradient(37, 21);  // odd sizes catch stride mistakes
  const std::string path = (outputDir() / "roundtrip.png").string();
  ASSERT_TRUE(hr::writePng(path, image).ok());
  auto read = hr::readPng(path);
  ASSERT_TRUE(read.ok()) << read.error();
  EXPECT_EQ(read->width, 37);
  EXPECT_EQ(read->height, 21);
  EXPECT_EQ(read->rgba, image.rgba);
}

TEST(Png, ReadMissingFileNamesThePath) {
  auto read = hr::readPng("/nonexistent/dir/none.png");
  ASSERT_FALSE(read.ok());
  EXPECT_NE(read.error().find("/nonexistent/dir/none.png"), std::string::npos) << read.error();
}

TEST(Png, ReadNonPngFails) {
  const fs::path path = outputDir() / "not_a_png.png";
  std::ofstream(path) << "this is not a PNG file at all";
  auto read = hr::readPng(path.string());
  ASSERT_FALSE(read.ok());
  EXPECT_NE(read.error().find("not_a_png.png"), std::string::npos) << read.error();
}

TEST(Png, WriteRejectsMalformedImage) {
  hr::Image image(4, 4);
  image.rgba.resize(10);
  auto status = hr::writePng((outputDir() / "bad.png").string(), image);
  ASSERT_FALSE(status.ok());
  EXPECT_NE(status.error().find("does not match"), std::string::npos) << status.error();
  EXPECT_FALSE(hr::writePng((outputDir() / "empty.png").string(), hr::Image{}).ok());
}

TEST(Png, WriteToMissingDirectoryFails) {
  auto status = hr::writePng("/nonexistent/dir/out.png", gradient(4, 4));
  ASSERT_FALSE(status.ok());
  EXPECT_NE(status.error().find("/nonexistent/dir/out.png"), std::string::npos);
}

TEST(CompareImages, CountsDifferences) {
  hr::Image a = gradient(10, 10);
  hr::Image b = a;
  auto same = hr::compareImages(a, b, 0);
  ASSERT_TRUE(same.ok());
  EXPECT_EQ(same->mean_abs_diff, 0.0);
  EXPECT_EQ(same->fraction_over, 0.0);

  b.pixel(3, 4)[1] = static_cast<std::uint8_t>(a.pixel(3, 4)[1] ^ 0x80);  // one channel off by 128
  auto diff = hr::compareImages(a, b, 24);
  ASSERT_TRUE(diff.ok());
  EXPECT_EQ(diff->max_abs_diff, 128);
  EXPECT_DOUBLE_EQ(diff->fraction_over, 0.01);
  EXPECT_NEAR(diff->mean_abs_diff, 128.0 / 300.0, 1e-12);
  EXPECT_EQ(diff->diff.pixel(3, 4)[1], 255);

  EXPECT_FALSE(hr::compareImages(a, gradient(10, 11), 0).ok());
}
