#include "hysim/engine/simulation.hpp"
#include "hysim/engine/organ_mesh.hpp"

#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include <algorithm>
#include <assimp/Importer.hpp>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <functional>
#include <limits>

#include "hysim/cutting/cut3d.hpp"
#include "hysim/cutting/input_file.hpp"
#include "hysim/engine/mesh_faces.hpp"
#include "hysim/cutting/mesh_io.hpp"
#include "hysim/cutting/mesh_stats.hpp"
#include "hysim/sim/tissue_update3d.hpp"

namespace hysim::engine {
namespace {

// Closest point to p on segment [a, b].
Eigen::Vector3d closestOnSegment(const Eigen::Vector3d& p, const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  const Eigen::Vector3d ab = b - a;
  const double len2 = ab.squaredNorm();
  const double t = len2 > 0.0 ? std::clamp((p - a).dot(ab) / len2, 0.0, 1.0) : 0.0;
  return a + t * ab;
}

// The coupling's gains: the device's unless the scene sets them, which must stay within the
// device's stiffness and damp at least k T, what limitToDevice asks of every model (twice
// the passivity bound), so the haptic thread renders the coupling the proxy was solved with.
// The scripted, keyboard and mirrored devices share these limits; a hardware device with
// other limits has to derive its own.
Result<haptics::CouplingGains> couplingFor(const Scene& scene) {
  const haptics::DeviceInfo device = haptics::ScriptedDevice::defaultInfo();
  const double period_s = 1.0 / device.rate_hz;
  haptics::CouplingGains gains = haptics::couplingGains(device, period_s);
  const CouplingSettings& c = scene.coupling;
  if (c.stiffness_n_per_mm > 0.0) gains.stiffness_n_per_mm = c.stiffness_n_per_mm;
  if (c.damping_n_s_per_mm > 0.0) gains.damping_n_s_per_mm = c.damping_n_s_per_mm;
  if (gains.stiffness_n_per_mm > device.max_stiffness_n_per_mm) {
    return Error{scene.path + ": coupling.stiffness_n_per_mm " + std::to_string(gains.stiffness_n_per_mm) +
                 " is stiffer than the device renders (" + std::to_string(device.max_stiffness_n_per_mm) + ")"};
  }
  const double needed = gains.stiffness_n_per_mm * period_s;
  if (gains.damping_n_s_per_mm < needed) {  // passive too: k T > k T / 2
    return Error{scene.path + ": coupling.damping_n_s_per_mm " + std::to_string(gains.damping_n_s_per_mm) +
                 " is below k T = " + std::to_string(needed) +
                 " N s/mm (twice the passivity bound k T / 2, which the device needs)"};
  }
  return gains;
}

}  // namespace

Result<render::SurfaceMesh> loadSurface(const std::string& path, render::SurfaceMaterial material) {
  // assimp reads the file itself: refuse devices, FIFOs and huge files before it does.
  if (Status s = checkInputFile(path, kMaxMeshFileBytes, "surface"); !s.ok()) return Error{s.error()};
  Assimp::Importer importer;
  const aiScene* scene = importer.ReadFile(
      path, aiProcess_Triangulate | aiProcess_JoinIdenticalVertices | aiProcess_PreTransformVertices);
  if (scene == nullptr || scene->mNumMeshes == 0) {
    return Error{path + ": cannot load surface: " + std::string(importer.GetErrorString())};
  }
  render::SurfaceMesh out;
  for (unsigned m = 0; m < scene->mNumMeshes; ++m) {
    const aiMesh* mesh = scene->mMeshes[m];
    const auto base = static_cast<std::uint32_t>(out.positions.size() / 3);
    for (unsigned v = 0; v < mesh->mNumVertices; ++v) {
      const aiVector3D& p = mesh->mVertices[v];
      if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) {
        return Error{path + ": non-finite vertex " + std::to_string(v)};
      }
      if (std::max({std::abs(p.x), std::abs(p.y), std::abs(p.z)}) > cutting::kMaxCoordinateMm) {
        return Error{path + ": vertex " + std::to_string(v) + " has a coordinate beyond +-1e30 mm"};
      }
      out.positions.insert(out.positions.end(), {p.x, p.y, p.z});
      out.material.push_back(material);
    }
    for (unsigned f = 0; f < mesh->mNumFaces; ++f) {
      const aiFace& face = mesh->mFaces[f];
      if (face.mNumIndices != 3) continue;  // points and lines
      for (int c = 0; c < 3; ++c) out.triangles.push_back(base + face.mIndices[c]);
    }
  }
  if (out.triangles.empty()) return Error{path + ": surface has no triangles"};
  return out;
}

