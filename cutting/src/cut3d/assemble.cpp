// Stage 5, assembly: the output mesh and the TopologyChange of the cut, from the work arrays.
#include <numeric>

#include "cut3d_stages.hpp"

namespace hysim::cutting::cut3d_detail {

void Cut3D::assemble() {
  N1 = w.numNodes();
  M1 = w.numTets();
  assembleMesh();
  assembleChange();
  lap(result.report.assemble_ms);
}

// The input arrays (column copies), the rows the cut wrote, then the appended rows.
void Cut3D::assembleMesh() {
  TetMesh& out = result.mesh;
  out.X.resize(N1, 3);
  out.X.topRows(N0) = input.X;
  for (const int i : w.changedNodes) out.X.row(i) = w.X[i].transpose();
  for (int i = N0; i < N1; ++i) out.X.row(i) = w.X[i].transpose();
  out.T.resize(M1, 4);
  out.T.topRows(M0) = input.T;
  std::int32_t* d[4] = {out.T.col(0).data(), out.T.col(1).data(), out.T.col(2).data(), out.T.col(3).data()};
  for (const int t : w.changedTets)
    for (int k = 0; k < 4; ++k) d[k][t] = w.T[t][k];
  for (int t = M0; t < M1; ++t)
    for (int k = 0; k < 4; ++k) d[k][t] = w.T[t][k];
  out.material.resize(M1);
  if (input.material.size() != 0) {
    out.material.head(M0) = input.material;
  } else {
    out.material.head(M0).setZero();
  }
  for (int t = M0; t < M1; ++t) out.material(t) = w.extraMat[t - M0];
}

// Added: the pieces of the split tets, i.e. each split original (its first piece keeps its
// index) and every appended tet (the subdivision appends nothing else), ascending: the
// originals (< M0) in order, then M0 .. M1-1.
void Cut3D::assembleChange() {
  TopologyChange& change = result.change;
  change.old_num_nodes = N0;
  change.old_num_elements = M0;
  change.node_old_to_new.resize(N0);
  std::iota(change.node_old_to_new.begin(), change.node_old_to_new.end(), 0);
  change.element_old_to_new.resize(M0);
  std::iota(change.element_old_to_new.begin(), change.element_old_to_new.end(), 0);
  {  // (Each split original once: sorted through a bit per tet, as std::sort.)
    IndexBits tetBits(M0);
    for (const int o : splitOriginals) tetBits.mark(o);
    splitOriginals.clear();
    tetBits.drainInto(splitOriginals);
  }
  change.removed_elements.reserve(splitOriginals.size());
  change.added_elements.reserve(splitOriginals.size() + static_cast<size_t>(M1 - M0));
  for (int o : splitOriginals) {
    change.element_old_to_new[o] = -1;
    change.removed_elements.push_back(o);
    change.added_elements.push_back(o);
  }
  for (int t = M0; t < M1; ++t) change.added_elements.push_back(t);
}

}  // namespace hysim::cutting::cut3d_detail
