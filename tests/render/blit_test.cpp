// The windowed path of the Renderer: draw() without read-back, then blitTo() into another
// framebuffer (in the app: the SDL window's default framebuffer). Checked headless through
// EGL with a plain framebuffer object standing in for the window.
// (SdlWindow itself needs a display and is exercised by running hysim-app, not by tests.)
#include <epoxy/gl.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <memory>

#include "hysim/render/demo_scene.hpp"
#include "hysim/render/renderer.hpp"
#include "require_gl.hpp"

namespace hr = hysim::render;

namespace {

// A single-sampled RGBA8 framebuffer object (the stand-in for a window).
class TargetFbo {
 public:
  TargetFbo(int w, int h) : w_(w), h_(h) {
    glGenFramebuffers(1, &fbo_);
    glGenRenderbuffers(1, &color_);
    glBindRenderbuffer(GL_RENDERBUFFER, color_);
    glRenderbufferStorage(GL_RENDERBUFFER, GL_RGBA8, w, h);
    glBindFramebuffer(GL_FRAMEBUFFER, fbo_);
    glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, color_);
    complete_ = glCheckFramebufferStatus(GL_FRAMEBUFFER) == GL_FRAMEBUFFER_COMPLETE;
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
  }
  ~TargetFbo() {
    glDeleteFramebuffers(1, &fbo_);
    glDeleteRenderbuffers(1, &color_);
  }
  bool complete() const { return complete_; }
  GLuint name() const { return fbo_; }
  void clear(float r, float g, float b) {
    glBindFramebuffer(GL_FRAMEBUFFER, fbo_);
    glViewport(0, 0, w_, h_);
    glDisable(GL_SCISSOR_TEST);
    glClearColor(r, g, b, 1.0f);
    glClear(GL_COLOR_BUFFER_BIT);
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
  }
  // Row 0 = top, like hr::Image.
  hr::Image read() const {
    hr::Image image(w_, h_);
    glBindFramebuffer(GL_READ_FRAMEBUFFER, fbo_);
    glReadBuffer(GL_COLOR_ATTACHMENT0);
    glPixelStorei(GL_PACK_ALIGNMENT, 1);
    glReadPixels(0, 0, w_, h_, GL_RGBA, GL_UNSIGNED_BYTE, image.rgba.data());
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    const std::size_t row = static_cast<std::size_t>(w_) * 4;
    for (int y = 0; y < h_ / 2; ++y) {
      std::swap_ranges(image.rgba.begin() + y * row, image.rgba.begin() + (y + 1) * row,
                       image.rgba.begin() + (h_ - 1 - y) * row);
    }
    return image;
  }

 private:
  int w_, h_;
  GLuint fbo_ = 0, color_ = 0;
  bool complete_ = false;
};

}  // namespace

class BlitTest : public ::testing::Test {
 protected:
  void SetUp() override {
    auto created = hr::OffscreenRenderer::create(160, 120);
    if (!created.ok()) {
      HYSIM_SKIP_OR_FAIL_WITHOUT_GL("no headless EGL/GL here: " << created.error());
    }
    r_ = std::move(*created);
    ASSERT_TRUE(r_->context().makeCurrent().ok());
  }
  std::unique_ptr<hr::OffscreenRenderer> r_;
};

TEST_F(BlitTest, SameSizeBlitEqualsReadBack) {
  const hr::RenderSnapshot snapshot = hr::makeDemoSnapshot({.target_triangles = 2000});
  const hr::Image expected = r_->render(snapshot);

  TargetFbo target(160, 120);
  ASSERT_TRUE(target.complete());
  target.clear(0, 1, 0);
  r_->renderer().draw(snapshot);
  r_->renderer().blitTo(target.name(), 0, 0, 160, 120);
  GLint bound = -1;
  glGetIntegerv(GL_DRAW_FRAMEBUFFER_BINDING, &bound);
  EXPECT_EQ(bound, static_cast<GLint>(target.name())) << "blitTo leaves the target bound";
  EXPECT_EQ(glGetError(), static_cast<GLenum>(GL_NO_ERROR));

  const hr::Image actual = target.read();
  auto diff = hr::compareImages(expected, actual, 0);
  ASSERT_TRUE(diff.ok()) << diff.error();
  EXPECT_EQ(diff->max_abs_diff, 0);
}

TEST_F(BlitTest, ScaledBlitFillsOnlyItsRectangle) {
  const hr::RenderSnapshot snapshot = hr::makeDemoSnapshot({.target_triangles = 2000});
  TargetFbo target(400, 200);
  ASSERT_TRUE(target.complete());
  target.clear(0, 1, 0);
  r_->renderer().draw(snapshot);
  // GL window coordinates: origin bottom-left. 240x180 at (100, 10) = rows 10..189 from the top.
  r_->renderer().blitTo(target.name(), 100, 10, 240, 180);
  EXPECT_EQ(glGetError(), static_cast<GLenum>(GL_NO_ERROR));
  const hr::Image image = target.read();

  auto isGreen = [](const std::uint8_t* p) { return p[0] == 0 && p[1] == 255 && p[2] == 0; };
  EXPECT_TRUE(isGreen(image.pixel(50, 100)));   // left of the rectangle
  EXPECT_TRUE(isGreen(image.pixel(370, 100)));  // right of it
  EXPECT_TRUE(isGreen(image.pixel(200, 5)));    // above it (rows 0..9 from the top)
  EXPECT_TRUE(isGreen(image.pixel(200, 195)));  // below it
  // Inside: the scope image, a black frame corner and lit tissue in the middle.
  const std::uint8_t* corner = image.pixel(102, 12);
  EXPECT_LT(corner[0] + corner[1] + corner[2], 10);
  const std::uint8_t* centre = image.pixel(220, 100);
  EXPECT_FALSE(isGreen(centre));
  EXPECT_GT(centre[0], 40) << "tissue in the middle of the view is lit";
}

TEST_F(BlitTest, EmptyRectangleIsANoOp) {
  TargetFbo target(32, 32);
  ASSERT_TRUE(target.complete());
  target.clear(0, 1, 0);
  r_->renderer().draw(hr::makeDemoSnapshot({.target_triangles = 500}));
  r_->renderer().blitTo(target.name(), 0, 0, 0, 10);
  r_->renderer().blitTo(target.name(), 0, 0, 10, -1);
  EXPECT_EQ(glGetError(), static_cast<GLenum>(GL_NO_ERROR));
  const hr::Image image = target.read();
  for (int y = 0; y < 32; ++y) {
    for (int x = 0; x < 32; ++x) ASSERT_EQ(image.pixel(x, y)[1], 255);
  }
}