bool Simulation::mapToRest(const Eigen::Vector3d& p, double displacement, Eigen::Vector3d& rest) const {
  const int t = tissue_->locator.locate(tissue_->mesh, state_.x, p, displacement);
  if (t < 0) {
    // Outside the tissue (in the cavity): the nearest surface node's offset, carried over
    // rigidly. Extrapolating a tet's barycentric coordinates this far out would magnify the
    // offset by the tet's flatness and throw the cut surface's vertex across the organ.
    const int nearest = tissue_->nearest.nearest(p);
    if (nearest < 0) return false;
    rest = tissue_->mesh.X.row(nearest).transpose() + (p - state_.x.row(nearest).transpose());
    return true;
  }
  // Barycentric coordinates of p in tet t at positions state_.x (may lie outside [0, 1]).
  const Eigen::Vector3d a = state_.x.row(tissue_->mesh.T(t, 0)).transpose();
  Eigen::Matrix3d m;
  for (int k = 0; k < 3; ++k) m.col(k) = state_.x.row(tissue_->mesh.T(t, k + 1)).transpose() - a;
  const Eigen::Vector3d w = m.inverse() * (p - a);
  rest = (1.0 - w.sum()) * tissue_->mesh.X.row(tissue_->mesh.T(t, 0)).transpose();
  for (int k = 0; k < 3; ++k) rest += w[k] * tissue_->mesh.X.row(tissue_->mesh.T(t, k + 1)).transpose();
  return true;
}

bool Simulation::mapRow(int row, const Eigen::Vector3d& shift, bool last_rows) {
  // A query looks at the cells within the nodes' largest displacement since the locator's
  // build: past a millimetre, a fresh build (~0.6 ms) costs less than the row's queries
  // over the rest of the pass. For the pass's last rows (last_rows) it does not: they are
  // the locator's last queries before the cut rebuilds it anyway (up to the locator's
  // margin, the displacement it is built for).
  double displacement = tissue_->locator.maxDisplacement(state_.x);
  if (displacement > (last_rows ? tissue_->locator.margin() : 1.0)) {
    tissue_->locator.build(tissue_->mesh, state_.x);
    displacement = 0.0;
  }
  for (int i = 0; i < sweep_.rowSize(); ++i) {
    Eigen::Vector3d rest;
    if (!mapToRest(sweep_.point(row, i) + shift, displacement, rest)) return false;
    rest_rows_.push_back(rest);
  }
  return true;
}

void Simulation::mapSweepRows(bool last_rows) {
  const int rows = sweep_.numRows(), n = sweep_.rowSize();
  if (rows < 2 || map_failed_) return;
  if (rest_rows_.empty()) {  // the row before the start
    const Eigen::Vector3d shift = -1.5 * sweep_.motion(0, 1);
    if (!mapRow(0, shift, last_rows)) {
      map_failed_ = true;
      return;
    }
    kept_middle_ = sweep_.point(0, n / 2) + shift;
  }
  for (; swept_rows_mapped_ < rows; ++swept_rows_mapped_) {
    const Eigen::Vector3d middle = sweep_.point(swept_rows_mapped_, n / 2);
    if ((middle - kept_middle_).norm() < 0.3) continue;
    if (!mapRow(swept_rows_mapped_, Eigen::Vector3d::Zero(), last_rows)) {
      map_failed_ = true;
      return;
    }
    kept_middle_ = middle;
  }
}

