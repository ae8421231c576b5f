#pragma once
// The fixed-step loop's state: tissue model, tool, contact. One call of step() advances the
// whole simulation by the scene's dt; it never reads the wall clock and never allocates.
#include <functional>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "hysim/cutting/mesh.hpp"
#include "hysim/engine/collision.hpp"
#include "hysim/engine/outer_wall.hpp"
#include "hysim/engine/chips.hpp"
#include "hysim/engine/mesh_faces.hpp"
#include "hysim/engine/scene.hpp"
#include "hysim/engine/tet_locator.hpp"
#include "hysim/engine/tool.hpp"
#include "hysim/haptics/device.hpp"
#include "hysim/render/snapshot.hpp"
#include "hysim/sim/model.hpp"

namespace hysim::engine {

// One shaving pass: the loop entered the tissue with the pedal down and left it (or the
// pedal was released); the accumulated sweep was cut with the hybrid method.
struct PassRecord {
  double time_s = 0.0;
  int elements = 0;          // after the pass (chips removed)
  int nodes = 0;
  double q_min = 0.0;        // q* = r_in / R_circ of the worst tet after the pass
  double cut_ms = 0.0;       // cut + chip removal + model rebuild (the whole pass, wall time)
  // cut_ms split into its parts (wall time, ms): carrying the sweep to the rest shape,
  // cutting::cut3d, current positions of the cut mesh, free pieces found and removed (mesh
  // compacted), the tissue model (masses, springs, stability), boundary/render/contact
  // arrays, the FCL hierarchy, the tet locator, chip shapes and bodies, mesh statistics;
  // other_ms is what is left (cut_ms minus the parts). The model update's first part (masses
  // and springs around the cut) runs on a second thread from the end of cut3d, beside the
  // remap and the piece search; model_ms counts the wait for it and the second part. The
  // boundary and FCL hierarchy (surface_ms, collision_ms: that thread's wall time) are then
  // built on the same thread while this one updates the model (model_ms) and computes the
  // mesh statistics (stats_ms); geometry_wait_ms is how long this thread then waited for them
  // (what they add to cut_ms), and other_ms is computed with geometry_wait_ms in place of
  // those two. The tet locator (locator_ms) is built on a
  // background thread after the pass has ended, beside the following steps, and is not part
  // of cut_ms (at the start of a run, setTopology builds it in place); the same thread finds
  // the new mesh's distances to the anchors (for the next pass's piece search) and, when the
  // pass searched for free pieces near its cut only, counts `components`: locator_ms includes
  // both.
  double map_ms = 0.0, cut3d_ms = 0.0, remap_ms = 0.0, components_ms = 0.0, model_ms = 0.0, surface_ms = 0.0,
         collision_ms = 0.0, locator_ms = 0.0, chips_ms = 0.0, stats_ms = 0.0, other_ms = 0.0,
         geometry_wait_ms = 0.0;
  int chips = 0;             // free pieces removed
  double removed_mm3 = 0.0;  // volume of the removed chips
  double removed_myoma_mm3 = 0.0;
  double sweep_area_mm2 = 0.0;  // area of the cut surface (the loop's sweep)
  int crossed_edges = 0, snapped_nodes = 0, split_edges = 0, duplicated_nodes = 0, cut_faces = 0;
  int unoptimised_chip_elements = 0;  // chips.optimize false: the tets the cut left as cut
  int components = 0;        // pieces of the cut mesh (chips included); passes() waits for it
  int substeps = 0;          // of the rebuilt model
  double added_mass_g = 0.0; // mass scaling needed to keep substeps within the cap (since the start)
  int stability_nodes = 0;   // free nodes of the model update's frequency estimate
  bool global_stability = false;  // that estimate covered the whole mesh (the highest mode was near the cut)
  bool cut_failed = false;   // the cut was refused (the mesh is left as it was)
  std::string message;
};

// One perforation event: while the electrode was active, the loop's wire came closer than
// the scene's safety.perforation_margin_mm to the outer (serosal) surface, or went beyond it.
struct PerforationEvent {
  double time_s = 0.0;           // first step of the event
  double end_s = 0.0;            // last step of the event (still open: the latest step)
  double min_distance_mm = 0.0;  // closest approach of the wire's surface; < 0: beyond the serosa
};

class PassWorker;  // pass_worker.hpp

class Simulation {
 public:
  // Loads the meshes named by the scene, anchors nodes, builds the tissue model.
  static Result<std::unique_ptr<Simulation>> create(const Scene& scene);
  ~Simulation();  // waits for a locator build still running

