#pragma once
// The fixed-step loop's state: tissue model, tool, contact. One call of step() advances the
// whole simulation by the scene's dt; it never reads the wall clock and never allocates.
#include <chrono>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "hysim/cutting/mesh.hpp"
#include "hysim/engine/chips.hpp"
#include "hysim/engine/collision.hpp"
#include "hysim/engine/cut_job.hpp"
#include "hysim/engine/cut_worker.hpp"
#include "hysim/engine/mesh_faces.hpp"
#include "hysim/engine/outer_wall.hpp"
#include "hysim/engine/pass_record.hpp"
#include "hysim/engine/scene.hpp"
#include "hysim/engine/tet_locator.hpp"
#include "hysim/engine/tissue.hpp"
#include "hysim/engine/tool.hpp"
#include "hysim/haptics/device.hpp"
#include "hysim/haptics/local_force_model.hpp"
#include "hysim/haptics/recording.hpp"
#include "hysim/haptics/virtual_coupling.hpp"
#include "hysim/render/snapshot.hpp"
#include "hysim/sim/model.hpp"

namespace hysim::engine {

// One perforation event: while the electrode was active, the loop's wire came closer than
// the scene's safety.perforation_margin_mm to the outer (serosal) surface, or went beyond it.
struct PerforationEvent {
  double time_s = 0.0;           // first step of the event
  double end_s = 0.0;            // last step of the event (still open: the latest step)
  double min_distance_mm = 0.0;  // closest approach of the wire's surface; < 0: beyond the serosa
};

class Simulation {
 public:
  // Loads the meshes named by the scene, anchors nodes, builds the tissue model.
  static Result<std::unique_ptr<Simulation>> create(const Scene& scene);
  ~Simulation();  // waits for a cut still on the worker

  // Advances one fixed step. Allocates nothing, also while the loop cuts through tissue and
  // on the step that commits a cut (it swaps in what the cut worker prepared), except on the
  // step a shaving pass ends (the loop leaves the tissue), which hands the cut to the worker,
  // and, with simulated chips, the commit step (chips enter the rigid-body world).
  void step();

  // Fills a snapshot for the renderer. Reuses the snapshot's buffers (no allocation after
  // the first call with the same topology).
  void fillSnapshot(render::RenderSnapshot& snapshot) const;

  const Scene& scene() const { return scene_; }
  const cutting::TetMesh& mesh() const { return tissue_->mesh; }
  const sim::Model& model() const { return tissue_->model; }
  const sim::State& state() const { return state_; }
  // The simulated tool: the device's pose, with the tip at the coupling's proxy (scene
  // coupling: spring) or at the device's tip (rigid).
  const haptics::ToolPose& toolPose() const { return pose_; }
  const haptics::Device& device() const { return *device_; }
  // The device's state this step's tool followed.
  const haptics::DeviceState& deviceState() const { return device_state_; }
  // Replaces the device that drives the tool (e.g. a keyboard device in the trainee app); the
  // coupling's proxy starts on its tip.
  void setDevice(std::unique_ptr<haptics::Device> device);
  // Records every device state the simulation consumes from now on into `writer` (the
  // current one first, as an attach; then one per step and one per setDevice), or stops
  // recording (null). Only before the first step, where a replay starts. The writer must
  // outlive the recording.
  Status recordInputTo(haptics::RecordingWriter* writer);
  int numAnchored() const { return tissue_->num_anchored; }
  int numDeformableTets() const { return tissue_->num_deformable_tets; }  // tets with at least one free node
  int numSurfaceNodes() const { return static_cast<int>(tissue_->surface_nodes.size()); }
  // Reaction force on the tool from tissue contact in the last step, newtons.
  const Eigen::Vector3d& toolForceN() const { return tool_force_n_; }
  // How that force changes with the tool's position (N/mm, symmetric, negative
  // semi-definite: pushing further in pushes back harder): the local model the haptic
  // thread renders between steps.
  const Eigen::Matrix3d& toolStiffnessNPerMm() const { return tool_stiffness_; }
  // The force on the user's hand after the last step (what the device was commanded): the
  // coupling spring-damper, or with a rigid coupling the tissue's reaction.
  const Eigen::Vector3d& handForceN() const { return hand_force_n_; }
  // The same force as a local model for the haptic thread, about the device's state of the
  // last step (see haptics::LocalForceModel).
  haptics::LocalForceModel hapticModel() const;
  // Distance between the simulated tool's tip and the device's tip, mm (0 when rigid).
  double couplingOffsetMm() const { return (pose_.tip - device_state_.pose.tip).norm(); }
  const haptics::CouplingGains& couplingGains() const { return coupling_.gains(); }
  // Positions and velocities of the tissue, and the simulated chips' poses (when there are any).
  std::uint64_t stateHash() const { return chips_ ? chips_->hash(sim::stateHash(state_)) : sim::stateHash(state_); }
  // The simulated chips (scene `chips: simulate`); null when chips are removed.
  const ChipWorld* chips() const { return chips_.get(); }
  // Wall time spent stepping the chips (Bullet), seconds, and the steps that had chips.
  double chipStepSeconds() const { return chip_step_s_; }
  long chipSteps() const { return chip_steps_; }
  // Committed passes, in order (a pass whose cut is still on the worker is not yet here).
  const std::vector<PassRecord>& passes() const { return passes_; }
  bool cutPending() const { return pending_ != nullptr; }
  // Commit steps that waited for the worker, and the whole wait (wall time, ms).
  int stalls() const { return stalls_; }
  double stallMs() const { return stall_ms_; }
  // Waits for the worker and commits a pending cut now (end of a run: its pass is reported).
  void commitPendingCut();
  // Testing: called on the worker before each cut job (see CutWorker::setDelayForTesting).
  void setCutDelayForTesting(std::function<void()> delay);
  bool loopInTissue() const { return loop_in_tissue_; }
  const LoopGeometry& loop() const { return loop_; }
  int topologyVersion() const { return topology_version_; }
  const TissueCollision& collision() const { return tissue_->collision; }
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
  // Reads the device for the end of this step and places the tool (through the coupling).
  void followDevice();
  void computeContact();
  static void contactForces(void* self, const sim::NodeVectors& x, const sim::NodeVectors& v);
  void contactForces(const sim::NodeVectors& x, const sim::NodeVectors& v);
  // Does the loop touch the tissue this step? Its sweep since the last step against the
  // boundary (FCL), else whether the wire is buried (one point in a tet).
  bool loopTouchesTissue();
  // The shaving part of a step: pass entry, sweep rows, exit.
  void advanceShaving();
  // The pass ends: its sweep goes to the cut worker (or, in sync mode, is cut here), to be
  // committed scene.cut.commit_steps steps later.
  void finishPass();
  void failPass(const std::string& why);
  // Swaps the worker's result in: the next tissue epoch, the state remapped from this step's
  // positions and velocities, the serosa's node numbers, the chips.
  void commitCut();
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
  void checkPerforation();

