// Peeling: a sliver (q* below peel_quality) with a face on the boundary is removed when the
// mesh stays manifold: the boundary faces around each of its nodes still form one closed loop
// (a disc), or the node had no other tet (it goes with the sliver). Its volume (tiny: it is
// flat) is lost, within the volume budget.
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <vector>

#include "cut_optimizer.hpp"
#include "hysim/cutting/mesh_stats.hpp"

namespace hysim::cutting::opt3d {

void CutOptimizer::peel() {
  if (!(options.peel_quality > 0)) return;
  std::vector<std::int32_t> candidates;
  regionTets(candidates);
  candidates.erase(std::remove_if(candidates.begin(), candidates.end(),
                                  [&](int t) { return !(ed.quality(t) < options.peel_quality); }),
                   candidates.end());
  // A candidate's tests (a boundary face, the discs around its nodes) look only at the
  // live tets around its nodes: one that failed them is not tested again until a tet with
  // one of its nodes was peeled (peelStamp, per node: the count of peels when it last lost
  // a tet; failedAt, per candidate: that count when it failed). The budget is asked anew.
  if (peelStamp.empty()) peelStamp.assign(N, -1);
  failedAt.assign(candidates.size(), -1);
  for (bool again = true; again;) {
    again = false;
    for (size_t i = 0; i < candidates.size(); ++i) {
      const int t = candidates[i];
      if (dead[t]) continue;
      if (failedAt[i] >= 0) {
        int last = -1;
        for (int k = 0; k < 4; ++k) last = std::max(last, peelStamp[mesh.T(t, k)]);
        if (last <= failedAt[i]) continue;
        failedAt[i] = -1;
      }
      if (boundaryFaceCount(t) == 0) {
        failedAt[i] = peelCount;
        continue;
      }
      if (!budget.fits(-tetVolumeHere(mesh, t))) continue;
      ed.markDead(t);
      bool ok = true;
      for (int k = 0; k < 4 && ok; ++k) {
        ed.liveStar(mesh.T(t, k), around, nullptr);
        ok = discAround(mesh.T(t, k), around);
      }
      if (!ok) {
        dead[t] = 0;
        failedAt[i] = peelCount;
        continue;
      }
      ++peelCount;
      for (int k = 0; k < 4; ++k) peelStamp[mesh.T(t, k)] = peelCount;
      again = true;
      budget.spend(-tetVolumeHere(mesh, t));
      if (counts) {
        ++counts->peeled;
        counts->peeled_volume += tetVolumeHere(mesh, t);
      }
    }
  }
}

}  // namespace hysim::cutting::opt3d
