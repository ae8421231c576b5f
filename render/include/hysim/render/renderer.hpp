#pragma once
// The GL renderer of a RenderSnapshot: OpenGL 3.3 core, draws into its own off-screen
// framebuffer (RGBA8 + depth24, optional MSAA) and reads the frame back as an Image.
// It needs a current GL 3.3 context but does not care who made it (EGL headless, SDL2).
#include <array>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "hysim/cutting/result.hpp"
#include "hysim/render/egl_headless_context.hpp"
#include "hysim/render/image.hpp"
#include "hysim/render/snapshot.hpp"

namespace hysim::render {

struct RendererOptions {
  // MSAA samples (0 or 1 = none; clamped to what GL offers). Off by default: 4x costs
  // 3-4x the frame time on llvmpipe (about 28 ms vs 6 ms at 640x480), over the budget.
  int samples = 0;
  float ambient = 0.04f;      // fraction of the albedo seen without the tip light
  float light_radius_mm = 18.0f;  // distance at which light_intensity 1 gives full diffuse
  float shininess = 48.0f;    // Blinn-Phong exponent of the wet tissue highlight
  float vignette = 0.18f;     // darkening at the rim of the circular image (0 = none)
  float mask_edge_px = 2.5f;  // width of the soft edge of the circular mask
  float exposure = 1.4f;      // tone curve 1 - exp(-exposure * colour): soft highlight roll-off
};

// Per-vertex smooth normals: area-weighted sum of the face normals of the incident
// triangles, normalised. Triangles with an out-of-range index are ignored. Vertices
// without a (non-degenerate) triangle get (0, 0, 0).
// positions: #V*3, triangles: #F*3, normals (out): resized to #V*3.
void computeVertexNormals(const std::vector<float>& positions,
                          const std::vector<std::uint32_t>& triangles,
                          std::vector<float>& normals);

// Column-major 4x4 matrices of the hysteroscope camera (OpenGL conventions).
struct CameraMatrices {
  std::array<float, 16> view{};
  std::array<float, 16> projection{};
  std::array<float, 3> view_dir{};  // unit, axis tilted by lens_deg towards -up
  std::array<float, 3> image_up{};  // unit, what is "up" in the image
};
CameraMatrices cameraMatrices(const Camera& camera, int width, int height);

class Renderer {
 public:
  // Needs a current OpenGL 3.3 core context on the calling thread (for its whole life).
  static hysim::Result<std::unique_ptr<Renderer>> create(int width, int height,
                                                         const RendererOptions& options = {});
  ~Renderer();
  Renderer(const Renderer&) = delete;
  Renderer& operator=(const Renderer&) = delete;

  // Draws the snapshot and reads it back (row 0 = top). Bad input (indices out of range,
  // missing materials) is skipped or defaulted, never a crash.
  Image render(const RenderSnapshot& snapshot);
  // Same, reusing `out`'s storage (no allocation once it has the right size).
  void render(const RenderSnapshot& snapshot, Image& out);
  // Draws the snapshot into the renderer's framebuffer (resolved if MSAA) without reading
  // it back: for windowed apps, followed by blitTo().
  void draw(const RenderSnapshot& snapshot);
  // Copies the last drawn frame into `framebuffer` (0 = the window's default framebuffer),
  // scaled into the rectangle (x, y, w, h) in GL window coordinates (origin bottom-left),
  // and leaves `framebuffer` bound. The target must not be multisampled.
  void blitTo(unsigned framebuffer, int x, int y, int w, int h) const;

  int width() const { return width_; }
  int height() const { return height_; }
  int samples() const { return samples_; }  // MSAA samples actually used (0 = none)
  // Triangles drawn in the last frame (after dropping bad ones).
  std::size_t lastTriangleCount() const { return last_triangles_; }

 private:
  struct MeshBuffers;
  Renderer(int width, int height, const RendererOptions& options);
  hysim::Status init();
  void upload(const SurfaceMesh& mesh, SurfaceMaterial default_material, MeshBuffers& buffers);
  void drawMesh(const MeshBuffers& buffers, const std::array<float, 16>& model,
                const std::array<float, 9>& normal_matrix);

  int width_;
  int height_;
  int samples_ = 0;
  RendererOptions options_;
  std::size_t last_triangles_ = 0;

  // GL object names (GLuint); 0 = none.
  unsigned program_ = 0;
  unsigned msaa_fbo_ = 0, msaa_color_ = 0, msaa_depth_ = 0;
  unsigned resolve_fbo_ = 0, resolve_color_ = 0, resolve_depth_ = 0;
  std::unique_ptr<MeshBuffers> tissue_;
  std::unique_ptr<MeshBuffers> tool_;
  std::unique_ptr<MeshBuffers> chips_;
  SurfaceMesh chips_world_;  // all chips in world coordinates (scratch, reused every frame)

  // Uniform locations.
  int u_view_proj_ = -1, u_model_ = -1, u_normal_matrix_ = -1, u_palette_ = -1, u_eye_ = -1,
      u_light_color_ = -1, u_light_scale_ = -1, u_ambient_ = -1, u_shininess_ = -1,
      u_center_ = -1, u_radius_ = -1, u_edge_ = -1, u_vignette_ = -1, u_exposure_ = -1;

  std::vector<std::uint8_t> readback_;  // bottom-up rows as GL returns them
};

// The usual bundle for CI and tools: an EGL headless context plus a Renderer on it.
class OffscreenRenderer {
 public:
  static hysim::Result<std::unique_ptr<OffscreenRenderer>> create(
      int width, int height, const RendererOptions& options = {},
      const EglOptions& egl = {});
  ~OffscreenRenderer();

  // Makes this renderer's context current, then draws (see Renderer::render).
  Image render(const RenderSnapshot& snapshot);
  void render(const RenderSnapshot& snapshot, Image& out);
  // Draws the snapshot into the renderer's framebuffer (resolved if MSAA) without reading
  // it back: for windowed apps, followed by blitTo().
  void draw(const RenderSnapshot& snapshot);
  // Copies the last drawn frame into `framebuffer` (0 = the window's default framebuffer),
  // scaled into the rectangle (x, y, w, h) in GL window coordinates (origin bottom-left),
  // and leaves `framebuffer` bound. The target must not be multisampled.
  void blitTo(unsigned framebuffer, int x, int y, int w, int h) const;
  // Renders and writes a PNG.
  hysim::Status renderToPng(const RenderSnapshot& snapshot, const std::string& path);

  Renderer& renderer() { return *renderer_; }
  EglHeadlessContext& context() { return *context_; }

 private:
  OffscreenRenderer() = default;
  // Declared first so it is destroyed last: the Renderer's GL objects need the context.
  std::unique_ptr<EglHeadlessContext> context_;
  std::unique_ptr<Renderer> renderer_;
};

}  // namespace hysim::render
