// Stage 4, separation: faces lying in the cut and shared by two tets are cut faces; each node
// on them gets a copy per group of its tets connected through faces not cut
// (separate_nodes.cpp).
#include <algorithm>
#include <chrono>

#include "cut3d_stages.hpp"

namespace hysim::cutting::cut3d_detail {

void Cut3D::separate() {
  collectLocalTets();
  findCutFaces();
  if (!cutFaceList.empty()) separateNodes();
  for (const auto& [t, opp] : cutFaceSides) {
    const Tet tv = w.tet(t);
    result.change.cut_faces.push_back({tv[kFace[opp][0]], tv[kFace[opp][1]], tv[kFace[opp][2]]});
  }
  const auto cutEnd = Clock::now();
  result.report.cut_ms = std::chrono::duration<double, std::milli>(cutEnd - start).count();
  lap(result.report.separate_ms, cutEnd);  // (the stages so far add up to cut_ms)
}

// Local tets: the current stars of all nodes on the cut.
void Cut3D::collectLocalTets() {
  inLocal.assign(w.numTets(), 0);
  auto add = [&](int t) {
    if (!inLocal[t] && !isDeleted(t)) {
      inLocal[t] = 1;
      local.push_back(t);
    }
  };
  for (int n : onNodes)
    for (int s = stars.off[n]; s < stars.off[n + 1]; ++s) {
      const int o = stars.star[s];
      if (localOf[o] < 0) {
        add(o);
      } else {
        for (int f : fragments[localOf[o]]) add(f);
      }
    }
  for (const auto& frag : fragments)
    for (int f : frag) add(f);
}

// Faces of the local tets with every node on the cut, used by two tets on opposite sides;
// in a deterministic order.
void Cut3D::findCutFaces() {
  FlatMap<FaceKey, FaceUse, FaceFlatHash> onFaces(kNoFace);
  if (options.separate) {
    for (int t : local) {
      const Tet tv = w.tet(t);
      for (int f = 0; f < 4; ++f) {
        const int i0 = tv[kFace[f][0]], i1 = tv[kFace[f][1]], i2 = tv[kFace[f][2]];
        if (!on[i0] || !on[i1] || !on[i2]) continue;
        FaceUse& u = *onFaces.tryEmplace(makeFace(i0, i1, i2), FaceUse{}).first;
        if (u.count < 2) {
          u.tet[u.count] = t;
          u.opposite[u.count] = static_cast<std::int8_t>(f);
        }
        ++u.count;
      }
    }
  }
  onFaces.forEach([&](const FaceKey& key, const FaceUse& use) {
    if (faceOnCut(key, use)) cutFaceList.emplace_back(key, use);
  });
  std::sort(cutFaceList.begin(), cutFaceList.end(), [](const auto& x, const auto& y) { return x.first.v < y.first.v; });
  for (const auto& [key, use] : cutFaceList) {
    cutFaceSides.emplace_back(use.tet[0], use.opposite[0]);
    cutFaceSides.emplace_back(use.tet[1], use.opposite[1]);
  }
  result.report.cut_faces = static_cast<int>(cutFaceList.size());
}

// Only a face between the two sides is cut (with through-node approximation, a face of
// on-nodes may have both its tets on one side); on a curved surface it must lie in it.
bool Cut3D::faceOnCut(const FaceKey& key, const FaceUse& use) const {
  if (use.count != 2) return false;
  if (!approx.empty() && !(sideOf(use.tet[0]) * sideOf(use.tet[1]) < 0)) return false;
  return plane || faceInSurface(key, use);
}

// Side of a tet: the sign of the distances of its nodes off the cut (all alike after the
// subdivision); when every node is on the cut, of the nodes the cut was routed through (a
// node treated as on the surface without moving keeps its own small distance).
double Cut3D::sideOf(int t) const {
  const Tet tv = w.tet(t);
  double off = 0, routed = 0;
  for (int v : tv) {
    if (v >= N0 || (on[v] && !approx[v])) continue;
    const double d = plane ? phi[v] : surface.signedDistance(w.x(v));
    (on[v] ? routed : off) += d;
  }
  return off != 0 ? off : routed;
}

// The face lies in the surface, not just has its corners on it.
bool Cut3D::faceInSurface(const FaceKey& key, const FaceUse& use) const {
  const Vec3 a = w.x(key.v[0]), b = w.x(key.v[1]), c = w.x(key.v[2]);
  const double size = std::max({(b - a).norm(), (c - a).norm(), (c - b).norm()});
  const Vec3 centre = (a + b + c) / 3.0;
  if (surface.within(centre, eps + 0.05 * size)) return true;
  // On a curved surface a flat face with its corners on the surface lies off it by the
  // sagitta (about size^2 / (8 R)), and a thin tet next to it may lie wholly on the far side
  // of the surface. The face is still on the cut when the surface passes between the two
  // tets there: the segment between their vertices opposite the face (or, where one of those
  // is on the surface, between their centroids) crosses it near the face.
  auto crossesNear = [&](const Vec3& p, const Vec3& q) {
    CutSurface::Hit hit;
    return surface.intersectSegment(p, q, eps, &hit) && (hit.point - centre).norm() <= std::max(size, (q - p).norm());
  };
  auto centroid = [&](int t) {
    const Tet tv = w.tet(t);
    return Vec3((w.x(tv[0]) + w.x(tv[1]) + w.x(tv[2]) + w.x(tv[3])) / 4.0);
  };
  const int o0 = w.tet(use.tet[0])[use.opposite[0]], o1 = w.tet(use.tet[1])[use.opposite[1]];
  return (!on[o0] && !on[o1] && crossesNear(w.x(o0), w.x(o1))) ||
         crossesNear(centroid(use.tet[0]), centroid(use.tet[1]));
}

}  // namespace hysim::cutting::cut3d_detail
