#pragma once
// What a cut changed, so that sim/ and render/ update themselves without re-scanning the
// mesh: new nodes with their parents, removed and added elements, old -> new index maps.
#include <array>
#include <cstdint>
#include <vector>

namespace hysim::cutting {

// A node of the new mesh that did not exist before the cut. It was created at
// sum_k weights[k] * x(parents[k]) (k < num_parents) with the parents' positions at that
// moment (a parent may have been displaced onto the cut first); the optimisation may move
// it along the cut afterwards. For interpolating state (velocities) the weights are what
// to use; for geometry read the new mesh.
struct NewNode {
  std::int32_t id = -1;                      // index in the new mesh
  int num_parents = 0;                       // 1 (duplicate of a node), 2 (on an edge) or 3
  std::array<std::int32_t, 3> parents{-1, -1, -1};  // old node indices
  std::array<double, 3> weights{0, 0, 0};    // barycentric weights, sum 1
  bool duplicate = false;                    // a copy made to separate the two sides
};

struct TopologyChange {
  int old_num_nodes = 0, old_num_elements = 0;
  int new_num_nodes = 0, new_num_elements = 0;
  // #old nodes: new index of each old node. A node merged away by an edge collapse maps to
  // the node it was merged into; -1 only for nodes removed with their elements (deletion).
  std::vector<std::int32_t> node_old_to_new;
  // #old elements: new index, or -1 when the element was removed (split, flipped, collapsed,
  // deleted). Elements whose nodes only moved or were renumbered keep their identity.
  std::vector<std::int32_t> element_old_to_new;
  std::vector<NewNode> new_nodes;               // sorted by id
  std::vector<std::int32_t> removed_elements;   // old indices, ascending
  std::vector<std::int32_t> added_elements;     // new indices, ascending
  std::vector<std::int32_t> moved_nodes;        // new indices of surviving old nodes that moved
  std::vector<std::int32_t> cut_nodes;          // new indices of the nodes on the cut (both sides)
  // Node pairs (new indices) of the edges the cut runs along, one entry per side.
  std::vector<std::array<std::int32_t, 2>> cut_edges;
  // 3D cuts: the triangles on the cut (new indices), one entry per side, each oriented
  // outward from the tet it belongs to (for rendering the wound surface).
  std::vector<std::array<std::int32_t, 3>> cut_faces;
};

}  // namespace hysim::cutting
