#include "tet_picture.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <vector>

#include "hysim/cutting/cut3d.hpp"

namespace hysim::tools {
namespace {

using Vec3 = Eigen::Vector3d;
// Outward faces of a positive tet, by the local index of the opposite vertex (as cut3d.cpp).
constexpr int kFace[4][3] = {{1, 2, 3}, {0, 3, 2}, {0, 1, 3}, {0, 2, 1}};

struct Face {
  std::array<std::int32_t, 3> key;  // sorted node indices
  std::array<std::int32_t, 3> v;    // outward order
  std::int32_t tet;
};

// Faces used by exactly one tet, outward.
std::vector<Face> outerFaces(const cutting::TetMesh& mesh) {
  std::vector<Face> all;
  all.reserve(4 * static_cast<size_t>(mesh.numTets()));
  for (int t = 0; t < mesh.numTets(); ++t)
    for (const auto& f : kFace) {
      Face face;
      face.v = {mesh.T(t, f[0]), mesh.T(t, f[1]), mesh.T(t, f[2])};
      face.key = face.v;
      std::sort(face.key.begin(), face.key.end());
      face.tet = t;
      all.push_back(face);
    }
  std::sort(all.begin(), all.end(), [](const Face& a, const Face& b) { return a.key < b.key; });
  std::vector<Face> out;
  for (size_t i = 0; i < all.size();) {
    size_t j = i + 1;
    while (j < all.size() && all[j].key == all[i].key) ++j;
    if (j == i + 1) out.push_back(all[i]);
    i = j;
  }
  return out;
}

}  // namespace

render::Image drawTetMesh(const cutting::TetMesh& mesh, const TetPictureOptions& o) {
  render::Image img(std::max(1, o.width), std::max(1, o.height));
  for (size_t i = 0; i < img.rgba.size(); ++i) img.rgba[i] = 255;
  if (mesh.numTets() == 0) return img;

  // Node positions, each piece moved away from the cut plane.
  std::vector<Vec3> X(mesh.numNodes());
  for (int i = 0; i < mesh.numNodes(); ++i) X[i] = mesh.X.row(i).transpose();
  const Vec3 pn = o.plane_normal.normalized();
  if (o.has_plane) {
    const auto comps = cutting::tetComponents(mesh);
    std::vector<Vec3> centre(comps.count, Vec3::Zero());
    std::vector<double> weight(comps.count, 0.0);
    for (int t = 0; t < mesh.numTets(); ++t) {
      const double v = std::abs(cutting::tetVolume(mesh, t));
      Vec3 c = Vec3::Zero();
      for (int k = 0; k < 4; ++k) c += 0.25 * X[mesh.T(t, k)];
      centre[comps.label[t]] += v * c;
      weight[comps.label[t]] += v;
    }
    std::vector<Vec3> shift(comps.count, Vec3::Zero());
    for (int c = 0; c < comps.count; ++c) {
      if (!(weight[c] > 0)) continue;
      const double side = pn.dot(centre[c] / weight[c] - o.plane_point);
      shift[c] = (side >= 0 ? o.gap : -o.gap) * pn;
    }
    std::vector<std::uint8_t> done(mesh.numNodes(), 0);
    for (int t = 0; t < mesh.numTets(); ++t)
      for (int k = 0; k < 4; ++k) {
        const int n = mesh.T(t, k);
        if (done[n]) continue;
        done[n] = 1;
        X[n] += shift[comps.label[t]];
      }
  }

  // Camera: w toward the eye, r to the right, u up on the screen.
  const Vec3 w = o.view_from.normalized();
  const Vec3 r = (-w).cross(o.up).normalized();
  const Vec3 u = r.cross(-w);
  Vec3 lo, hi;
  if (o.frame_min.x() <= o.frame_max.x()) {
    lo = o.frame_min - Vec3::Constant(o.has_plane ? o.gap : 0.0);
    hi = o.frame_max + Vec3::Constant(o.has_plane ? o.gap : 0.0);
  } else {
    lo = hi = X[mesh.T(0, 0)];
    for (const auto& x : X) {
      lo = lo.cwiseMin(x);
      hi = hi.cwiseMax(x);
    }
  }
  double sx0 = std::numeric_limits<double>::infinity(), sx1 = -sx0, sy0 = sx0, sy1 = -sx0;
  for (int c = 0; c < 8; ++c) {
    const Vec3 p((c & 1) ? hi.x() : lo.x(), (c & 2) ? hi.y() : lo.y(), (c & 4) ? hi.z() : lo.z());
    sx0 = std::min(sx0, r.dot(p));
    sx1 = std::max(sx1, r.dot(p));
    sy0 = std::min(sy0, u.dot(p));
    sy1 = std::max(sy1, u.dot(p));
  }
  const double margin = 0.04;
  const double scale = (1 - 2 * margin) * std::min(img.width / std::max(sx1 - sx0, 1e-12), img.height / std::max(sy1 - sy0, 1e-12));
  const double cx = 0.5 * (sx0 + sx1), cy = 0.5 * (sy0 + sy1);
  auto screen = [&](const Vec3& p) {
    return Eigen::Vector3d(0.5 * img.width + scale * (r.dot(p) - cx), 0.5 * img.height - scale * (u.dot(p) - cy), w.dot(p));
  };

  const double diag = (mesh.X.colwise().maxCoeff() - mesh.X.colwise().minCoeff()).norm();
  const double onTol = 1e-6 * diag;
  const Vec3 light = (w + 0.5 * u + 0.3 * r).normalized();
  std::vector<double> depth(static_cast<size_t>(img.width) * img.height, -std::numeric_limits<double>::infinity());
  for (const Face& f : outerFaces(mesh)) {
    const Vec3 a = X[f.v[0]], b = X[f.v[1]], c = X[f.v[2]];
    const Vec3 n = (b - a).cross(c - a).normalized();
    if (!(n.dot(w) > 0)) continue;  // back face (the pieces are closed surfaces)
    bool onCut = o.has_plane;
    for (int k = 0; k < 3 && onCut; ++k) onCut = std::abs(pn.dot(mesh.X.row(f.v[k]).transpose() - o.plane_point)) <= onTol;
    const int mat = mesh.material.size() == mesh.numTets() ? mesh.material[f.tet] : 0;
    std::array<double, 3> base = onCut ? std::array<double, 3>{205, 70, 80}
                                 : mat == 2 ? std::array<double, 3>{235, 215, 170}
                                            : std::array<double, 3>{235, 165, 155};
    const double shade = 0.35 + 0.65 * std::max(0.0, n.dot(light));
    const Vec3 P[3] = {screen(a), screen(b), screen(c)};
    const double area = (P[1].x() - P[0].x()) * (P[2].y() - P[0].y()) - (P[1].y() - P[0].y()) * (P[2].x() - P[0].x());
    if (std::abs(area) < 1e-12) continue;
    double len[3];
    for (int k = 0; k < 3; ++k) len[k] = std::max(1e-9, (P[(k + 1) % 3] - P[k]).head<2>().norm());
    const int x0 = std::max(0, static_cast<int>(std::floor(std::min({P[0].x(), P[1].x(), P[2].x()}))));
    const int x1 = std::min(img.width - 1, static_cast<int>(std::ceil(std::max({P[0].x(), P[1].x(), P[2].x()}))));
    const int y0 = std::max(0, static_cast<int>(std::floor(std::min({P[0].y(), P[1].y(), P[2].y()}))));
    const int y1 = std::min(img.height - 1, static_cast<int>(std::ceil(std::max({P[0].y(), P[1].y(), P[2].y()}))));
    for (int y = y0; y <= y1; ++y)
      for (int x = x0; x <= x1; ++x) {
        const double px = x + 0.5, py = y + 0.5;
        double e[3];  // edge functions: e[k] for the edge k -> k+1, scaled so that sum = 1
        for (int k = 0; k < 3; ++k) {
          const Vec3& p = P[k];
          const Vec3& q = P[(k + 1) % 3];
          e[k] = ((q.x() - p.x()) * (py - p.y()) - (q.y() - p.y()) * (px - p.x())) / area;
        }
        if (e[0] < 0 || e[1] < 0 || e[2] < 0) continue;
        // e[k] is the barycentric weight of the vertex opposite edge k (vertex k + 2).
        const double z = e[0] * P[2].z() + e[1] * P[0].z() + e[2] * P[1].z();
        double& d = depth[static_cast<size_t>(y) * img.width + x];
        if (z <= d) continue;
        d = z;
        // Distance in pixels to the nearest edge: e[k] * |area| / |edge k|.
        double edgeDist = std::numeric_limits<double>::infinity();
        for (int k = 0; k < 3; ++k) edgeDist = std::min(edgeDist, e[k] * std::abs(area) / len[k]);
        const double ink = edgeDist < 0.6 ? 0.35 : edgeDist < 1.2 ? 0.7 : 1.0;
        auto* pix = img.pixel(x, y);
        for (int ch = 0; ch < 3; ++ch) pix[ch] = static_cast<std::uint8_t>(std::clamp(base[ch] * shade * ink, 0.0, 255.0));
        pix[3] = 255;
      }
  }
  return img;
}

}  // namespace hysim::tools
