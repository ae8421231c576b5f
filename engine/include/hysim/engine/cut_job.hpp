#pragma once
// A shaving pass's cut as one whole job: from the tissue epoch the pass ran on and the sweep
// carried to the rest shape, the next epoch (cut mesh with the free pieces removed, updated
// model, surface, collision hierarchy, locator), the chips, and the map that carries the
// state across at the commit step. Single-threaded and deterministic: the same input gives
// the same outcome to the last bit, whichever thread runs it and whenever.
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "hysim/cutting/mesh.hpp"
#include "hysim/engine/chips.hpp"
#include "hysim/engine/mesh_faces.hpp"
#include "hysim/engine/pass_record.hpp"
#include "hysim/engine/scene.hpp"
#include "hysim/engine/tissue.hpp"
#include "hysim/sim/model.hpp"

namespace hysim::engine {

struct CutJobInput {
  cutting::Positions rest_rows;  // (rows * row_size) x 3: the sweep's kept rows, rest shape
  int rows = 0, row_size = 0;
  // Positions and velocities at the exit step (numbering of the epoch cut): the chips start
  // there, and the new epoch's hierarchy and locator are built there.
  sim::NodeVectors x, v;
  std::string dump_prefix;  // non-empty: write the cut's input to PREFIXmesh.msh, PREFIXsurface.msh
};

// How the state of the epoch that was cut becomes the state of the next one. Kept node j:
// x_j = sum_k w_k x_old(p_k) + offset_j and v_j = sum_k w_k v_old(p_k), over its parents
// [first[j], first[j+1]): a surviving node has itself (w = 1) and the rest-shape move the cut
// gave it as offset; a new node its parents' interpolation and the same for its rest shape.
struct StateRemap {
  std::vector<int> first;      // #kept + 1
  std::vector<int> parent;     // old node ids
  std::vector<double> weight;
  sim::NodeVectors offset;     // #kept x 3, mm
  // Writes x, v (sized #kept x 3 already); allocates nothing.
  void apply(const sim::NodeVectors& x_old, const sim::NodeVectors& v_old, sim::NodeVectors& x,
             sim::NodeVectors& v) const;
};

// The free pieces of a cut (scene chips: simulate), kept to become chips at the commit step,
// where the pieces are then: the cut mesh, a state map onto all of its nodes, its pieces and
// its nodes on a cut surface.
struct ChipSource {
  cutting::TetMesh mesh;
  StateRemap remap;
  Pieces pieces;
  std::vector<std::uint8_t> on_cut;
};
// The chips of `source` at the state (x, v) of the epoch that was cut.
std::vector<ChipShape> chipsAt(const ChipSource& source, const Scene& scene, const sim::NodeVectors& x,
                               const sim::NodeVectors& v);

struct CutOutcome {
  Status status;                   // not ok: the cut was refused, the epoch stays
  PassRecord record;               // what the job did and its wall times
  std::unique_ptr<Tissue> tissue;  // the next epoch
  StateRemap remap;
  std::vector<int> old_to_kept;    // #N of the epoch cut: its node in the next one, or -1
  ChipSource chips;                // free pieces (empty unless scene chips: simulate)
  sim::State state;                // step arrays sized for the next model; x, v filled at commit
};

// Cuts `base` (not modified; read only) with the input's sweep. Fills `out` whole.
void runCutJob(const Tissue& base, const Scene& scene, const CutJobInput& input, CutOutcome& out);

}  // namespace hysim::engine
