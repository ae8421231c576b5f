// GL 3.3 core renderer of a RenderSnapshot into an off-screen framebuffer.
//
// Per frame: smooth normals are recomputed on the CPU (the tissue deforms and is cut, so
// cached normals would be stale), interleaved into a vertex array that lives as long as
// the renderer, and streamed into GL buffers that only grow. Lighting is a point light at
// the scope tip (as in a real hysteroscope, where the light fibres surround the lens).
#include "hysim/render/renderer.hpp"

#include <epoxy/gl.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>

namespace hysim::render {
namespace {

constexpr float kPi = 3.14159265358979323846f;

// Shaders: lighting in world space so the light (= eye) position is a plain uniform.
constexpr const char* kVertexShader = R"glsl(
#version 330 core
layout(location = 0) in vec3 a_position;
layout(location = 1) in vec3 a_normal;
layout(location = 2) in float a_material;  // SurfaceMaterial as 0..3

uniform mat4 u_view_proj;
uniform mat4 u_model;
uniform mat3 u_normal_matrix;
uniform vec4 u_palette[4];  // rgb = albedo, a = specular strength

out vec3 v_world;
out vec3 v_normal;
out vec4 v_material;  // interpolated, so materials blend smoothly across triangles

void main() {
  vec4 world = u_model * vec4(a_position, 1.0);
  v_world = world.xyz;
  v_normal = u_normal_matrix * a_normal;
  v_material = u_palette[clamp(int(a_material + 0.5), 0, 3)];
  gl_Position = u_view_proj * world;
}
)glsl";

constexpr const char* kFragmentShader = R"glsl(
#version 330 core
in vec3 v_world;
in vec3 v_normal;
in vec4 v_material;

uniform vec3 u_eye;          // scope tip: camera and light position
uniform vec3 u_light_color;
uniform float u_light_scale; // intensity * reference distance^2
uniform float u_ambient;
uniform float u_shininess;
uniform vec2 u_center;       // image centre in window coordinates
uniform float u_radius;      // radius of the circular image (pixels)
uniform float u_edge;        // soft edge width (pixels)
uniform float u_vignette;
uniform float u_exposure;

out vec4 frag_color;

void main() {
  // Circular endoscope image first: outside it nothing needs lighting (about 40% of a
  // 4:3 frame; llvmpipe skips a branch when a whole block of pixels agrees).
  float r = length(gl_FragCoord.xy - u_center);
  float mask = clamp((u_radius - r) / u_edge, 0.0, 1.0);
  if (mask <= 0.0) {
    frag_color = vec4(0.0, 0.0, 0.0, 1.0);
    return;
  }

  vec3 to_light = u_eye - v_world;
  float d2 = max(dot(to_light, to_light), 1e-8);
  vec3 L = to_light * inversesqrt(d2);
  float nn = dot(v_normal, v_normal);
  vec3 N = nn > 1e-20 ? v_normal * inversesqrt(nn) : L;
  // Two-sided: the scope sees the cavity's inner faces, whose outward normals point away.
  if (dot(N, L) < 0.0) N = -N;
  float ndl = max(dot(N, L), 0.0);
  // Blinn-Phong with light and eye at the same point: the half vector is L, so the wet
  // highlight sits where the tissue faces the scope head-on.
  float spec = v_material.a * pow(ndl, u_shininess);
  // Inverse square falloff; clamped at 1 mm so touching tissue does not blow up.
  float atten = u_light_scale / max(d2, 1.0);
  vec3 color = v_material.rgb * u_ambient +
               u_light_color * atten * (v_material.rgb * ndl + vec3(spec));
  // Exposure curve instead of a hard clip: near tissue saturates softly towards white,
  // as overexposed tissue does on a real scope camera.
  color = vec3(1.0) - exp(-u_exposure * color);

  // Soft rim and a slight vignette, as the scope's optics give.
  float rr = r / u_radius;
  float vignette = 1.0 - u_vignette * rr * rr;
  frag_color = vec4(color * (mask * vignette), 1.0);
}
)glsl";

// Interleaved vertex: 28 bytes.
struct GpuVertex {
  float position[3];
  float normal[3];
  std::uint8_t material;
  std::uint8_t pad[3];
};
static_assert(sizeof(GpuVertex) == 28);

