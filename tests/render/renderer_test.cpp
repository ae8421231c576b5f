// Off-screen rendering through EGL: golden image, mask, lighting, materials, robustness.
// Skips (with the reason) only where no headless EGL display exists at all, and fails
// instead where HYSIM_REQUIRE_GL=1.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <memory>
#include <thread>

#include "hysim/render/demo_scene.hpp"
#include "hysim/render/renderer.hpp"
#include "require_gl.hpp"

namespace hr = hysim::render;
namespace fs = std::filesystem;

namespace {

fs::path outputDir(const std::string& sub) {
  fs::path dir = fs::path(HYSIM_TEST_OUTPUT_DIR) / sub;
  fs::create_directories(dir);
  return dir;
}

double luma(const std::uint8_t* p) { return 0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2]; }

// Mean colour over a small square, to be robust to MSAA and rasterisation details.
std::array<double, 3> meanColor(const hr::Image& image, int cx, int cy, int half = 3) {
  std::array<double, 3> sum{};
  int n = 0;
  for (int y = cy - half; y <= cy + half; ++y) {
    for (int x = cx - half; x <= cx + half; ++x) {
      for (int c = 0; c < 3; ++c) sum[c] += image.pixel(x, y)[c];
      ++n;
    }
  }
  for (double& s : sum) s /= n;
  return sum;
}

double saturation(const std::array<double, 3>& c) {
  const double mx = std::max({c[0], c[1], c[2]}), mn = std::min({c[0], c[1], c[2]});
  return mx > 0 ? (mx - mn) / mx : 0.0;
}

// A square grid facing the camera at distance `distance` (mm), camera at the origin
// looking along +z with a straight (0 degree) lens.
hr::RenderSnapshot planeSnapshot(float distance, hr::SurfaceMaterial material,
                                 bool facing_camera = true) {
  hr::RenderSnapshot s;
  const int n = 20;
  const float half = 3.0f * distance;
  for (int j = 0; j <= n; ++j) {
    for (int i = 0; i <= n; ++i) {
      s.tissue.positions.insert(s.tissue.positions.end(),
                                {-half + 2 * half * i / n, -half + 2 * half * j / n, distance});
      s.tissue.material.push_back(material);
    }
  }
  for (int j = 0; j < n; ++j) {
    for (int i = 0; i < n; ++i) {
      const auto a = static_cast<std::uint32_t>(j * (n + 1) + i), b = a + 1,
                 c = a + static_cast<std::uint32_t>(n + 1), d = c + 1;
      // CCW seen from -z (facing the camera) or from +z.
      if (facing_camera) {
        s.tissue.triangles.insert(s.tissue.triangles.end(), {a, c, b, b, c, d});
      } else {
        s.tissue.triangles.insert(s.tissue.triangles.end(), {a, b, c, b, d, c});
      }
    }
  }
  s.camera.tip = {0, 0, 0};
  s.camera.axis = {0, 0, 1};
  s.camera.up = {0, 1, 0};
  s.camera.lens_deg = 0.0f;
  return s;
}

// One renderer per size, shared by the tests (creating EGL contexts is slow-ish).
class RenderTest : public ::testing::Test {
 protected:
  static void TearDownTestSuite() { renderers().clear(); }

  hr::OffscreenRenderer* renderer(int w, int h) {
    auto key = std::make_pair(w, h);
    auto& map = renderers();
    auto it = map.find(key);
    if (it != map.end()) return it->second.get();
    auto created = hr::OffscreenRenderer::create(w, h);
    if (!created.ok()) {
      last_error_ = created.error();
      return nullptr;
    }
    return (map[key] = std::move(*created)).get();
  }

  static std::map<std::pair<int, int>, std::unique_ptr<hr::OffscreenRenderer>>& renderers() {
    static std::map<std::pair<int, int>, std::unique_ptr<hr::OffscreenRenderer>> map;
    return map;
  }
  std::string last_error_;
};

