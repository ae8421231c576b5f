// Volume kept: the last stage brings each material label's volume back to its target (what
// the cut's input had) by moving boundary nodes along their volume gradients. A tet's volume
// is linear in each of its nodes' positions, so moving one node by d changes the volume by
// exactly g . d, g the sum of its tets' gradients (zero inside the mesh); the moves
// d_i = lambda g_i with lambda = deficit / sum |g_i|^2 are the smallest (least squares) that
// restore it. Refused moves and the nodes' shared tets leave a rest: a few sweeps take it.
#include <algorithm>
#include <cmath>
#include <vector>

#include <Eigen/Geometry>

#include "cut_optimizer.hpp"

namespace hysim::cutting::opt3d {
namespace {

constexpr int kVolumeSweeps = 8;

}  // namespace

bool CutOptimizer::leftAlone(int t) const {
  const std::vector<std::uint8_t>* alone = region.left_alone;
  return alone != nullptr && t < static_cast<int>(alone->size()) && (*alone)[t] != 0;
}

// Per label, the volume of the tets the output keeps: the live ones and the pieces left alone.
void CutOptimizer::volumesNow(std::vector<MaterialVolume>& volumes, double MaterialVolume::*field) const {
  addMaterialVolumes(mesh, field, &volumes, &dead, region.left_alone);
}

// The nodes within `rings` edge steps of the region's tets whose live tets all have `label`
// and whose volume gradient is not zero (boundary nodes: inside the mesh the gradients
// cancel), off the cut (the cut's faces stay on its surface, the sides apart); a node of a
// piece left alone stays. Sorted by index.
void CutOptimizer::volumeMovers(std::int32_t label, int rings, std::vector<std::int32_t>& nodes) {
  nodes.clear();
  std::vector<std::int32_t> tets, frontier, next;
  regionTets(tets);
  std::vector<std::uint8_t> reached(N, 0);
  for (int t : tets)
    for (int k = 0; k < 4; ++k)
      if (!reached[mesh.T(t, k)]) {
        reached[mesh.T(t, k)] = 1;
        frontier.push_back(mesh.T(t, k));
      }
  nodes = frontier;
  for (int r = 0; r < rings && !frontier.empty(); ++r) {
    next.clear();
    for (int n : frontier)
      for (const std::int32_t *s = ed.starBegin(n), *e = ed.starEnd(n); s < e; ++s)
        for (int k = 0; k < 4 && !dead[*s]; ++k) {
          const int v = mesh.T(*s, k);
          if (reached[v]) continue;
          reached[v] = 1;
          next.push_back(v);
        }
    nodes.insert(nodes.end(), next.begin(), next.end());
    frontier.swap(next);
  }
  std::sort(nodes.begin(), nodes.end());
  nodes.erase(std::remove_if(nodes.begin(), nodes.end(),
                             [&](int n) { return onCut[n] || !(labelGradient(n, label).squaredNorm() > 0); }),
              nodes.end());
}

// The gradient of `label`'s volume at node n; zero where a tet around n has another label or
// belongs to a piece left alone, or where the tets' gradients cancel (inside the mesh).
Vec3 CutOptimizer::labelGradient(int n, std::int32_t label) const {
  Vec3 g = Vec3::Zero();
  double scale2 = 0;
  for (const std::int32_t *s = ed.starBegin(n), *e = ed.starEnd(n); s < e; ++s) {
    if (dead[*s]) {
      if (leftAlone(*s)) return Vec3::Zero();
      continue;
    }
    if (labelOf(mesh, *s) != label) return Vec3::Zero();
    int k = 0;
    while (mesh.T(*s, k) != n) ++k;
    const Vec3 gs = tetVolumeGradient(mesh, *s, k);
    g += gs;
    scale2 += gs.squaredNorm();
  }
  return g.squaredNorm() > 1e-12 * scale2 ? g : Vec3::Zero();
}

// The volume of the live tets around n.
double CutOptimizer::starVolumeOf(int n) const {
  double v = 0;
  for (const std::int32_t *s = ed.starBegin(n), *e = ed.starEnd(n); s < e; ++s)
    if (!dead[*s]) v += tetVolumeHere(mesh, *s);
  return v;
}

// One sweep for one label: each mover takes its share of the deficit (the smallest moves in
// total), each within the step limit of where it started (`from`); movers refused
// (inversion, quality) leave the list. Returns the volume put back.
double CutOptimizer::volumeSweep(std::int32_t label, double deficit, std::vector<std::int32_t>& movers,
                                 std::vector<Vec3>& from) {
  std::vector<Vec3> grads(movers.size());
  double sum = 0;
  for (size_t i = 0; i < movers.size(); ++i) {
    grads[i] = labelGradient(movers[i], label);
    sum += grads[i].squaredNorm();
  }
  if (!(sum > 0)) return 0;
  const double lambda = deficit / sum;
  const double maxStep = options.keep_volume_step * region.edge_length;
  double restored = 0;
  size_t kept = 0;
  for (size_t i = 0; i < movers.size(); ++i) {
    const int n = movers[i];
    Vec3 y = ed.position(n) + lambda * grads[i];
    const Vec3 total = y - from[i];
    if (total.norm() > maxStep) y = from[i] + total * (maxStep / total.norm());
    if (y == ed.position(n) || !ed.moveAllowed(n, y, options.quality_target)) continue;
    const double before = starVolumeOf(n);
    ed.setPosition(n, y);
    restored += starVolumeOf(n) - before;
    didMove[n] = 1;
    movers[kept] = n;
    from[kept++] = from[i];
    if (counts) ++counts->volume_moves;
  }
  movers.resize(kept);
  from.resize(kept);
  return restored;
}

void CutOptimizer::keepVolume() {
  if (!options.keep_volume) return;
  ed.refreshStars();
  std::vector<MaterialVolume> volumes = region.volume_target;
  if (volumes.empty()) volumes = startVolumes;
  for (MaterialVolume& m : volumes) m.after = 0;
  volumesNow(volumes, &MaterialVolume::after);
  const double tolerance = options.keep_volume_tolerance * meshVolume;
  std::vector<std::int32_t> movers;
  std::vector<Vec3> from;
  for (MaterialVolume& m : volumes)
    for (const int rings : {0, options.keep_volume_rings, 2 * options.keep_volume_rings}) {
      if (!(std::abs(m.drift()) > tolerance)) break;
      volumeMovers(m.label, rings, movers);
      from.resize(movers.size());
      for (size_t i = 0; i < movers.size(); ++i) from[i] = ed.position(movers[i]);
      for (int sweep = 0; sweep < kVolumeSweeps && std::abs(m.drift()) > tolerance && !movers.empty(); ++sweep) {
        const double restored = volumeSweep(m.label, m.drift(), movers, from);
        m.after += restored;
        if (counts) counts->volume_restored += restored;
      }
    }
}

}  // namespace hysim::cutting::opt3d
