#include "mesh_picture.hpp"

#include <algorithm>
#include <array>
#include <cmath>

#include "hysim/cutting/mesh_stats.hpp"

namespace hysim::tools {

MeshPictureBox pictureBox(const cutting::TriMesh& mesh, double margin) {
  MeshPictureBox b;
  if (mesh.numNodes() == 0) return b;
  b.x0 = mesh.X.col(0).minCoeff();
  b.x1 = mesh.X.col(0).maxCoeff();
  b.y0 = mesh.X.col(1).minCoeff();
  b.y1 = mesh.X.col(1).maxCoeff();
  const double m = margin * std::max(b.x1 - b.x0, b.y1 - b.y0);
  b.x0 -= m;
  b.x1 += m;
  b.y0 -= m;
  b.y1 += m;
  return b;
}

namespace {

void put(render::Image& img, int x, int y, std::array<std::uint8_t, 3> c) {
  if (x < 0 || y < 0 || x >= img.width || y >= img.height) return;
  auto* p = img.pixel(x, y);
  p[0] = c[0];
  p[1] = c[1];
  p[2] = c[2];
  p[3] = 255;
}

void line(render::Image& img, double x0, double y0, double x1, double y1, std::array<std::uint8_t, 3> c, int thick) {
  const int steps = static_cast<int>(std::ceil(std::max(std::abs(x1 - x0), std::abs(y1 - y0)))) + 1;
  for (int i = 0; i <= steps; ++i) {
    const double t = static_cast<double>(i) / steps;
    const int x = static_cast<int>(std::lround(x0 + t * (x1 - x0)));
    const int y = static_cast<int>(std::lround(y0 + t * (y1 - y0)));
    for (int dx = -(thick / 2); dx <= thick / 2; ++dx)
      for (int dy = -(thick / 2); dy <= thick / 2; ++dy) put(img, x + dx, y + dy, c);
  }
}

}  // namespace

render::Image drawMesh(const cutting::TriMesh& mesh, const MeshPictureBox& box, int width,
                       const std::vector<std::array<int, 2>>& cut_edges) {
  const double sx = width / (box.x1 - box.x0);
  const int height = std::max(1, static_cast<int>(std::lround((box.y1 - box.y0) * sx)));
  render::Image img(width, height);
  for (std::size_t i = 0; i < img.rgba.size(); i += 4) {
    img.rgba[i] = img.rgba[i + 1] = img.rgba[i + 2] = 255;
    img.rgba[i + 3] = 255;
  }
  auto px = [&](int n) { return (mesh.X(n, 0) - box.x0) * sx; };
  auto py = [&](int n) { return (box.y1 - mesh.X(n, 1)) * sx; };  // y up
  for (int f = 0; f < mesh.numTris(); ++f) {
    const int a = mesh.F(f, 0), b = mesh.F(f, 1), c = mesh.F(f, 2);
    const double q = cutting::radiusRatio(mesh.X.row(a).transpose(), mesh.X.row(b).transpose(), mesh.X.row(c).transpose());
    const double s = std::clamp(q / 0.5, 0.0, 1.0);
    const std::array<std::uint8_t, 3> col = {static_cast<std::uint8_t>(255 - 135 * s), static_cast<std::uint8_t>(120 + 110 * s),
                                             static_cast<std::uint8_t>(120 + 20 * s)};
    const double X[3] = {px(a), px(b), px(c)}, Y[3] = {py(a), py(b), py(c)};
    const int xmin = std::max(0, static_cast<int>(std::floor(std::min({X[0], X[1], X[2]}))));
    const int xmax = std::min(width - 1, static_cast<int>(std::ceil(std::max({X[0], X[1], X[2]}))));
    const int ymin = std::max(0, static_cast<int>(std::floor(std::min({Y[0], Y[1], Y[2]}))));
    const int ymax = std::min(height - 1, static_cast<int>(std::ceil(std::max({Y[0], Y[1], Y[2]}))));
    for (int y = ymin; y <= ymax; ++y)
      for (int x = xmin; x <= xmax; ++x) {
        const double cx = x + 0.5, cy = y + 0.5;
        double e[3];
        for (int k = 0; k < 3; ++k) {
          const int k1 = (k + 1) % 3;
          e[k] = (X[k1] - X[k]) * (cy - Y[k]) - (Y[k1] - Y[k]) * (cx - X[k]);
        }
        if ((e[0] >= 0 && e[1] >= 0 && e[2] >= 0) || (e[0] <= 0 && e[1] <= 0 && e[2] <= 0)) put(img, x, y, col);
      }
  }
  for (int f = 0; f < mesh.numTris(); ++f)
    for (int k = 0; k < 3; ++k) {
      const int a = mesh.F(f, k), b = mesh.F(f, (k + 1) % 3);
      line(img, px(a), py(a), px(b), py(b), {70, 70, 70}, 1);
    }
  for (const auto& e : cut_edges) line(img, px(e[0]), py(e[0]), px(e[1]), py(e[1]), {0, 0, 0}, 3);
  return img;
}

}  // namespace hysim::tools