Result<std::unique_ptr<Simulation>> Simulation::create(const Scene& scene) {
  std::unique_ptr<Simulation> s(new Simulation());
  s->scene_ = scene;
  if (s->scene_.mesh_path.empty() && scene.organ.given) {
    auto meshed = organMeshFile(scene.organ);
    if (!meshed.ok()) return Error{scene.path + ": " + meshed.error()};
    s->scene_.mesh_path = meshed->path;
  }
  auto mesh = cutting::readTetMesh(s->scene_.mesh_path);
  if (!mesh.ok()) return Error{mesh.error()};
  if (auto valid = cutting::validate(*mesh); !valid.ok()) {
    return Error{s->scene_.mesh_path + ": invalid mesh: " + valid.error()};
  }

  auto coupling = couplingFor(scene);
  if (!coupling.ok()) return Error{coupling.error()};
  s->coupling_ = haptics::VirtualCoupling(coupling.value(), scene.sim.dt);
  s->setDevice(std::make_unique<haptics::ScriptedDevice>(haptics::Trajectory(scene.tool_path)));
  s->loop_.loop_radius_mm = scene.contact.loop_radius_mm;
  s->loop_.reach_mm = scene.contact.loop_reach_mm;
  s->loop_.drop_mm = scene.contact.loop_drop_mm;
  loopPoints(s->loop_, s->pose_, s->wire_);  // sizes the wire buffers once
  s->previous_wire_ = s->wire_;
  s->swept_wire_.reset(static_cast<int>(s->wire_.rows()));
  s->sweep_.reserve(10000, static_cast<int>(s->wire_.rows()));  // a 10 s pass without allocating
  s->rest_rows_.reserve(2000 * static_cast<size_t>(s->wire_.rows()));  // its kept rows, 0.3 mm apart
  if (scene.chips.mode == ChipSettings::Mode::Simulate) {
    ChipToolGeometry tool;
    tool.shaft_radius_mm = scene.contact.shaft_radius_mm;
    tool.shaft_length_mm = scene.contact.shaft_length_mm;
    tool.loop = s->loop_;
    s->chips_ = std::make_unique<ChipWorld>(scene.chips, scene.sim.gravity, scene.sim.dt, tool);
    s->chips_->moveTool(s->pose_);
  }
  auto tissue = makeTissue(std::move(mesh.value()), scene);
  if (!tissue.ok()) return Error{scene.path + ": " + tissue.error()};
  s->tissue_ = std::move(tissue.value());
  const Tissue& t0 = *s->tissue_;
  s->state_ = sim::makeState(t0.model, t0.mesh);
  s->contact_force_ = sim::NodeVectors::Zero(t0.mesh.numNodes(), 3);
  if (s->chips_) s->chips_->setCavity(s->state_.x, t0.surface_faces);
  // The serosa of the initial mesh; exact distances are needed up to margin + wire radius.
  s->outer_wall_.build(t0.mesh, t0.model.fixed, scene.safety.perforation_margin_mm + s->loop_.wire_radius_mm);
  s->perforation_events_.reserve(kMaxPerforationEvents);
  s->passes_.reserve(4096);
  s->serosa_clearance_mm_ = std::numeric_limits<double>::infinity();
  for (const sim::Material& m : scene.materials) {
    if (m.name != "myoma") continue;
    for (int t = 0; t < t0.mesh.numTets(); ++t) {
      if (t0.mesh.material[t] == m.label) s->initial_myoma_mm3_ += cutting::tetVolume(t0.mesh, t);
    }
  }

  if (!scene.tool_mesh_path.empty()) {
    auto tool = loadSurface(scene.tool_mesh_path, render::SurfaceMaterial::Tool);
    if (!tool.ok()) return Error{tool.error()};
    s->tool_surface_ = std::move(tool.value());
  }
  return s;
}

