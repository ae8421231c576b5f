#pragma once
// Which tet contains a point, for the loop electrode's "is the wire in the tissue" test.
// A uniform grid over the tets' bounding boxes at the build; queries use the current node
// positions and look in the cells within the nodes' displacement since the build, so the grid
// stays valid however far they moved; the caller rebuilds when one has moved further than
// the margin (queries get slower with the displacement) and after topology changes.
//
// The step uses it only for the wire's "buried" case, once per contact-free stretch: contact
// with the tissue's surface is FCL's job (collision.hpp).
#include <Eigen/Core>
#include <vector>

#include "hysim/cutting/mesh.hpp"
#include "hysim/sim/model.hpp"

namespace hysim::engine {

class TetLocator {
 public:
  void build(const cutting::TetMesh& mesh, const sim::NodeVectors& x, double margin_mm = 3.0);
  // Tet containing p at positions x, or -1. Allocates nothing. max_displacement: a bound on
  // how far the nodes moved since the build (maxDisplacement(x)), when the caller knows one
  // (the answer is the same, found faster); else the margin.
  int locate(const cutting::TetMesh& mesh, const sim::NodeVectors& x, const Eigen::Vector3d& p,
             double max_displacement = -1.0) const;
  // Largest node displacement since the build (O(#N)); rebuild when it exceeds margin().
  double maxDisplacement(const sim::NodeVectors& x) const;
  double margin() const { return margin_; }

 private:
  // p lies in tet t at positions x.
  bool containsNow(const cutting::TetMesh& mesh, const sim::NodeVectors& x, int t, const Eigen::Vector3d& p) const;

  struct Entry {  // a cell's tet and its build box (see build())
    float lo[3], hi[3];
    int tet;
  };

  Eigen::Vector3d origin_{0, 0, 0};
  double cell_ = 1.0;
  double inv_cell_ = 1.0;  // 1 / cell_
  Eigen::Vector3i dims_{0, 0, 0};
  std::vector<int> cell_start_;  // #cells + 1
  std::vector<Entry> cell_boxes_;  // the cells' tets in increasing order, cell after cell
  std::vector<int> fill_;        // build scratch
  std::vector<Eigen::Vector3i> ranges_;  // build scratch: first and last cell of each tet
  std::vector<double> boxes_;            // 6 #T: each tet's box at the build (min xyz, max xyz)
  sim::NodeVectors built_x_;
  double margin_ = 1.0;
  double max_box_ = 0.0;                 // largest extent of a tet's box at the build
};

}  // namespace hysim::engine
