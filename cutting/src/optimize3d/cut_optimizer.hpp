#pragma once
// The local optimisation after a 3D cut as a pipeline of stages over a TetMeshEditor (the
// paper's 2D regularisation carried to 3D). optimizeAroundCut (pipeline.cpp) runs:
//   repair region -> peel -> snap near -> collapse -> flips -> smooth (iterated)
//   -> snap near -> collapse -> flips -> peel -> (curved cuts) flap peel -> last-resort collapse
//   -> keep volume (each material's volume back to the cut's input's)
// One file per stage; the shared pieces: constraints.cpp (where a node may move), manifold.cpp
// (boundary faces, disc checks), region.cpp (which tets and nodes take part).
//
// What may move and how (all stages keep the local minimum quality from falling):
//  - interior nodes freely, but never onto or across the cut surface (sides are kept);
//  - nodes on the cut only within the cut plane (plane cuts; on a curved surface only where
//    their cut faces are smooth), and only if every boundary face around them lies in the cut;
//  - other boundary nodes only where their boundary is flat, perpendicular to its normal (the
//    volume is linear in one node's position with gradient (1/3) x the sum of its boundary
//    faces' area vectors, so such a move keeps the volume exactly);
//  - on curved cuts (shaving), more within volume budgets: curved boundaries, ridges (the rim
//    where the cut meets the boundary, creases), flips, collapses off the cut;
//  - nodes between materials only perpendicular to each material's volume gradient;
//  - last, boundary nodes off the cut along their volume gradients, to give back what the
//    stages before lost or gained (keep_volume.cpp).
#include <array>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <vector>

#include <Eigen/Geometry>

#include "../optimize3d_internal.hpp"
#include "../tet_geometry_inline.hpp"
#include "hysim/cutting/tet_mesh_editor.hpp"
#include "hysim/cutting/tet_faces.hpp"

