// The cut job, in stages: cut -> free pieces -> kept mesh -> model -> state map -> chips ->
// surface and lookups. Each stage is a named function over the Kept record below.
#include "hysim/engine/cut_job.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>

#include "hysim/cutting/cut3d.hpp"
#include "hysim/cutting/mesh_io.hpp"
#include "hysim/cutting/mesh_stats.hpp"
#include "hysim/sim/tissue_update3d.hpp"

namespace hysim::engine {
namespace {

// Wall time of the stages (measurement only: nothing simulated depends on it).
class StageTimer {
 public:
  void lap(double* into) {
    const auto now = std::chrono::steady_clock::now();
    if (into != nullptr) *into += std::chrono::duration<double, std::milli>(now - last_).count();
    last_ = now;
  }

 private:
  std::chrono::steady_clock::time_point last_ = std::chrono::steady_clock::now();
};

// What the stages pass on: the cut mesh and which of it is kept.
struct Kept {
  std::vector<std::uint8_t> anchored_after;  // #N of the cut mesh
  std::vector<int> face_next;                // 4 #T of the cut mesh (empty: unknown)
  Pieces comps;
  FaceChange face_change;
  bool near_cut = false;                     // free pieces searched near the cut only
  std::vector<int> tets;                     // kept tets of the cut mesh
  std::vector<std::int32_t> new_index;       // #N of the cut mesh: kept number or -1
  int nodes = 0;
};

Status dumpInput(const Tissue& base, const CutJobInput& in) {
  const cutting::Tris rf = cutting::CutSurface::stripTriangles(in.rows, in.row_size);
  const cutting::TriMesh sweep_mesh{in.rest_rows, rf, cutting::Labels::Zero(rf.rows())};
  Status st = cutting::writeMesh(in.dump_prefix + "mesh.msh", base.mesh);
  if (st.ok()) st = cutting::writeMesh(in.dump_prefix + "surface.msh", sweep_mesh);
  if (!st.ok()) return Error{"--dump-cuts: " + st.error()};
  return Status::Ok();
}

// Anchors of the cut mesh: surviving nodes that did not move keep theirs; new, moved and
// cut nodes are looked up by position.
std::vector<std::uint8_t> anchorsAfter(const Tissue& base, const Scene& scene, const cutting::TetMesh& after,
                                       const cutting::TopologyChange& change) {
  const int n = after.numNodes();
  std::vector<std::uint8_t> anchored(static_cast<size_t>(n), 0);
  for (int i = 0; i < static_cast<int>(change.node_old_to_new.size()); ++i) {
    const int j = change.node_old_to_new[i];
    if (j >= 0 && i < static_cast<int>(base.anchored.size())) anchored[j] = base.anchored[i];
  }
  auto reanchor = [&](int j) {
    if (j >= 0 && j < n) anchored[j] = anchoredAt(scene, after.X.row(j).transpose()) ? 1 : 0;
  };
  for (const cutting::NewNode& nn : change.new_nodes) reanchor(nn.id);
  for (int j : change.moved_nodes) reanchor(j);
  for (int j : change.cut_nodes) reanchor(j);
  return anchored;
}

// The pieces of the cut mesh; those connected to no anchored node are chips. Face neighbours
// come from the previous mesh's, rematching only the faces near the cut (all faces when that
// cannot be done). When every piece before the cut was anchored and stays so, only the tets
// near the cut are searched: the free pieces are the same, in the same order.
void findPieces(const Tissue& base, const cutting::TetMesh& after, const cutting::TopologyChange& change, Kept& k) {
  const int n = after.numNodes();
  if (updateFaces(base.mesh, base.face_next, after, change.node_old_to_new, change.element_old_to_new, k.face_next,
                  &k.face_change)) {
    k.near_cut = base.pieces_anchored && base.anchor_distance.size() == static_cast<size_t>(base.mesh.numTets()) &&
                 base.anchored.size() == change.node_old_to_new.size();
    for (size_t i = 0; i < change.node_old_to_new.size() && k.near_cut; ++i) {
      const int j = change.node_old_to_new[i];
      k.near_cut = !base.anchored[i] || (j >= 0 && j < n && k.anchored_after[j]);
    }
    k.comps = k.near_cut ? freePiecesAfterCut(after, k.face_next, k.anchored_after, k.face_change, base.anchor_distance)
                         : tetPieces(after, k.face_next, k.anchored_after);
  } else if (matchFaces(after, k.face_next)) {
    k.comps = tetPieces(after, k.face_next, k.anchored_after);
  } else {  // not reached for a valid mesh
    std::vector<int> anchored;
    for (int i = 0; i < n; ++i)
      if (k.anchored_after[i]) anchored.push_back(i);
    const cutting::Components3D c = cutting::tetComponents(after, anchored);
    k.comps.count = c.count;
    k.comps.label.assign(c.label.data(), c.label.data() + c.label.size());
    k.comps.free.assign(c.free.begin(), c.free.end());
    k.face_next.clear();
  }
}

// The kept tets (free pieces leave, their volume counted as resected) and the kept nodes,
// renumbered in their order so that the model's arrays compact in place.
void keepAnchored(const Scene& scene, const cutting::TetMesh& after, Kept& k, PassRecord& rec) {
  const MyomaLabels myoma = myomaLabels(scene);
  k.tets.reserve(static_cast<size_t>(after.numTets()));
  for (int t = 0; t < after.numTets(); ++t) {
    if (!k.comps.free[k.comps.label[t]]) {
      k.tets.push_back(t);
      continue;
    }
    const double vol = std::abs(cutting::tetVolume(after, t));
    rec.removed_mm3 += vol;
    if (myoma.has(after.material[t])) rec.removed_myoma_mm3 += vol;
  }
  for (int c = 0; c < k.comps.count; ++c) rec.chips += k.comps.free[c] ? 1 : 0;
  rec.components = k.near_cut ? -1 : k.comps.count;
  k.new_index.assign(static_cast<size_t>(after.numNodes()), -1);
  for (int t : k.tets)
    for (int c = 0; c < 4; ++c) k.new_index[after.T(t, c)] = 0;
  k.nodes = 0;
  for (int& idx : k.new_index)
    if (idx == 0) idx = k.nodes++;
}

// Nodes of the cut mesh on a cut surface, this pass's and earlier ones'.
std::vector<std::uint8_t> onCutAfter(const Tissue& base, const cutting::TetMesh& after,
                                     const cutting::TopologyChange& change) {
  const int n = after.numNodes();
  std::vector<std::uint8_t> on_cut(static_cast<size_t>(n), 0);
  for (int i = 0; i < static_cast<int>(change.node_old_to_new.size()); ++i) {
    const int j = change.node_old_to_new[i];
    if (j >= 0 && i < static_cast<int>(base.on_cut.size()) && base.on_cut[i]) on_cut[j] = 1;
  }
  for (int c : change.cut_nodes)
    if (c >= 0 && c < n) on_cut[c] = 1;
  return on_cut;
}

// The kept mesh (rest positions, tets, materials), its anchors and on-cut flags.
void buildKeptMesh(const cutting::TetMesh& after, const std::vector<std::uint8_t>& on_cut, const Kept& k,
                   Tissue& next) {
  const int n = after.numNodes();
  next.mesh.X.resize(k.nodes, 3);
  next.on_cut.assign(static_cast<size_t>(k.nodes), 0);
  next.anchored.assign(static_cast<size_t>(k.nodes), 0);
  for (int i = 0; i < n; ++i) {
    const int j = k.new_index[i];
    if (j < 0) continue;
    next.mesh.X.row(j) = after.X.row(i);
    next.on_cut[j] = on_cut[i];
    next.anchored[j] = k.anchored_after[i];
  }
  next.mesh.T.resize(static_cast<Eigen::Index>(k.tets.size()), 4);
  next.mesh.material.resize(static_cast<Eigen::Index>(k.tets.size()));
  for (size_t e = 0; e < k.tets.size(); ++e) {
    for (int c = 0; c < 4; ++c) next.mesh.T(static_cast<Eigen::Index>(e), c) = k.new_index[after.T(k.tets[e], c)];
    next.mesh.material[static_cast<Eigen::Index>(e)] = after.material[k.tets[e]];
  }
}

// The kept mesh's face neighbours and boundary slots (a kept tet's neighbours are kept too:
// pieces are closed under faces).
void keptFaces(const cutting::TetMesh& after, const Kept& k, Tissue& next, std::vector<std::uint8_t>& boundary) {
  next.face_next.clear();
  boundary.clear();
  if (k.face_next.empty()) return;
  boundary.resize(4 * k.tets.size());
  for (size_t e = 0; e < k.tets.size(); ++e)
    for (int f = 0; f < 4; ++f) boundary[4 * e + f] = k.face_next[4 * static_cast<size_t>(k.tets[e]) + f] < 0;
  if (k.tets.size() == static_cast<size_t>(after.numTets())) {  // no piece removed
    next.face_next = k.face_next;
    return;
  }
  std::vector<int> kept_of(static_cast<size_t>(after.numTets()), -1);
  for (size_t e = 0; e < k.tets.size(); ++e) kept_of[k.tets[e]] = static_cast<int>(e);
  next.face_next.resize(4 * k.tets.size());
  for (size_t e = 0; e < k.tets.size(); ++e)
    for (int f = 0; f < 4; ++f) {
      const int p = k.face_next[4 * static_cast<size_t>(k.tets[e]) + f];
      if (p >= 0 && kept_of[p / 4] < 0) {  // not reached: pieces are closed under faces
        next.face_next.clear();
        return;
      }
      next.face_next[4 * e + f] = p < 0 ? -1 : 4 * kept_of[p / 4] + p % 4;
    }
}

// Each kept element's quality: kept from the epoch cut unless the element is new, renumbered
// onto other nodes, or has a node the cut moved.
void keptQuality(const Tissue& base, const cutting::TetMesh& after, const cutting::TopologyChange& change,
                 const Kept& k, Tissue& next, PassRecord& rec) {
  const int n = after.numNodes();
  std::vector<std::uint8_t> moved(static_cast<size_t>(n), 0);
  for (int j : change.moved_nodes)
    if (j >= 0 && j < n) moved[j] = 1;
  const bool old_known = k.face_change.old_of.size() == static_cast<size_t>(after.numTets());
  std::vector<int> mapped;
  if (!old_known) {
    mapped.assign(static_cast<size_t>(after.numTets()), -1);
    for (int t = 0; t < static_cast<int>(change.element_old_to_new.size()); ++t) {
      const int u = change.element_old_to_new[t];
      if (u >= 0 && u < after.numTets()) mapped[u] = t;
    }
  }
  const std::vector<int>& old_of = old_known ? k.face_change.old_of : mapped;
  next.tet_quality.resize(k.tets.size());
  rec.q_min = std::numeric_limits<double>::infinity();
  for (size_t e = 0; e < k.tets.size(); ++e) {
    const int t = k.tets[e], o = old_of[t];
    bool same = o >= 0 && o < static_cast<int>(base.tet_quality.size());
    for (int c = 0; c < 4 && same; ++c) {
      const int node = after.T(t, c);
      same = !moved[node] && (old_known || change.node_old_to_new[base.mesh.T(o, c)] == node);
    }
    next.tet_quality[e] = same ? base.tet_quality[o] : tetQuality(after, t);
    rec.q_min = std::min(rec.q_min, next.tet_quality[e]);
  }
}

// The state map (see StateRemap) onto the nodes j of the cut mesh with new_index[j] >= 0, in
// that numbering (increasing with j).
void buildRemap(const Tissue& base, const cutting::TetMesh& after, const cutting::TopologyChange& change,
                const std::vector<std::int32_t>& new_index, int kept_nodes, StateRemap& r) {
  const int n = after.numNodes();
  std::vector<int> source(static_cast<size_t>(n), -1);   // surviving old node of each cut-mesh node
  for (int i = 0; i < static_cast<int>(change.node_old_to_new.size()); ++i) {
    const int j = change.node_old_to_new[i];
    if (j >= 0 && j < n && source[j] < 0) source[j] = i;
  }
  std::vector<const cutting::NewNode*> born(static_cast<size_t>(n), nullptr);
  for (const cutting::NewNode& nn : change.new_nodes)
    if (nn.id >= 0 && nn.id < n && source[nn.id] < 0 && born[nn.id] == nullptr) born[nn.id] = &nn;
  r.first.assign(1, 0);
  r.parent.clear();
  r.weight.clear();
  r.offset.resize(kept_nodes, 3);
  for (int j = 0; j < n; ++j) {
    const int kept = new_index[j];
    if (kept < 0) continue;
    Eigen::RowVector3d rest_before = Eigen::RowVector3d::Zero();
    if (source[j] >= 0) {
      r.parent.push_back(source[j]);
      r.weight.push_back(1.0);
      rest_before = base.mesh.X.row(source[j]);
    } else if (born[j] != nullptr) {
      for (int p = 0; p < born[j]->num_parents; ++p) {
        r.parent.push_back(born[j]->parents[p]);
        r.weight.push_back(born[j]->weights[p]);
        rest_before += born[j]->weights[p] * base.mesh.X.row(born[j]->parents[p]);
      }
    }
    r.offset.row(kept) = after.X.row(j) - rest_before;
    r.first.push_back(static_cast<int>(r.parent.size()));
  }
}

}  // namespace

void StateRemap::apply(const sim::NodeVectors& x_old, const sim::NodeVectors& v_old, sim::NodeVectors& x,
                       sim::NodeVectors& v) const {
  const int n = static_cast<int>(first.size()) - 1;
  for (int j = 0; j < n; ++j) {
    Eigen::RowVector3d xs = Eigen::RowVector3d::Zero(), vs = xs;
    for (int k = first[j]; k < first[j + 1]; ++k) {
      xs += weight[k] * x_old.row(parent[k]);
      vs += weight[k] * v_old.row(parent[k]);
    }
    x.row(j) = xs + offset.row(j);
    v.row(j) = vs;
  }
}

namespace {

// The free pieces of a cut mesh as chips: surface (current positions), material for
// drawing, volume, mass, centre of mass and mean velocity. `after` holds the current
// positions; v (#N x 3) the velocities; on_cut (#N) marks nodes on a cut surface.
std::vector<ChipShape> chipShapes(const cutting::TetMesh& after, const sim::NodeVectors& v,
                                  const Pieces& comps, const std::vector<std::uint8_t>& on_cut,
                                  const std::vector<sim::Material>& materials, const MyomaLabels& myoma) {
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
        if (!myoma.has(piece.material[face_tet[f]])) chip.material[vertex[p]] = render::SurfaceMaterial::Endometrium;
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

// What the chips are made of at the commit step.
void keepChipSource(const Tissue& base, const cutting::TetMesh& after, const cutting::TopologyChange& change,
                    const Kept& k, const std::vector<std::uint8_t>& on_cut, CutOutcome& out) {
  std::vector<std::int32_t> every(static_cast<size_t>(after.numNodes()));
  for (int i = 0; i < after.numNodes(); ++i) every[i] = i;
  buildRemap(base, after, change, every, after.numNodes(), out.chips.remap);
  out.chips.mesh = after;
  out.chips.pieces = k.comps;
  out.chips.on_cut = on_cut;
}

}  // namespace

std::vector<ChipShape> chipsAt(const ChipSource& source, const Scene& scene, const sim::NodeVectors& x,
                               const sim::NodeVectors& v) {
  const int n = source.mesh.numNodes();
  sim::NodeVectors xs(n, 3), vs(n, 3);
  source.remap.apply(x, v, xs, vs);
  cutting::TetMesh deformed = source.mesh;
  deformed.X = xs;
  return chipShapes(deformed, vs, source.pieces, source.on_cut, scene.materials, myomaLabels(scene));
}

void runCutJob(const Tissue& base, const Scene& scene, const CutJobInput& in, CutOutcome& out) {
  StageTimer timer;
  const auto t0 = std::chrono::steady_clock::now();
  PassRecord& rec = out.record;
  auto fail = [&](const std::string& why) {
    out.status = Error{why};
    rec.cut_failed = true;
    rec.message = why;
    rec.elements = base.mesh.numTets();
    rec.nodes = base.mesh.numNodes();
  };
  if (!in.dump_prefix.empty()) {
    if (Status st = dumpInput(base, in); !st.ok()) return fail(st.error());
  }
  auto surface = cutting::CutSurface::strip(in.rest_rows, in.rows, in.row_size);
  if (!surface.ok()) return fail(surface.error());
  cutting::Cut3DOptions options;
  options.method = cutting::CutMethod::Hybrid;
  // chips.optimize false: the pieces the cut cuts off (the chips) are not optimised; cut3d
  // finds them with the anchors (the nodes' flags; by position where the cut made, moved or
  // put a node on the cut).
  if (!scene.chips.optimize) {
    options.anchored_nodes = &base.anchored;
    options.anchored_at = [&scene](const Eigen::Vector3d& rest) { return anchoredAt(scene, rest); };
  }
  auto cut = cutting::cut3d(base.mesh, *surface, options);
  if (!cut.ok()) return fail(cut.error());
  timer.lap(&rec.cut3d_ms);
  const cutting::TopologyChange& change = cut->change;
  const cutting::TetMesh& after = cut->mesh;
  rec.crossed_edges = cut->report.crossed_edges;
  rec.snapped_nodes = cut->report.snapped_nodes;
  rec.split_edges = cut->report.split_edges;
  rec.duplicated_nodes = cut->report.duplicated_nodes;
  rec.unoptimised_chip_elements = cut->report.cut_off_elements;
  rec.cut_faces = cut->report.cut_faces;
  rec.volume_drift_mm3 = cut->report.volume_drift;
  rec.peeled_mm3 = cut->report.peeled_volume;
  const MyomaLabels myoma = myomaLabels(scene);
  for (const cutting::MaterialVolume& m : cut->report.material_volumes)
    if (myoma.has(m.label)) rec.volume_drift_myoma_mm3 += m.drift();

  Kept k;
  k.anchored_after = anchorsAfter(base, scene, after, change);
  findPieces(base, after, change, k);
  keepAnchored(scene, after, k, rec);
  auto next = std::make_unique<Tissue>();
  const std::vector<std::uint8_t> on_cut = onCutAfter(base, after, change);
  buildKeptMesh(after, on_cut, k, *next);
  std::vector<std::uint8_t> boundary;
  keptFaces(after, k, *next, boundary);
  timer.lap(&rec.components_ms);
  keptQuality(base, after, change, k, *next, rec);
  timer.lap(&rec.stats_ms);

  // The tissue model, updated around the cut (moment-preserving masses, Van Gelder springs,
  // stability estimate near the cut); the chips leave with their masses.
  next->model = base.model;
  sim::CutUpdate3DReport update;
  if (Status st = sim::updateModelAfterCut3D(next->model, base.mesh, after, change, k.anchored_after, k.new_index, {},
                                             &update);
      !st.ok()) {
    return fail(st.error());
  }
  rec.stability_nodes = update.stability_nodes;
  rec.global_stability = update.global_stability;
  countElements(*next);
  sim::sizeStepArrays(next->model, out.state);
  out.state.x.resize(k.nodes, 3);
  out.state.v.resize(k.nodes, 3);
  timer.lap(&rec.model_ms);

  buildRemap(base, after, change, k.new_index, k.nodes, out.remap);
  out.old_to_kept.assign(change.node_old_to_new.size(), -1);
  for (size_t i = 0; i < change.node_old_to_new.size(); ++i) {
    const int j = change.node_old_to_new[i];
    if (j >= 0 && j < after.numNodes()) out.old_to_kept[i] = k.new_index[j];
  }
  sim::NodeVectors x_kept(k.nodes, 3), v_kept(k.nodes, 3);
  out.remap.apply(in.x, in.v, x_kept, v_kept);
  if (scene.chips.mode == ChipSettings::Mode::Simulate && rec.chips > 0) keepChipSource(base, after, change, k, on_cut, out);
  timer.lap(&rec.chips_ms);
  if (Status st = buildSurface(*next, scene, x_kept, boundary.empty() ? nullptr : &boundary, &rec); !st.ok()) {
    return fail(st.error());
  }
  timer.lap(nullptr);
  buildLookups(*next, x_kept);
  const int kept_pieces = findAnchorPieces(*next, k.near_cut);
  if (k.near_cut) rec.components = kept_pieces < 0 ? -1 : kept_pieces + rec.chips;
  timer.lap(&rec.locator_ms);

  rec.elements = next->mesh.numTets();
  rec.nodes = next->mesh.numNodes();
  rec.substeps = next->model.substeps;
  rec.added_mass_g = next->model.added_mass;
  out.tissue = std::move(next);
  out.status = Status::Ok();
  rec.cut_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  rec.other_ms = std::max(0.0, rec.cut_ms - (rec.cut3d_ms + rec.components_ms + rec.stats_ms + rec.model_ms +
                                             rec.chips_ms + rec.surface_ms + rec.collision_ms + rec.locator_ms));
}

}  // namespace hysim::engine