void Simulation::setDevice(std::unique_ptr<haptics::Device> device) {
  device_ = std::move(device);
  device_state_ = device_->read(state_.time);
  if (recorder_ != nullptr) recorder_->append(device_state_, true);
  pose_ = device_state_.pose;
  coupling_.reset(pose_.tip, device_state_.velocity_mm_s);
  // The loop starts where the new device holds it: no sweep from the old tool's place.
  if (wire_.rows() > 0) {
    loopPoints(loop_, pose_, wire_);
    previous_wire_ = wire_;
  }
  // The last step's reaction was at the old tool; the new one starts free of it.
  tool_force_n_.setZero();
  tool_stiffness_.setZero();
  hand_force_n_.setZero();
}

Status Simulation::recordInputTo(haptics::RecordingWriter* writer) {
  if (writer != nullptr && state_.steps != 0) {
    return Error{"a recording starts before the first step (this simulation has taken " +
                 std::to_string(state_.steps) + ")"};
  }
  recorder_ = writer;
  if (recorder_ != nullptr) recorder_->append(device_state_, true);
  return Status::Ok();
}

void Simulation::followDevice() {
  device_state_ = device_->read(state_.time + scene_.sim.dt);
  if (recorder_ != nullptr) recorder_->append(device_state_, false);
  pose_ = device_state_.pose;
  if (scene_.coupling.mode != CouplingSettings::Mode::Spring) return;
  if (!tool_force_n_.allFinite() || !tool_stiffness_.allFinite()) {
    // A diverged tissue (counted as a warning) must not leave the tool at NaN for good.
    coupling_.reset(device_state_.pose.tip, device_state_.velocity_mm_s);
    return;
  }
  // The tissue's reaction of the last step, at the proxy where it was then.
  coupling_.step(device_state_.pose.tip, device_state_.velocity_mm_s, tool_force_n_, tool_stiffness_);
  pose_.tip = coupling_.proxyTip();
}

haptics::LocalForceModel Simulation::hapticModel() const {
  const auto step = static_cast<std::int64_t>(state_.steps);
  if (scene_.coupling.mode == CouplingSettings::Mode::Spring) {
    return coupling_.forceModel(step, device_state_.pose.tip, device_state_.velocity_mm_s);
  }
  haptics::LocalForceModel m;
  m.step = step;
  m.f0_n = tool_force_n_;
  m.stiffness_n_per_mm = tool_stiffness_;
  m.x_ref_mm = pose_.tip;
  return m;
}

void Simulation::computeContact() {
  // The tool's pose is fixed for the step; the forces are computed per substep (below).
  const ContactSettings& c = scene_.contact;
  const Eigen::Vector3d axis = pose_.rotation.col(2);
  const Eigen::Vector3d up = pose_.rotation.col(1);
  contact_shaft_a_ = pose_.tip - c.shaft_length_mm * axis;
  contact_shaft_b_ = pose_.tip;
  contact_loop_ = pose_.tip + (c.loop_reach_mm + pose_.extension_mm) * axis - c.loop_drop_mm * up;
  tool_force_n_.setZero();
  tool_stiffness_.setZero();
  contact_calls_ = 0;
  for (int node : tissue_->contact_nodes) contact_force_.row(node).setZero();
}

void Simulation::contactForces(void* self, const sim::NodeVectors& x, const sim::NodeVectors& v) {
  static_cast<Simulation*>(self)->contactForces(x, v);
}