namespace hysim::cutting::opt3d {

using Vec3 = Eigen::Vector3d;
inline constexpr const auto& kFace = kTetFace;

enum class Freedom { Free, Plane, Surface, Fan, Ridge, Fixed };

// A volume budget: the net change stays within `limit`, the sum of the absolute changes
// within churn_factor x limit.
struct VolumeBudget {
  double limit = 0, churn_factor = 1, net = 0, churn = 0;
  bool fits(double dv) const {
    return std::abs(net + dv) <= limit && churn + std::abs(dv) <= churn_factor * limit;
  }
  void spend(double dv) {
    net += dv;
    churn += std::abs(dv);
  }
};

struct Constraint {
  Freedom kind = Freedom::Fixed;
  Vec3 normal = Vec3::Zero();  // Plane: moves are perpendicular to it
  Vec3 ridge[2];               // Ridge: the two neighbours along the ridge
};

// Per label, the volume of a star's tets before and after an operation (collapse_material_limit).
struct MatVol {
  std::int32_t m;
  double before, after;
};

// constraintOf's scratch: a node's neighbours, their local numbers (-1 elsewhere; also
// discAround's), a table over pairs of them; the faces by pair, per live star tet its tet and
// its nodes' local numbers; the boundary faces and, for Fan, their corners; the kept boundary
// faces of the nodes looked at (bfPool, see CutOptimizer::bfStart).
struct FaceUse {
  std::int32_t t, f, count, key;
};
struct BFace {
  std::int32_t u, v;
  Vec3 area;  // outward area vector (x2 the area)
  Vec3 unit;  // area.normalized()
};
struct ConsScratch {
  std::vector<std::int32_t> nbrs, localId, pairCount, consLocal;
  std::vector<FaceUse> consFaces;
  std::vector<BFace> faces;
  std::vector<std::array<Vec3, 3>> fan;
  std::vector<std::array<std::int32_t, 2>> bfPool;
};

// Distance of a node to the cut, kept with the position it was measured at: exact
// (|distance| and nearest point) or a lower bound (within() said no).
struct DistEntry {
  Vec3 x;
  double d;
  Vec3 closest;
  std::int8_t kind;  // 0 none, 1 exact, 2 lower bound
};

struct FlipFailed {
  std::int32_t t, clock, avail;
};
// A live tet around a tried tet's nodes 0..2, with the mask of the tried tet's nodes it holds.
struct NearTet {
  std::int32_t s;
  std::uint32_t c;
#ifdef HYSIM_CHECK_EXACT
  std::uint32_t m;
#endif
};
// What a tried tet's neighbourhood offers the flips: tets around each edge, the neighbour
// across each face.
struct FlipNeighbourhood {
  std::int32_t edgeTetsOf[6][6];
  int edgeN[6] = {0, 0, 0, 0, 0, 0}, edgeSameMat[6] = {1, 1, 1, 1, 1, 1};
  int faceU[4] = {-1, -1, -1, -1};
};
// The best flip found for a tet: kind 0 = 2-3 across face f (neighbour u, far node i),
// 1 = 3-2 about edge (i, j), 2 = edge removal of (i, j).
struct FlipChoice {
  double best = 0;
  int kind = -1, f = -1, u = -1, i = -1, j = -1;
  std::int32_t ring[3] = {-1, -1, -1}, ringTets[3] = {-1, -1, -1};
  std::int32_t erRing[6], erTets[6];
  int erN = 0, erApex = -1;
};

struct CollapseCand {
  double len;
  std::int32_t u, v;
  bool shortEdge;
  bool offCut;       // v is not on the cut (curved cuts, collapse_off_cut)
  std::int32_t tet;  // the tet it came from
};
struct Refused {
  std::int32_t v, next;
  std::uint32_t stampU, stampV;
  bool shortEdge, offCut;
};

struct StarVolTet {  // per live star tet in the move loop's volume check
  double p[3][4];    // the corners' x, y, z
  double a[3], b[3], e[3], nrm[3];  // p1 - p0, p2 - p0, p3 - p0, b x e (where kn != 0)
  double old;        // its volume where n is
  int kn;            // n's corner
};
// The move loop's scratch, what an iteration gathers, and what the part being moved spent.
struct MoveScratch {
  std::vector<double> starVolume;
  std::vector<StarVolTet> starVol;
  double largest = 0, scale = 0;
  bool split = false;         // moving a part (see moveRun): half the budget left at its start
  double net = 0, churn = 0;  // (split) the volume change the part spent
};
// One node's candidate moves (smooth.cpp).
struct MoveTry {
  int n = -1, wt = -1, wtK = -1;
  Vec3 x, wtP[4], dirs[3];
  Constraint c;
  int farFromCut = 0;  // -1: not asked yet
};

// One snapNear group being tried (snap_near.cpp).
struct SnapScratch {
  std::vector<std::int32_t> dying, changing, group, tets, tetsMerged, prevTets;
  std::vector<Vec3> targets, groupTo, groupFrom;
  std::vector<std::uint64_t> targetEdges;
  std::vector<std::uint32_t> groupVer;
  std::vector<std::int8_t> groupAt;  // 1 + place in the group, 0 elsewhere
  std::vector<double> prevVol, prevQ, curVol, curQ;
  size_t prevGroup = 0;
  double near = 0;
};

// One collapse batch's working lists (collapse.cpp).
struct CollapseScratch {
  std::vector<std::uint8_t> locked;
  std::vector<std::int32_t> dying, changing, vstar, checked, changedTets;
  std::vector<double> detAfter;
  std::vector<std::array<std::int32_t, 4>> keysB;
  std::vector<CollapseCand> raw, cands;
  bool offCutToo = false;
};

class CutOptimizer {
 public:
  CutOptimizer(TetMesh& mesh, const CutRegion& region, const Optimize3DOptions& options,
               std::vector<std::int32_t>* moved, std::vector<std::uint8_t>* dead, OptimizeCounts* counts);
  void run();

