// Stage 1, classification: nodes on the surface, crossed edges and tets, the work arrays and
// the node -> tets lists.
#include <algorithm>
#include <cmath>

#include "cut3d_stages.hpp"

namespace hysim::cutting::cut3d_detail {

Cut3D::Cut3D(const TetMesh& input_, const CutSurface& surface_, const Cut3DOptions& options_, Clock::time_point start_)
    : input(input_),
      surface(surface_),
      options(options_),
      start(start_),
      mark(start_),
      N0(input_.numNodes()),
      M0(input_.numTets()),
      plane(surface_.isPlane()),
      deleting(options_.method == CutMethod::Delete),
      cosFeature(std::cos(options_.feature_angle_deg * M_PI / 180.0)) {}

void Work::init(const TetMesh& input, size_t extraNodes, size_t extraTets) {
  N0 = input.numNodes();
  M0 = input.numTets();
  X.reserve(N0 + extraNodes);
  T.reserve(M0 + extraTets);
  extraMat.reserve(extraTets);
  X.resize(N0);
  const double* c[3] = {input.X.col(0).data(), input.X.col(1).data(), input.X.col(2).data()};
  for (int i = 0; i < N0; ++i) X[i] = Vec3(c[0][i], c[1][i], c[2][i]);
  T.resize(M0);
  const std::int32_t* d[4] = {input.T.col(0).data(), input.T.col(1).data(), input.T.col(2).data(),
                              input.T.col(3).data()};
  for (int t = 0; t < M0; ++t) T[t] = {d[0][t], d[1][t], d[2][t], d[3][t]};
}

bool Cut3D::classify() {
  const Vec3 lo = input.X.colwise().minCoeff().transpose(), hi = input.X.colwise().maxCoeff().transpose();
  const double diag = (hi - lo).norm();
  if (!(diag > 0)) return false;
  eps = options.on_surface_tolerance * diag;
  on.assign(N0, 0);
  if (plane) {
    classifyPlane();
  } else {
    classifySurface();
  }
  result.report.crossed_edges = static_cast<int>(crossed.size());
  result.report.crossed_elements = static_cast<int>(crossedTets.size());
  indexCrossedEdges();
  // Room for what the cut appends (split nodes and their tets, copies), so that the working
  // arrays are not copied as they grow (a guess; they still grow past it if needed).
  w.init(input, 4 * crossed.size() + 64, 12 * crossed.size() + 64);
  // All tets, each list ascending. The stages look only at the stars within one edge step of
  // the crossed tets and of the nodes on the surface; the optimisation takes the lists over,
  // patched where the cut changed tets (one O(#T) build for both).
  buildStarLists(input.T, N0, &stars);
  lap(result.report.classify_ms);
  return true;
}

// Signed distances; crossed tets have nodes strictly on both sides.
void Cut3D::classifyPlane() {
  phi.resize(N0);
  const Vec3 n = surface.planeNormal(), p = surface.planePoint();
  // Per node: 1 strictly on the positive side, 2 strictly on the negative side.
  std::vector<std::uint8_t> sideBits(N0);
  for (int i = 0; i < N0; ++i) {
    phi[i] = n.dot(input.X.row(i).transpose() - p);
    sideBits[i] = static_cast<std::uint8_t>((phi[i] > eps ? 1 : 0) | (phi[i] < -eps ? 2 : 0));
    if (std::abs(phi[i]) <= eps) {
      on[i] = 1;
      onNodes.push_back(i);
    }
  }
  const std::int32_t* T0c[4] = {input.T.col(0).data(), input.T.col(1).data(), input.T.col(2).data(),
                                input.T.col(3).data()};
  for (int t = 0; t < M0; ++t)
    if ((sideBits[T0c[0][t]] | sideBits[T0c[1][t]] | sideBits[T0c[2][t]] | sideBits[T0c[3][t]]) == 3)
      crossedTets.push_back(t);
  edgeIndex.reserve(crossedTets.size());  // about as many crossed edges as crossed tets
  for (const int t : crossedTets) {
    const std::int32_t tv[4] = {T0c[0][t], T0c[1][t], T0c[2][t], T0c[3][t]};
    for (const auto& e : kEdge) {
      const int a = tv[e[0]], b = tv[e[1]];
      if (!((phi[a] > eps && phi[b] < -eps) || (phi[a] < -eps && phi[b] > eps))) continue;
      const auto key = edgeKey(a, b);
      if (!edgeIndex.tryEmplace(key, static_cast<std::int32_t>(crossed.size())).second) continue;
      const int lo_ = std::min(a, b), hi_ = std::max(a, b);
      const double tt = phi[lo_] / (phi[lo_] - phi[hi_]);
      crossed.push_back({lo_, hi_, tt, Vec3::Zero(), true});
    }
  }
}

// Open surface: tets near the surface's tree are tested edge by edge; crossed tets have a
// crossed edge.
void Cut3D::classifySurface() {
  std::vector<std::uint8_t> seen(N0, 0);
  FlatMap<std::uint64_t, std::uint8_t, EdgeKeyHash> tested(kNoEdge);
  // Outcodes against the surface's box grown by 2 eps (bit per side and axis): a tet whose
  // nodes share a bit lies outside that box, which is what mayTouch tests first.
  std::vector<std::uint8_t> outcode(N0);
  {
    const Eigen::Array3d blo = surface.bounds().min().array() - 2 * eps, bhi = surface.bounds().max().array() + 2 * eps;
    // Column by column (contiguous coordinates: the compares vectorise).
    const double *x0 = input.X.col(0).data(), *x1 = input.X.col(1).data(), *x2 = input.X.col(2).data();
    const double lo0 = blo[0], lo1 = blo[1], lo2 = blo[2], hi0 = bhi[0], hi1 = bhi[1], hi2 = bhi[2];
    std::uint8_t* oc = outcode.data();
    for (int i = 0; i < N0; ++i)
      oc[i] = static_cast<std::uint8_t>((x0[i] < lo0 ? 1 : 0) | (x0[i] > hi0 ? 2 : 0) | (x1[i] < lo1 ? 4 : 0) |
                                        (x1[i] > hi1 ? 8 : 0) | (x2[i] < lo2 ? 16 : 0) | (x2[i] > hi2 ? 32 : 0));
  }
  for (int t = 0; t < M0; ++t) {
    if (outcode[input.T(t, 0)] & outcode[input.T(t, 1)] & outcode[input.T(t, 2)] & outcode[input.T(t, 3)]) continue;
    Eigen::AlignedBox3d box;
    for (int k = 0; k < 4; ++k) box.extend(input.X.row(input.T(t, k)).transpose());
    // Tets away from every leaf of the surface's tree have no node on it and no crossed
    // edge (the margin 2 eps only adds tets, which then find nothing).
    if (!surface.mayTouch(box, 2 * eps)) continue;
    for (int k = 0; k < 4; ++k) {
      const int v = input.T(t, k);
      if (seen[v]) continue;
      seen[v] = 1;
      if (surface.within(input.X.row(v).transpose(), eps)) {
        on[v] = 1;
        onNodes.push_back(v);
      }
    }
    bool any = false;
    for (const auto& e : kEdge) {
      const int a = std::min(input.T(t, e[0]), input.T(t, e[1]));
      const int b = std::max(input.T(t, e[0]), input.T(t, e[1]));
      const auto key = edgeKey(a, b);
      if (edgeIndex.contains(key)) {
        any = true;
        continue;
      }
      if (on[a] || on[b] || !tested.tryEmplace(key, 1).second) continue;
      CutSurface::Hit hit;
      if (!surface.intersectSegment(input.X.row(a).transpose(), input.X.row(b).transpose(), eps, &hit)) continue;
      edgeIndex.tryEmplace(key, static_cast<std::int32_t>(crossed.size()));
      crossed.push_back({a, b, hit.t, hit.point, true});
      crossedNormal.push_back(hit.normal);
      any = true;
    }
    if (any) crossedTets.push_back(t);
  }
  std::sort(onNodes.begin(), onNodes.end());
}

// Crossed edges by end node (CSR): the edges of n that are in edgeIndex.
void Cut3D::indexCrossedEdges() {
  crossOff.assign(N0 + 1, 0);
  crossAt.resize(2 * crossed.size());
  for (const auto& ce : crossed) {
    ++crossOff[ce.a + 1];
    ++crossOff[ce.b + 1];
  }
  for (int i = 0; i < N0; ++i) crossOff[i + 1] += crossOff[i];
  std::vector<std::int32_t> fill(crossOff.begin(), crossOff.end() - 1);
  for (int e = 0; e < static_cast<int>(crossed.size()); ++e) {
    crossAt[fill[crossed[e].a]++] = e;
    crossAt[fill[crossed[e].b]++] = e;
  }
}

}  // namespace hysim::cutting::cut3d_detail
