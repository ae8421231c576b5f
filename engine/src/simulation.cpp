#include "hysim/engine/simulation.hpp"

#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include <algorithm>
#include <assimp/Importer.hpp>
#include <cmath>

#include "hysim/cutting/mesh_io.hpp"

namespace hysim::engine {
namespace {

// Closest point to p on segment [a, b].
Eigen::Vector3d closestOnSegment(const Eigen::Vector3d& p, const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  const Eigen::Vector3d ab = b - a;
  const double len2 = ab.squaredNorm();
  const double t = len2 > 0.0 ? std::clamp((p - a).dot(ab) / len2, 0.0, 1.0) : 0.0;
  return a + t * ab;
}

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

Result<std::unique_ptr<Simulation>> Simulation::create(const Scene& scene) {
  std::unique_ptr<Simulation> s(new Simulation());
  s->scene_ = scene;
  auto mesh = cutting::readTetMesh(scene.mesh_path);
  if (!mesh.ok()) return Error{mesh.error()};
  s->mesh_ = std::move(mesh.value());
  if (auto valid = cutting::validate(s->mesh_); !valid.ok()) {
    return Error{scene.mesh_path + ": invalid mesh: " + valid.error()};
  }

  std::vector<int> fixed;
  for (int i = 0; i < s->mesh_.numNodes(); ++i) {
    const Eigen::Vector3d p = s->mesh_.X.row(i).transpose();
    for (const AnchorRegion& a : scene.anchors) {
      if (a.contains(p)) {
        fixed.push_back(i);
        break;
      }
    }
  }
  s->num_anchored_ = static_cast<int>(fixed.size());
  auto model = sim::buildModel(s->mesh_, scene.materials, fixed, scene.sim);
  if (!model.ok()) return Error{scene.path + ": " + model.error()};
  s->model_ = std::move(model.value());
  s->state_ = sim::makeState(s->model_, s->mesh_);
  for (int t = 0; t < s->mesh_.numTets(); ++t) {
    bool moves = false;
    for (int c = 0; c < 4; ++c) moves = moves || !s->model_.fixed[s->mesh_.T(t, c)];
    s->num_deformable_tets_ += moves ? 1 : 0;
  }
  s->device_ = std::make_unique<haptics::ScriptedDevice>(haptics::Trajectory(scene.tool_path));
  s->pose_ = s->device_->read(0.0).pose;

  // Surface for contact and rendering: boundary faces, compacted vertex numbering.
  Eigen::VectorXi face_tet;
  s->surface_faces_ = cutting::boundaryFaces(s->mesh_, &face_tet);
  std::vector<int> local(s->mesh_.numNodes(), -1);
  // A surface vertex is drawn as myoma when all its boundary faces belong to myoma tets:
  // the rim where the myoma meets the wall keeps the endometrium colour, so the colour
  // blend happens on the myoma's side (its base is covered by endometrium in reality).
  int myoma_label = -1;
  for (const sim::Material& m : scene.materials) {
    if (m.name == "myoma") myoma_label = m.label;
  }
  for (int f = 0; f < s->surface_faces_.rows(); ++f) {
    for (int c = 0; c < 3; ++c) {
      const int node = s->surface_faces_(f, c);
      if (local[node] < 0) {
        local[node] = static_cast<int>(s->surface_nodes_.size());
        s->surface_nodes_.push_back(node);
        s->surface_material_.push_back(render::SurfaceMaterial::Myoma);
      }
      s->surface_triangles_.push_back(static_cast<std::uint32_t>(local[node]));
      if (s->mesh_.material[face_tet[f]] != myoma_label) {
        s->surface_material_[local[node]] = render::SurfaceMaterial::Endometrium;
      }
    }
  }
  for (int node : s->surface_nodes_) {
    if (!s->model_.fixed[node]) s->contact_nodes_.push_back(node);
  }
  s->contact_force_ = sim::NodeVectors::Zero(s->mesh_.numNodes(), 3);

  if (!scene.tool_mesh_path.empty()) {
    auto tool = loadSurface(scene.tool_mesh_path, render::SurfaceMaterial::Tool);
    if (!tool.ok()) return Error{tool.error()};
    s->tool_surface_ = std::move(tool.value());
  }
  return s;
}

void Simulation::computeContact() {
  const ContactSettings& c = scene_.contact;
  tool_force_n_.setZero();
  for (int node : contact_nodes_) contact_force_.row(node).setZero();
  if (!c.enabled) return;
  const Eigen::Vector3d axis = pose_.rotation.col(2);
  const Eigen::Vector3d up = pose_.rotation.col(1);
  const Eigen::Vector3d shaft_a = pose_.tip - c.shaft_length_mm * axis;
  const Eigen::Vector3d shaft_b = pose_.tip;
  const Eigen::Vector3d loop = pose_.tip + (c.loop_reach_mm + pose_.extension_mm) * axis - c.loop_drop_mm * up;
  const double k = c.stiffness_n_per_mm * 1e6;   // N/mm -> uN/mm
  const double d = c.damping_n_s_per_mm * 1e6;   // N s/mm -> uN s/mm
  // The shaft and the (inactive) loop push tissue: penalty along the separation direction.
  auto push = [&](int node, const Eigen::Vector3d& closest, double radius) {
    const Eigen::Vector3d p = state_.x.row(node).transpose();
    Eigen::Vector3d n = p - closest;
    const double dist = n.norm();
    if (dist >= radius || dist <= 1e-12) return;
    n /= dist;
    const double vn = state_.v.row(node).dot(n);
    const double mag = std::max(0.0, k * (radius - dist) - d * vn);
    contact_force_.row(node) += mag * n.transpose();
    tool_force_n_ -= 1e-6 * mag * n;
  };
  for (int node : contact_nodes_) {
    const Eigen::Vector3d p = state_.x.row(node).transpose();
    push(node, closestOnSegment(p, shaft_a, shaft_b), c.shaft_radius_mm);
    push(node, loop, c.loop_radius_mm);
  }
}

void Simulation::step() {
  // The pose for the end of this step drives the contact of this step.
  pose_ = device_->read(state_.time + scene_.sim.dt).pose;
  computeContact();
  sim::StepInput input;
  input.external_force = &contact_force_;
  sim::step(model_, state_, input);
  device_->commandForce(tool_force_n_);  // clamped and NaN-guarded by the device
}

void Simulation::fillSnapshot(render::RenderSnapshot& snap) const {
  const size_t nv = surface_nodes_.size();
  snap.tissue.positions.resize(nv * 3);
  for (size_t i = 0; i < nv; ++i) {
    for (int c = 0; c < 3; ++c) snap.tissue.positions[3 * i + c] = static_cast<float>(state_.x(surface_nodes_[i], c));
  }
  if (snap.tissue.triangles.size() != surface_triangles_.size()) snap.tissue.triangles = surface_triangles_;
  if (snap.tissue.material.size() != surface_material_.size()) snap.tissue.material = surface_material_;
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
  snap.step = state_.steps;
  snap.time_s = state_.time;
}

}  // namespace hysim::engine
