// TetMeshEditor's checked operations: each leaves the mesh valid (stars refreshed) or
// changes nothing, and is recorded for the TopologyChange that compact() completes.
#include <algorithm>
#include <array>
#include <string>

#include <Eigen/Geometry>

#include "hysim/cutting/mesh_stats.hpp"
#include "hysim/cutting/tet_mesh_editor.hpp"
#include "hysim/cutting/tet_faces.hpp"

namespace hysim::cutting {
namespace {

constexpr const auto& kFaceOf = kTetFace;

double volume6Of(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c,
                 const Eigen::Vector3d& d) {
  return (b - a).dot((c - a).cross(d - a));
}

bool holds(const TetMesh& mesh, int t, int n) {
  return mesh.T(t, 0) == n || mesh.T(t, 1) == n || mesh.T(t, 2) == n || mesh.T(t, 3) == n;
}

}  // namespace

void TetMeshEditor::ensureTracking() {
  if (tracking_) return;
  tracking_ = true;
  change_ = TopologyChange{};
  change_.old_num_nodes = numNodes();
  change_.old_num_elements = numTets();
  tetOrigin_.resize(numTets());
  for (int t = 0; t < numTets(); ++t) tetOrigin_[t] = t;
  nodeOrigin_.resize(numNodes());
  for (int n = 0; n < numNodes(); ++n) nodeOrigin_[n] = n;
  mergedInto_.assign(numNodes(), -1);
  movedFlag_.assign(numNodes(), 0);
}

int TetMeshEditor::addNode(const Vec3& x) {
  ensureTracking();
  const int n = numNodes();
  mesh_.X.conservativeResize(n + 1, 3);
  mesh_.X.row(n) = x.transpose();
  touched_.push_back(0);
  nodeVer_.push_back(++verClock_);
  poolStart_.push_back(static_cast<std::int32_t>(pool_.size()));  // (an empty pool row)
  poolLen_.push_back(0);
  nodeOrigin_.push_back(-1);
  mergedInto_.push_back(-1);
  movedFlag_.push_back(0);
  return n;
}

int TetMeshEditor::takeSlot(std::int32_t label) {
  ensureTracking();
  while (!killed_.empty() && !dead_[killed_.back()]) killed_.pop_back();
  int t;
  if (!killed_.empty()) {
    t = killed_.back();
    killed_.pop_back();
  } else {
    t = numTets();
    mesh_.T.conservativeResize(t + 1, 4);
    mesh_.T.row(t) = mesh_.T.row(0);  // (any live nodes; setTetNodes writes the real ones)
    mesh_.material.conservativeResize(t + 1);
    dead_.push_back(1);
    qSlot_.push_back(-1);
    qPool_.resize(qPool_.size() + 1);
    tetOrigin_.push_back(-1);
  }
  dead_[t] = 0;
  mesh_.material(t) = label;
  tetOrigin_[t] = -1;
  return t;
}

void TetMeshEditor::rewrite(int t, const std::array<int, 4>& v) {
  ensureTracking();
  tetOrigin_[t] = -1;
  setTetNodes(t, v[0], v[1], v[2], v[3]);
}

bool TetMeshEditor::isEdge(int a, int b) const {
  for (const std::int32_t *s = starBegin(a), *e = starEnd(a); s < e; ++s)
    if (!dead_[*s] && holds(mesh_, *s, b)) return true;
  return false;
}

int TetMeshEditor::faceUses(int a, int b, int c) const {
  int uses = 0;
  for (const std::int32_t *s = starBegin(a), *e = starEnd(a); s < e; ++s)
    if (!dead_[*s] && holds(mesh_, *s, b) && holds(mesh_, *s, c)) ++uses;
  return uses;
}

int TetMeshEditor::splitEdge(int a, int b, double w) {
  if (a == b || !(w > 0 && w < 1)) return -1;
  std::vector<std::int32_t> around;
  for (const std::int32_t *s = starBegin(a), *e = starEnd(a); s < e; ++s)
    if (!dead_[*s] && holds(mesh_, *s, b)) around.push_back(*s);
  if (around.empty()) return -1;
  // Both halves of every tet must stay positive (a near-flat tet may not).
  const Vec3 x = (1 - w) * position(a) + w * position(b);
  for (int t : around) {
    Vec3 nearA[4], nearB[4];
    for (int k = 0; k < 4; ++k) {
      const int v = mesh_.T(t, k);
      nearA[k] = v == b ? x : position(v);
      nearB[k] = v == a ? x : position(v);
    }
    if (!(volume6Of(nearA[0], nearA[1], nearA[2], nearA[3]) > 0) ||
        !(volume6Of(nearB[0], nearB[1], nearB[2], nearB[3]) > 0))
      return -1;
  }
  const int m = addNode(x);
  NewNode nn;
  nn.id = m;
  nn.num_parents = 2;
  nn.parents = {a, b, -1};
  nn.weights = {1 - w, w, 0};
  newNodes_.push_back(nn);
  for (int t : around) {
    std::array<int, 4> nearA{}, nearB{};
    for (int k = 0; k < 4; ++k) {
      const int v = mesh_.T(t, k);
      nearA[k] = v == b ? m : v;  // the half at a: b's corner moves to m (same orientation)
      nearB[k] = v == a ? m : v;
    }
    const int s = takeSlot(mesh_.material(t));
    rewrite(t, nearA);
    rewrite(s, nearB);
  }
  refreshStars();
  return m;
}

bool TetMeshEditor::moveNode(int n, const Vec3& y, double floor) {
  if (!moveAllowed(n, y, floor)) return false;
  setPosition(n, y);
  ensureTracking();
  if (nodeOrigin_[n] >= 0) movedFlag_[n] = 1;
  return true;
}

bool TetMeshEditor::moveAllowed(int n, const Vec3& y, double floor) {
  if (!y.allFinite()) return false;
  double before = 1.0;
  for (const std::int32_t *s = starBegin(n), *e = starEnd(n); s < e; ++s)
    if (!dead_[*s]) before = std::min(before, quality(*s));
  const double bound = std::min(floor, before);
  for (const std::int32_t *s = starBegin(n), *e = starEnd(n); s < e; ++s) {
    if (dead_[*s]) continue;
    const double q = qualityWith(*s, n, y);
    if (q < 0 || q < bound) return false;
  }
  return true;
}

int TetMeshEditor::duplicateNode(int n, const std::vector<std::int32_t>& tets) {
  if (tets.empty()) return -1;
  for (int t : tets)
    if (t < 0 || t >= numTets() || dead_[t] || !holds(mesh_, t, n)) return -1;
  const int m = addNode(position(n));
  NewNode nn;
  nn.id = m;
  nn.num_parents = 1;
  nn.parents = {n, -1, -1};
  nn.weights = {1, 0, 0};
  nn.duplicate = true;
  newNodes_.push_back(nn);
  for (int t : tets) {
    int v[4];
    for (int k = 0; k < 4; ++k) v[k] = mesh_.T(t, k) == n ? m : mesh_.T(t, k);
    setTetNodes(t, v[0], v[1], v[2], v[3]);  // (the element keeps its identity: a node renumbered)
  }
  refreshStars();
  return m;
}

void TetMeshEditor::removeTet(int t) {
  if (t < 0 || t >= numTets() || dead_[t]) return;
  markDead(t);
  refreshStars();
}

bool TetMeshEditor::collapseEdge(int u, int v) {
  if (u == v || !isEdge(u, v)) return false;
  std::vector<std::int32_t> dying, changing;
  for (const std::int32_t *s = starBegin(u), *e = starEnd(u); s < e; ++s) {
    if (dead_[*s]) continue;
    (holds(mesh_, *s, v) ? dying : changing).push_back(*s);
  }
  // Nothing inverts or goes flat; no changed tet coincides with a tet around v.
  std::vector<std::array<int, 4>> keysV;
  for (const std::int32_t *s = starBegin(v), *e = starEnd(v); s < e; ++s) {
    if (dead_[*s] || holds(mesh_, *s, u)) continue;
    std::array<int, 4> k{mesh_.T(*s, 0), mesh_.T(*s, 1), mesh_.T(*s, 2), mesh_.T(*s, 3)};
    std::sort(k.begin(), k.end());
    keysV.push_back(k);
  }
  for (int t : changing) {
    Vec3 p[4];
    std::array<int, 4> k{};
    for (int j = 0; j < 4; ++j) {
      k[j] = mesh_.T(t, j) == u ? v : mesh_.T(t, j);
      p[j] = position(k[j]);
    }
    if (!(volume6Of(p[0], p[1], p[2], p[3]) > 0)) return false;
    std::sort(k.begin(), k.end());
    if (std::find(keysV.begin(), keysV.end(), k) != keysV.end()) return false;
  }
  for (int t : dying) markDead(t);
  for (int t : changing) {
    int w[4];
    for (int j = 0; j < 4; ++j) w[j] = mesh_.T(t, j) == u ? v : mesh_.T(t, j);
    setTetNodes(t, w[0], w[1], w[2], w[3]);  // (the element keeps its identity: u merged into v)
  }
  refreshStars();
  // No face may end up in more than two tets (where the mesh folds); undo if one does.
  bool overused = false;
  for (size_t i = 0; i < changing.size() && !overused; ++i)
    for (int f = 0; f < 4 && !overused; ++f) {
      const int t = changing[i];
      overused = faceUses(mesh_.T(t, kFaceOf[f][0]), mesh_.T(t, kFaceOf[f][1]), mesh_.T(t, kFaceOf[f][2])) > 2;
    }
  if (overused) {
    for (int t : changing) {
      int w[4];
      for (int j = 0; j < 4; ++j) w[j] = mesh_.T(t, j) == v ? u : mesh_.T(t, j);
      setTetNodes(t, w[0], w[1], w[2], w[3]);
    }
    for (int t : dying) {
      dead_[t] = 0;
      for (int j = 0; j < 4; ++j) {
        touch(mesh_.T(t, j));
        noteGained(mesh_.T(t, j), t);
      }
    }
    refreshStars();
    return false;
  }
  ensureTracking();
  mergedInto_[u] = v;
  return true;
}

bool TetMeshEditor::flip23(int t, int f) {
  if (t < 0 || t >= numTets() || dead_[t] || f < 0 || f > 3) return false;
  const int a = mesh_.T(t, kFaceOf[f][0]), b = mesh_.T(t, kFaceOf[f][1]), c = mesh_.T(t, kFaceOf[f][2]);
  const int d = mesh_.T(t, f);
  int u = -1;
  for (const std::int32_t *s = starBegin(a), *e = starEnd(a); s < e && u < 0; ++s)
    if (*s != t && !dead_[*s] && holds(mesh_, *s, b) && holds(mesh_, *s, c)) u = *s;
  if (u < 0 || mesh_.material(u) != mesh_.material(t)) return false;
  int far = -1;
  for (int k = 0; k < 4; ++k)
    if (mesh_.T(u, k) != a && mesh_.T(u, k) != b && mesh_.T(u, k) != c) far = mesh_.T(u, k);
  if (far < 0 || far == d || isEdge(d, far)) return false;
  // The three new tets: t with one face node replaced by the far node (t's own orientation).
  std::array<std::array<int, 4>, 3> nt;
  for (int r = 0; r < 3; ++r) {
    for (int k = 0; k < 4; ++k) nt[r][k] = mesh_.T(t, k);
    nt[r][kFaceOf[f][r]] = far;
    if (!(volume6Of(position(nt[r][0]), position(nt[r][1]), position(nt[r][2]), position(nt[r][3])) > 0))
      return false;
  }
  const int extra = takeSlot(mesh_.material(t));
  rewrite(t, nt[0]);
  rewrite(u, nt[1]);
  rewrite(extra, nt[2]);
  refreshStars();
  return true;
}

bool TetMeshEditor::flip32(int a, int b) {
  if (a == b) return false;
  std::vector<std::int32_t> ring;
  for (const std::int32_t *s = starBegin(a), *e = starEnd(a); s < e; ++s)
    if (!dead_[*s] && holds(mesh_, *s, b)) ring.push_back(*s);
  if (ring.size() != 3) return false;
  if (mesh_.material(ring[1]) != mesh_.material(ring[0]) || mesh_.material(ring[2]) != mesh_.material(ring[0]))
    return false;
  // The ring's other nodes: a closed ring uses each of three nodes twice.
  std::vector<int> others;
  for (int t : ring)
    for (int k = 0; k < 4; ++k)
      if (mesh_.T(t, k) != a && mesh_.T(t, k) != b) others.push_back(mesh_.T(t, k));
  std::vector<int> p(others);
  std::sort(p.begin(), p.end());
  p.erase(std::unique(p.begin(), p.end()), p.end());
  if (p.size() != 3) return false;
  for (int x : p)
    if (std::count(others.begin(), others.end(), x) != 2) return false;
  if (faceUses(p[0], p[1], p[2]) > 0) return false;  // the triangle is a face already
  const double va = volume6Of(position(p[0]), position(p[1]), position(p[2]), position(a));
  const int top = va > 0 ? a : b, bottom = va > 0 ? b : a;
  const std::array<int, 4> up{p[0], p[1], p[2], top}, down{p[0], p[2], p[1], bottom};
  for (const auto& w : {up, down})
    if (!(volume6Of(position(w[0]), position(w[1]), position(w[2]), position(w[3])) > 0)) return false;
  rewrite(ring[0], up);
  rewrite(ring[1], down);
  markDead(ring[2]);
  refreshStars();
  return true;
}

}  // namespace hysim::cutting