#define GET_RENDERER_OR_SKIP(var, w, h)                                          \
  hr::OffscreenRenderer* var = renderer(w, h);                                   \
  if (var == nullptr) {                                                          \
    HYSIM_SKIP_OR_FAIL_WITHOUT_GL("no headless EGL/GL here: " << last_error_);  \
  }

}  // namespace

TEST_F(RenderTest, ContextDescribesItself) {
  GET_RENDERER_OR_SKIP(r, 64, 48);
  std::printf("render context: %s (MSAA %d)\n", r->context().description().c_str(),
              r->renderer().samples());
  EXPECT_NE(r->context().description().find("GL"), std::string::npos);
}

// Golden image of the demo scene. HYSIM_UPDATE_GOLDEN=1 rewrites the golden file. On a
// mismatch, expected/actual/diff PNGs go to <output>/golden/{expected,actual,diff}/.
TEST_F(RenderTest, DemoSceneMatchesGolden) {
  GET_RENDERER_OR_SKIP(r, 320, 240);
  const hr::Image actual = r->render(hr::makeDemoSnapshot({}));
  const std::string name = "cavity_myoma_320x240.png";
  const fs::path golden = fs::path(HYSIM_TEST_DATA_DIR) / "render" / name;

  const char* update = std::getenv("HYSIM_UPDATE_GOLDEN");
  if (update != nullptr && std::string(update) == "1") {
    fs::create_directories(golden.parent_path());
    ASSERT_TRUE(hr::writePng(golden.string(), actual).ok());
    std::printf("golden updated: %s\n", golden.string().c_str());
    return;
  }
  auto expected = hr::readPng(golden.string());
  ASSERT_TRUE(expected.ok()) << expected.error()
                             << "\n(create it with HYSIM_UPDATE_GOLDEN=1 ./test_render)";
  auto diff = hr::compareImages(*expected, actual, 24);
  ASSERT_TRUE(diff.ok()) << diff.error();
  const bool pass = diff->mean_abs_diff <= 2.0 && diff->fraction_over <= 0.01;
  if (!pass) {
    const std::string e = (outputDir("golden/expected") / name).string();
    const std::string a = (outputDir("golden/actual") / name).string();
    const std::string d = (outputDir("golden/diff") / name).string();
    (void)hr::writePng(e, *expected);
    (void)hr::writePng(a, actual);
    (void)hr::writePng(d, diff->diff);
    ADD_FAILURE() << "render differs from golden " << golden << ": mean abs diff "
                  << diff->mean_abs_diff << " (max 2), pixels off by > 24: "
                  << 100.0 * diff->fraction_over << "% (max 1%)\n  expected: " << e
                  << "\n  actual:   " << a << "\n  diff:     " << d;
  }
}

TEST_F(RenderTest, WritesSamplePngAndLooksLikeAHysteroscopicView) {
  GET_RENDERER_OR_SKIP(r, 640, 480);
  const hr::RenderSnapshot snapshot = hr::makeDemoSnapshot({});
  const hr::Image image = r->render(snapshot);
  ASSERT_EQ(image.width, 640);
  ASSERT_EQ(image.height, 480);
  const std::string path = (outputDir("render") / "cavity_myoma_640x480.png").string();
  ASSERT_TRUE(hr::writePng(path, image).ok());
  std::printf("sample frame: %s\n", path.c_str());

  // Circular mask: corners and everything clearly outside the circle is pure black.
  for (auto [x, y] : {std::pair{0, 0}, {639, 0}, {0, 479}, {639, 479}, {78, 240}, {561, 240}}) {
    const std::uint8_t* p = image.pixel(x, y);
    EXPECT_EQ(p[0] + p[1] + p[2], 0) << "at " << x << "," << y;
    EXPECT_EQ(p[3], 255);
  }
  // Inside the circle and close to its rim: not black (the cavity wall is everywhere).
  EXPECT_GT(luma(image.pixel(320, 240)), 60.0);
  // The rim is soft: the luma ramps over a few pixels instead of a hard step.
  const double outer = luma(image.pixel(320 + 239, 240));
  const double inner = luma(image.pixel(320 + 235, 240));
  EXPECT_LT(outer, inner);
  // Tissue is red-dominant.
  const auto centre = meanColor(image, 320, 240);
  EXPECT_GT(centre[0], centre[1]);
  EXPECT_GT(centre[0], centre[2]);
}