void Simulation::contactForces(const sim::NodeVectors& x, const sim::NodeVectors& v) {
  // Called by the integrator before each substep, with that substep's positions: the penalty
  // is then as explicit as the springs, at the substep's dt, which the springs' stability
  // already bounds (a force held over the whole step made light canal nodes bounce 2 mm in
  // and out of the sheath every step), except for very light nodes (small elements left by
  // cuts): their penalty is capped at 0.5 m / h^2 for the substep h, which keeps them stable.
  // The reaction on the tool is the substeps' mean.
  const ContactSettings& c = scene_.contact;
  for (int node : tissue_->contact_nodes) contact_force_.row(node).setZero();
  if (!c.enabled) return;
  const double k = c.stiffness_n_per_mm * 1e6;   // N/mm -> uN/mm
  const double d = c.damping_n_s_per_mm * 1e6;   // N s/mm -> uN s/mm
  const double h = tissue_->model.substep;
  // The shaft and the (inactive) loop push tissue: penalty along the separation direction.
  auto push = [&](int node, const Eigen::Vector3d& closest, double radius) {
    const Eigen::Vector3d p = x.row(node).transpose();
    Eigen::Vector3d n = p - closest;
    const double dist = n.norm();
    if (dist >= radius || dist <= 1e-12) return;
    n /= dist;
    const double vn = v.row(node).dot(n);
    const double m = tissue_->model.mass[node];
    const double kn = std::min(k, 0.5 * m / (h * h)), dn = std::min(d, m / h);
    const double mag = std::max(0.0, kn * (radius - dist) - dn * vn);
    contact_force_.row(node) += mag * n.transpose();
    tool_force_n_ -= 1e-6 * mag * n;
    if (mag > 0.0) tool_stiffness_ -= (1e-6 * kn) * (n * n.transpose());  // uN/mm -> N/mm
  };
  for (int node : tissue_->contact_nodes) {
    const Eigen::Vector3d p = x.row(node).transpose();
    push(node, closestOnSegment(p, contact_shaft_a_, contact_shaft_b_), c.shaft_radius_mm);
    if (!pose_.pedal) push(node, contact_loop_, c.loop_radius_mm);  // an active electrode cuts instead
  }
  ++contact_calls_;
}

bool Simulation::loopTouchesTissue() {
  // Refitted when the electrode becomes active (or after a topology change), then followed:
  // only vertices that moved further than the margin get their boxes refitted.
  if (!collision_active_) {
    tissue_->collision.refit(state_.x);
    collision_active_ = true;
  } else {
    tissue_->collision.update(state_.x);
  }
  swept_wire_.update(previous_wire_, wire_);
  if (tissue_->collision.touches(swept_wire_, loop_.wire_radius_mm)) {
    buried_known_ = false;
    return true;
  }
  // The sweep meets no boundary face: the wire (connected, part of the sweep) is wholly
  // inside or wholly outside the tissue, and one of its points tells which. It stays on that
  // side until the next contact, so the test runs once per contact-free stretch.
  if (!buried_known_) {
    double moved = tissue_->locator.maxDisplacement(state_.x);
    if (moved > tissue_->locator.margin()) {
      tissue_->locator.build(tissue_->mesh, state_.x);
      moved = 0.0;
    }
    buried_ = tissue_->locator.locate(tissue_->mesh, state_.x, wire_.row(wire_.rows() / 2).transpose(), moved) >= 0;
    buried_known_ = true;
  }
  return buried_;
}

void Simulation::step() {
  if (pending_ && state_.steps >= pending_->commit_step) commitCut();
  // The pose for the end of this step drives the contact of this step.
  const Eigen::Vector3d previous_tip = pose_.tip;
  followDevice();
  path_length_mm_ += (pose_.tip - previous_tip).norm();
  if (pose_.pedal) electrode_active_s_ += scene_.sim.dt;
  computeContact();
  sim::StepInput input;
  input.external_force = &contact_force_;
  input.refresh_external = &Simulation::contactForces;
  input.context = this;
  sim::step(tissue_->model, state_, input);
  if (contact_calls_ > 1) {
    tool_force_n_ /= static_cast<double>(contact_calls_);
    tool_stiffness_ /= static_cast<double>(contact_calls_);
  }
  hand_force_n_ = scene_.coupling.mode == CouplingSettings::Mode::Spring
                      ? coupling_.handForce(device_state_.pose.tip, device_state_.velocity_mm_s)
                      : tool_force_n_;
  device_->commandForce(hand_force_n_);  // clamped and NaN-guarded by the device
  if (chips_) {
    chips_->moveTool(pose_);
    if (chips_->numChips() > 0) {
      const auto t0 = std::chrono::steady_clock::now();  // measurement only
      chips_->step();
      chip_step_s_ += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      ++chip_steps_;
    }
  }
  advanceShaving();
}