  Scene scene_;
  std::unique_ptr<Tissue> tissue_;  // the epoch being stepped
  sim::State state_;
  std::unique_ptr<haptics::Device> device_;  // the scene's scripted device unless replaced
  haptics::RecordingWriter* recorder_ = nullptr;  // see recordInputTo
  haptics::DeviceState device_state_;
  haptics::VirtualCoupling coupling_{haptics::CouplingGains{}, 1e-3};
  haptics::ToolPose pose_;
  Eigen::Vector3d hand_force_n_{0, 0, 0};

  sim::NodeVectors contact_force_;                // #N x 3, uN
  Eigen::Vector3d tool_force_n_{0, 0, 0};
  Eigen::Matrix3d tool_stiffness_ = Eigen::Matrix3d::Zero();
  Eigen::Vector3d contact_shaft_a_{0, 0, 0}, contact_shaft_b_{0, 0, 0}, contact_loop_{0, 0, 0};  // this step's tool
  int contact_calls_ = 0;                         // substeps that computed contact this step
  render::SurfaceMesh tool_surface_;              // body frame

  // Shaving.
  LoopGeometry loop_;
  SweptWire swept_wire_;       // the wire's motion in the last step
  bool collision_active_ = false;  // the hierarchy was refitted and is followed step by step
  // Whether the wire is buried (in the tissue, touching no surface), known since the last
  // contact: without contact the wire cannot change sides, so one TetLocator test per
  // contact-free stretch is enough.
  bool buried_known_ = false;
  bool buried_ = false;
  Eigen::Matrix<double, Eigen::Dynamic, 3> wire_, previous_wire_;
  Sweep sweep_;
  std::vector<Eigen::Vector3d> rest_rows_;  // the open pass's kept rows, rest shape (mapSweepRows)
  int swept_rows_mapped_ = 0;               // sweep rows looked at by mapSweepRows
  Eigen::Vector3d kept_middle_{0, 0, 0};    // deformed middle point of the last kept row
  bool map_failed_ = false;                 // a point had no tissue to map to
  bool loop_in_tissue_ = false;
  bool cutting_ = false;
  int topology_version_ = 0;
  std::vector<PassRecord> passes_;
  std::string cut_dump_dir_;  // see setCutDumpDir

  // The cut in flight: its input and outcome, the step that commits it, and when its pass
  // ended (wall time, for the latency). spent_ holds the last committed one, whose outcome
  // now owns the previous epoch: the next job frees it on the worker.
  struct PendingCut {
    CutJobInput input;
    CutOutcome outcome;
    sim::NodeVectors contact_force;  // #N x 3 of the next epoch, zero
    std::uint64_t commit_step = 0;
    // The exit step's part of the pass's record (the outcome's is the worker's until then).
    double time_s = 0.0, map_ms = 0.0, sweep_area_mm2 = 0.0;
    std::int64_t exit_step = 0;
    std::chrono::steady_clock::time_point exit_time;
  };
  std::unique_ptr<PendingCut> pending_, spent_;
  std::unique_ptr<CutWorker> worker_;  // started with the first async pass
  std::function<void()> cut_delay_;    // setCutDelayForTesting
  int stalls_ = 0;
  double stall_ms_ = 0.0;
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