struct Vec3 {
  float x, y, z;
};
Vec3 operator+(Vec3 a, Vec3 b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
Vec3 operator-(Vec3 a, Vec3 b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
Vec3 operator*(float s, Vec3 a) { return {s * a.x, s * a.y, s * a.z}; }
float dot(Vec3 a, Vec3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
Vec3 cross(Vec3 a, Vec3 b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
Vec3 normalized(Vec3 a, Vec3 fallback) {
  const float len = std::sqrt(dot(a, a));
  if (!(len > 1e-12f) || !std::isfinite(len)) return fallback;
  return (1.0f / len) * a;
}
Vec3 toVec(const std::array<float, 3>& a) { return {a[0], a[1], a[2]}; }

std::array<float, 16> multiply(const std::array<float, 16>& a, const std::array<float, 16>& b) {
  std::array<float, 16> r{};
  for (int col = 0; col < 4; ++col) {
    for (int row = 0; row < 4; ++row) {
      float s = 0.0f;
      for (int k = 0; k < 4; ++k) s += a[k * 4 + row] * b[col * 4 + k];
      r[col * 4 + row] = s;
    }
  }
  return r;
}

constexpr std::array<float, 16> kIdentity4{1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
constexpr std::array<float, 9> kIdentity3{1, 0, 0, 0, 1, 0, 0, 0, 1};

// Inverse transpose of a column-major 3x3 (normals under a non-rigid model matrix);
// equals the matrix itself for a rotation. Singular matrices give the identity.
std::array<float, 9> normalMatrix(const std::array<float, 9>& m) {
  // Columns c0, c1, c2; inverse transpose = [c1 x c2, c2 x c0, c0 x c1] / det.
  const Vec3 c0{m[0], m[1], m[2]}, c1{m[3], m[4], m[5]}, c2{m[6], m[7], m[8]};
  const Vec3 a = cross(c1, c2), b = cross(c2, c0), c = cross(c0, c1);
  const float det = dot(c0, a);
  if (!(std::fabs(det) > 1e-12f) || !std::isfinite(det)) return kIdentity3;
  const float s = 1.0f / det;
  return {s * a.x, s * a.y, s * a.z, s * b.x, s * b.y, s * b.z, s * c.x, s * c.y, s * c.z};
}

std::string shaderLog(GLuint shader) {
  GLint length = 0;
  glGetShaderiv(shader, GL_INFO_LOG_LENGTH, &length);
  std::string log(static_cast<std::size_t>(std::max(length, 1)), '\0');
  glGetShaderInfoLog(shader, length, nullptr, log.data());
  return log;
}

hysim::Result<GLuint> compileShader(GLenum type, const char* source) {
  GLuint shader = glCreateShader(type);
  glShaderSource(shader, 1, &source, nullptr);
  glCompileShader(shader);
  GLint ok = GL_FALSE;
  glGetShaderiv(shader, GL_COMPILE_STATUS, &ok);
  if (ok != GL_TRUE) {
    std::string message = std::string(type == GL_VERTEX_SHADER ? "vertex" : "fragment") +
                          " shader does not compile: " + shaderLog(shader);
    glDeleteShader(shader);
    return hysim::Error{message};
  }
  return shader;
}

}  // namespace

struct Renderer::MeshBuffers {
  GLuint vao = 0, vbo = 0, ibo = 0;
  std::size_t vbo_capacity = 0;  // bytes allocated in GL; grows, never shrinks
  std::size_t ibo_capacity = 0;
  GLsizei index_count = 0;
  // CPU scratch reused every frame.
  std::vector<float> normals;             // #V*3
  std::vector<GpuVertex> vertices;        // #V
  std::vector<std::uint32_t> valid_tris;  // only used when some triangles are bad
};

void computeVertexNormals(const std::vector<float>& positions,
                          const std::vector<std::uint32_t>& triangles,
                          std::vector<float>& normals) {
  const std::size_t nv = positions.size() / 3;
  normals.assign(nv * 3, 0.0f);
  const std::size_t nt = triangles.size() / 3;
  const float* p = positions.data();
  for (std::size_t t = 0; t < nt; ++t) {
    const std::uint32_t i0 = triangles[3 * t], i1 = triangles[3 * t + 1],
                        i2 = triangles[3 * t + 2];
    if (i0 >= nv || i1 >= nv || i2 >= nv) continue;
    const Vec3 a{p[3 * i0], p[3 * i0 + 1], p[3 * i0 + 2]};
    const Vec3 b{p[3 * i1], p[3 * i1 + 1], p[3 * i1 + 2]};
    const Vec3 c{p[3 * i2], p[3 * i2 + 1], p[3 * i2 + 2]};
    // The unnormalised cross product has length 2*area: area weighting for free.
    const Vec3 n = cross(b - a, c - a);
    for (std::uint32_t i : {i0, i1, i2}) {
      normals[3 * i] += n.x;
      normals[3 * i + 1] += n.y;
      normals[3 * i + 2] += n.z;
    }
  }
  for (std::size_t v = 0; v < nv; ++v) {
    const Vec3 n = normalized({normals[3 * v], normals[3 * v + 1], normals[3 * v + 2]},
                              {0.0f, 0.0f, 0.0f});
    normals[3 * v] = n.x;
    normals[3 * v + 1] = n.y;
    normals[3 * v + 2] = n.z;
  }
}

CameraMatrices cameraMatrices(const Camera& camera, int width, int height) {
  const Vec3 eye = toVec(camera.tip);
  const Vec3 axis = normalized(toVec(camera.axis), {0, 0, 1});
  // Make `up` orthogonal to the axis even if the caller's is slightly off.
  Vec3 up = toVec(camera.up);
  up = up - dot(up, axis) * axis;
  up = normalized(up, normalized(cross(axis, {1, 0, 0}), normalized(cross(axis, {0, 1, 0}),
                                                                    {0, 1, 0})));
  const float lens = camera.lens_deg * kPi / 180.0f;
  // Fore-oblique lens: the view direction is the axis tilted by lens_deg towards -up.
  const Vec3 dir = std::cos(lens) * axis - std::sin(lens) * up;
  const Vec3 image_up = std::sin(lens) * axis + std::cos(lens) * up;
  const Vec3 right = cross(dir, image_up);

  CameraMatrices m;
  m.view_dir = {dir.x, dir.y, dir.z};
  m.image_up = {image_up.x, image_up.y, image_up.z};
  // View matrix rows: right, image_up, -dir (column-major storage).
  m.view = {right.x, image_up.x, -dir.x, 0,
            right.y, image_up.y, -dir.y, 0,
            right.z, image_up.z, -dir.z, 0,
            -dot(right, eye), -dot(image_up, eye), dot(dir, eye), 1};

  // The circle spans the image height, so fov is the vertical field of view.
  const float fov = std::clamp(camera.fov_deg, 1.0f, 179.0f) * kPi / 180.0f;
  const float aspect = height > 0 ? static_cast<float>(width) / static_cast<float>(height) : 1;
  const float f = 1.0f / std::tan(fov / 2.0f);
  const float n = camera.near_mm > 1e-4f ? camera.near_mm : 1e-4f;
  const float fa = camera.far_mm > n * 1.001f ? camera.far_mm : n * 1000.0f;
  m.projection = {f / aspect, 0, 0, 0,
                  0, f, 0, 0,
                  0, 0, (fa + n) / (n - fa), -1,
                  0, 0, 2.0f * fa * n / (n - fa), 0};
  return m;
}

Renderer::Renderer(int width, int height, const RendererOptions& options)
    : width_(width), height_(height), options_(options),
      tissue_(std::make_unique<MeshBuffers>()), tool_(std::make_unique<MeshBuffers>()),
      chips_(std::make_unique<MeshBuffers>()) {}

hysim::Result<std::unique_ptr<Renderer>> Renderer::create(int width, int height,
                                                          const RendererOptions& options) {
  if (width <= 0 || height <= 0 || width > 16384 || height > 16384) {
    return hysim::Error{"Renderer: bad image size " + std::to_string(width) + "x" +
                        std::to_string(height)};
  }
  if (epoxy_gl_version() < 33 || !epoxy_is_desktop_gl()) {
    return hysim::Error{"Renderer: needs a current desktop OpenGL 3.3 context"};
  }
  auto renderer = std::unique_ptr<Renderer>(new Renderer(width, height, options));
  hysim::Status status = renderer->init();
  if (!status.ok()) return hysim::Error{"Renderer: " + status.error()};
  return renderer;
}

hysim::Status Renderer::init() {
  // Program.
  auto vs = compileShader(GL_VERTEX_SHADER, kVertexShader);
  if (!vs.ok()) return hysim::Error{vs.error()};
  auto fs = compileShader(GL_FRAGMENT_SHADER, kFragmentShader);
  if (!fs.ok()) {
    glDeleteShader(*vs);
    return hysim::Error{fs.error()};
  }
  program_ = glCreateProgram();
  glAttachShader(program_, *vs);
  glAttachShader(program_, *fs);
  glLinkProgram(program_);
  glDeleteShader(*vs);
  glDeleteShader(*fs);
  GLint linked = GL_FALSE;
  glGetProgramiv(program_, GL_LINK_STATUS, &linked);
  if (linked != GL_TRUE) {
    GLint length = 0;
    glGetProgramiv(program_, GL_INFO_LOG_LENGTH, &length);
    std::string log(static_cast<std::size_t>(std::max(length, 1)), '\0');
    glGetProgramInfoLog(program_, length, nullptr, log.data());
    return hysim::Error{"shader program does not link: " + log};
  }
  u_view_proj_ = glGetUniformLocation(program_, "u_view_proj");
  u_model_ = glGetUniformLocation(program_, "u_model");
  u_normal_matrix_ = glGetUniformLocation(program_, "u_normal_matrix");
  u_palette_ = glGetUniformLocation(program_, "u_palette");
  u_eye_ = glGetUniformLocation(program_, "u_eye");
  u_light_color_ = glGetUniformLocation(program_, "u_light_color");
  u_light_scale_ = glGetUniformLocation(program_, "u_light_scale");
  u_ambient_ = glGetUniformLocation(program_, "u_ambient");
  u_shininess_ = glGetUniformLocation(program_, "u_shininess");
  u_center_ = glGetUniformLocation(program_, "u_center");
  u_radius_ = glGetUniformLocation(program_, "u_radius");
  u_edge_ = glGetUniformLocation(program_, "u_edge");
  u_vignette_ = glGetUniformLocation(program_, "u_vignette");
  u_exposure_ = glGetUniformLocation(program_, "u_exposure");

  // Constant uniforms.
  glUseProgram(program_);
  // Albedo (linear-ish, before the tone curve) and specular strength per SurfaceMaterial.
  const GLfloat palette[16] = {
      0.85f, 0.42f, 0.40f, 0.35f,  // Endometrium: pink-red
      0.93f, 0.80f, 0.75f, 0.30f,  // Myoma: paler, whitish pink
      0.55f, 0.22f, 0.17f, 0.20f,  // Cut: darker red-brown, duller
      0.45f, 0.47f, 0.50f, 0.90f,  // Tool: metallic grey, strong highlight
  };
  glUniform4fv(u_palette_, 4, palette);
  glUniform3f(u_light_color_, 1.0f, 0.95f, 0.88f);  // halogen/LED light: slightly warm
  glUniform1f(u_ambient_, options_.ambient);
  glUniform1f(u_shininess_, options_.shininess);
  glUniform2f(u_center_, 0.5f * static_cast<float>(width_), 0.5f * static_cast<float>(height_));
  glUniform1f(u_radius_, 0.5f * static_cast<float>(height_));
  glUniform1f(u_edge_, std::max(options_.mask_edge_px, 0.01f));
  glUniform1f(u_vignette_, options_.vignette);
  glUniform1f(u_exposure_, options_.exposure);
  glUseProgram(0);

  // Framebuffers: a multisampled one to draw in (if MSAA) and a single-sampled one to
  // resolve into and read back from.
  GLint max_samples = 0;
  glGetIntegerv(GL_MAX_SAMPLES, &max_samples);
  samples_ = options_.samples > 1 ? std::min(options_.samples, static_cast<int>(max_samples)) : 0;
  if (samples_ < 2) samples_ = 0;

  glGenFramebuffers(1, &resolve_fbo_);
  glBindFramebuffer(GL_FRAMEBUFFER, resolve_fbo_);
  glGenRenderbuffers(1, &resolve_color_);
  glBindRenderbuffer(GL_RENDERBUFFER, resolve_color_);
  glRenderbufferStorage(GL_RENDERBUFFER, GL_RGBA8, width_, height_);
  glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, resolve_color_);
  if (samples_ == 0) {
    glGenRenderbuffers(1, &resolve_depth_);
    glBindRenderbuffer(GL_RENDERBUFFER, resolve_depth_);
    glRenderbufferStorage(GL_RENDERBUFFER, GL_DEPTH_COMPONENT24, width_, height_);
    glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER,
                              resolve_depth_);
  }
  if (glCheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE) {
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    return hysim::Error{"off-screen framebuffer (RGBA8 + depth24) is incomplete"};
  }
  if (samples_ > 0) {
    glGenFramebuffers(1, &msaa_fbo_);
    glBindFramebuffer(GL_FRAMEBUFFER, msaa_fbo_);
    glGenRenderbuffers(1, &msaa_color_);
    glBindRenderbuffer(GL_RENDERBUFFER, msaa_color_);
    glRenderbufferStorageMultisample(GL_RENDERBUFFER, samples_, GL_RGBA8, width_, height_);
    glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, msaa_color_);
    glGenRenderbuffers(1, &msaa_depth_);
    glBindRenderbuffer(GL_RENDERBUFFER, msaa_depth_);
    glRenderbufferStorageMultisample(GL_RENDERBUFFER, samples_, GL_DEPTH_COMPONENT24, width_,
                                     height_);
    glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, msaa_depth_);
    if (glCheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE) {
      // MSAA is a nicety: fall back to drawing straight into the resolve target.
      glDeleteRenderbuffers(1, &msaa_color_);
      glDeleteRenderbuffers(1, &msaa_depth_);
      glDeleteFramebuffers(1, &msaa_fbo_);
      msaa_fbo_ = msaa_color_ = msaa_depth_ = 0;
      samples_ = 0;
      glBindFramebuffer(GL_FRAMEBUFFER, resolve_fbo_);
      glGenRenderbuffers(1, &resolve_depth_);
      glBindRenderbuffer(GL_RENDERBUFFER, resolve_depth_);
      glRenderbufferStorage(GL_RENDERBUFFER, GL_DEPTH_COMPONENT24, width_, height_);
      glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER,
                                resolve_depth_);
    }
  }
  glBindRenderbuffer(GL_RENDERBUFFER, 0);
  glBindFramebuffer(GL_FRAMEBUFFER, 0);

  // Vertex arrays: layout fixed once, buffers refilled every frame.
  for (MeshBuffers* b : {tissue_.get(), tool_.get(), chips_.get()}) {
    glGenVertexArrays(1, &b->vao);
    glGenBuffers(1, &b->vbo);
    glGenBuffers(1, &b->ibo);
    glBindVertexArray(b->vao);
    glBindBuffer(GL_ARRAY_BUFFER, b->vbo);
    glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, b->ibo);  // recorded in the VAO
    glEnableVertexAttribArray(0);
    glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, sizeof(GpuVertex),
                          reinterpret_cast<const void*>(offsetof(GpuVertex, position)));
    glEnableVertexAttribArray(1);
    glVertexAttribPointer(1, 3, GL_FLOAT, GL_FALSE, sizeof(GpuVertex),
                          reinterpret_cast<const void*>(offsetof(GpuVertex, normal)));
    glEnableVertexAttribArray(2);
    glVertexAttribPointer(2, 1, GL_UNSIGNED_BYTE, GL_FALSE, sizeof(GpuVertex),
                          reinterpret_cast<const void*>(offsetof(GpuVertex, material)));
    glBindVertexArray(0);
  }
  glBindBuffer(GL_ARRAY_BUFFER, 0);

  readback_.clear();
  const GLenum error = glGetError();
  if (error != GL_NO_ERROR) {
    return hysim::Error{"GL error during set-up: 0x" + [&] {
      char buf[16];
      std::snprintf(buf, sizeof buf, "%04x", error);
      return std::string(buf);
    }()};
  }
  return hysim::Status::Ok();
}

