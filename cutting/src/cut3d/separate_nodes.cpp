// Stage 4, node separation: each node on a cut face gets one copy per group of its incident
// tets connected through faces not cut, so every tet keeps the copy of its side and a crack
// tip (partial cut) stays connected.
#include <algorithm>
#include <cstring>
#include <numeric>

#include "cut3d_stages.hpp"

namespace hysim::cutting::cut3d_detail {

void Cut3D::separateNodes() {
  {  // (Sorted without repeats, as sort + unique, through a bit per node.)
    IndexBits nodeBits(w.numNodes());
    for (const auto& key : cutFaceList)
      for (int v : key.first.v) nodeBits.mark(v);
    nodeBits.drainInto(cutNodes);
  }
  std::vector<std::int32_t> cutStarOff, cutStarTet;
  buildCutStars(&cutStarOff, &cutStarTet);
  // Cut faces by tet: bit k of cutMask[t]: the face opposite local vertex k of t is cut.
  std::vector<std::uint8_t> cutMask(w.numTets(), 0);
  for (const auto& [key, use] : cutFaceList)
    for (int side = 0; side < 2; ++side) cutMask[use.tet[side]] |= static_cast<std::uint8_t>(1u << use.opposite[side]);
  const std::int32_t numSep = w.numNodes();
  const size_t numCut = cutNodes.size();  // (the copies are appended to cutNodes)
  for (size_t i = 0; i < numCut; ++i)
    separateNode(cutNodes[i], std::span<const std::int32_t>(cutStarTet.data() + cutStarOff[i], cutStarTet.data() + cutStarOff[i + 1]),
                 cutMask, numSep);
  // The copies were appended in increasing id order, above every node before them: still
  // sorted (the check is cheap; the sort is kept for safety).
  if (!std::is_sorted(cutNodes.begin(), cutNodes.end())) std::sort(cutNodes.begin(), cutNodes.end());
}

// Stars of the cut nodes within the local tets (CSR, each ascending: filled from the local
// tets in ascending order). One pass over the local tets lists (cut node, tet).
void Cut3D::buildCutStars(std::vector<std::int32_t>* off, std::vector<std::int32_t>* tets) const {
  std::vector<std::int32_t> slot(w.numNodes(), -1);
  for (size_t i = 0; i < cutNodes.size(); ++i) slot[cutNodes[i]] = static_cast<std::int32_t>(i);
  const size_t numCut = cutNodes.size();
  off->assign(numCut + 1, 0);
  std::vector<std::array<std::int32_t, 2>> incidence;
  incidence.reserve(4 * local.size());
  // (The flags are scanned eight at a time: few tets are local.)
  const int numFlags = static_cast<int>(inLocal.size());
  for (int t = 0; t < numFlags; ++t) {
    if ((t & 7) == 0 && t + 8 <= numFlags) {
      std::uint64_t word;
      std::memcpy(&word, inLocal.data() + t, 8);
      if (word == 0) {
        t += 7;
        continue;
      }
    }
    if (!inLocal[t]) continue;
    for (const int v : w.tet(t)) {
      const std::int32_t sl = slot[v];
      if (sl < 0) continue;
      ++(*off)[sl + 1];
      incidence.push_back({sl, t});
    }
  }
  for (size_t i = 0; i < numCut; ++i) (*off)[i + 1] += (*off)[i];
  tets->resize((*off)[numCut]);
  std::vector<std::int32_t> fill(off->begin(), off->end() - 1);
  for (const auto& [sl, t] : incidence) (*tets)[fill[sl]++] = t;
}

// Groups n's star (tets sharing a face with n that is not cut are in one group): the group
// of the first tet keeps n, every other group gets a copy.
void Cut3D::separateNode(int n, std::span<const std::int32_t> st, const std::vector<std::uint8_t>& cutMask,
                         std::int32_t numSep) {
  parent.resize(st.size());
  std::iota(parent.begin(), parent.end(), 0);
  auto find = [this](int x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  };
  const size_t numPairs = pairFaces(n, st);
  // A face is cut where this tet's face opposite `opp` was found cut and is still that
  // face: its other two nodes are not copies made since (copies are >= numSep).
  for (size_t q = 0; q < numPairs; ++q) {
    const auto& [first, j, opp, ids] = facePairs[q];
    if (!((cutMask[st[j]] >> opp) & 1) || ids >= numSep) parent[find(first)] = find(j);
  }
  copyOf.assign(st.size(), -1);
  const int keep = find(0);
  for (size_t j = 0; j < st.size(); ++j) {
    const int g = find(static_cast<int>(j));
    if (g == keep) continue;
    if (copyOf[g] < 0) copyOf[g] = copyNode(n);
    Tet tv = w.tet(st[j]);
    tv[localOfN[j]] = copyOf[g];
    w.setTet(st[j], tv);
  }
}

// Faces of n's star by the pair of their other two nodes (local numbers over n's neighbours,
// given as they are met: at most 3 per tet, stride L): each occurrence after the first gives
// a pair (first tet, this tet, the local vertex opposite the face in this tet, the face's
// larger other node) in facePairs; returns their number.
size_t Cut3D::pairFaces(int n, std::span<const std::int32_t> st) {
  if (sepLocal.size() < static_cast<size_t>(w.numNodes())) sepLocal.resize(w.numNodes(), -1);
  sepNbrs.clear();
  const size_t L = 3 * st.size();
  if (firstTet.size() < L * L) firstTet.resize(L * L, -1);  // all -1 between nodes
  firstUsed.resize(3 * st.size());
  facePairs.resize(3 * st.size());
  localOfN.resize(st.size());  // n's local index in each tet of its star
  size_t numPairs = 0;
  for (size_t j = 0, q = 0; j < st.size(); ++j) {
    const Tet& tv = w.tet(st[j]);
    const int ln = findLocal(tv, n);
    localOfN[j] = static_cast<std::int8_t>(ln);
    for (int k = 0; k < 4; ++k)
      if (k != ln && sepLocal[tv[k]] < 0) {
        sepLocal[tv[k]] = static_cast<std::int32_t>(sepNbrs.size());
        sepNbrs.push_back(tv[k]);
      }
    for (const auto& pair : kFacePairs[ln]) {
      const std::int32_t o0 = tv[pair[0]], o1 = tv[pair[1]];
      const std::int32_t a = sepLocal[o0], b = sepLocal[o1];
      const std::int32_t at = static_cast<std::int32_t>(std::min(a, b) * L + std::max(a, b));
      const std::int32_t first = firstTet[at];
      firstTet[at] = first < 0 ? static_cast<std::int32_t>(j) : first;
      firstUsed[q++] = at;
      facePairs[numPairs] = {first, static_cast<std::int32_t>(j), 6 - ln - pair[0] - pair[1], std::max(o0, o1)};
      numPairs += first >= 0 ? 1 : 0;
    }
  }
  for (int v : sepNbrs) sepLocal[v] = -1;
  for (const std::int32_t at : firstUsed) firstTet[at] = -1;
  return numPairs;
}

// A copy of n (an input node, or a split node: its parents) for the other side.
int Cut3D::copyNode(int n) {
  std::vector<NewNode>& newNodes = result.change.new_nodes;
  NewNode nn;
  nn.id = w.addNode(w.x(n));
  on.push_back(1);
  nn.duplicate = true;
  if (n < N0) {
    nn.num_parents = 1;
    nn.parents = {n, -1, -1};
    nn.weights = {1.0, 0.0, 0.0};
  } else {
    const NewNode& src = newNodes[n - N0];  // split nodes come first, in id order
    nn.num_parents = src.num_parents;
    nn.parents = src.parents;
    nn.weights = src.weights;
  }
  newNodes.push_back(nn);
  cutNodes.push_back(nn.id);
  ++result.report.duplicated_nodes;
  return nn.id;
}

}  // namespace hysim::cutting::cut3d_detail