  // Advances one fixed step. Allocates nothing, also while the loop cuts through tissue,
  // except on the step a shaving pass ends (the loop leaves the tissue), when the cut
  // changes the topology.
  void step();

  // Fills a snapshot for the renderer. Reuses the snapshot's buffers (no allocation after
  // the first call with the same topology).
  void fillSnapshot(render::RenderSnapshot& snapshot) const;

  const Scene& scene() const { return scene_; }
  const cutting::TetMesh& mesh() const { return mesh_; }
  const sim::Model& model() const { return model_; }
  const sim::State& state() const { return state_; }
  const haptics::ToolPose& toolPose() const { return pose_; }
  const haptics::Device& device() const { return *device_; }
  // Replaces the device that drives the tool (e.g. a keyboard device in the trainee app).
  void setDevice(std::unique_ptr<haptics::Device> device) { device_ = std::move(device); }
  int numAnchored() const { return num_anchored_; }
  int numDeformableTets() const { return num_deformable_tets_; }  // tets with at least one free node
  int numSurfaceNodes() const { return static_cast<int>(surface_nodes_.size()); }
  // Reaction force on the tool from tissue contact in the last step, newtons.
  const Eigen::Vector3d& toolForceN() const { return tool_force_n_; }
  // Positions and velocities of the tissue, and the simulated chips' poses (when there are any).
  std::uint64_t stateHash() const { return chips_ ? chips_->hash(sim::stateHash(state_)) : sim::stateHash(state_); }
  // The simulated chips (scene `chips: simulate`); null when chips are removed.
  const ChipWorld* chips() const { return chips_.get(); }
  // Wall time spent stepping the chips (Bullet), seconds, and the steps that had chips.
  double chipStepSeconds() const { return chip_step_s_; }
  long chipSteps() const { return chip_steps_; }
  const std::vector<PassRecord>& passes() const {
    waitLocator();  // the last pass's locator_ms
    return passes_;
  }
  bool loopInTissue() const { return loop_in_tissue_; }
  const LoopGeometry& loop() const { return loop_; }
  int topologyVersion() const { return topology_version_; }
  const TissueCollision& collision() const { return collision_; }
  // Metrics of the run so far.
  double initialMyomaVolume() const { return initial_myoma_mm3_; }  // mm^3, rest shape
  double electrodeActiveSeconds() const { return electrode_active_s_; }
  double pathLengthMm() const { return path_length_mm_; }         // of the scope tip
  // Perforation check (runs while the pedal is down). perforations() counts events; the
  // list keeps the first kMaxPerforationEvents of them.
  static constexpr int kMaxPerforationEvents = 1000;
  int perforations() const { return perforation_count_; }
  const std::vector<PerforationEvent>& perforationEvents() const { return perforation_events_; }
  bool perforating() const { return perforating_; }  // an event is open now
  // Distance of the wire's surface from the serosa at the last active step, mm: exact below
  // the margin, otherwise some value >= the margin (+inf before the first active step).
  double serosaClearanceMm() const { return serosa_clearance_mm_; }
  const OuterWall& outerWall() const { return outer_wall_; }
  // Puts back a state saved from this simulation (benchmarks restore one before each batch).
  // Same topology only; copies into the existing buffers.
  void restoreState(const sim::State& saved) { state_ = saved; }
  // Debugging: when set, each pass writes the cut's input into this folder before cutting:
  // the rest mesh (pass_NNN_mesh.msh) and the cut surface (pass_NNN_surface.msh), NNN the
  // pass's number from 1, full precision; `hysim cut MESH --surface SURFACE --method hybrid`
  // then repeats the pass's cut exactly. Empty (the default): nothing is written.
  void setCutDumpDir(std::string dir) { cut_dump_dir_ = std::move(dir); }

