// Which nodes and tets take part: the seeds (and, on curved cuts, the poor tets near them),
// the region's tets, the rings of nodes that may move and the first work list.
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <vector>

#include "cut_optimizer.hpp"
#include "hysim/cutting/mesh_stats.hpp"

namespace hysim::cutting::opt3d {

// Curved cuts: the repair region also takes the poor tets (q* below flip_quality) within
// repair_rings edge steps of what the cut touched, left there by earlier cuts (a shaving
// pass sweeps over the surfaces of earlier ones): their nodes join the seeds.
void CutOptimizer::addRepairSeeds() {
  if (!(curved && options.repair_rings > 0 && options.flip_quality > 0)) return;
  std::vector<std::uint8_t> reached(N, 0);
  std::vector<std::int32_t> frontier, next;
  for (int n : region.seeds)
    if (n >= 0 && n < N && !reached[n]) {
      reached[n] = 1;
      frontier.push_back(n);
    }
  for (int r = 0; r < options.repair_rings && !frontier.empty(); ++r) {
    next.clear();
    for (int n : frontier)
      for (const std::int32_t *s = ed.starBegin(n), *sEnd = ed.starEnd(n); s < sEnd; ++s) {
        if (dead[*s]) continue;
        const bool poor = ed.quality(*s) < options.flip_quality;
        for (int k = 0; k < 4; ++k) {
          const int v = mesh.T(*s, k);
          if (reached[v]) continue;
          reached[v] = 1;
          next.push_back(v);
          if (poor) seeds.push_back(v);
        }
        if (poor)
          for (int k = 0; k < 4; ++k) seeds.push_back(mesh.T(*s, k));
      }
    frontier.swap(next);
  }
  // The added seeds sorted, without repeats (as sort + unique).
  const size_t base = region.seeds.size();
  if (seeds.size() > base) {
    IndexBits added(N);
    for (size_t i = base; i < seeds.size(); ++i) added.mark(seeds[i]);
    seeds.resize(base);
    added.drainInto(seeds);
  }
}

// The live tets around the seeds, each once, in index order (the live tets with a seed
// node). Kept (regionKept) with the topology clock's value when found: while no tet has taken
// other nodes since and none came alive (only a written slot or an undone removal does, and
// no one asks between a removal and its undo), the list is the kept one without the tets
// that died since.
void CutOptimizer::regionTets(std::vector<std::int32_t>& out) {
  out.clear();
  if (regionClock == ed.topologyClock()) {
    size_t kept = 0;
    for (const std::int32_t t : regionKept)
      if (!dead[t]) regionKept[kept++] = t;
    regionKept.resize(kept);
    out.assign(regionKept.begin(), regionKept.end());
#ifdef HYSIM_CHECK_EXACT
    std::vector<std::int32_t> ref;
    for (int n : seeds)
      for (const std::int32_t *s = ed.starBegin(n), *sEnd = ed.starEnd(n); s < sEnd; ++s)
        if (!dead[*s]) tetBits.mark(*s);
    tetBits.drainInto(ref);
    if (ref != out) std::abort();
#endif
    return;
  }
  for (int n : seeds)
    for (const std::int32_t *s = ed.starBegin(n), *sEnd = ed.starEnd(n); s < sEnd; ++s)
      if (!dead[*s]) tetBits.mark(*s);
  tetBits.drainInto(out);
  regionKept.assign(out.begin(), out.end());
  regionClock = ed.topologyClock();
}

// Nodes up to `rings` edge steps from the seeds may move.
void CutOptimizer::markRings() {
  std::vector<std::int32_t> frontier, next;
  for (int n : seeds)
    if (n >= 0 && n < N && ring[n] < 0) {
      ring[n] = 0;
      frontier.push_back(n);
    }
  for (int r = 1; r <= options.rings && !frontier.empty(); ++r) {
    next.clear();
    for (int n : frontier)
      for (const std::int32_t *s = ed.starBegin(n), *sEnd = ed.starEnd(n); s < sEnd; ++s)
        for (int k = 0; k < 4; ++k) {
          const int v = mesh.T((*s), k);
          if (ring[v] < 0) {
            ring[v] = static_cast<std::int8_t>(r);
            next.push_back(v);
          }
        }
    frontier.swap(next);
  }
}

// t's nodes within the rings, each once a round, join the work list.
void CutOptimizer::addNodesOf(int t, int round) {
  for (int k = 0; k < 4; ++k) {
    const int v = mesh.T(t, k);
    if (ring[v] >= 0 && stamp[v] != round) {
      stamp[v] = round;
      work.push_back(v);
    }
  }
}

void CutOptimizer::addBadAround(int n, int round) {
  for (const std::int32_t *s = ed.starBegin(n), *sEnd = ed.starEnd(n); s < sEnd; ++s) {
    const int t = (*s);
    if (dead[t] || ed.quality(t) >= options.quality_target) continue;
    addNodesOf(t, round);
  }
}

// The first work list: the nodes of poor elements around the seeds (as addBadAround(n, 0) for
// each seed n: the poor tets met, in order, then their nodes).
void CutOptimizer::initialWork() {
  std::vector<std::int32_t> poor;
  for (int n : seeds)
    if (n >= 0 && n < N)
      for (const std::int32_t *s = ed.starBegin(n), *sEnd = ed.starEnd(n); s < sEnd; ++s)
        if (!dead[*s] && ed.quality(*s) < options.quality_target) poor.push_back(*s);
  for (const int t : poor) addNodesOf(t, 0);
}

}  // namespace hysim::cutting::opt3d