Renderer::~Renderer() {
  // GL objects need the context; callers keep it current (OffscreenRenderer does).
  for (MeshBuffers* b : {tissue_.get(), tool_.get(), chips_.get()}) {
    if (b == nullptr) continue;
    if (b->vao) glDeleteVertexArrays(1, &b->vao);
    if (b->vbo) glDeleteBuffers(1, &b->vbo);
    if (b->ibo) glDeleteBuffers(1, &b->ibo);
  }
  for (GLuint* rb : {&msaa_color_, &msaa_depth_, &resolve_color_, &resolve_depth_}) {
    if (*rb) glDeleteRenderbuffers(1, rb);
  }
  if (msaa_fbo_) glDeleteFramebuffers(1, &msaa_fbo_);
  if (resolve_fbo_) glDeleteFramebuffers(1, &resolve_fbo_);
  if (program_) glDeleteProgram(program_);
}

void Renderer::upload(const SurfaceMesh& mesh, SurfaceMaterial default_material,
                      MeshBuffers& b) {
  const std::size_t nv = mesh.positions.size() / 3;
  const std::size_t nt = mesh.triangles.size() / 3;

  // Bad indices would make GL read outside the buffer: drop those triangles. The common
  // case (all valid) uploads the caller's array without a copy.
  const std::uint32_t* indices = mesh.triangles.data();
  std::size_t index_count = nt * 3;
  const bool all_valid = std::all_of(mesh.triangles.begin(), mesh.triangles.begin() +
                                     static_cast<std::ptrdiff_t>(nt * 3),
                                     [nv](std::uint32_t i) { return i < nv; });
  if (!all_valid) {
    b.valid_tris.clear();
    for (std::size_t t = 0; t < nt; ++t) {
      const std::uint32_t* tri = &mesh.triangles[3 * t];
      if (tri[0] < nv && tri[1] < nv && tri[2] < nv) b.valid_tris.insert(b.valid_tris.end(), tri, tri + 3);
    }
    indices = b.valid_tris.data();
    index_count = b.valid_tris.size();
  }

  computeVertexNormals(mesh.positions, mesh.triangles, b.normals);
  b.vertices.resize(nv);
  const bool has_material = mesh.material.size() == nv;
  for (std::size_t v = 0; v < nv; ++v) {
    GpuVertex& g = b.vertices[v];
    std::memcpy(g.position, &mesh.positions[3 * v], sizeof g.position);
    std::memcpy(g.normal, &b.normals[3 * v], sizeof g.normal);
    const auto m = static_cast<std::uint8_t>(has_material ? mesh.material[v] : default_material);
    g.material = m <= 3 ? m : static_cast<std::uint8_t>(default_material);
  }

  // Buffers grow to the largest mesh seen and are then refilled in place.
  const std::size_t vbytes = nv * sizeof(GpuVertex);
  const std::size_t ibytes = index_count * sizeof(std::uint32_t);
  glBindBuffer(GL_ARRAY_BUFFER, b.vbo);
  if (vbytes > b.vbo_capacity) {
    glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(vbytes), b.vertices.data(),
                 GL_DYNAMIC_DRAW);
    b.vbo_capacity = vbytes;
  } else if (vbytes > 0) {
    glBufferSubData(GL_ARRAY_BUFFER, 0, static_cast<GLsizeiptr>(vbytes), b.vertices.data());
  }
  glBindBuffer(GL_ARRAY_BUFFER, 0);
  // The element buffer binding is VAO state.
  glBindVertexArray(b.vao);
  if (ibytes > b.ibo_capacity) {
    glBufferData(GL_ELEMENT_ARRAY_BUFFER, static_cast<GLsizeiptr>(ibytes), indices,
                 GL_DYNAMIC_DRAW);
    b.ibo_capacity = ibytes;
  } else if (ibytes > 0) {
    glBufferSubData(GL_ELEMENT_ARRAY_BUFFER, 0, static_cast<GLsizeiptr>(ibytes), indices);
  }
  glBindVertexArray(0);
  b.index_count = static_cast<GLsizei>(index_count);
}