void Simulation::advanceShaving() {
  // Entry is the first contact of the active loop with the tissue (its sweep over this step
  // touches the surface, or it is buried); the sweep grows while it touches; on exit (no
  // contact any more, or pedal release) the sweep goes to the cut. Collision runs only while
  // the electrode is active or a pass is open.
  previous_wire_ = wire_;
  loopPoints(loop_, pose_, wire_);
  if (pose_.pedal) {
    checkPerforation();
  } else {
    perforating_ = false;  // an inactive loop cannot perforate: the event ends
  }
  if (!pose_.pedal && !cutting_) {
    loop_in_tissue_ = false;
    collision_active_ = false;
    buried_known_ = false;
    return;
  }
  loop_in_tissue_ = pose_.pedal && loopTouchesTissue();
  if (loop_in_tissue_ && !cutting_) {
    cutting_ = true;
    sweep_.clear();
    rest_rows_.clear();
    swept_rows_mapped_ = 0;
    map_failed_ = false;
    if (previous_wire_.rows() == wire_.rows()) sweep_.advance(previous_wire_);
    sweep_.advance(wire_);
    mapSweepRows();
  } else if (loop_in_tissue_) {
    sweep_.advance(wire_);
    mapSweepRows();
  } else if (cutting_) {
    sweep_.advance(wire_);
    finishPass();
  }
}

void Simulation::checkPerforation() {
  outer_wall_.update(state_.x);  // a serosa with free nodes moves with the tissue
  double clearance = std::numeric_limits<double>::infinity();
  for (Eigen::Index i = 0; i < wire_.rows(); ++i) {
    clearance = std::min(clearance, outer_wall_.clearance(wire_.row(i).transpose()) - loop_.wire_radius_mm);
  }
  serosa_clearance_mm_ = clearance;
  if (!(clearance < scene_.safety.perforation_margin_mm)) {
    perforating_ = false;
    return;
  }
  if (!perforating_) {
    perforating_ = true;
    ++perforation_count_;
    // Within the reserved capacity only: the step never allocates.
    if (perforation_events_.size() < perforation_events_.capacity()) {
      perforation_events_.push_back({state_.time, state_.time, clearance});
    }
    return;
  }
  if (!perforation_events_.empty() && static_cast<int>(perforation_events_.size()) == perforation_count_) {
    PerforationEvent& e = perforation_events_.back();
    e.end_s = state_.time;
    e.min_distance_mm = std::min(e.min_distance_mm, clearance);
  }
}

void Simulation::failPass(const std::string& why) {
  PassRecord rec;
  rec.time_s = state_.time;
  rec.exit_step = rec.commit_step = static_cast<std::int64_t>(state_.steps);
  rec.cut_failed = true;
  rec.message = why;
  rec.elements = tissue_->mesh.numTets();
  rec.nodes = tissue_->mesh.numNodes();
  passes_.push_back(rec);
}