 private:
  Simulation() = default;
  void computeContact();
  static void contactForces(void* self, const sim::NodeVectors& x, const sim::NodeVectors& v);
  void contactForces(const sim::NodeVectors& x, const sim::NodeVectors& v);
  // Replaces the mesh (rest positions) and everything built from it; x, v (#N x 3) are the
  // current positions and velocities (null: rest and zero).
  // current positions and velocities (null: rest and zero). `timing` (optional) receives the
  // wall time of the parts (model_ms, surface_ms, collision_ms, locator_ms, chips_ms).
  Status setTopology(cutting::TetMesh rest_mesh, const sim::NodeVectors* x, const sim::NodeVectors* v,
                     PassRecord* timing = nullptr);
  // Everything built from mesh_ and state_.x for contact, collision and drawing: boundary
  // faces, render surface, contact nodes, FCL hierarchy, tet locator, chips' cavity.
  // `boundary` (optional, 4 #T): which tet faces (slot 4 t + k, face k opposite vertex k) lie
  // on the boundary, when the caller knows; else they are found from mesh_.
  Status rebuildGeometry(PassRecord* timing, const std::vector<std::uint8_t>* boundary = nullptr);
  // rebuildGeometry's first part, for `mesh` at positions x (the next mesh_ and state_.x): the
  // boundary faces, render surface and FCL hierarchy. It writes only those members
  // (surface_*, collision_) and reads on_cut_ and scene_, so a pass runs it on a second
  // thread beside the model update. Times surface_ms, collision_ms. (The tet locator is
  // rebuildGeometry's, or the pass's background thread's.) `renumber` (optional, #N of the
  // mesh the hierarchy was last built for): the node each of its nodes became in `mesh`, or
  // -1; with it, the hierarchy's chunks whose faces did not change are kept (see
  // TissueCollision::build).
  Status buildGeometry(const cutting::TetMesh& mesh, const sim::NodeVectors& x, PassRecord* timing,
                       const std::vector<std::uint8_t>* boundary, const std::vector<int>* renumber = nullptr);
  // rebuildGeometry's second part, once mesh_, model_ and state_ are the new ones: contact
  // nodes and forces, collision flags, chips' cavity, topology version.
  void finishGeometry(PassRecord* timing);
  // State for model_ and mesh_ with positions x and velocities v (null: rest, zero), keeping
  // the step count, time and warnings; counts anchored and deformable elements.
  void resetState(const sim::NodeVectors* x, const sim::NodeVectors* v);
  bool isAnchored(const Eigen::Vector3d& rest) const;
  static double tetQuality(const cutting::TetMesh& mesh, int t);  // q* = r_in / R_circ, rest shape
  // Does the loop touch the tissue this step? Its sweep since the last step against the
  // boundary (FCL), else whether the wire is buried (one point in a tet).
  bool loopTouchesTissue();
  void finishPass();
  // The cut surface in the rest shape, built while the pass runs: each new sweep row that lies
  // 0.3 mm or more (its middle point) from the last kept one is carried from the tissue as it
  // is at that step to the rest shape (mapToRest), so the cut follows the material the wire
  // passed through when it passed. The first call also maps the row 1.5 mm before the start.
  // last_rows: the pass ends (see mapRow).
  void mapSweepRows(bool last_rows = false);
  // Rest position of the point p of the deformed tissue: through the tet that contains it
  // (state_.x), else the affine map of a tet at the nearest surface node, which continues the
  // deformation smoothly. False when there is no tissue to map to.
  bool mapToRest(const Eigen::Vector3d& p, double displacement, Eigen::Vector3d& rest) const;
  // Appends row `row` of the sweep (or, with `shift`, that row moved by it) to rest_rows_.
  // The locator is rebuilt first when the nodes moved more than a millimetre since its
  // build, or, for the pass's last rows (last_rows), more than its margin: the answers are
  // the same either way (locate() gives the lowest-numbered tet holding the point, whatever
  // the grid).
  bool mapRow(int row, const Eigen::Vector3d& shift, bool last_rows = false);
  // The lookups mapToRest needs besides the locator, for mesh_ at positions x: the nearest
  // surface node (over a copy of x, surface_nodes_) and a tet at each node. Built with the
  // locator (after a pass: on its background thread).
  void buildNearest(const cutting::TetMesh& mesh, const sim::NodeVectors& x);
  void checkPerforation();

  Scene scene_;
  cutting::TetMesh mesh_;
  sim::Model model_;
  sim::State state_;
  std::unique_ptr<haptics::Device> device_;  // the scene's scripted device (hardware later)
  haptics::ToolPose pose_;