 private:
  // Runs step() and adds its wall time to *ms (counts' timings, when counts are asked for).
  template <class Step>
  void timed(double OptimizeCounts::*ms, Step&& step) {
    const auto start = std::chrono::steady_clock::now();
    step();
    if (counts)
      counts->*ms += std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  }
  void finish();
  // region.cpp
  void addRepairSeeds();
  void regionTets(std::vector<std::int32_t>& out);
  void markRings();
  void addNodesOf(int t, int round);
  void addBadAround(int n, int round);
  void initialWork();
  // volume.cpp
  void matAdd(int t, double before, double after);
  bool matFits(double starBefore) const;
  // constraints.cpp
  Constraint constraintOf(int n);
  void gatherBoundaryFaces(int n);
  bool ridgeOf(Constraint& c, bool nodeOnCut);
  bool sideKept(int n, const Vec3& x, const Vec3& y) const;
  // manifold.cpp
  int boundaryFaceCount(int t) const;
  bool discAround(int v, const std::vector<std::int32_t>& around, bool linkOnly = false);
  bool linkIsOneLoop(std::int32_t L);
  // peel.cpp
  void peel();
  // keep_volume.cpp
  void keepVolume();
  bool leftAlone(int t) const;
  void volumesNow(std::vector<MaterialVolume>& volumes, double MaterialVolume::*field) const;
  // What keepVolume asks of a move: more volume for `label` (from the boundary, other < 0,
  // or from the material `other` across their interface), and what the moves changed.
  struct VolumeGoal {
    std::int32_t label, other;
  };
  struct VolumeChange {
    double label = 0, other = 0;
  };
  // A node near the region as keepVolume sees it (gatherVolumeNodes).
  struct VolumeNode {
    std::int32_t n, a, b;  // the labels around it (b -1: one)
    std::int8_t ring;      // edge steps from the region's tets
    bool boundary;         // else inside
  };
  void gatherVolumeNodes(int maxRings);
  bool describeVolumeNode(int n, VolumeNode* info) const;
  void volumeMovers(const VolumeGoal& goal, int rings, std::vector<std::int32_t>& nodes);
  Vec3 goalGradient(int n, const VolumeGoal& goal) const;
  double starVolumeOf(int n, std::int32_t label) const;
  void volumeSweep(const VolumeGoal& goal, double amount, std::vector<std::int32_t>& movers, std::vector<Vec3>& from,
                   VolumeChange* change);
  VolumeChange restoreVolume(const VolumeGoal& goal, double amount, double tolerance);
  void exchangeVolume(MaterialVolume& a, MaterialVolume& b, double amount, double tolerance);
  void boundaryVolume(MaterialVolume& m, double tolerance);
  // flips.cpp
  void flips();
  void flipCandidates(int round, std::vector<std::int32_t>& cands);
  bool flipSkip(int t);
  void gatherNear(int t, int nearOff[4]);
  void neighbourhoodOf(int t, const int nearOff[4], FlipNeighbourhood& nb);
  void bestFlip23(int t, double qt, const FlipNeighbourhood& nb, FlipChoice& ch);
  void bestFlip32(int t, const FlipNeighbourhood& nb, FlipChoice& ch);
  void bestEdgeRemoval(int t, const FlipNeighbourhood& nb, FlipChoice& ch);
  void applyFlip(int t, const FlipChoice& ch);
  void afterFlip();
  int availSlots();
  void flipSetTet(int t, int a, int b, int c, int d);
  double vol6(int a, int b, int c, int d) const;
  double q4(int a, int b, int c, int d) const;
  // collapse.cpp
  void collapseEdges();
  void collapseCandidates(int batch);
  void candidatesOf(int t, std::vector<CollapseCand>& out);
  bool onBoundary(int n);
  bool refusedBefore(const CollapseCand& c) const;
  void refuse(const CollapseCand& c);
  bool tryCollapse(const CollapseCand& c);
  bool gatherCollapse(const CollapseCand& c);
  int collapseVolume(double* dv);
  bool collapseQualityOk(const CollapseCand& c);
  bool collapseCoincides(const CollapseCand& c);
  bool applyCollapse(const CollapseCand& c);
  // snap_near.cpp
  void snapNear();
  void snapTargets(int u);
  bool trySnap(int* partner);
  bool trySnapMarked(int* partner);
  bool evaluateSnap(int* partner, double* before, double* after);
  bool applySnap(double before, double after);
  void namePartner(int worstTet, int* partner);
  DistEntry& distEntry(int n);
  double nodeDistance(int n, Vec3* closest, double within = std::numeric_limits<double>::infinity());
  bool nodeWithin(int n, double r);
  // smooth.cpp
  void smooth();
  void moveNode(int n);
  bool prepareMove(MoveTry& mt, double* before);
  bool placeCandidate(const MoveTry& mt, Vec3& y);
  bool moveVolumeOk(const MoveTry& mt, const Vec3& y, double* dv);
  double wtQAt(const MoveTry& mt, const Vec3& y) const;
  bool sideOk(MoveTry& mt, const Vec3& y);
  void onCutAgain(const MoveTry& mt, Vec3& y);
  bool moveFits(double dv) const;
  bool splitWork(const std::vector<std::int32_t>& list);
  void moveRun(const std::vector<std::int32_t>& list);
  // starAbove (smooth.cpp): is the worst q* around n with n at y above floor?
  bool starAbove(int n, const Vec3& y, int first, double firstQ, double floor, double* q);
  void keepMaterials(MoveTry& mt);