void Simulation::finishPass() {
  const auto t0 = std::chrono::steady_clock::now();
  cutting_ = false;
  // A pass that ends before the previous one's commit step commits that one first: the next
  // cut must start from the epoch the previous one makes.
  if (pending_) commitCut();
  const int rows = sweep_.numRows(), row_size = sweep_.rowSize();
  if (rows < 2 || row_size < 2) {
    sweep_.clear();
    return failPass("sweep too short");
  }
  const double sweep_area = sweep_.extendedArea(1.5);
  // The cut happens in the rest configuration, so that the mesh the model is built from (and
  // the cut's quality guarantees) are the cut's own, not a deformed copy mapped back. The
  // sweep's rows up to this step were carried to the rest shape as they came (mapSweepRows);
  // the row 1.5 mm past the end follows now.
  mapSweepRows(true);
  if (!map_failed_ && !mapRow(rows - 1, 1.5 * sweep_.motion(rows - 2, rows - 1), true)) map_failed_ = true;
  sweep_.clear();
  if (map_failed_) return failPass("no tissue to map the sweep to");

  std::unique_ptr<PendingCut> job = spent_ ? std::move(spent_) : std::make_unique<PendingCut>();
  CutJobInput& in = job->input;
  in.row_size = row_size;
  in.rows = static_cast<int>(rest_rows_.size()) / row_size;
  in.rest_rows.resize(static_cast<Eigen::Index>(in.rows) * row_size, 3);
  for (Eigen::Index i = 0; i < in.rest_rows.rows(); ++i) in.rest_rows.row(i) = rest_rows_[static_cast<size_t>(i)].transpose();
  in.x = state_.x;
  in.v = state_.v;
  in.dump_prefix.clear();
  if (!cut_dump_dir_.empty()) {  // debugging (setCutDumpDir): the cut's input, to repeat offline
    char name[64];
    std::snprintf(name, sizeof(name), "/pass_%03d_", static_cast<int>(passes_.size()) + 1);
    in.dump_prefix = cut_dump_dir_ + name;
  }
  job->commit_step = state_.steps + static_cast<std::uint64_t>(scene_.cut.commit_steps);
  job->exit_time = t0;
  job->time_s = state_.time;
  job->exit_step = static_cast<std::int64_t>(state_.steps);
  job->sweep_area_mm2 = sweep_area;
  PendingCut* p = job.get();
  const Tissue* base = tissue_.get();
  auto work = [p, base, this] {
    p->outcome = CutOutcome{};  // frees the epoch before last here, not on the simulation thread
    runCutJob(*base, scene_, p->input, p->outcome);
    if (p->outcome.tissue) p->contact_force = sim::NodeVectors::Zero(p->outcome.tissue->mesh.numNodes(), 3);
  };
  job->map_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  pending_ = std::move(job);
  if (scene_.cut.mode == CutSettings::Mode::Sync) {
    work();
  } else {
    if (!worker_) {
      worker_ = std::make_unique<CutWorker>();
      if (cut_delay_) worker_->setDelayForTesting(cut_delay_);
    }
    worker_->start(work);
  }
}

void Simulation::commitCut() {
  const auto t0 = std::chrono::steady_clock::now();
  double stall_ms = 0.0;
  if (worker_ && !worker_->done()) {  // a stall: the state sequence waits, it does not change
    worker_->wait();
    stall_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    ++stalls_;
    stall_ms_ += stall_ms;
  }
  const auto t1 = std::chrono::steady_clock::now();
  PendingCut& p = *pending_;
  CutOutcome& out = p.outcome;
  PassRecord& rec = out.record;
  rec.time_s = p.time_s;
  rec.exit_step = p.exit_step;
  rec.commit_step = static_cast<std::int64_t>(state_.steps);
  rec.map_ms = p.map_ms;
  rec.sweep_area_mm2 = p.sweep_area_mm2;
  rec.stall_ms = stall_ms;
  rec.stalled = stall_ms > 0.0;
  if (out.status.ok()) {
    // Chips start where their pieces are now (simulated chips only; this allocates).
    std::vector<ChipShape> chips;
    if (chips_ && out.record.chips > 0) chips = chipsAt(out.chips, scene_, state_.x, state_.v);
    // The state of this step carried into the next epoch's numbering, in buffers sized there.
    out.remap.apply(state_.x, state_.v, out.state.x, out.state.v);
    out.state.steps = state_.steps;
    out.state.time = state_.time;
    out.state.warnings = state_.warnings;
    out.state.diverged = false;
    std::swap(state_, out.state);
    std::swap(tissue_, out.tissue);  // the outcome now owns the epoch before: freed on the worker
    std::swap(contact_force_, p.contact_force);
    outer_wall_.remapNodes(out.old_to_kept);
    collision_active_ = false;  // refitted to this step's positions before its next use
    buried_known_ = false;
    ++topology_version_;
    if (chips_) {
      chips_->setCavity(state_.x, tissue_->surface_faces);
      for (const ChipShape& chip : chips) chips_->addChip(chip);
    }
  }
  const auto t2 = std::chrono::steady_clock::now();
  rec.commit_us = std::chrono::duration<double, std::micro>(t2 - t1).count();
  rec.latency_ms = std::chrono::duration<double, std::milli>(t2 - p.exit_time).count();
  passes_.push_back(rec);  // within the capacity reserved at create()
  spent_ = std::move(pending_);
}