  cutting::Tris surface_faces_;                   // #B x 3 boundary faces, model node ids
  std::vector<int> surface_nodes_;                // #V model node ids on the boundary
  std::vector<std::uint32_t> surface_triangles_;  // #B*3 indices into surface_nodes_
  std::vector<render::SurfaceMaterial> surface_material_;  // #V
  std::vector<int> contact_nodes_;                // free surface nodes (contact candidates)
  sim::NodeVectors contact_force_;                // #N x 3, uN
  Eigen::Vector3d tool_force_n_{0, 0, 0};
  Eigen::Vector3d contact_shaft_a_{0, 0, 0}, contact_shaft_b_{0, 0, 0}, contact_loop_{0, 0, 0};  // this step's tool
  int contact_calls_ = 0;                         // substeps that computed contact this step
  render::SurfaceMesh tool_surface_;              // body frame
  int num_anchored_ = 0;
  int num_deformable_tets_ = 0;

  // Shaving.
  LoopGeometry loop_;
  TissueCollision collision_;  // boundary faces, refitted only while the electrode is active
  SweptWire swept_wire_;       // the wire's motion in the last step
  bool collision_active_ = false;  // the hierarchy was refitted and is followed step by step
  // Whether the wire is buried (in the tissue, touching no surface), known since the last
  // contact: without contact the wire cannot change sides, so one TetLocator test per
  // contact-free stretch is enough.
  bool buried_known_ = false;
  bool buried_ = false;
  TetLocator locator_;
  // The locator's build after a pass (see finishPass); waitLocator() joins it. Everything
  // that reads locator_ (the buried test, the next pass, rebuildGeometry) waits first.
  mutable std::thread locator_thread_;
  void waitLocator() const;
  // The second thread of finishPass (made at the first pass; it sleeps between passes).
  std::unique_ptr<PassWorker> pass_worker_;
  // anchor_distance_ and pieces_anchored_ of mesh_, face_next_ and anchored_ (cleared and
  // false when face_next_ is unknown); with count, returns the number of pieces of mesh_
  // (a whole labelling; -1: unknown), else 0.
  int anchorPieces(bool count);
  Eigen::Matrix<double, Eigen::Dynamic, 3> wire_, previous_wire_;
  Sweep sweep_;
  std::vector<Eigen::Vector3d> rest_rows_;  // the open pass's kept rows, rest shape (mapSweepRows)
  int swept_rows_mapped_ = 0;               // sweep rows looked at by mapSweepRows
  Eigen::Vector3d kept_middle_{0, 0, 0};    // deformed middle point of the last kept row
  bool map_failed_ = false;                 // a point had no tissue to map to
  sim::NodeVectors nearest_x_;              // positions the NearestPoint grid was built at
  NearestPoint nearest_surface_;            // over surface_nodes_ at nearest_x_
  std::vector<int> node_tet_;               // #N: a tet around each node (the last that has it)
  bool loop_in_tissue_ = false;
  bool cutting_ = false;
  int topology_version_ = 0;
  std::vector<PassRecord> passes_;
  std::string cut_dump_dir_;  // see setCutDumpDir
  std::vector<std::uint8_t> on_cut_;  // #N: node lies on a cut surface (drawn as cut tissue)
  std::vector<std::uint8_t> anchored_;  // #N: rest position in an anchor region (fixed)
  std::vector<double> tet_quality_;     // #T: q* of each element (rest shape), for q_min
  std::vector<int> face_next_;          // 4 #T: matchFaces' next of mesh_ (empty: unknown)
  // #T: anchorDistance of mesh_ (empty: unknown), and whether every piece of mesh_ has an
  // anchored node (then a pass searches for free pieces near its cut only, see finishPass).
  // After a pass both are computed on the locator's background thread.
  std::vector<int> anchor_distance_;
  bool pieces_anchored_ = false;
  double initial_myoma_mm3_ = 0.0;
  double electrode_active_s_ = 0.0;
  double path_length_mm_ = 0.0;

  // Perforation.
  OuterWall outer_wall_;  // serosa of the initial mesh
  std::vector<PerforationEvent> perforation_events_;  // capacity reserved at create()
  int perforation_count_ = 0;
  bool perforating_ = false;
  double serosa_clearance_mm_ = 0.0;
  // Chips (simulate mode).
  std::unique_ptr<ChipWorld> chips_;
  double chip_step_s_ = 0.0;
  long chip_steps_ = 0;
};

// Loads a surface (OBJ, STL, PLY, glTF...) with assimp, triangulated, in millimetres.
Result<render::SurfaceMesh> loadSurface(const std::string& path, render::SurfaceMaterial material);

}  // namespace hysim::engine
