#pragma once
// The stages of one 3D cut (cut3d.cpp drives them in order): classify -> snap -> subdivide ->
// separate -> assemble -> optimise -> compact. Cut3D holds the working state the stages
// hand on; each stage is a member function defined in the file of its name.
#include <Eigen/Geometry>
#include <array>
#include <chrono>
#include <cstdint>
#include <functional>
#include <span>
#include <utility>
#include <vector>

#include "../optimize3d_internal.hpp"
#include "cut3d_maps.hpp"
#include "hysim/cutting/cut3d.hpp"

namespace hysim::cutting::cut3d_detail {

struct CrossedEdge {
  std::int32_t a, b;   // original node indices
  double t;            // crossing at a + t (b - a)
  Vec3 point;          // crossing point (surface) -- plane recomputes from phi
  bool alive = true;   // still crossed (neither end snapped)
};

// Working mesh: row-major copies of the input arrays (a node's or a tet's entries in one
// place, which the local passes read over and over) plus appended nodes and tets. The output
// mesh is written once from them (assemble).
struct Work {
  std::vector<Vec3> X;  // #nodes: input rows (may move), then appended nodes
  // #tets: input rows (modified in place), then appended tets (not zeroed as it grows: init
  // writes every input row, addTet the appended ones).
  std::vector<Tet, NoInitAllocator<Tet>> T;
  std::vector<std::int32_t> extraMat;  // material of the appended tets
  std::vector<std::int32_t> changedNodes, changedTets;  // input rows written (may repeat)
  int N0 = 0, M0 = 0;

  void init(const TetMesh& input, size_t extraNodes, size_t extraTets);
  int numNodes() const { return static_cast<int>(X.size()); }
  int numTets() const { return static_cast<int>(T.size()); }
  const Vec3& x(int i) const { return X[i]; }
  const Tet& tet(int t) const { return T[t]; }
  void setTet(int t, const Tet& v) {
    T[t] = v;
    if (t < M0) changedTets.push_back(t);
  }
  void setX(int i, const Vec3& p) {
    X[i] = p;
    if (i < N0) changedNodes.push_back(i);
  }
  int addTet(Tet v, std::int32_t material) {
    T.push_back(v);
    extraMat.push_back(material);
    return numTets() - 1;
  }
  int addNode(Vec3 p) {
    X.push_back(p);
    return numNodes() - 1;
  }
};

// The paper's four rotationally invariant cases of a tet the cut passes through, after
// snapping: how many of its nodes lie on the cut (and are separated there). The rest of the
// tet is subdivided: no node on the cut, three or four edges split; one node, two edges; two
// nodes, the opposite edge; three nodes, none (the tet's face is the cut).
TetCutCase tetCutCase(int nodesOnCut);

// Boundary faces around a node (faces with it used by one tet of its star): the other two
// nodes and the unit normal.
struct BFace {
  std::int32_t u, v;
  Vec3 normal;
};

// Feature edges of a boundary node: boundary edges whose two faces meet at more than the
// feature angle. `straight`: exactly two, nearly straight through the node (a ridge node).
// Non-manifold: none.
struct FeatureEdges {
  std::vector<std::int32_t> to;
  bool straight = false;
  bool polyhedral = false;  // all boundary faces around the node in coplanar groups
};

// Memo of boundaryFacesOf: the topology does not change before the subdivision, so the faces
// found for a node (three corners in the first tet's orientation, and the other two nodes)
// are kept; the normals come from the current positions.
struct BoundaryFaceCache {
  struct Topo {
    std::int32_t i0, i1, i2, u, v;
  };
  struct Seen {
    std::int32_t u, v, i0, i1, i2, count;
  };
  struct FeEdge {  // a boundary edge by its other node, its face count and first two normals
    std::int32_t v, count;
    Vec3 normal[2];
  };
  std::vector<std::int32_t> start, count;  // #N0: start in pool (-1: not yet found), count
  std::vector<Topo> pool;
  // Scratch, kept so that no call allocates once it has grown.
  std::vector<Seen> seen;
  std::vector<std::int32_t> nbrs, local, faceAt;
  std::vector<BFace> featureFaces, neighbourFaces;
  std::vector<FeEdge> edges;
};

// A face on the cut between two tets: the tets and the local vertex opposite it in each.
struct FaceUse {
  std::int32_t tet[2];
  std::int8_t opposite[2];
  int count = 0;
};

class Cut3D {
 public:
  using Clock = std::chrono::steady_clock;
  Cut3D(const TetMesh& input, const CutSurface& surface, const Cut3DOptions& options, Clock::time_point start);

  bool classify();  // false: degenerate bounding box
  void snap();
  void subdivide();
  void separate();
  void assemble();
  void optimise();
  void compact();

  Cut3DResult result;
  std::vector<MaterialVolume> inputVolumes;  // per label, where the optimisation asked for them