void Simulation::commitPendingCut() {
  if (pending_) commitCut();
}

void Simulation::setCutDelayForTesting(std::function<void()> delay) {
  cut_delay_ = delay;
  if (worker_) worker_->setDelayForTesting(std::move(delay));
}

Simulation::~Simulation() {
  if (worker_) worker_->wait();  // the job reads tissue_ and scene_
}


void Simulation::fillSnapshot(render::RenderSnapshot& snap) const {
  const size_t nv = tissue_->surface_nodes.size();
  snap.tissue.positions.resize(nv * 3);
  for (size_t i = 0; i < nv; ++i) {
    for (int c = 0; c < 3; ++c) snap.tissue.positions[3 * i + c] = static_cast<float>(state_.x(tissue_->surface_nodes[i], c));
  }
  if (snap.topology_version != topology_version_) {
    snap.tissue.triangles = tissue_->surface_triangles;
    snap.tissue.material = tissue_->surface_material;
    snap.topology_version = topology_version_;
  }
  if (snap.tool.positions.size() != tool_surface_.positions.size()) snap.tool = tool_surface_;
  snap.tool_visible = !tool_surface_.triangles.empty();
  // The sheath stays at the scope tip; the electrode (everything ahead of the tip in the
  // body frame) slides out along the axis by the extension.
  const float extension = static_cast<float>(pose_.extension_mm);
  for (size_t v = 0; v < tool_surface_.positions.size() / 3; ++v) {
    const float z = tool_surface_.positions[3 * v + 2];
    snap.tool.positions[3 * v + 2] = z > 0.0f ? z + extension : z;
  }
  for (int r = 0; r < 3; ++r) {
    snap.tool_pose.position[r] = static_cast<float>(pose_.tip[r]);
    for (int c = 0; c < 3; ++c) snap.tool_pose.rotation[3 * c + r] = static_cast<float>(pose_.rotation(r, c));
  }
  for (int r = 0; r < 3; ++r) {
    snap.camera.tip[r] = static_cast<float>(pose_.tip[r]);
    snap.camera.axis[r] = static_cast<float>(pose_.rotation(r, 2));
    snap.camera.up[r] = static_cast<float>(pose_.rotation(r, 1));
  }
  snap.camera.lens_deg = static_cast<float>(scene_.camera.lens_deg);
  snap.camera.fov_deg = static_cast<float>(scene_.camera.fov_deg);
  snap.camera.light_intensity = static_cast<float>(scene_.camera.light);
  if (chips_) {
    const std::vector<ChipBody>& chips = chips_->chips();
    if (snap.chips_version != chips_->version() || snap.chips.size() != chips.size()) {
      snap.chips.resize(chips.size());
      for (size_t i = 0; i < chips.size(); ++i) snap.chips[i].surface = chips[i].surface;
      snap.chips_version = chips_->version();
    }
    for (size_t i = 0; i < chips.size(); ++i) {
      render::Pose& pose = snap.chips[i].pose;
      for (int r = 0; r < 3; ++r) {
        pose.position[r] = static_cast<float>(chips[i].position[r]);
        for (int c = 0; c < 3; ++c) pose.rotation[3 * c + r] = static_cast<float>(chips[i].rotation(r, c));
      }
    }
  } else if (!snap.chips.empty()) {
    snap.chips.clear();
  }
  snap.step = state_.steps;
  snap.time_s = state_.time;
}

}  // namespace hysim::engine
