// Node -> tets lists of a mesh, built once and patched where a cut changed tets.
#include "../optimize3d_internal.hpp"

namespace hysim::cutting {

void buildStarLists(const Tets& T, int numNodes, StarLists* lists) {
  const int M = static_cast<int>(T.rows());
  std::vector<std::int32_t>& off = lists->off;
  StarVector& star = lists->star;
  // Counts at off[n + 2], their prefix sums, then each tet at off[n + 1]++: afterwards
  // off[n] .. off[n + 1] is n's row (ascending: the tets in index order).
  off.assign(static_cast<size_t>(numNodes) + 2, 0);
  star.resize(4 * static_cast<size_t>(M));
  const std::int32_t *c0 = T.col(0).data(), *c1 = T.col(1).data(), *c2 = T.col(2).data(), *c3 = T.col(3).data();
  std::int32_t* o = off.data();
  std::int32_t* s = star.data();
  for (int t = 0; t < M; ++t) {
    ++o[c0[t] + 2];
    ++o[c1[t] + 2];
    ++o[c2[t] + 2];
    ++o[c3[t] + 2];
  }
  for (int i = 0; i < numNodes; ++i) o[i + 2] += o[i + 1];
  for (int t = 0; t < M; ++t) {
    s[o[c0[t] + 1]++] = t;
    s[o[c1[t] + 1]++] = t;
    s[o[c2[t] + 1]++] = t;
    s[o[c3[t] + 1]++] = t;
  }
  off.pop_back();
  lists->pool_start.clear();
  lists->pool_len.clear();
  lists->pool.clear();
}

void patchStarLists(const Tets& before, const Tets& after, int numNodesAfter, std::vector<std::int32_t> changed,
                    StarLists* lists) {
  const int M0 = static_cast<int>(before.rows()), M1 = static_cast<int>(after.rows());
  const int N0 = static_cast<int>(lists->off.size()) - 1;
  // The changed rows sorted, without repeats (what sort + unique gives), from a bit per row
  // (the words that got a bit, sorted, then each word's bits in order); the merge below reads
  // the bits.
  IndexBits changedBits(M0);
  for (const int t : changed) changedBits.mark(t);
  changed.clear();
  changedBits.listInto(changed);
  auto isChanged = [&changedBits](std::int32_t t) { return changedBits.has(t); };
  // The nodes whose lists change (those of the changed tets before and after, and of the
  // appended tets), numbered as met; for each, the changed and appended tets that have it
  // now (CSR over those numbers, ascending: the tets are visited in index order).
  std::vector<std::int32_t> local(numNodesAfter, -1), nodes, count;
  auto number = [&](std::int32_t n) {
    if (local[n] < 0) {
      local[n] = static_cast<std::int32_t>(nodes.size());
      nodes.push_back(n);
      count.push_back(0);
    }
    return local[n];
  };
  for (const int t : changed)
    for (int k = 0; k < 4; ++k) {
      number(before(t, k));
      ++count[number(after(t, k))];
    }
  for (int t = M0; t < M1; ++t)
    for (int k = 0; k < 4; ++k) ++count[number(after(t, k))];
  std::vector<std::int32_t> gainedOff(nodes.size() + 1, 0), gained;
  for (size_t i = 0; i < nodes.size(); ++i) gainedOff[i + 1] = gainedOff[i] + count[i];
  gained.resize(gainedOff.back());
  for (size_t i = 0; i < nodes.size(); ++i) count[i] = gainedOff[i];  // fill positions
  for (const int t : changed)
    for (int k = 0; k < 4; ++k) gained[count[local[after(t, k)]]++] = t;
  for (int t = M0; t < M1; ++t)
    for (int k = 0; k < 4; ++k) gained[count[local[after(t, k)]]++] = t;
  // Appended nodes: empty CSR rows.
  lists->off.resize(static_cast<size_t>(numNodesAfter) + 1, lists->off[N0]);
  lists->pool_start.assign(numNodesAfter, -1);
  lists->pool_len.assign(numNodesAfter, 0);
  std::vector<std::int32_t>& pool = lists->pool;
  pool.clear();
  pool.reserve(gained.size() + 8 * nodes.size());
  for (size_t i = 0; i < nodes.size(); ++i) {
    // Merge n's old row without the changed tets and the tets that now have n.
    const int n = nodes[i];
    const std::int32_t* o = n < N0 ? lists->star.data() + lists->off[n] : nullptr;
    const std::int32_t* oEnd = n < N0 ? lists->star.data() + lists->off[n + 1] : nullptr;
    const std::int32_t* g = gained.data() + gainedOff[i];
    const std::int32_t* gEnd = gained.data() + gainedOff[i + 1];
    const size_t start = pool.size();
    for (;;) {
      while (o < oEnd && isChanged(*o)) ++o;
      const bool haveOld = o < oEnd, haveNew = g < gEnd;
      if (!haveOld && !haveNew) break;
      if (haveOld && (!haveNew || *o < *g)) {
        pool.push_back(*o++);
      } else {
        pool.push_back(*g++);
      }
    }
    lists->pool_start[n] = static_cast<std::int32_t>(start);
    lists->pool_len[n] = static_cast<std::int32_t>(pool.size() - start);
  }
}

}  // namespace hysim::cutting
