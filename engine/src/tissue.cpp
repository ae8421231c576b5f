#include "hysim/engine/tissue.hpp"

#include <algorithm>
#include <chrono>
#include <limits>

#include "hysim/cutting/mesh_stats.hpp"

namespace hysim::engine {
namespace {

double msSince(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

// The render surface: boundary vertices numbered compactly, each drawn as myoma when all
// its boundary faces belong to myoma tets (the rim where the myoma meets the wall keeps the
// endometrium colour: its base is covered by endometrium in reality), as cut tissue when it
// lies on a cut.
void buildRenderSurface(Tissue& tissue, const Eigen::VectorXi& face_tet, const MyomaLabels& myoma) {
  const cutting::TetMesh& mesh = tissue.mesh;
  tissue.surface_nodes.clear();
  tissue.surface_triangles.clear();
  tissue.surface_material.clear();
  std::vector<int> local(static_cast<size_t>(mesh.numNodes()), -1);
  for (int f = 0; f < tissue.surface_faces.rows(); ++f) {
    for (int c = 0; c < 3; ++c) {
      const int node = tissue.surface_faces(f, c);
      if (local[node] < 0) {
        local[node] = static_cast<int>(tissue.surface_nodes.size());
        tissue.surface_nodes.push_back(node);
        tissue.surface_material.push_back(render::SurfaceMaterial::Myoma);
      }
      tissue.surface_triangles.push_back(static_cast<std::uint32_t>(local[node]));
      if (!myoma.has(mesh.material[face_tet[f]])) {
        tissue.surface_material[local[node]] = render::SurfaceMaterial::Endometrium;
      }
    }
  }
  if (tissue.on_cut.size() == static_cast<size_t>(mesh.numNodes())) {
    for (size_t v = 0; v < tissue.surface_nodes.size(); ++v) {
      if (tissue.on_cut[tissue.surface_nodes[v]]) tissue.surface_material[v] = render::SurfaceMaterial::Cut;
    }
  }
  tissue.contact_nodes.clear();
  for (int node : tissue.surface_nodes) {
    if (!tissue.model.fixed[node]) tissue.contact_nodes.push_back(node);
  }
}

}  // namespace

MyomaLabels myomaLabels(const Scene& scene) {
  MyomaLabels out;
  for (const sim::Material& m : scene.materials) {
    if (m.name == "myoma") out.labels.push_back(m.label);
  }
  return out;
}

bool anchoredAt(const Scene& scene, const Eigen::Vector3d& rest) {
  for (const AnchorRegion& a : scene.anchors) {
    if (a.contains(rest)) return true;
  }
  return false;
}

double tetQuality(const cutting::TetMesh& mesh, int t) {
  return cutting::radiusRatio(mesh.X.row(mesh.T(t, 0)).transpose(), mesh.X.row(mesh.T(t, 1)).transpose(),
                              mesh.X.row(mesh.T(t, 2)).transpose(), mesh.X.row(mesh.T(t, 3)).transpose());
}

Result<std::unique_ptr<Tissue>> makeTissue(cutting::TetMesh mesh, const Scene& scene) {
  auto tissue = std::make_unique<Tissue>();
  tissue->mesh = std::move(mesh);
  const cutting::TetMesh& m = tissue->mesh;
  std::vector<int> fixed;
  tissue->anchored.assign(static_cast<size_t>(m.numNodes()), 0);
  for (int i = 0; i < m.numNodes(); ++i) {
    if (anchoredAt(scene, m.X.row(i).transpose())) {
      tissue->anchored[i] = 1;
      fixed.push_back(i);
    }
  }
  auto model = sim::buildModel(m, scene.materials, fixed, scene.sim);
  if (!model.ok()) return Error{model.error()};
  tissue->model = std::move(model.value());
  tissue->on_cut.assign(static_cast<size_t>(m.numNodes()), 0);
  if (!matchFaces(m, tissue->face_next)) tissue->face_next.clear();
  findAnchorPieces(*tissue, false);
  countElements(*tissue);
  tissue->tet_quality.resize(static_cast<size_t>(m.numTets()));
  for (int t = 0; t < m.numTets(); ++t) tissue->tet_quality[t] = tetQuality(m, t);
  if (Status st = buildSurface(*tissue, scene, m.X, nullptr, nullptr); !st.ok()) return Error{st.error()};
  buildLookups(*tissue, m.X);
  return tissue;
}

Status buildSurface(Tissue& tissue, const Scene& scene, const sim::NodeVectors& x,
                    const std::vector<std::uint8_t>* boundary, PassRecord* timing) {
  auto t0 = std::chrono::steady_clock::now();
  Eigen::VectorXi face_tet;
  if (boundary != nullptr && boundary->size() == 4 * static_cast<size_t>(tissue.mesh.numTets())) {
    boundaryFromSlots(tissue.mesh, *boundary, tissue.surface_faces, face_tet);
  } else {
    tissue.surface_faces = cutting::boundaryFaces(tissue.mesh, &face_tet);
  }
  buildRenderSurface(tissue, face_tet, myomaLabels(scene));
  if (timing != nullptr) timing->surface_ms += msSince(t0);
  t0 = std::chrono::steady_clock::now();
  // Boxes grown by half a millimetre: while the tissue near the loop moves less than that, a
  // step only moves the vertices (see collision.hpp).
  Status st = tissue.collision.build(tissue.surface_faces, x, 0.5, &tissue.mesh.X);
  if (timing != nullptr) timing->collision_ms += msSince(t0);
  return st;
}

void buildLookups(Tissue& tissue, const sim::NodeVectors& x) {
  tissue.locator.build(tissue.mesh, x);
  tissue.nearest_x = x;
  tissue.nearest.build(tissue.nearest_x, tissue.surface_nodes);
}

int findAnchorPieces(Tissue& tissue, bool count) {
  tissue.anchor_distance.clear();
  tissue.pieces_anchored = false;
  if (tissue.face_next.size() != 4 * static_cast<size_t>(tissue.mesh.numTets()) ||
      tissue.anchored.size() != static_cast<size_t>(tissue.mesh.numNodes())) {
    return -1;
  }
  tissue.anchor_distance = anchorDistance(tissue.mesh, tissue.face_next, tissue.anchored);
  tissue.pieces_anchored = std::find(tissue.anchor_distance.begin(), tissue.anchor_distance.end(),
                                     std::numeric_limits<int>::max()) == tissue.anchor_distance.end();
  return count ? tetPieces(tissue.mesh, tissue.face_next, tissue.anchored).count : 0;
}

void countElements(Tissue& tissue) {
  tissue.num_anchored = 0;
  for (std::uint8_t a : tissue.anchored) tissue.num_anchored += a;
  tissue.num_deformable_tets = 0;
  for (int t = 0; t < tissue.mesh.numTets(); ++t) {
    bool moves = false;
    for (int c = 0; c < 4; ++c) moves = moves || !tissue.model.fixed[tissue.mesh.T(t, c)];
    tissue.num_deformable_tets += moves ? 1 : 0;
  }
}

}  // namespace hysim::engine