TEST_F(RenderTest, MyomaIsPalerThanEndometrium) {
  GET_RENDERER_OR_SKIP(r, 160, 120);
  // Sampled 30 degrees off the view axis, away from the (white) specular highlight.
  auto sample = [&](hr::SurfaceMaterial m) {
    return meanColor(r->render(planeSnapshot(15, m)), 115, 60);
  };
  const auto endo = sample(hr::SurfaceMaterial::Endometrium);
  const auto myoma = sample(hr::SurfaceMaterial::Myoma);
  const auto cut = sample(hr::SurfaceMaterial::Cut);
  const auto tool = sample(hr::SurfaceMaterial::Tool);
  auto lum = [](const std::array<double, 3>& c) {
    return 0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2];
  };
  // Endometrium pink-red; myoma reddish-white (less saturated, brighter); cut surface
  // darker red; the tool grey.
  EXPECT_GT(endo[0], endo[1] + 30);
  EXPECT_GE(myoma[0], myoma[1]);
  EXPECT_GE(myoma[1], myoma[2]);
  EXPECT_LT(saturation(myoma), saturation(endo) - 0.15);
  EXPECT_GT(lum(myoma), lum(endo) + 20);
  EXPECT_LT(lum(cut), lum(endo));
  EXPECT_GT(saturation(cut), saturation(myoma));
  EXPECT_LT(saturation(tool), 0.15);
}

TEST_F(RenderTest, LightFallsOffWithDistance) {
  GET_RENDERER_OR_SKIP(r, 160, 120);
  const auto near_c = meanColor(r->render(planeSnapshot(12, hr::SurfaceMaterial::Endometrium)), 80, 60);
  const auto far_c = meanColor(r->render(planeSnapshot(70, hr::SurfaceMaterial::Endometrium)), 80, 60);
  EXPECT_GT(near_c[0], 150.0);  // 10-20 mm: well lit
  EXPECT_LT(far_c[0], 45.0);    // 60+ mm: dark
  // Dimming the scope light dims the image.
  auto dim = planeSnapshot(12, hr::SurfaceMaterial::Endometrium);
  dim.camera.light_intensity = 0.25f;
  EXPECT_LT(meanColor(r->render(dim), 80, 60)[0], near_c[0] - 30);
}

TEST_F(RenderTest, BothSidesAreLit) {
  GET_RENDERER_OR_SKIP(r, 160, 120);
  const auto front = meanColor(r->render(planeSnapshot(15, hr::SurfaceMaterial::Myoma, true)), 80, 60);
  const auto back = meanColor(r->render(planeSnapshot(15, hr::SurfaceMaterial::Myoma, false)), 80, 60);
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(front[c], back[c], 1.0);
  EXPECT_GT(front[0], 100.0);
}

TEST_F(RenderTest, ToolIsDrawnOnlyWhenVisible) {
  GET_RENDERER_OR_SKIP(r, 320, 240);
  hr::RenderSnapshot s = hr::makeDemoSnapshot({});
  const hr::Image with_tool = r->render(s);
  s.tool_visible = false;
  const hr::Image without = r->render(s);
  auto diff = hr::compareImages(with_tool, without, 24);
  ASSERT_TRUE(diff.ok());
  EXPECT_GT(diff->fraction_over, 0.002);  // the rod covers part of the view
  EXPECT_LT(diff->fraction_over, 0.3);
  // Where the tool is, it is grey (metal), not red.
  int grey = 0;
  for (int y = 0; y < 240; ++y) {
    for (int x = 0; x < 320; ++x) {
      const std::uint8_t* a = with_tool.pixel(x, y);
      const std::uint8_t* b = without.pixel(x, y);
      if (std::abs(a[0] - b[0]) + std::abs(a[1] - b[1]) + std::abs(a[2] - b[2]) > 60 &&
          std::abs(a[0] - a[2]) < 30) {
        ++grey;
      }
    }
  }
  EXPECT_GT(grey, 50);
}

