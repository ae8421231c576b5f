#include "hysim/engine/tet_locator.hpp"

#include <Eigen/LU>

#include <algorithm>
#include <cmath>
#include <limits>

namespace hysim::engine {
namespace {

// A float at or below (above) v: a box rounded outwards. The cast rounds to the nearest float
// (within 2^-24 |v|); two float steps more make sure of the side.
float roundDown(double v) { return static_cast<float>(v - 2.4e-7 * std::abs(v) - 1e-30); }
float roundUp(double v) { return static_cast<float>(v + 2.4e-7 * std::abs(v) + 1e-30); }

}  // namespace

void TetLocator::build(const cutting::TetMesh& mesh, const sim::NodeVectors& x, double margin_mm) {
  margin_ = margin_mm;
  max_box_ = 0.0;
  built_x_ = x;
  const int nt = mesh.numTets();
  dims_.setZero();
  if (nt == 0 || x.rows() == 0) {
    cell_start_.clear();
    cell_boxes_.clear();
    return;
  }
  Eigen::Vector3d lo = x.colwise().minCoeff().transpose(), hi = x.colwise().maxCoeff().transpose();
  lo.array() -= margin_;
  hi.array() += margin_;
  // Cells about twice the mean tet size: a few tets per cell.
  const double volume = (hi - lo).prod();
  cell_ = std::max(1e-6, 2.0 * std::cbrt(volume / nt));
  // Cells by multiplication (a division per coordinate was a third of the build). Rounding
  // of x * inv_cell_ is monotone in x, as build and locate use the same map: a tet whose box
  // meets a query's box still shares a cell with it.
  inv_cell_ = 1.0 / cell_;
  origin_ = lo;
  for (int c = 0; c < 3; ++c) dims_[c] = std::max(1, static_cast<int>(std::ceil((hi[c] - lo[c]) / cell_)));
  const long cells = static_cast<long>(dims_.x()) * dims_.y() * dims_.z();
  // Buffers keep their capacity between builds: a rebuild during a pass allocates nothing
  // unless the grid grew.
  std::vector<int>& count = cell_start_;
  count.assign(static_cast<size_t>(cells) + 1, 0);
  // Each tet is listed in the cells its box (at the build, not grown) meets: a few cells per
  // tet. A query grows its own point by how far the nodes may have moved since (locate()).
  auto cellRange = [&](int t, Eigen::Vector3i& a, Eigen::Vector3i& b) {
    Eigen::Vector3d tlo = x.row(mesh.T(t, 0)).transpose(), thi = tlo;
    for (int k = 1; k < 4; ++k) {
      tlo = tlo.cwiseMin(x.row(mesh.T(t, k)).transpose());
      thi = thi.cwiseMax(x.row(mesh.T(t, k)).transpose());
    }
    double* box = &boxes_[6 * static_cast<size_t>(t)];
    for (int c = 0; c < 3; ++c) {
      box[c] = tlo[c];
      box[3 + c] = thi[c];
    }
    max_box_ = std::max(max_box_, (thi - tlo).maxCoeff());
    for (int c = 0; c < 3; ++c) {
      a[c] = std::clamp(static_cast<int>(std::floor((tlo[c] - origin_[c]) * inv_cell_)), 0, dims_[c] - 1);
      b[c] = std::clamp(static_cast<int>(std::floor((thi[c] - origin_[c]) * inv_cell_)), 0, dims_[c] - 1);
    }
  };
  auto index = [&](int i, int j, int k) { return (static_cast<long>(k) * dims_.y() + j) * dims_.x() + i; };
  // Each tet's cell range, kept for the second pass.
  ranges_.resize(2 * static_cast<size_t>(nt));
  boxes_.resize(6 * static_cast<size_t>(nt));
  for (int t = 0; t < nt; ++t) {
    Eigen::Vector3i& a = ranges_[2 * static_cast<size_t>(t)];
    Eigen::Vector3i& b = ranges_[2 * static_cast<size_t>(t) + 1];
    cellRange(t, a, b);
    for (int k = a.z(); k <= b.z(); ++k)
      for (int j = a.y(); j <= b.y(); ++j)
        for (int i = a.x(); i <= b.x(); ++i) ++count[index(i, j, k) + 1];
  }
  for (long c = 0; c < cells; ++c) count[c + 1] += count[c];
  std::vector<int>& fill = fill_;
  fill.assign(cell_start_.begin(), cell_start_.end() - 1);
  // Each entry also holds its tet's build box grown by the query filter's relative part
  // (1e-6 of its largest extent, see locate()) and rounded outwards to floats: the filter
  // then reads the cell's entries in order instead of each tet's box elsewhere.
  cell_boxes_.resize(static_cast<size_t>(cell_start_.back()));
  for (int t = 0; t < nt; ++t) {
    const Eigen::Vector3i& a = ranges_[2 * static_cast<size_t>(t)];
    const Eigen::Vector3i& b = ranges_[2 * static_cast<size_t>(t) + 1];
    const double* box = &boxes_[6 * static_cast<size_t>(t)];
    const double pad = 1e-6 * std::max({box[3] - box[0], box[4] - box[1], box[5] - box[2]});
    Entry entry;
    entry.tet = t;
    for (int c = 0; c < 3; ++c) {
      entry.lo[c] = roundDown(box[c] - pad);
      entry.hi[c] = roundUp(box[3 + c] + pad);
    }
    for (int k = a.z(); k <= b.z(); ++k)
      for (int j = a.y(); j <= b.y(); ++j)
        for (int i = a.x(); i <= b.x(); ++i) {
          cell_boxes_[fill[index(i, j, k)]++] = entry;
        }
  }
}

int TetLocator::locate(const cutting::TetMesh& mesh, const sim::NodeVectors& x, const Eigen::Vector3d& p,
                       double max_displacement) const {
  if (cell_start_.empty()) return -1;
  const double moved = max_displacement >= 0.0 ? max_displacement : margin_;
  // A tet that holds p now had a build box within `moved` of p (plus the tolerances below,
  // bounded by `slack`), so it is listed in a cell of the box around p grown by that.
  const double slack = moved + 1e-6 * (max_box_ + 2.0 * moved) + 1e-9;
  int lo[3], hi[3];
  for (int c = 0; c < 3; ++c) {
    const double a = std::floor((p[c] - slack - origin_[c]) * inv_cell_);
    const double b = std::floor((p[c] + slack - origin_[c]) * inv_cell_);
    if (b < 0.0 || a >= dims_[c]) return -1;
    lo[c] = static_cast<int>(std::max(a, 0.0));
    hi[c] = static_cast<int>(std::min(b, static_cast<double>(dims_[c] - 1)));
  }
  // An entry's box is grown by 1e-6 of its extent already; the rest of the growth is
  // moved + 1e-6 (2 moved) + 1e-9 (the tet's extent now is at most its build extent + 2 moved),
  // with another 1e-9 for rounding.
  const double grow = moved + 2e-6 * moved + 2e-9;
  // The lowest-numbered tet that holds p (a point on a shared face lies in several): the
  // same answer whichever cells list it.
  int best = -1;
  for (int k = lo[2]; k <= hi[2]; ++k)
    for (int j = lo[1]; j <= hi[1]; ++j)
      for (int i = lo[0]; i <= hi[0]; ++i) {
        const long cell = (static_cast<long>(k) * dims_.y() + j) * dims_.x() + i;
        for (int e = cell_start_[cell]; e < cell_start_[cell + 1]; ++e) {
          const Entry& entry = cell_boxes_[e];
          const int t = entry.tet;
          if (best >= 0 && t >= best) break;  // a cell lists its tets in increasing order
          // Tets whose build box, grown by how far the nodes may have moved and by
          // containsNow()'s tolerance, does not hold p would fail containsNow() too.
          if (p[0] < entry.lo[0] - grow || p[1] < entry.lo[1] - grow || p[2] < entry.lo[2] - grow ||
              p[0] > entry.hi[0] + grow || p[1] > entry.hi[1] + grow || p[2] > entry.hi[2] + grow) {
            continue;
          }
          if (containsNow(mesh, x, t, p)) {
            best = t;
            break;
          }
        }
      }
  return best;
}

// Whether p lies in tet t at positions x. (locate() first drops the tets whose build box,
// grown by how far the nodes may have moved since and by this test's tolerance below for the
// largest box the tet can have now, does not hold p: they would fail this test too.)
bool TetLocator::containsNow(const cutting::TetMesh& mesh, const sim::NodeVectors& x, int t,
                             const Eigen::Vector3d& p) const {
  const Eigen::Vector3d a = x.row(mesh.T(t, 0)).transpose();
  Eigen::Matrix3d m;
  for (int k = 0; k < 3; ++k) m.col(k) = x.row(mesh.T(t, k + 1)).transpose() - a;
  // The box is grown by a millionth of its size, far more than the test's rounding (which
  // would need a tet with a condition number ~1e9 to accept a point that much outside it).
  const Eigen::Array3d lo = m.rowwise().minCoeff().array().min(0.0) + a.array();
  const Eigen::Array3d hi = m.rowwise().maxCoeff().array().max(0.0) + a.array();
  const double tol = 1e-6 * (hi - lo).maxCoeff();
  if ((p.array() < lo - tol).any() || (p.array() > hi + tol).any()) return false;
  const double det = m.determinant();
  if (std::abs(det) < 1e-300) return false;
  const Eigen::Vector3d w = m.inverse() * (p - a);  // barycentric coordinates of nodes 1..3
  return w.minCoeff() >= 0.0 && w.sum() <= 1.0;
}

double TetLocator::maxDisplacement(const sim::NodeVectors& x) const {
  if (x.rows() != built_x_.rows()) return std::numeric_limits<double>::infinity();
  double worst = 0.0;
  for (Eigen::Index i = 0; i < x.rows(); ++i) worst = std::max(worst, (x.row(i) - built_x_.row(i)).squaredNorm());
  return std::sqrt(worst);
}

}  // namespace hysim::engine