 private:
  // classify.cpp
  void classifyPlane();
  void classifySurface();
  void indexCrossedEdges();
  // snap.cpp, move_away.cpp
  void snapOntoCut();
  bool snapTarget(int n, int edge, double region, Vec3* target, bool* boundary, bool* ridgeSnap);
  bool boundarySnapTarget(int n, int edge, double region, Vec3* target, bool* ridgeSnap);
  bool ridgeTarget(int n, double region, Vec3* target);
  bool tangentTarget(int n, int edge, const Vec3& normalSum, Vec3* target) const;
  void routeThroughNodes();
  void moveAway();
  bool awayDirection(int n, double sgn, const Vec3& pn, Vec3* dir, double* rate, double* maxStep);
  void moveAwayBy(int n, double need, const Vec3& dir, double rate, double maxStep);
  // snap_guard.cpp
  bool guardOk(int n, const Vec3& target);
  bool guardVolumes(int n, const Vec3& target) const;
  bool guardQuality(int n, const Vec3& target) const;
  void boundaryFacesOf(int n, std::vector<BFace>& out);
  void findBoundaryFaces(int n);
  FeatureEdges featureEdgesOf(int n);
  bool polyhedralCorner(int n, const std::vector<BFace>& bf);
  Vec3 crossingPoint(const CrossedEdge& e) const {
    if (!plane) return e.point;
    const Vec3 xa = w.x(e.a), xb = w.x(e.b);
    return xa + e.t * (xb - xa);
  }
  // subdivide.cpp
  void countCases();
  void splitEdge(const CrossedEdge& ce);
  // separate.cpp, separate_nodes.cpp
  void collectLocalTets();
  void findCutFaces();
  bool faceOnCut(const FaceKey& key, const FaceUse& use) const;
  bool faceInSurface(const FaceKey& key, const FaceUse& use) const;
  double sideOf(int t) const;
  void separateNodes();
  void buildCutStars(std::vector<std::int32_t>* off, std::vector<std::int32_t>* tets) const;
  void separateNode(int n, std::span<const std::int32_t> st, const std::vector<std::uint8_t>& cutMask,
                    std::int32_t numSep);
  size_t pairFaces(int n, std::span<const std::int32_t> st);
  int copyNode(int n);
  // assemble.cpp
  void assembleMesh();
  void assembleChange();
  // optimise.cpp
  void runOptimisation();
  CutRegion makeRegion();
  void checkPatchedStars() const;  // (HYSIM_CHECK_EXACT only)
  void markCutOffPieces(CutRegion* region, std::vector<std::uint8_t>* tets, std::vector<std::uint8_t>* nodes);
  void reportOptimisation(const OptimizeCounts& counts, size_t movedBefore);
  // compact.cpp
  void listMoved();
  std::vector<std::int32_t> droppedTets(bool anyPeeled) const;
  void compactMesh(const std::vector<std::int32_t>& drop);
  void remapChange(const std::vector<std::int32_t>& drop, const std::vector<std::int32_t>& nodeMap,
                   const std::int32_t* tetMap);

  // The steps' wall times (report.*_ms): each lap adds the time since the last.
  void lap(double& into, Clock::time_point now = Clock::now()) {
    into += std::chrono::duration<double, std::milli>(now - mark).count();
    mark = now;
  }
  int materialOf(int t) const { return input.material.size() != 0 ? input.material(t) : 0; }
  bool isDeleted(int t) const { return deleting && t < M0 && deleted[t]; }

  const TetMesh& input;
  const CutSurface& surface;
  const Cut3DOptions& options;
  const Clock::time_point start;
  Clock::time_point mark;
  const int N0, M0;
  const bool plane, deleting;
  const double cosFeature;
  double eps = 0;

  // Classification. on: on the surface (grows with new nodes).
  std::vector<double> phi;  // plane: signed distances
  std::vector<std::uint8_t> on;
  std::vector<CrossedEdge> crossed;
  std::vector<Vec3> crossedNormal;  // surface: normal of the hit triangle per crossed edge
  EdgeMap edgeIndex{kNoEdge};       // crossed edge -> index
  std::vector<std::int32_t> crossedTets;
  std::vector<std::int32_t> onNodes;          // original nodes on the surface
  std::vector<std::int32_t> crossOff, crossAt;  // crossed edges by end node (CSR)
  Work w;
  // Node -> tets (CSR) of the input mesh; the optimisation takes them over, patched.
  StarLists stars;

  // Snapping.
  std::vector<std::int32_t> moved;
  std::vector<std::uint8_t> approx;  // nodes treated as on the surface without moving
  std::vector<std::uint8_t> guardSeen;
  std::vector<std::int32_t> guardNbrs;
  BoundaryFaceCache bfCache;
  std::vector<BFace> candBf;  // scratch of the snap and away candidates

  // Subdivision.
  std::vector<std::uint8_t> deleted;
  std::vector<std::int32_t> localOf;  // original tet -> index into fragments
  std::vector<std::vector<std::int32_t>> fragments;
  std::vector<std::int32_t> splitOriginals;

  // Separation.
  std::vector<std::int32_t> local;
  std::vector<std::uint8_t> inLocal;
  std::vector<std::pair<FaceKey, FaceUse>> cutFaceList;
  std::vector<std::pair<std::int32_t, std::int8_t>> cutFaceSides;  // (tet, opposite local vertex)
  std::vector<std::int32_t> cutNodes;
  // Per-node scratch of separateNode.
  std::vector<int> parent, copyOf;
  std::vector<std::int32_t> sepLocal, sepNbrs, firstTet, firstUsed;
  std::vector<std::int8_t> localOfN;
  std::vector<std::array<std::int32_t, 4>> facePairs;

  // Assembly and after.
  int N1 = 0, M1 = 0;
  std::vector<std::uint8_t> peeled;  // #M1: slivers the optimisation removed
};

// Node-connected parts of `mesh` with no anchored node, searched from `seeds` (cut_off.cpp).
int cutOffPieces(const TetMesh& mesh, const StarLists& stars, const std::vector<std::int32_t>& seeds,
                 const std::function<bool(int)>& anchored, int limit, std::vector<std::uint8_t>* tets,
                 std::vector<std::uint8_t>* nodes);

}  // namespace hysim::cutting::cut3d_detail