TEST_F(RenderTest, DeterministicAndFollowsDeformation) {
  GET_RENDERER_OR_SKIP(r, 160, 120);
  hr::RenderSnapshot s = hr::makeDemoSnapshot({.target_triangles = 2000});
  const hr::Image first = r->render(s);
  // Squash the cavity: the per-frame buffers and normals must follow.
  hr::RenderSnapshot squashed = s;
  for (std::size_t i = 1; i < squashed.tissue.positions.size(); i += 3) {
    squashed.tissue.positions[i] *= 0.6f;
  }
  const hr::Image deformed = r->render(squashed);
  auto d = hr::compareImages(first, deformed, 24);
  ASSERT_TRUE(d.ok());
  EXPECT_GT(d->fraction_over, 0.05);
  // A bigger mesh (buffers grow), then the first again: bit-identical to the first frame.
  (void)r->render(hr::makeDemoSnapshot({.target_triangles = 20000}));
  hr::Image again;
  r->render(s, again);
  EXPECT_EQ(first.rgba, again.rgba);
}

// A cube chip (side a) in its body frame: 8 corners, 12 triangles.
hr::Chip cubeChip(float a, hr::SurfaceMaterial material) {
  hr::Chip chip;
  for (int k = 0; k < 8; ++k) {
    chip.surface.positions.insert(chip.surface.positions.end(),
                                  {(k & 1 ? 0.5f : -0.5f) * a, (k & 2 ? 0.5f : -0.5f) * a, (k & 4 ? 0.5f : -0.5f) * a});
    chip.surface.material.push_back(material);
  }
  chip.surface.triangles = {0, 2, 1, 1, 2, 3, 4, 5, 6, 5, 7, 6, 0, 1, 4, 1, 5, 4,
                            2, 6, 3, 3, 6, 7, 0, 4, 2, 2, 4, 6, 1, 3, 5, 3, 7, 5};
  return chip;
}

TEST_F(RenderTest, ChipsAreDrawnAtTheirPose) {
  GET_RENDERER_OR_SKIP(r, 320, 240);
  hr::RenderSnapshot s = hr::makeDemoSnapshot({.target_triangles = 2000, .with_tool = false});
  const hr::Image without = r->render(s);
  const std::size_t tissue_triangles = r->renderer().lastTriangleCount();
  // A 3 mm chip 10 mm ahead of the camera along its view direction.
  const hr::CameraMatrices cm = hr::cameraMatrices(s.camera, 320, 240);
  hr::Chip chip = cubeChip(3.0f, hr::SurfaceMaterial::Cut);
  for (int k = 0; k < 3; ++k) chip.pose.position[k] = s.camera.tip[k] + 10.0f * cm.view_dir[k];
  s.chips.push_back(chip);
  const hr::Image with_chip = r->render(s);
  EXPECT_EQ(r->renderer().lastTriangleCount(), tissue_triangles + 12);
  auto d = hr::compareImages(without, with_chip, 24);
  ASSERT_TRUE(d.ok());
  EXPECT_GT(d->fraction_over, 0.01);
  EXPECT_LT(d->fraction_over, 0.5);
  // Moved 2 mm along the image's up direction: drawn elsewhere.
  for (int k = 0; k < 3; ++k) s.chips[0].pose.position[k] += 2.0f * cm.image_up[k];
  const hr::Image moved = r->render(s);
  d = hr::compareImages(with_chip, moved, 24);
  ASSERT_TRUE(d.ok());
  EXPECT_GT(d->fraction_over, 0.002);
  // No chips again: the same frame as before (the chip buffers do not linger).
  s.chips.clear();
  EXPECT_EQ(r->render(s).rgba, without.rgba);
  // A chip with bad indices and no materials: its bad triangles are dropped, no crash.
  hr::Chip bad = cubeChip(3.0f, hr::SurfaceMaterial::Myoma);
  bad.surface.triangles.insert(bad.surface.triangles.end(), {0u, 1u, 99u});
  bad.surface.material.clear();
  s.chips.push_back(bad);
  (void)r->render(s);
  EXPECT_EQ(r->renderer().lastTriangleCount(), tissue_triangles + 12);
}

