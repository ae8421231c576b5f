#include "hysim/engine/simulation.hpp"

#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include <algorithm>
#include <assimp/Importer.hpp>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <functional>
#include <limits>
#include <thread>

#include "hysim/cutting/cut3d.hpp"
#include "hysim/engine/mesh_faces.hpp"
#include "hysim/engine/pass_worker.hpp"
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

// The free pieces of a cut mesh as chips: surface (current positions), material for
// drawing, volume, mass, centre of mass and mean velocity. `after` holds the current
// positions; v (#N x 3) the velocities; on_cut (#N) marks nodes on a cut surface.
std::vector<ChipShape> chipShapes(const cutting::TetMesh& after, const sim::NodeVectors& v,
                                  const Pieces& comps, const std::vector<std::uint8_t>& on_cut,
                                  const std::vector<sim::Material>& materials, int myoma_label) {
  std::vector<std::vector<int>> tets(static_cast<size_t>(comps.count));
  for (int t = 0; t < after.numTets(); ++t) {
    if (comps.free[comps.label[t]]) tets[comps.label[t]].push_back(t);
  }
  std::vector<ChipShape> out;
  std::vector<int> local(static_cast<size_t>(after.numNodes()), -1);
  for (int c = 0; c < comps.count; ++c) {
    if (tets[c].empty()) continue;
    // The piece as its own tet mesh (compact node numbering).
    std::vector<int> nodes;
    cutting::TetMesh piece;
    piece.T.resize(static_cast<Eigen::Index>(tets[c].size()), 4);
    piece.material.resize(static_cast<Eigen::Index>(tets[c].size()));
    ChipShape chip;
    for (size_t k = 0; k < tets[c].size(); ++k) {
      const int t = tets[c][k];
      for (int j = 0; j < 4; ++j) {
        const int node = after.T(t, j);
        if (local[node] < 0) {
          local[node] = static_cast<int>(nodes.size());
          nodes.push_back(node);
        }
        piece.T(static_cast<Eigen::Index>(k), j) = local[node];
      }
      piece.material[static_cast<Eigen::Index>(k)] = after.material[t];
      double density = 1.05e-3;
      for (const sim::Material& m : materials) {
        if (m.label == after.material[t]) density = m.density_g_mm3;
      }
      const double vol = std::abs(cutting::tetVolume(after, t));
      Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
      for (int j = 0; j < 4; ++j) centroid += 0.25 * after.X.row(after.T(t, j)).transpose();
      chip.volume_mm3 += vol;
      chip.mass_g += density * vol;
      chip.centre += density * vol * centroid;
    }
    if (chip.mass_g > 0.0) chip.centre /= chip.mass_g;
    piece.X.resize(static_cast<Eigen::Index>(nodes.size()), 3);
    for (size_t i = 0; i < nodes.size(); ++i) {
      piece.X.row(static_cast<Eigen::Index>(i)) = after.X.row(nodes[i]);
      chip.velocity += v.row(nodes[i]).transpose() / static_cast<double>(nodes.size());
    }
    // Its boundary, with the surface vertices numbered compactly.
    Eigen::VectorXi face_tet;
    const cutting::Tris faces = cutting::boundaryFaces(piece, &face_tet);
    std::vector<int> vertex(nodes.size(), -1);
    std::vector<int> surface;  // piece node of each surface vertex
    chip.triangles.resize(faces.rows(), 3);
    for (Eigen::Index f = 0; f < faces.rows(); ++f) {
      for (int j = 0; j < 3; ++j) {
        const int p = faces(f, j);
        if (vertex[p] < 0) {
          vertex[p] = static_cast<int>(surface.size());
          surface.push_back(p);
          chip.material.push_back(render::SurfaceMaterial::Myoma);
        }
        chip.triangles(f, j) = vertex[p];
        if (piece.material[face_tet[f]] != myoma_label) chip.material[vertex[p]] = render::SurfaceMaterial::Endometrium;
      }
    }
    chip.vertices.resize(static_cast<Eigen::Index>(surface.size()), 3);
    for (size_t i = 0; i < surface.size(); ++i) {
      const int node = nodes[surface[i]];
      chip.vertices.row(static_cast<Eigen::Index>(i)) = piece.X.row(surface[i]);
      if (node < static_cast<int>(on_cut.size()) && on_cut[node]) chip.material[i] = render::SurfaceMaterial::Cut;
    }
    for (int node : nodes) local[node] = -1;
    out.push_back(std::move(chip));
  }
  return out;
}

// Wall time of the parts of a pass (measurement only: nothing simulated depends on it).
// lap(&field) adds the time since the previous lap to field.
class PassTimer {
 public:
  void lap(double* into) {
    const auto now = std::chrono::steady_clock::now();
    if (into != nullptr) *into += std::chrono::duration<double, std::milli>(now - last_).count();
    last_ = now;
  }

 private:
  std::chrono::steady_clock::time_point last_ = std::chrono::steady_clock::now();
};

}  // namespace