void Renderer::drawMesh(const MeshBuffers& b, const std::array<float, 16>& model,
                        const std::array<float, 9>& normal_matrix) {
  if (b.index_count == 0) return;
  glUniformMatrix4fv(u_model_, 1, GL_FALSE, model.data());
  glUniformMatrix3fv(u_normal_matrix_, 1, GL_FALSE, normal_matrix.data());
  glBindVertexArray(b.vao);
  glDrawElements(GL_TRIANGLES, b.index_count, GL_UNSIGNED_INT, nullptr);
  glBindVertexArray(0);
  last_triangles_ += static_cast<std::size_t>(b.index_count) / 3;
}

Image Renderer::render(const RenderSnapshot& snapshot) {
  Image image;
  render(snapshot, image);
  return image;
}

void Renderer::render(const RenderSnapshot& snapshot, Image& out) {
  draw(snapshot);
  glBindFramebuffer(GL_READ_FRAMEBUFFER, resolve_fbo_);
  glReadBuffer(GL_COLOR_ATTACHMENT0);
  glPixelStorei(GL_PACK_ALIGNMENT, 1);
  out.width = width_;
  out.height = height_;
  const std::size_t row = static_cast<std::size_t>(width_) * 4;
  out.rgba.resize(row * static_cast<std::size_t>(height_));
  glReadPixels(0, 0, width_, height_, GL_RGBA, GL_UNSIGNED_BYTE, out.rgba.data());
  glBindFramebuffer(GL_FRAMEBUFFER, 0);

  // GL's row 0 is the bottom; the Image's row 0 is the top. Swap rows in place.
  for (int y = 0; y < height_ / 2; ++y) {
    std::uint8_t* a = out.rgba.data() + static_cast<std::size_t>(y) * row;
    std::uint8_t* b = out.rgba.data() + static_cast<std::size_t>(height_ - 1 - y) * row;
    std::swap_ranges(a, a + row, b);
  }
}

