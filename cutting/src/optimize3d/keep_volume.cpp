// Volume kept: the last stage brings each material label's volume back to its target (what
// the cut's input had) by moving boundary nodes along their volume gradients. A tet's volume
// is linear in each of its nodes' positions, so moving one node by d changes the volume by
// exactly g . d, g the sum of its tets' gradients (zero inside the mesh); the moves
// d_i = lambda g_i with lambda = deficit / sum |g_i|^2 are the smallest (least squares) that
// restore it. Refused moves and the nodes' shared tets leave a rest: a few sweeps take it.
// What one material gained from another goes back first by moving nodes of their interface
// (inside the mesh: the total stays), the rest through each material's boundary.
#include <algorithm>
#include <cmath>
#include <vector>

#include <Eigen/Geometry>

#include "cut_optimizer.hpp"

namespace hysim::cutting::opt3d {
namespace {

constexpr int kVolumeSweeps = 4;

}  // namespace

bool CutOptimizer::leftAlone(int t) const {
  const std::vector<std::uint8_t>* alone = region.left_alone;
  return alone != nullptr && t < static_cast<int>(alone->size()) && (*alone)[t] != 0;
}

// Per label, the volume of the tets the output keeps: the live ones and the pieces left alone.
void CutOptimizer::volumesNow(std::vector<MaterialVolume>& volumes, double MaterialVolume::*field) const {
  addMaterialVolumes(mesh, field, &volumes, &dead, region.left_alone);
}

// The nodes within `maxRings` edge steps of the region's tets, off the cut (the cut's faces
// stay on its surface, the sides apart), with the labels around them and whether they lie on
// the boundary or inside: what volumeMovers picks from. Sorted by node.
void CutOptimizer::gatherVolumeNodes(int maxRings) {
  gatheredRings = maxRings;
  volumeNodes.clear();
  std::vector<std::int32_t> tets, frontier, next;
  regionTets(tets);
  std::vector<std::int8_t> ringOf(N, -1);
  for (int t : tets)
    for (int k = 0; k < 4; ++k)
      if (ringOf[mesh.T(t, k)] < 0) {
        ringOf[mesh.T(t, k)] = 0;
        frontier.push_back(mesh.T(t, k));
      }
  std::vector<std::int32_t> nodes = frontier;
  for (int r = 1; r <= maxRings && !frontier.empty(); ++r) {
    next.clear();
    for (int n : frontier)
      for (const std::int32_t *s = ed.starBegin(n), *e = ed.starEnd(n); s < e; ++s)
        for (int k = 0; k < 4 && !dead[*s]; ++k) {
          const int v = mesh.T(*s, k);
          if (ringOf[v] >= 0) continue;
          ringOf[v] = static_cast<std::int8_t>(r);
          next.push_back(v);
        }
    nodes.insert(nodes.end(), next.begin(), next.end());
    frontier.swap(next);
  }
  std::sort(nodes.begin(), nodes.end());
  for (int n : nodes) {
    VolumeNode info;
    if (!onCut[n] && describeVolumeNode(n, &info)) {
      info.ring = ringOf[n];
      volumeNodes.push_back(info);
    }
  }
}

// The labels around n (at most two) and whether n is on the boundary (its tets' volume
// gradients do not cancel) or inside; false where n can serve no goal.
bool CutOptimizer::describeVolumeNode(int n, VolumeNode* info) const {
  info->n = n;
  info->a = info->b = -1;
  Vec3 total = Vec3::Zero();
  double scale2 = 0;
  for (const std::int32_t *s = ed.starBegin(n), *e = ed.starEnd(n); s < e; ++s) {
    if (dead[*s]) {
      if (leftAlone(*s)) return false;
      continue;
    }
    const std::int32_t label = labelOf(mesh, *s);
    if (info->a < 0 || info->a == label) {
      info->a = label;
    } else if (info->b < 0 || info->b == label) {
      info->b = label;
    } else {
      return false;
    }
    int k = 0;
    while (mesh.T(*s, k) != n) ++k;
    const Vec3 gs = tetVolumeGradient(mesh, *s, k);
    total += gs;
    scale2 += gs.squaredNorm();
  }
  info->boundary = total.squaredNorm() > 1e-12 * scale2;
  const bool inside = total.squaredNorm() <= 1e-24 * scale2;
  return info->a >= 0 && (info->boundary || inside);
}

// The nodes within `rings` (gathered as far as first asked) that can serve `goal`: on the boundary with only the
// goal's label around them, or (an exchange) inside with exactly its two labels.
void CutOptimizer::volumeMovers(const VolumeGoal& goal, int rings, std::vector<std::int32_t>& nodes) {
  if (gatheredRings < rings) gatherVolumeNodes(rings);
  nodes.clear();
  for (const VolumeNode& v : volumeNodes) {
    if (v.ring > rings) continue;
    const bool serves = goal.other < 0
                            ? v.boundary && v.a == goal.label && v.b < 0
                            : !v.boundary && ((v.a == goal.label && v.b == goal.other) || (v.a == goal.other && v.b == goal.label));
    if (serves) nodes.push_back(v.n);
  }
}

// The gradient of goal.label's volume at node n where moving n serves the goal, else zero.
// A boundary goal (other < 0): every live tet around n has the label and n is on the boundary
// (the tets' gradients do not cancel). An exchange goal: the tets around n have the label and
// `other` only, both, and n is inside the mesh (what one gains the other loses, the total
// stays). A node of a piece left alone serves none.
Vec3 CutOptimizer::goalGradient(int n, const VolumeGoal& goal) const {
  Vec3 g = Vec3::Zero(), total = Vec3::Zero();
  double scale2 = 0;
  bool hasOther = false;
  for (const std::int32_t *s = ed.starBegin(n), *e = ed.starEnd(n); s < e; ++s) {
    if (dead[*s]) {
      if (leftAlone(*s)) return Vec3::Zero();
      continue;
    }
    const std::int32_t label = labelOf(mesh, *s);
    if (label != goal.label && (goal.other < 0 || label != goal.other)) return Vec3::Zero();
    int k = 0;
    while (mesh.T(*s, k) != n) ++k;
    const Vec3 gs = tetVolumeGradient(mesh, *s, k);
    total += gs;
    scale2 += gs.squaredNorm();
    if (label == goal.label) {
      g += gs;
    } else {
      hasOther = true;
    }
  }
  if (goal.other < 0) return total.squaredNorm() > 1e-12 * scale2 ? g : Vec3::Zero();
  const bool inside = total.squaredNorm() <= 1e-24 * scale2;
  return hasOther && inside && g.squaredNorm() > 1e-12 * scale2 ? g : Vec3::Zero();
}

// The volume of the live tets with `label` around n.
double CutOptimizer::starVolumeOf(int n, std::int32_t label) const {
  double v = 0;
  for (const std::int32_t *s = ed.starBegin(n), *e = ed.starEnd(n); s < e; ++s)
    if (!dead[*s] && labelOf(mesh, *s) == label) v += tetVolumeHere(mesh, *s);
  return v;
}

// One sweep: each mover takes its share of `amount` (goal.label's volume to add; the smallest
// moves in total), each within the step limit of where it started (`from`); movers refused
// (inversion, quality, the cut's side) leave the list. Adds the volume changes to *change.
void CutOptimizer::volumeSweep(const VolumeGoal& goal, double amount, std::vector<std::int32_t>& movers,
                               std::vector<Vec3>& from, VolumeChange* change) {
  std::vector<Vec3> grads(movers.size());
  double sum = 0;
  for (size_t i = 0; i < movers.size(); ++i) {
    grads[i] = goalGradient(movers[i], goal);
    sum += grads[i].squaredNorm();
  }
  if (!(sum > 0)) return;
  const double lambda = amount / sum;
  const double maxStep = options.keep_volume_step * region.edge_length;
  size_t kept = 0;
  for (size_t i = 0; i < movers.size(); ++i) {
    const int n = movers[i];
    Vec3 y = ed.position(n) + lambda * grads[i];
    const Vec3 total = y - from[i];
    if (total.norm() > maxStep) y = from[i] + total * (maxStep / total.norm());
    const Vec3 x = ed.position(n);
    if (y == x || !ed.moveAllowed(n, y, volumeFloor)) continue;
    // A node near the cut stays on its side (and off it).
    if (region.surface != nullptr && nodeWithin(n, (y - x).norm() + 4.0 * region.eps) && !sideKept(n, x, y)) continue;
    const double before = starVolumeOf(n, goal.label);
    const double otherBefore = goal.other < 0 ? 0.0 : starVolumeOf(n, goal.other);
    ed.setPosition(n, y);
    change->label += starVolumeOf(n, goal.label) - before;
    if (goal.other >= 0) change->other += starVolumeOf(n, goal.other) - otherBefore;
    didMove[n] = 1;
    movers[kept] = n;
    from[kept++] = from[i];
    if (counts) ++counts->volume_moves;
  }
  movers.resize(kept);
  from.resize(kept);
}

// Adds `amount` to goal.label's volume as far as the movers allow: near the region first,
// then farther. Returns the changes made.
CutOptimizer::VolumeChange CutOptimizer::restoreVolume(const VolumeGoal& goal, double amount, double tolerance) {
  VolumeChange change;
  std::vector<std::int32_t> movers;
  std::vector<Vec3> from;
  for (const int rings : {0, options.keep_volume_rings, 2 * options.keep_volume_rings}) {
    if (!(std::abs(amount - change.label) > tolerance)) break;
    volumeMovers(goal, rings, movers);
    from.resize(movers.size());
    for (size_t i = 0; i < movers.size(); ++i) from[i] = ed.position(movers[i]);
    for (int sweep = 0; sweep < kVolumeSweeps && std::abs(amount - change.label) > tolerance && !movers.empty(); ++sweep)
      volumeSweep(goal, amount - change.label, movers, from, &change);
  }
  return change;
}

// What one material gained from another (the interface moved) goes back across the
// interface; each material's boundary gives or takes the rest. A material whose boundary
// cannot (its moves refused) passes what is left to a neighbouring material across their
// interface, whose boundary then takes it.
void CutOptimizer::keepVolume() {
  if (!options.keep_volume) return;
  ed.refreshStars();
  std::vector<MaterialVolume> volumes = region.volume_target;
  if (volumes.empty()) volumes = startVolumes;
  for (MaterialVolume& m : volumes) m.after = 0;
  volumesNow(volumes, &MaterialVolume::after);
  const double tolerance = options.keep_volume_tolerance * meshVolume;
  bool any = false;
  for (const MaterialVolume& m : volumes) any = any || std::abs(m.drift()) > tolerance;
  if (!any) return;
  gatheredRings = -1;
  // A move may lower the worst q* around a node down to the region's worst, no further: the
  // mesh's worst q* does not fall.
  std::vector<std::int32_t> tets;
  regionTets(tets);
  volumeFloor = 1.0;
  for (int t : tets) volumeFloor = std::min(volumeFloor, ed.quality(t));
  for (MaterialVolume& a : volumes)
    for (MaterialVolume& b : volumes)
      if (a.label < b.label && a.drift() * b.drift() < 0)
        exchangeVolume(a, b, std::copysign(std::min(std::abs(a.drift()), std::abs(b.drift())), a.drift()), tolerance);
  for (MaterialVolume& m : volumes) boundaryVolume(m, tolerance);
  for (MaterialVolume& a : volumes)
    for (MaterialVolume& b : volumes)
      if (a.label != b.label && std::abs(a.drift()) > tolerance) {
        exchangeVolume(a, b, a.drift(), tolerance);
        boundaryVolume(b, tolerance);
      }
}

// Moves `amount` of volume into a from b across their interface (as far as it allows).
void CutOptimizer::exchangeVolume(MaterialVolume& a, MaterialVolume& b, double amount, double tolerance) {
  if (!(std::abs(amount) > tolerance)) return;
  const VolumeChange c = restoreVolume(VolumeGoal{a.label, b.label}, amount, tolerance);
  a.after += c.label;
  b.after += c.other;
}

// Gives m back its drift through its boundary (as far as the moves allow).
void CutOptimizer::boundaryVolume(MaterialVolume& m, double tolerance) {
  if (!(std::abs(m.drift()) > tolerance)) return;
  const VolumeChange c = restoreVolume(VolumeGoal{m.label, -1}, m.drift(), tolerance);
  m.after += c.label;
  if (counts) counts->volume_restored += c.label;
}

}  // namespace hysim::cutting::opt3d