Result<render::SurfaceMesh> loadSurface(const std::string& path, render::SurfaceMaterial material) {
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

Status Simulation::setTopology(cutting::TetMesh rest_mesh, const sim::NodeVectors* x, const sim::NodeVectors* v,
                               PassRecord* timing) {
  PassTimer timer;
  mesh_ = std::move(rest_mesh);
  std::vector<int> fixed;
  anchored_.assign(static_cast<size_t>(mesh_.numNodes()), 0);
  for (int i = 0; i < mesh_.numNodes(); ++i) {
    if (isAnchored(mesh_.X.row(i).transpose())) {
      anchored_[i] = 1;
      fixed.push_back(i);
    }
  }
  auto model = sim::buildModel(mesh_, scene_.materials, fixed, scene_.sim);
  if (!model.ok()) return Error{model.error()};
  model_ = std::move(model.value());
  resetState(x, v);
  if (!matchFaces(mesh_, face_next_)) face_next_.clear();
  anchorPieces(false);
  timer.lap(timing ? &timing->model_ms : nullptr);
  tet_quality_.resize(static_cast<size_t>(mesh_.numTets()));
  for (int t = 0; t < mesh_.numTets(); ++t) tet_quality_[t] = tetQuality(mesh_, t);
  return rebuildGeometry(timing);
}

int Simulation::anchorPieces(bool count) {
  anchor_distance_.clear();
  pieces_anchored_ = false;
  if (face_next_.size() != 4 * static_cast<size_t>(mesh_.numTets()) ||
      anchored_.size() != static_cast<size_t>(mesh_.numNodes())) {
    return -1;
  }
  anchor_distance_ = anchorDistance(mesh_, face_next_, anchored_);
  pieces_anchored_ = std::find(anchor_distance_.begin(), anchor_distance_.end(), std::numeric_limits<int>::max()) ==
                     anchor_distance_.end();
  return count ? tetPieces(mesh_, face_next_, anchored_).count : 0;
}

double Simulation::tetQuality(const cutting::TetMesh& mesh, int t) {
  return cutting::radiusRatio(mesh.X.row(mesh.T(t, 0)).transpose(), mesh.X.row(mesh.T(t, 1)).transpose(),
                              mesh.X.row(mesh.T(t, 2)).transpose(), mesh.X.row(mesh.T(t, 3)).transpose());
}

bool Simulation::isAnchored(const Eigen::Vector3d& rest) const {
  for (const AnchorRegion& a : scene_.anchors) {
    if (a.contains(rest)) return true;
  }
  return false;
}

void Simulation::resetState(const sim::NodeVectors* x, const sim::NodeVectors* v) {
  // sim::makeState(model_, mesh_) with x and v given, keeping warnings, steps and time;
  // each array written once (not zeroed or copied first and then overwritten).
  const int n = model_.num_nodes;
  if (x != nullptr) {
    state_.x = *x;
  } else {
    state_.x = mesh_.X;
  }
  if (v != nullptr) {
    state_.v = *v;
  } else {
    state_.v.setZero(n, 3);
  }
  // The per-step arrays only sized, not zeroed (~0.8 MB of stores per pass saved).
  sim::sizeStepArrays(model_, state_);
  state_.diverged = false;
  num_anchored_ = 0;
  for (std::uint8_t a : anchored_) num_anchored_ += a;
  num_deformable_tets_ = 0;
  for (int t = 0; t < mesh_.numTets(); ++t) {
    bool moves = false;
    for (int c = 0; c < 4; ++c) moves = moves || !model_.fixed[mesh_.T(t, c)];
    num_deformable_tets_ += moves ? 1 : 0;
  }
}

Status Simulation::rebuildGeometry(PassRecord* timing, const std::vector<std::uint8_t>* boundary) {
  waitLocator();
  if (Status st = buildGeometry(mesh_, state_.x, timing, boundary); !st.ok()) return st;
  PassTimer timer;
  locator_.build(mesh_, state_.x);
  buildNearest(mesh_, state_.x);
  timer.lap(timing ? &timing->locator_ms : nullptr);
  finishGeometry(timing);
  return Status::Ok();
}

Status Simulation::buildGeometry(const cutting::TetMesh& mesh, const sim::NodeVectors& x, PassRecord* timing,
                                 const std::vector<std::uint8_t>* boundary, const std::vector<int>* renumber) {
  PassTimer timer;

  // Surface for contact and rendering: boundary faces, compacted vertex numbering.
  Eigen::VectorXi face_tet;
  if (boundary != nullptr && boundary->size() == 4 * static_cast<size_t>(mesh.numTets())) {
    boundaryFromSlots(mesh, *boundary, surface_faces_, face_tet);
  } else {
    surface_faces_ = cutting::boundaryFaces(mesh, &face_tet);
  }
  surface_nodes_.clear();
  surface_triangles_.clear();
  surface_material_.clear();
  std::vector<int> local(mesh.numNodes(), -1);
  // A surface vertex is drawn as myoma when all its boundary faces belong to myoma tets:
  // the rim where the myoma meets the wall keeps the endometrium colour, so the colour
  // blend happens on the myoma's side (its base is covered by endometrium in reality).
  int myoma_label = -1;
  for (const sim::Material& m : scene_.materials) {
    if (m.name == "myoma") myoma_label = m.label;
  }
  for (int f = 0; f < surface_faces_.rows(); ++f) {
    for (int c = 0; c < 3; ++c) {
      const int node = surface_faces_(f, c);
      if (local[node] < 0) {
        local[node] = static_cast<int>(surface_nodes_.size());
        surface_nodes_.push_back(node);
        surface_material_.push_back(render::SurfaceMaterial::Myoma);
      }
      surface_triangles_.push_back(static_cast<std::uint32_t>(local[node]));
      if (mesh.material[face_tet[f]] != myoma_label) {
        surface_material_[local[node]] = render::SurfaceMaterial::Endometrium;
      }
    }
  }
  if (on_cut_.size() == static_cast<size_t>(mesh.numNodes())) {
    for (size_t v = 0; v < surface_nodes_.size(); ++v) {
      if (on_cut_[surface_nodes_[v]]) surface_material_[v] = render::SurfaceMaterial::Cut;
    }
  }
  timer.lap(timing ? &timing->surface_ms : nullptr);
  // The boundary's hierarchy, with boxes grown by half a millimetre: while the tissue near
  // the loop moves less than that, a step only moves the vertices (see collision.hpp).
  if (Status st = collision_.build(surface_faces_, x, 0.5, &mesh.X, renumber); !st.ok()) return st;
  timer.lap(timing ? &timing->collision_ms : nullptr);
  return Status::Ok();
}

void Simulation::waitLocator() const {
  if (locator_thread_.joinable()) locator_thread_.join();
}

Simulation::~Simulation() { waitLocator(); }

void Simulation::buildNearest(const cutting::TetMesh& mesh, const sim::NodeVectors& x) {
  nearest_x_ = x;
  nearest_surface_.build(nearest_x_, surface_nodes_);
  node_tet_.assign(static_cast<size_t>(mesh.numNodes()), -1);
  for (int t = 0; t < mesh.numTets(); ++t)
    for (int k = 0; k < 4; ++k) node_tet_[mesh.T(t, k)] = t;
}

bool Simulation::mapToRest(const Eigen::Vector3d& p, double displacement, Eigen::Vector3d& rest) const {
  int t = locator_.locate(mesh_, state_.x, p, displacement);
  if (t < 0) {
    const int nearest = nearest_surface_.nearest(p);
    if (nearest < 0) return false;
    t = node_tet_[nearest];
    if (t < 0) return false;
  }
  // Barycentric coordinates of p in tet t at positions state_.x (may lie outside [0, 1]).
  const Eigen::Vector3d a = state_.x.row(mesh_.T(t, 0)).transpose();
  Eigen::Matrix3d m;
  for (int k = 0; k < 3; ++k) m.col(k) = state_.x.row(mesh_.T(t, k + 1)).transpose() - a;
  const Eigen::Vector3d w = m.inverse() * (p - a);
  rest = (1.0 - w.sum()) * mesh_.X.row(mesh_.T(t, 0)).transpose();
  for (int k = 0; k < 3; ++k) rest += w[k] * mesh_.X.row(mesh_.T(t, k + 1)).transpose();
  return true;
}

bool Simulation::mapRow(int row, const Eigen::Vector3d& shift, bool last_rows) {
  // A query looks at the cells within the nodes' largest displacement since the locator's
  // build: past a millimetre, a fresh build (~0.6 ms) costs less than the row's queries
  // over the rest of the pass. For the pass's last rows (last_rows) it does not: they are
  // the locator's last queries before the cut rebuilds it anyway (up to the locator's
  // margin, the displacement it is built for).
  double displacement = locator_.maxDisplacement(state_.x);
  if (displacement > (last_rows ? locator_.margin() : 1.0)) {
    locator_.build(mesh_, state_.x);
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
  waitLocator();  // the last pass's locator and nearest-node lookups (long done, in practice)
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

void Simulation::finishGeometry(PassRecord* timing) {
  PassTimer timer;
  if (on_cut_.size() != static_cast<size_t>(mesh_.numNodes())) on_cut_.assign(mesh_.numNodes(), 0);
  contact_nodes_.clear();
  for (int node : surface_nodes_) {
    if (!model_.fixed[node]) contact_nodes_.push_back(node);
  }
  contact_force_ = sim::NodeVectors::Zero(mesh_.numNodes(), 3);
  collision_active_ = true;  // just fitted
  buried_known_ = false;
  timer.lap(timing ? &timing->surface_ms : nullptr);
  if (chips_) chips_->setCavity(state_.x, surface_faces_);
  timer.lap(timing ? &timing->chips_ms : nullptr);
  ++topology_version_;
}

Result<std::unique_ptr<Simulation>> Simulation::create(const Scene& scene) {
  std::unique_ptr<Simulation> s(new Simulation());
  s->scene_ = scene;
  auto mesh = cutting::readTetMesh(scene.mesh_path);
  if (!mesh.ok()) return Error{mesh.error()};
  s->mesh_ = std::move(mesh.value());
  if (auto valid = cutting::validate(s->mesh_); !valid.ok()) {
    return Error{scene.mesh_path + ": invalid mesh: " + valid.error()};
  }

  s->device_ = std::make_unique<haptics::ScriptedDevice>(haptics::Trajectory(scene.tool_path));
  s->pose_ = s->device_->read(0.0).pose;
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
  if (Status st = s->setTopology(s->mesh_, nullptr, nullptr); !st.ok()) return Error{scene.path + ": " + st.error()};
  // The serosa of the initial mesh; exact distances are needed up to margin + wire radius.
  s->outer_wall_.build(s->mesh_, s->model_.fixed, scene.safety.perforation_margin_mm + s->loop_.wire_radius_mm);
  s->perforation_events_.reserve(kMaxPerforationEvents);
  s->serosa_clearance_mm_ = std::numeric_limits<double>::infinity();
  for (const sim::Material& m : scene.materials) {
    if (m.name != "myoma") continue;
    for (int t = 0; t < s->mesh_.numTets(); ++t) {
      if (s->mesh_.material[t] == m.label) s->initial_myoma_mm3_ += cutting::tetVolume(s->mesh_, t);
    }
  }

  if (!scene.tool_mesh_path.empty()) {
    auto tool = loadSurface(scene.tool_mesh_path, render::SurfaceMaterial::Tool);
    if (!tool.ok()) return Error{tool.error()};
    s->tool_surface_ = std::move(tool.value());
  }
  return s;
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
  contact_calls_ = 0;
  for (int node : contact_nodes_) contact_force_.row(node).setZero();
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
  for (int node : contact_nodes_) contact_force_.row(node).setZero();
  if (!c.enabled) return;
  const double k = c.stiffness_n_per_mm * 1e6;   // N/mm -> uN/mm
  const double d = c.damping_n_s_per_mm * 1e6;   // N s/mm -> uN s/mm
  const double h = model_.substep;
  // The shaft and the (inactive) loop push tissue: penalty along the separation direction.
  auto push = [&](int node, const Eigen::Vector3d& closest, double radius) {
    const Eigen::Vector3d p = x.row(node).transpose();
    Eigen::Vector3d n = p - closest;
    const double dist = n.norm();
    if (dist >= radius || dist <= 1e-12) return;
    n /= dist;
    const double vn = v.row(node).dot(n);
    const double m = model_.mass[node];
    const double kn = std::min(k, 0.5 * m / (h * h)), dn = std::min(d, m / h);
    const double mag = std::max(0.0, kn * (radius - dist) - dn * vn);
    contact_force_.row(node) += mag * n.transpose();
    tool_force_n_ -= 1e-6 * mag * n;
  };
  for (int node : contact_nodes_) {
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
    collision_.refit(state_.x);
    collision_active_ = true;
  } else {
    collision_.update(state_.x);
  }
  swept_wire_.update(previous_wire_, wire_);
  if (collision_.touches(swept_wire_, loop_.wire_radius_mm)) {
    buried_known_ = false;
    return true;
  }
  // The sweep meets no boundary face: the wire (connected, part of the sweep) is wholly
  // inside or wholly outside the tissue, and one of its points tells which. It stays on that
  // side until the next contact, so the test runs once per contact-free stretch.
  if (!buried_known_) {
    waitLocator();  // the last pass's build (allocates nothing; long done by now, in practice)
    double moved = locator_.maxDisplacement(state_.x);
    if (moved > locator_.margin()) {
      locator_.build(mesh_, state_.x);
      moved = 0.0;
    }
    buried_ = locator_.locate(mesh_, state_.x, wire_.row(wire_.rows() / 2).transpose(), moved) >= 0;
    buried_known_ = true;
  }
  return buried_;
}

void Simulation::step() {
  // The pose for the end of this step drives the contact of this step.
  const Eigen::Vector3d previous_tip = pose_.tip;
  pose_ = device_->read(state_.time + scene_.sim.dt).pose;
  path_length_mm_ += (pose_.tip - previous_tip).norm();
  if (pose_.pedal) electrode_active_s_ += scene_.sim.dt;
  computeContact();
  sim::StepInput input;
  input.external_force = &contact_force_;
  input.refresh_external = &Simulation::contactForces;
  input.context = this;
  sim::step(model_, state_, input);
  if (contact_calls_ > 1) tool_force_n_ /= static_cast<double>(contact_calls_);
  device_->commandForce(tool_force_n_);  // clamped and NaN-guarded by the device
  if (chips_) {
    chips_->moveTool(pose_);
    if (chips_->numChips() > 0) {
      const auto t0 = std::chrono::steady_clock::now();  // measurement only
      chips_->step();
      chip_step_s_ += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      ++chip_steps_;
    }
  }

  // Shaving: entry is the first contact of the active loop with the tissue (its sweep over
  // this step touches the surface, or it is buried); the sweep grows while it touches; on
  // exit (no contact any more, or pedal release) the sweep is cut. Collision runs only while
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

void Simulation::finishPass() {
  using Clock = std::chrono::steady_clock;
  waitLocator();  // the previous pass's build, before the clock starts (see PassRecord::locator_ms)
  const auto t0 = Clock::now();
  PassTimer timer;
  // The worker runs cut3d's node -> tets lists, the model update's first part, then the
  // geometry (below).
  if (!pass_worker_) pass_worker_ = std::make_unique<PassWorker>();
  PassWorker& worker = *pass_worker_;
  worker.begin();
  struct EndPass {
    PassWorker& worker;
    ~EndPass() { worker.end(); }  // every job posted was waited for on every return path
  } end_pass{worker};
  cutting_ = false;
  PassRecord rec;
  rec.time_s = state_.time;
  auto fail = [&](const std::string& why) {
    rec.cut_failed = true;
    rec.message = why;
    rec.elements = mesh_.numTets();
    rec.nodes = mesh_.numNodes();
    passes_.push_back(rec);
  };
  const int rows = sweep_.numRows(), row_size = sweep_.rowSize();
  if (rows < 2 || row_size < 2) {
    sweep_.clear();
    return fail("sweep too short");
  }
  rec.sweep_area_mm2 = sweep_.extendedArea(1.5);
  // The cut happens in the rest configuration, so that the mesh the model is built from (and
  // the cut's quality guarantees) are the cut's own, not a deformed copy mapped back. The
  // sweep's rows up to this step were carried to the rest shape as they came (mapSweepRows:
  // a row every ~0.3 mm, through the tissue as it was then); the row 1.5 mm past the end
  // follows now.
  mapSweepRows(true);
  if (!map_failed_ && !mapRow(rows - 1, 1.5 * sweep_.motion(rows - 2, rows - 1), true)) map_failed_ = true;
  sweep_.clear();
  if (map_failed_) return fail("no tissue to map the sweep to");
  const int kept = static_cast<int>(rest_rows_.size()) / row_size;
  cutting::Positions rv(static_cast<Eigen::Index>(kept) * row_size, 3);
  for (Eigen::Index i = 0; i < rv.rows(); ++i) rv.row(i) = rest_rows_[static_cast<size_t>(i)].transpose();
  auto surface = cutting::CutSurface::strip(rv, kept, row_size);
  if (!surface.ok()) return fail(surface.error());
  timer.lap(&rec.map_ms);
  if (!cut_dump_dir_.empty()) {  // debugging (setCutDumpDir): the cut's input, to repeat offline
    char name[64];
    std::snprintf(name, sizeof(name), "/pass_%03d_", static_cast<int>(passes_.size()) + 1);
    const cutting::Tris rf = cutting::CutSurface::stripTriangles(kept, row_size);
    const cutting::TriMesh sweep_mesh{rv, rf, cutting::Labels::Zero(rf.rows())};
    Status st = cutting::writeMesh(cut_dump_dir_ + name + "mesh.msh", mesh_);
    if (st.ok()) st = cutting::writeMesh(cut_dump_dir_ + name + "surface.msh", sweep_mesh);
    if (!st.ok()) return fail("--dump-cuts: " + st.error());
  }
  cutting::Cut3DOptions options;
  options.method = cutting::CutMethod::Hybrid;
  // cut3d's work beside (its node -> tets lists, half of each move iteration of the
  // optimisation) goes to the worker too.
  options.beside = worker.lend();
  // chips.optimize false: the pieces the cut cuts off (chips, removed below) are not
  // optimised; cut3d finds them with the anchors used below (the nodes' flags; by position
  // where the cut made, moved or put a node on the cut).
  if (!scene_.chips.optimize) {
    options.anchored_nodes = &anchored_;
    options.anchored_at = [this](const Eigen::Vector3d& rest) { return isAnchored(rest); };
  }
  auto cut = cutting::cut3d(mesh_, *surface, options);
  if (!cut.ok()) return fail(cut.error());
  timer.lap(&rec.cut3d_ms);
  const cutting::TopologyChange& change = cut->change;
  const cutting::TetMesh& after = cut->mesh;
  // The first part of the tissue model's update (masses and springs around the cut) does not
  // depend on which pieces are kept: the pass's worker thread computes it while this one finds
  // them. It reads the model, the old and the cut mesh and the change, which nothing writes
  // before the wait below.
  sim::CutUpdate3DPrepared model_prepared;
  Status model_prepare_status;
  auto prepare_model = [&] {
    model_prepare_status = sim::prepareModelAfterCut3D(model_, mesh_, after, change, {}, &model_prepared);
  };
  const std::int64_t prepare_ticket = worker.post(prepare_model);
  rec.crossed_edges = cut->report.crossed_edges;
  rec.snapped_nodes = cut->report.snapped_nodes;
  rec.split_edges = cut->report.split_edges;
  rec.duplicated_nodes = cut->report.duplicated_nodes;
  rec.unoptimised_chip_elements = cut->report.cut_off_elements;
  rec.cut_faces = cut->report.cut_faces;

  // Current positions and velocities of the new mesh: surviving nodes keep theirs (plus what
  // the cut moved them by in the rest shape); new nodes interpolate their parents.
  const int n = after.numNodes();
  const cutting::Positions& rest = after.X;
  sim::NodeVectors xnew(n, 3), v(n, 3);
  std::vector<char> known(n, 0);
  for (int i = 0; i < static_cast<int>(change.node_old_to_new.size()); ++i) {
    const int j = change.node_old_to_new[i];
    if (j < 0 || known[j]) continue;
    xnew.row(j) = state_.x.row(i) + (after.X.row(j) - mesh_.X.row(i));
    v.row(j) = state_.v.row(i);
    known[j] = 1;
  }
  for (const cutting::NewNode& nn : change.new_nodes) {
    if (nn.id < 0 || nn.id >= n || known[nn.id]) continue;
    Eigen::RowVector3d r = Eigen::RowVector3d::Zero(), x = r, vel = r;
    for (int k = 0; k < nn.num_parents; ++k) {
      r += nn.weights[k] * mesh_.X.row(nn.parents[k]);
      x += nn.weights[k] * state_.x.row(nn.parents[k]);
      vel += nn.weights[k] * state_.v.row(nn.parents[k]);
    }
    xnew.row(nn.id) = x + (after.X.row(nn.id) - r);
    v.row(nn.id) = vel;
    known[nn.id] = 1;
  }
  timer.lap(&rec.remap_ms);

  // Anchors of the new mesh: surviving nodes that did not move keep theirs.
  std::vector<std::uint8_t> anchored_after(static_cast<size_t>(n), 0);
  for (int i = 0; i < static_cast<int>(change.node_old_to_new.size()); ++i) {
    const int j = change.node_old_to_new[i];
    if (j >= 0 && i < static_cast<int>(anchored_.size())) anchored_after[j] = anchored_[i];
  }
  auto reanchor = [&](int j) {
    if (j >= 0 && j < n) anchored_after[j] = isAnchored(rest.row(j).transpose()) ? 1 : 0;
  };
  for (const cutting::NewNode& nn : change.new_nodes) reanchor(nn.id);
  for (int j : change.moved_nodes) reanchor(j);
  for (int j : change.cut_nodes) reanchor(j);
  // Chips: pieces connected to no anchored node are removed (their volume is resected).
  // Face neighbours of the cut mesh: from the previous mesh's, rematching only the faces
  // near the cut (all faces when that cannot be done).
  // When every piece before the cut was anchored and stays so, only the tets near the cut
  // are searched (freePiecesAfterCut): the free pieces are the same, in the same order, and
  // the number of pieces (rec.components) is counted after the pass, beside the locator.
  std::vector<int> face_next;
  Pieces comps;
  FaceChange face_change;
  bool near_cut = false;
  if (updateFaces(mesh_, face_next_, after, change.node_old_to_new, change.element_old_to_new, face_next,
                  &face_change)) {
    near_cut = pieces_anchored_ && anchor_distance_.size() == static_cast<size_t>(mesh_.numTets()) &&
               anchored_.size() == change.node_old_to_new.size();
    for (size_t i = 0; i < change.node_old_to_new.size() && near_cut; ++i) {
      const int j = change.node_old_to_new[i];
      near_cut = !anchored_[i] || (j >= 0 && j < n && anchored_after[j]);
    }
    comps = near_cut ? freePiecesAfterCut(after, face_next, anchored_after, face_change, anchor_distance_)
                     : tetPieces(after, face_next, anchored_after);
  } else if (matchFaces(after, face_next)) {
    comps = tetPieces(after, face_next, anchored_after);
  } else {  // not reached for a valid mesh
    std::vector<int> anchored;
    for (int i = 0; i < n; ++i)
      if (anchored_after[i]) anchored.push_back(i);
    const cutting::Components3D c = cutting::tetComponents(after, anchored);
    comps.count = c.count;
    comps.label.assign(c.label.data(), c.label.data() + c.label.size());
    comps.free.assign(c.free.begin(), c.free.end());
    face_next.clear();
  }
  int myoma_label = -1;
  for (const sim::Material& m : scene_.materials) {
    if (m.name == "myoma") myoma_label = m.label;
  }
  std::vector<int> keep_tets;
  keep_tets.reserve(after.numTets());
  for (int t = 0; t < after.numTets(); ++t) {
    if (!comps.free[comps.label[t]]) {
      keep_tets.push_back(t);
      continue;
    }
    const double vol = std::abs(cutting::tetVolume(after, t));
    rec.removed_mm3 += vol;
    if (after.material[t] == myoma_label) rec.removed_myoma_mm3 += vol;
  }
  for (int c = 0; c < comps.count; ++c) rec.chips += comps.free[c] ? 1 : 0;
  rec.components = comps.count;  // near_cut: replaced after the pass
  // The kept nodes, renumbered in their order (so the model's arrays compact in place).
  std::vector<std::int32_t> new_index(n, -1);
  for (int t : keep_tets)
    for (int k = 0; k < 4; ++k) new_index[after.T(t, k)] = 0;
  int kept_nodes = 0;
  for (int i = 0; i < n; ++i)
    if (new_index[i] == 0) new_index[i] = kept_nodes++;
  // Nodes on a cut surface, this pass's and earlier ones', in the new numbering.
  std::vector<std::uint8_t> on_cut(n, 0);
  for (int i = 0; i < static_cast<int>(change.node_old_to_new.size()); ++i) {
    const int j = change.node_old_to_new[i];
    if (j >= 0 && i < static_cast<int>(on_cut_.size()) && on_cut_[i]) on_cut[j] = 1;
  }
  for (int c : change.cut_nodes) {
    if (c >= 0 && c < n) on_cut[c] = 1;
  }
  on_cut_.assign(kept_nodes, 0);
  for (int i = 0; i < n; ++i) {
    if (new_index[i] >= 0) on_cut_[new_index[i]] = on_cut[i];
  }
  // This thread compacts the kept mesh; then the worker (after the model's first part) builds
  // its boundary, render surface and FCL hierarchy (buildGeometry): they depend on the kept
  // mesh, positions, pieces and on-cut flags only, which this thread only reads until the
  // wait (serosa, statistics, chips, the model update), none of which depends on them, and
  // each writes its own members, so the result is the same as one after the other.
  // The old mesh's nodes in the kept numbering (the collision hierarchy's and the serosa's).
  std::vector<int> old_to_kept(change.node_old_to_new.size(), -1);
  for (size_t i = 0; i < change.node_old_to_new.size(); ++i) {
    const int j = change.node_old_to_new[i];
    if (j >= 0 && j < n) old_to_kept[i] = new_index[j];
  }
  // The kept mesh (rest positions, tets), its positions, velocities and anchors, and its
  // boundary: the kept tets' faces that no other tet shares (a kept tet's neighbours are in
  // its component, so kept too), in the order cutting::boundaryFaces gives.
  cutting::TetMesh rest_mesh;
  sim::NodeVectors x_kept, v_kept;
  std::vector<std::uint8_t> anchored_kept, kept_boundary;
  Status geometry;
  std::vector<int> kept_next;
  std::vector<double> kept_quality;
  rest_mesh.X.resize(kept_nodes, 3);
  x_kept.resize(kept_nodes, 3);
  v_kept.resize(kept_nodes, 3);
  anchored_kept.assign(static_cast<size_t>(kept_nodes), 0);
  for (int i = 0; i < n; ++i) {
    if (new_index[i] < 0) continue;
    rest_mesh.X.row(new_index[i]) = rest.row(i);
    x_kept.row(new_index[i]) = xnew.row(i);
    v_kept.row(new_index[i]) = v.row(i);
    anchored_kept[new_index[i]] = anchored_after[i];
  }
  rest_mesh.T.resize(static_cast<Eigen::Index>(keep_tets.size()), 4);
  rest_mesh.material.resize(static_cast<Eigen::Index>(keep_tets.size()));
  for (size_t k = 0; k < keep_tets.size(); ++k) {
    for (int c = 0; c < 4; ++c) rest_mesh.T(static_cast<Eigen::Index>(k), c) = new_index[after.T(keep_tets[k], c)];
    rest_mesh.material[static_cast<Eigen::Index>(k)] = after.material[keep_tets[k]];
  }
  if (!face_next.empty()) {
    kept_boundary.resize(4 * keep_tets.size());
    for (size_t k = 0; k < keep_tets.size(); ++k)
      for (int f = 0; f < 4; ++f) kept_boundary[4 * k + f] = face_next[4 * static_cast<size_t>(keep_tets[k]) + f] < 0;
  }
  auto geometry_job = [&] {
    geometry = buildGeometry(rest_mesh, x_kept, &rec, kept_boundary.empty() ? nullptr : &kept_boundary, &old_to_kept);
  };
  const std::int64_t geometry_ticket = worker.post(geometry_job);
  // The serosa follows its nodes into the new numbering.
  outer_wall_.remapNodes(old_to_kept);
  timer.lap(&rec.components_ms);
  // q_min: each element's quality is kept from the previous pass unless the element is new,
  // renumbered onto other nodes, or has a node the cut moved (mesh_ is the old mesh until
  // the wait below). A kept tet's quality is that of its tet in `after` (the same corners in
  // the same order), so this does not wait for the worker's compacted mesh.
  {
    kept_quality.resize(keep_tets.size());
    std::vector<std::uint8_t> moved(static_cast<size_t>(n), 0);
    for (int j : change.moved_nodes)
      if (j >= 0 && j < n) moved[j] = 1;
    // The old element with the same nodes in the same order: updateFaces found it (its
    // old_of); otherwise the element map's, its nodes compared here.
    const bool old_known = face_change.old_of.size() == static_cast<size_t>(after.numTets());
    std::vector<int> mapped;
    if (!old_known) {
      mapped.assign(static_cast<size_t>(after.numTets()), -1);
      for (int t = 0; t < static_cast<int>(change.element_old_to_new.size()); ++t) {
        const int u = change.element_old_to_new[t];
        if (u >= 0 && u < after.numTets()) mapped[u] = t;
      }
    }
    const std::vector<int>& old_of = old_known ? face_change.old_of : mapped;
    rec.q_min = std::numeric_limits<double>::infinity();
    for (size_t k = 0; k < keep_tets.size(); ++k) {
      const int t = keep_tets[k], o = old_of[t];
      bool same = o >= 0 && o < static_cast<int>(tet_quality_.size());
      for (int c = 0; c < 4 && same; ++c) {
        const int node = after.T(t, c);
        same = !moved[node] && (old_known || change.node_old_to_new[mesh_.T(o, c)] == node);
      }
      kept_quality[k] = same ? tet_quality_[o] : tetQuality(after, t);
      rec.q_min = std::min(rec.q_min, kept_quality[k]);
    }
  }
  timer.lap(&rec.stats_ms);
  std::vector<ChipShape> chip_shapes;
  if (chips_) {
    cutting::TetMesh deformed = after;  // chips start where the pieces are now
    deformed.X = xnew;
    chip_shapes = chipShapes(deformed, v, comps, on_cut, scene_.materials, myoma_label);
  }
  timer.lap(&rec.chips_ms);
  // The kept mesh's face neighbours, for the next pass (a kept tet's neighbours are kept),
  // while the worker finishes the model's first part.
  if (!face_next.empty()) {
    if (keep_tets.size() == static_cast<size_t>(after.numTets())) {  // no piece removed
      kept_next = face_next;
    } else {
      std::vector<int> kept_of(static_cast<size_t>(after.numTets()), -1);
      for (size_t k = 0; k < keep_tets.size(); ++k) kept_of[keep_tets[k]] = static_cast<int>(k);
      kept_next.resize(4 * keep_tets.size());
      for (size_t k = 0; k < keep_tets.size() && !kept_next.empty(); ++k)
        for (int f = 0; f < 4; ++f) {
          const int p = face_next[4 * static_cast<size_t>(keep_tets[k]) + f];
          if (p >= 0 && kept_of[p / 4] < 0) {  // not reached: pieces are closed under faces
            kept_next.clear();
            break;
          }
          kept_next[4 * k + f] = p < 0 ? -1 : 4 * kept_of[p / 4] + p % 4;
        }
    }
  }
  timer.lap(&rec.components_ms);
  // The tissue model, updated around the cut (moment-preserving masses, Van Gelder springs,
  // stability estimate near the cut); the chips leave with their masses.
  sim::CutUpdate3DReport update;
  worker.wait(prepare_ticket);
  const Status model_status =
      model_prepare_status.ok()
          ? sim::finishModelAfterCut3D(model_, after, change, anchored_after, new_index, {}, model_prepared, &update)
          : model_prepare_status;
  timer.lap(&rec.model_ms);
  worker.wait(geometry_ticket);
  timer.lap(&rec.geometry_wait_ms);
  if (!model_status.ok() || !geometry.ok()) {  // not reached for a valid mesh
    (void)rebuildGeometry(nullptr);            // the hierarchy and locator of mesh_ again
    return fail(!model_status.ok() ? model_status.error() : geometry.error());
  }
  mesh_ = std::move(rest_mesh);
  face_next_ = std::move(kept_next);
  anchored_ = std::move(anchored_kept);
  resetState(&x_kept, &v_kept);
  rec.stability_nodes = update.stability_nodes;
  rec.global_stability = update.global_stability;
  timer.lap(&rec.model_ms);
  finishGeometry(&rec);
  timer.lap(nullptr);
  for (const ChipShape& chip : chip_shapes) chips_->addChip(chip);  // after the cavity is rebuilt
  timer.lap(&rec.chips_ms);
  tet_quality_ = std::move(kept_quality);
  timer.lap(nullptr);
  rec.elements = mesh_.numTets();
  rec.nodes = mesh_.numNodes();
  rec.substeps = model_.substeps;
  rec.added_mass_g = model_.added_mass;
  rec.cut_ms = std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
  rec.other_ms = std::max(0.0, rec.cut_ms - (rec.map_ms + rec.cut3d_ms + rec.remap_ms + rec.components_ms + rec.model_ms +
                                             rec.geometry_wait_ms + rec.chips_ms + rec.stats_ms));
  passes_.push_back(rec);
  // The tet locator of the new mesh (for the buried-wire test and the next pass's map) is
  // built on a background thread after the pass, beside the steps that follow: they do not
  // read it, and whoever does first waits for it (waitLocator). It reads mesh_ (unchanged
  // until the next pass, which waits first) and its own copy of the positions at the cut,
  // so it is the same locator as one built here. Its time goes to this pass's locator_ms
  // (passes_ grows only in finishPass, after the wait).
  // The same thread finds the new mesh's distances to the anchors for the next pass and, when
  // this pass searched near its cut only, counts the pieces (the kept mesh's, all anchored,
  // and the chips).
  double* locator_ms = &passes_.back().locator_ms;
  int* components = near_cut ? &passes_.back().components : nullptr;
  locator_thread_ = std::thread([this, x = std::move(x_kept), locator_ms, components, chips = rec.chips] {
    PassTimer build_timer;
    locator_.build(mesh_, x);
    buildNearest(mesh_, x);
    const int kept_pieces = anchorPieces(components != nullptr);
    if (components != nullptr) *components = kept_pieces < 0 ? -1 : kept_pieces + chips;
    build_timer.lap(locator_ms);
  });
}

void Simulation::fillSnapshot(render::RenderSnapshot& snap) const {
  const size_t nv = surface_nodes_.size();
  snap.tissue.positions.resize(nv * 3);
  for (size_t i = 0; i < nv; ++i) {
    for (int c = 0; c < 3; ++c) snap.tissue.positions[3 * i + c] = static_cast<float>(state_.x(surface_nodes_[i], c));
  }
  if (snap.topology_version != topology_version_) {
    snap.tissue.triangles = surface_triangles_;
    snap.tissue.material = surface_material_;
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