void Renderer::blitTo(unsigned framebuffer, int x, int y, int w, int h) const {
  if (w <= 0 || h <= 0) return;
  glBindFramebuffer(GL_READ_FRAMEBUFFER, resolve_fbo_);
  glReadBuffer(GL_COLOR_ATTACHMENT0);
  glBindFramebuffer(GL_DRAW_FRAMEBUFFER, framebuffer);
  glDisable(GL_SCISSOR_TEST);
  // Linear filtering: the window's view area rarely has the renderer's size.
  const GLenum filter = (w == width_ && h == height_) ? GL_NEAREST : GL_LINEAR;
  glBlitFramebuffer(0, 0, width_, height_, x, y, x + w, y + h, GL_COLOR_BUFFER_BIT, filter);
  glBindFramebuffer(GL_FRAMEBUFFER, framebuffer);
}

void Renderer::draw(const RenderSnapshot& snapshot) {
  const Camera& camera = snapshot.camera;
  const CameraMatrices cm = cameraMatrices(camera, width_, height_);
  const std::array<float, 16> view_proj = multiply(cm.projection, cm.view);

  glBindFramebuffer(GL_FRAMEBUFFER, samples_ > 0 ? msaa_fbo_ : resolve_fbo_);
  glViewport(0, 0, width_, height_);
  glDisable(GL_SCISSOR_TEST);  // the clear covers the whole frame
  glClearColor(0.0f, 0.0f, 0.0f, 1.0f);
  glClearDepth(1.0);
  glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
  glEnable(GL_DEPTH_TEST);
  glDepthFunc(GL_LESS);
  glDisable(GL_CULL_FACE);  // inner faces of the cavity are what the scope sees
  glDisable(GL_BLEND);

  glUseProgram(program_);
  glUniformMatrix4fv(u_view_proj_, 1, GL_FALSE, view_proj.data());
  glUniform3f(u_eye_, camera.tip[0], camera.tip[1], camera.tip[2]);
  const float r0 = options_.light_radius_mm;
  glUniform1f(u_light_scale_, std::max(camera.light_intensity, 0.0f) * r0 * r0);

  // Only the circle's bounding square can be non-black: scissor the rest away (a quarter
  // of a 4:3 frame that llvmpipe then neither rasterises nor shades). The clear above
  // already made it black.
  const int side = std::min(width_, height_);
  glEnable(GL_SCISSOR_TEST);
  glScissor((width_ - side) / 2, (height_ - side) / 2, side, side);

  last_triangles_ = 0;
  // The tool first: it is in front, so the tissue behind it fails the early depth test.
  if (snapshot.tool_visible && !snapshot.tool.triangles.empty()) {
    const Pose& pose = snapshot.tool_pose;
    const auto& r = pose.rotation;
    const std::array<float, 16> model = {r[0], r[1], r[2], 0, r[3], r[4], r[5], 0,
                                         r[6], r[7], r[8], 0, pose.position[0],
                                         pose.position[1], pose.position[2], 1};
    upload(snapshot.tool, SurfaceMaterial::Tool, *tool_);
    drawMesh(*tool_, model, normalMatrix(r));
  }
  // Chips: each body-frame surface moved by its pose, all into one world-frame mesh (one
  // upload and one draw call for up to a few dozen small meshes).
  if (!snapshot.chips.empty()) {
    SurfaceMesh& w = chips_world_;
    w.positions.clear();
    w.triangles.clear();
    w.material.clear();
    for (const Chip& chip : snapshot.chips) {
      const std::size_t nv = chip.surface.positions.size() / 3;
      const auto base = static_cast<std::uint32_t>(w.positions.size() / 3);
      const auto& r = chip.pose.rotation;
      const auto& t = chip.pose.position;
      for (std::size_t v = 0; v < nv; ++v) {
        const float* p = &chip.surface.positions[3 * v];
        for (int k = 0; k < 3; ++k) w.positions.push_back(r[k] * p[0] + r[3 + k] * p[1] + r[6 + k] * p[2] + t[k]);
      }
      for (std::uint32_t i : chip.surface.triangles) {
        w.triangles.push_back(i < nv ? base + i : 0xffffffffu);  // bad indices stay bad
      }
      for (std::size_t v = 0; v < nv; ++v) {
        w.material.push_back(v < chip.surface.material.size() ? chip.surface.material[v] : SurfaceMaterial::Cut);
      }
    }
    upload(w, SurfaceMaterial::Cut, *chips_);
    drawMesh(*chips_, kIdentity4, kIdentity3);
  }
  upload(snapshot.tissue, SurfaceMaterial::Endometrium, *tissue_);
  drawMesh(*tissue_, kIdentity4, kIdentity3);
  glDisable(GL_SCISSOR_TEST);
  glUseProgram(0);

  if (samples_ > 0) {
    glBindFramebuffer(GL_READ_FRAMEBUFFER, msaa_fbo_);
    glBindFramebuffer(GL_DRAW_FRAMEBUFFER, resolve_fbo_);
    glBlitFramebuffer(0, 0, width_, height_, 0, 0, width_, height_, GL_COLOR_BUFFER_BIT,
                      GL_NEAREST);
  }
  glBindFramebuffer(GL_FRAMEBUFFER, 0);
}

