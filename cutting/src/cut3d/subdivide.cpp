// Stage 3, subdivision: every edge still crossed is split (conforming bisection of the tets
// around it), or, for deletion, the crossed tets are removed.
#include "cut3d_stages.hpp"

namespace hysim::cutting::cut3d_detail {

TetCutCase tetCutCase(int nodesOnCut) {
  switch (nodesOnCut) {
    case 0: return TetCutCase::NoNodeSeparated;
    case 1: return TetCutCase::OneNodeSeparated;
    case 2: return TetCutCase::TwoNodesSeparated;
    default: return TetCutCase::ThreeNodesSeparated;
  }
}

void Cut3D::subdivide() {
  localOf.assign(M0, -1);
  if (deleting) {
    deleted.assign(M0, 0);
    for (int t : crossedTets) deleted[t] = 1;
    result.report.deleted_elements = static_cast<int>(crossedTets.size());
  } else {
    countCases();
    for (const auto& ce : crossed)
      if (ce.alive) splitEdge(ce);
    result.report.split_elements = static_cast<int>(splitOriginals.size());
  }
  lap(result.report.subdivide_ms);
}

// The case of each crossed tet the cut still passes through after snapping: one with an edge
// still crossed, or with a face on the cut. (Snapping may leave a crossed tet touching the
// cut at a node or an edge only: no case.)
void Cut3D::countCases() {
  for (const int t : crossedTets) {
    const Tet& tv = w.tet(t);
    int nodesOn = 0, edgesCrossed = 0;
    for (const int v : tv) nodesOn += on[v];
    for (const auto& e : kEdge) {
      const std::int32_t* it = edgeIndex.find(edgeKey(tv[e[0]], tv[e[1]]));
      edgesCrossed += it != nullptr && crossed[*it].alive;
    }
    if (nodesOn > 3 || (edgesCrossed == 0 && nodesOn < 3)) continue;
    ++result.report.tets_by_case[static_cast<int>(tetCutCase(nodesOn))];
  }
}

// A node at the crossing; each piece of a tet around the edge becomes two.
void Cut3D::splitEdge(const CrossedEdge& ce) {
  const Vec3 p = crossingPoint(ce);
  const int pn = w.addNode(p);
  on.push_back(1);
  NewNode nn;
  nn.id = pn;
  nn.num_parents = 2;
  nn.parents = {ce.a, ce.b, -1};
  nn.weights = {1.0 - ce.t, ce.t, 0.0};
  result.change.new_nodes.push_back(nn);
  ++result.report.split_edges;
  for (int s = stars.off[ce.a]; s < stars.off[ce.a + 1]; ++s) {
    const int o = stars.star[s];
    if (findLocal(Tet{input.T(o, 0), input.T(o, 1), input.T(o, 2), input.T(o, 3)}, ce.b) < 0) continue;
    if (localOf[o] < 0) {
      localOf[o] = static_cast<std::int32_t>(fragments.size());
      fragments.push_back({o});
      splitOriginals.push_back(o);
    }
    auto& list = fragments[localOf[o]];
    const size_t count = list.size();
    for (size_t f = 0; f < count; ++f) {
      const int t = list[f];
      Tet tv = w.tet(t);
      const int la = findLocal(tv, ce.a), lb = findLocal(tv, ce.b);
      if (la < 0 || lb < 0) continue;
      Tet other = tv;
      tv[lb] = pn;
      other[la] = pn;
      w.setTet(t, tv);
      list.push_back(w.addTet(other, materialOf(o)));
    }
  }
}

}  // namespace hysim::cutting::cut3d_detail