  TetMesh& mesh;
  const CutRegion& region;
  const Optimize3DOptions& options;
  std::vector<std::int32_t>* moved;
  std::vector<std::uint8_t>& dead;
  OptimizeCounts* counts;
  TetMeshEditor ed;
  int N = 0, M = 0;
  bool plane = false, curved = false;
  double cosFlat = 1, cosCurved = 1, cosRidge = 1;
  std::vector<std::uint8_t> onCut;  // grows: nodes snapped onto the cut here

  // Budgets (volume.cpp): peeling and collapses together within volume_budget of the mesh's
  // volume; moves on curved surfaces within move_volume_budget.
  double meshVolume = 0, edgeTet = 0, refVolume = 0;
  VolumeBudget budget, moveBudget;
  std::vector<MatVol> matVol;
  std::vector<MaterialVolume> startVolumes;  // keep_volume without region.volume_target
  std::vector<VolumeNode> volumeNodes;       // keep_volume.cpp: gathered within gatheredRings
  int gatheredRings = -1;
  double volumeFloor = 1.0;  // the region's worst q* when keepVolume starts

  // Seeds and region (region.cpp).
  std::vector<std::int32_t> seeds, lateSnapped, around;
  IndexBits tetBits;
  std::vector<std::int32_t> regionKept;
  std::uint64_t regionClock = ~std::uint64_t{0};

  // constraints.cpp: the boundary faces per node are kept while bfStart is not empty.
  ConsScratch cons;
  std::vector<std::int32_t> bfStart, bfLen;
  // manifold.cpp scratch (grows only).
  std::vector<std::int32_t> link, linkDeg, linkInc, tetLocal, faceKey, discNbrs;
  std::vector<std::uint16_t> faceUses;

  // peel.cpp
  std::vector<std::int32_t> peelStamp, failedAt;
  int peelCount = 0;

  // flips.cpp
  std::vector<std::int32_t> freeSlots;
  std::vector<FlipFailed> failedPrev, failedNow;
  std::vector<std::int32_t> flipMark, flipRebuilt, flipChanged, flipSeeds, candsMerged;
  std::vector<std::uint8_t> flipNodeBit;
  std::vector<NearTet> nearTets;
  std::int32_t flipClock = 0;
  int availNow = -1;

  // collapse.cpp
  bool lastResort = false;
  std::vector<std::uint8_t> isSeed, tetChanged;
  std::vector<std::uint32_t> starStamp;
  std::uint32_t stampClock = 0;
  std::vector<std::int32_t> refusedHead, refusedUs;
  std::vector<Refused> refusedPool;
  CollapseScratch col;

  // snap_near.cpp
  std::vector<std::int32_t> distSlot;
  std::vector<DistEntry, NoInitAllocator<DistEntry>> distPool;
  std::int32_t distNext = 0;
  SnapScratch sn;

  // smooth.cpp
  std::vector<std::int8_t> ring;
  std::vector<std::int32_t> stamp, work, movedNow, lastBelow;
  std::vector<std::uint8_t> didMove;
  MoveScratch mv;
  std::vector<std::int32_t> workAt, ringStart, ringLen, ringMark, ringPool;
  std::vector<std::int32_t> adjOff, adj, rankOf, reach, below, partA, partB, partS, moveRest;
  std::vector<std::pair<double, std::int32_t>> keyed;
};

}  // namespace hysim::cutting::opt3d