hysim::Result<std::unique_ptr<OffscreenRenderer>> OffscreenRenderer::create(
    int width, int height, const RendererOptions& options, const EglOptions& egl) {
  auto context = EglHeadlessContext::create(egl);
  if (!context.ok()) return hysim::Error{context.error()};
  auto renderer = Renderer::create(width, height, options);
  if (!renderer.ok()) return hysim::Error{renderer.error()};
  auto result = std::unique_ptr<OffscreenRenderer>(new OffscreenRenderer());
  result->context_ = std::move(*context);
  result->renderer_ = std::move(*renderer);
  return result;
}

OffscreenRenderer::~OffscreenRenderer() {
  // The renderer's GL objects are deleted in the context, so it must be current here.
  if (context_ && renderer_) {
    if (context_->makeCurrent().ok()) {
      renderer_.reset();
    } else {
      (void)renderer_.release();  // leak the GL names rather than call GL without a context
    }
  }
}

void OffscreenRenderer::render(const RenderSnapshot& snapshot, Image& out) {
  // Several renderers may live on one thread: draw in ours. Re-binding the current
  // context is a no-op for the driver.
  (void)context_->makeCurrent();
  renderer_->render(snapshot, out);
}

Image OffscreenRenderer::render(const RenderSnapshot& snapshot) {
  Image image;
  render(snapshot, image);
  return image;
}

hysim::Status OffscreenRenderer::renderToPng(const RenderSnapshot& snapshot,
                                             const std::string& path) {
  return writePng(path, render(snapshot));
}

}  // namespace hysim::render
