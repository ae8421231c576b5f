#pragma once
// Shared between cut3d.cpp and optimize3d.cpp: what the local optimisation after a cut needs
// to know about the cut (which nodes lie on it, the surface for side checks) and where to
// start (the nodes the cut touched).
#include <algorithm>
#include <bit>
#include <cstdint>
#include <memory>
#include <new>
#include <utility>
#include <vector>

#include "hysim/cutting/cut3d.hpp"
#include "hysim/cutting/no_init_allocator.hpp"
#include "hysim/cutting/tet_mesh_editor.hpp"

namespace hysim::cutting {

// A set of indices below n as a bit per index: mark() sets one (noting each word that gets
// its first bit), has() tests one, drainInto() appends the set ones in increasing order (the sorted list without
// repeats, as sort + unique of what was marked) and clears them, so the bits are all zero
// between uses.
struct IndexBits {
  explicit IndexBits(int n) : bits(static_cast<size_t>(n) / 64 + 1, 0) {}
  void mark(int i) {
    std::uint64_t& word = bits[static_cast<size_t>(i) >> 6];
    if (word == 0) words.push_back(i >> 6);
    word |= std::uint64_t{1} << (i & 63);
  }
  bool has(int i) const { return ((bits[static_cast<size_t>(i) >> 6] >> (i & 63)) & 1) != 0; }
  // Appends the set ones in increasing order and keeps them (has() still answers).
  void listInto(std::vector<std::int32_t>& out) {
    std::sort(words.begin(), words.end());
    for (const int wi : words)
      for (std::uint64_t word = bits[wi]; word; word &= word - 1) out.push_back(wi * 64 + std::countr_zero(word));
  }
  void drainInto(std::vector<std::int32_t>& out) {
    listInto(out);
    for (const int wi : words) bits[wi] = 0;
    words.clear();
  }

 private:
  std::vector<std::uint64_t> bits;
  std::vector<std::int32_t> words;
};

// `lists` holds the lists of `before`; `after` is the same mesh with the rows `changed` (below
// before.rows(), may repeat) rewritten and rows appended, with numNodesAfter nodes (nodes
// appended too). Afterwards `lists` holds the lists of `after`: the rows of the nodes of the
// changed and appended tets go to the pool; the others keep their CSR rows.
void patchStarLists(const Tets& before, const Tets& after, int numNodesAfter, std::vector<std::int32_t> changed,
                    StarLists* lists);

// The mesh's volume as optimizeAroundCut's volume budgets take it (tet volumes added in
// index order).
double optimizeMeshVolume(const TetMesh& mesh);

struct CutRegion {
  const CutSurface* surface = nullptr;
  double eps = 0;                       // on-surface tolerance (absolute)
  std::vector<std::int32_t> seeds;      // nodes the cut created, moved or separated
  std::vector<std::uint8_t> on_cut;     // #N of the output mesh: node lies on the cut
  double edge_length = 0;               // mean length of the crossed edges (the local mesh size)
  // Optional: the output mesh's node -> tet lists (cut3d: the input's, patched where the cut
  // changed tets), which optimizeAroundCut takes over (moved from) instead of building them.
  StarLists* stars = nullptr;
  // Optional (#T): tets left as they are (pieces the cut cut off), as if already removed:
  // no operation reads or changes them. They start marked in *dead (the caller unmarks them).
  const std::vector<std::uint8_t>* left_alone = nullptr;
  // Optional: per material label, ascending, the volume the output keeps (`before`: the cut's
  // input); empty: the volumes the mesh has when the optimisation starts.
  std::vector<MaterialVolume> volume_target;
};

// Adds, per material label, the volume of mesh's tets to `field` of *volumes (ascending by
// label), skipping the tets marked in *skip unless marked in *keepAnyway (material_volumes.cpp).
void addMaterialVolumes(const TetMesh& mesh, double MaterialVolume::*field, std::vector<MaterialVolume>* volumes,
                        const std::vector<std::uint8_t>* skip = nullptr,
                        const std::vector<std::uint8_t>* keepAnyway = nullptr);

struct OptimizeCounts {
  int iterations = 0;
  int peeled = 0;
  int collapsed = 0;
  int late_snaps = 0;
  int flips = 0;
  int flap_peeled = 0;  // of peeled: in flaps (flap_peel.cpp)
  std::vector<std::int32_t> onto_cut;  // the nodes late snapping moved onto the cut
  double peeled_volume = 0;
  double volume_restored = 0;  // keep_volume: the volume put back (net, all labels)
  int volume_moves = 0;
  double collapse_ms = 0, late_snap_ms = 0, move_ms = 0, keep_volume_ms = 0;  // wall time of those steps
};

// See Optimize3DOptions. Appends the nodes it moved to *moved; *dead (#T) marks the slivers
// it peeled (the caller removes them).
void optimizeAroundCut(TetMesh& mesh, const CutRegion& region, const Optimize3DOptions& options,
                       std::vector<std::int32_t>* moved, std::vector<std::uint8_t>* dead, OptimizeCounts* counts);

}  // namespace hysim::cutting