TEST_F(RenderTest, BadInputDoesNotCrash) {
  GET_RENDERER_OR_SKIP(r, 160, 120);
  hr::RenderSnapshot s = hr::makeDemoSnapshot({.target_triangles = 500, .with_tool = true});
  const std::size_t good = s.tissue.triangles.size() / 3 + s.tool.triangles.size() / 3;
  s.tissue.triangles.insert(s.tissue.triangles.end(), {0u, 1u, 4000000000u});  // out of range
  s.tissue.triangles.push_back(2u);                                             // dangling
  s.tissue.material.resize(3);                                                  // too short
  s.tool.material.clear();
  (void)r->render(s);
  EXPECT_EQ(r->renderer().lastTriangleCount(), good);

  hr::RenderSnapshot empty;
  const hr::Image black = r->render(empty);
  EXPECT_EQ(black.width, 160);
  EXPECT_TRUE(std::all_of(black.rgba.begin(), black.rgba.end(),
                          [i = 0](std::uint8_t v) mutable { return (i++ % 4 == 3) ? v == 255 : v == 0; }));

  hr::RenderSnapshot nonsense = planeSnapshot(15, hr::SurfaceMaterial::Myoma);
  nonsense.camera.axis = {0, 0, 0};  // degenerate camera: falls back, still renders
  nonsense.camera.up = {0, 0, 0};
  nonsense.camera.fov_deg = -5;
  nonsense.camera.near_mm = -1;
  nonsense.camera.far_mm = 0;
  (void)r->render(nonsense);
  nonsense.tissue.positions[0] = std::nanf("");
  (void)r->render(nonsense);
}

TEST(RendererCreate, RejectsBadSize) {
  auto bad = hr::Renderer::create(0, 480);
  ASSERT_FALSE(bad.ok());
  EXPECT_NE(bad.error().find("size"), std::string::npos) << bad.error();
}

TEST_F(RenderTest, RendererNeedsACurrentContext) {
  GET_RENDERER_OR_SKIP(r, 64, 48);  // GL has been used in this process...
  std::string error;
  std::thread([&] {                 // ...but no context is current on a new thread
    auto renderer = hr::Renderer::create(64, 48);
    error = renderer.ok() ? "created" : renderer.error();
  }).join();
  EXPECT_NE(error.find("needs a current"), std::string::npos) << error;
}

TEST(EglHeadless, MissingDeviceGivesAnError) {
  hr::EglOptions options;
  options.platform = hr::EglPlatform::Device;
  options.device_index = 999;
  auto context = hr::EglHeadlessContext::create(options);
  ASSERT_FALSE(context.ok());
  EXPECT_NE(context.error().find("no headless display"), std::string::npos) << context.error();
  std::printf("error as reported: %s\n", context.error().c_str());
}

// glvnd loads EGL vendors once per process; pointing it at no vendor at all simulates a
// machine without any EGL driver. A threadsafe death test re-executes this binary, so the
// child starts with the environment variable set and nothing loaded.
TEST(EglHeadlessDeathTest, NoEglVendorGivesAnErrorNotACrash) {
  GTEST_FLAG_SET(death_test_style, "threadsafe");
  setenv("__EGL_VENDOR_LIBRARY_FILENAMES", "/nonexistent/egl_vendor.json", 1);
  EXPECT_EXIT(
      {
        auto context = hr::EglHeadlessContext::create();
        if (context.ok()) std::_Exit(3);
        std::fprintf(stderr, "%s\n", context.error().c_str());
        auto renderer = hr::OffscreenRenderer::create(64, 48);
        std::_Exit(renderer.ok() ? 4 : 0);
      },
      ::testing::ExitedWithCode(0), "EGL");
  unsetenv("__EGL_VENDOR_LIBRARY_FILENAMES");
}
