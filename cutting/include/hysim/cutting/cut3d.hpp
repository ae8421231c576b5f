#pragma once
// Cutting tetrahedral meshes with a plane or an open triangulated surface: the hybrid method
// of section 4 of the paper (per intersected edge, snap the near node onto the cut or
// subdivide near the middle; zero to three nodes of a tet separated), a local 3D mesh
// optimisation after the cut (beyond the paper), and the baselines with the same interface
// (standard subdivision, snapping only, element deletion).
//
// Outline of one cut (cut3d.cpp drives the stages, one file each in src/cut3d/):
//  1. classify nodes against the surface (tolerance eps, see cut_surface.hpp); find the
//     crossed edges (end points strictly on opposite sides, crossing inside the surface);
//  2. hybrid/snap: a node whose crossing lies within snap_region * |e| of it moves onto the
//     cut (interior node: nearest point of the cut; boundary node: along a crossed boundary
//     edge, only where its boundary is flat, i.e. not a feature). A move that would invert,
//     flatten or badly degrade (q* below min(before, min_quality)) an element, or shorten an
//     edge below min_edge_fraction of its length, is refused and the edges stay crossed;
//  3. every edge still crossed is split at the crossing (conforming edge bisection: each tet
//     around the edge becomes two), which gives the subdivided configurations (1-3 and 2-2
//     splits into 4 and 6 tets, partial patterns where the surface ends inside the tet); a
//     crossed tet is then one of the paper's four cases (TetCutCase: 0-3 nodes on the cut);
//  4. node separation: faces lying in the cut and shared by two tets are cut faces; each node
//     on the cut gets one copy per group of its incident tets connected through non-cut
//     faces, so every element keeps the copy of its side and a crack tip (partial cut) stays
//     connected;
//  5. hybrid: local optimisation (see Optimize3DOptions).
#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <functional>
#include <vector>

#include "hysim/cutting/cut2d.hpp"  // CutMethod, parseCutMethod, cutMethodName
#include "hysim/cutting/cut_surface.hpp"
#include "hysim/cutting/mesh.hpp"
#include "hysim/cutting/result.hpp"
#include "hysim/cutting/topology_change.hpp"

namespace hysim::cutting {

// Local optimisation after a hybrid cut (optimize3d.cpp). Starting from the nodes the cut
// created, moved or separated, every node of an element with q* below quality_target tries to
// raise the worst q* around it: ascent along the gradient of its worst element's q*, a damped
// spring step toward the local mean edge length, a push away from the face opposite it in its
// worst element, each at decreasing lengths. A move is kept only if no incident tet inverts
// and the worst incident q* rises, so the local minimum quality never drops. Interior nodes
// move freely but never onto or across the cut; nodes on the cut slide within the cut plane
// (move_cut_nodes; rim nodes, also on the outer boundary, stay); other boundary nodes slide
// where their boundary is flat (move_boundary_nodes, boundary_flat_deg), perpendicular to
// their area-weighted normal, which keeps the volume exactly. Nodes whose neighbours moved
// are tried again; sweeps stop when the largest move is below stop_fraction * mean edge
// length, or after max_iterations. Before and after the moves, nodes within collapse_fraction
// of the local edge length of the cut that have tets with three nodes on it move onto it (the
// tets that go flat are removed), and short or poor edges with an end on the cut collapse
// into that end (see optimize3d.cpp). Slivers near the cut (q*
// below peel_quality) with a boundary face are peeled off (removed) where the mesh stays
// manifold: flat tets left where the cut meets the boundary at a shallow angle, which no move
// can repair; their volume is tiny (Cut3DReport::peeled_volume). 0 disables peeling.
// Local: one O(#T) node->tet pass, no whole-mesh sweep.
struct Optimize3DOptions {
  bool enabled = true;
  int rings = 2;  // nodes up to this many edge steps from what the cut touched may move
  double step_gain = 0.3;
  double stop_fraction = 0.02;
  int max_iterations = 8;
  // Each move iteration's nodes are split into two parts with no neighbours in common, each
  // moving within half of the move budget left, then the rest, split again; lists shorter
  // than this move one node after another. The split sets the move order, so it is part of
  // the result. 0 or 1: always split where a split leaves both parts nodes.
  int parallel_min_nodes = 8;
  double quality_target = 0.12;  // q* in [0, 1/3]; nodes with better neighbourhoods stay
  bool move_cut_nodes = true;
  bool move_boundary_nodes = true;
  double boundary_flat_deg = 20.0;
  // The next five options and collapse_volume_fraction_of_edge_tet act on curved cut surfaces
  // only (shaving sweeps); plane cuts are unaffected.
  // Curved boundaries: a boundary node off the cut whose faces are within this angle of
  // their mean normal (but not within boundary_flat_deg) moves on its boundary faces as they
  // are (the tangent move is put back onto the nearest of them), which keeps the boundary's
  // shape to within the chords; a node on a curved cut slides on the cut where its cut faces
  // are within this angle. Below boundary_flat_deg: as that.
  double boundary_curved_deg = 50.0;
  // Nodes on a ridge (the rim, where the cut meets the boundary; a crease of the boundary,
  // whose faces meet at more than this angle), with exactly two ridge edges, slide along them
  // (nodes on the cut then back onto the cut). 0 keeps them fixed.
  double ridge_deg = 30.0;
  // Moves on curved surfaces (cut, curved boundary, ridges) change the volume a little (the
  // faces are chords): each by at most this fraction of a regular tet of the local edge...
  double move_volume_fraction = 0.02;
  // ... and all of them together by at most this fraction of the mesh's volume.
  double move_volume_budget = 2e-5;
  // Tets below this q* near the cut are retriangulated with their neighbours (2-3 and 3-2
  // flips of interior faces and edges, within one material) where that raises the worst q*
  // of the tets involved. 0 disables.
  double flip_quality = 0.1;
  // Curved cuts: poor tets (q* below flip_quality) within this many edge steps of what the
  // cut touched join the repair (earlier cuts' leftovers the sweep passes near). 0: only
  // the tets around the cut.
  int repair_rings = 2;
  // Curved cuts: interior edges with 4 to 6 tets around, all of one material, are removed
  // (the ring of their other nodes triangulated as a fan, each triangle joined to both ends)
  // where that raises the worst q* of the tets involved. Needs free tet slots beyond 4.
  bool edge_removal = true;
  double peel_quality = 0.03;
  double collapse_fraction = 0.25;  // edges with an end on the cut shorter than this x their tet's mean edge
  // Curved cuts: edges of poor tets near the cut (or short ones) with neither end on the cut
  // are collapsed too (either way; within one material; a boundary node only into a
  // boundary node), with the checks of the collapses on the cut.
  bool collapse_off_cut = true;
  double collapse_volume_fraction = 0.1;  // a collapse changes its star's volume by at most this
  // ... of the star or, where the star is smaller, of a regular tet with the cut's local edge.
  bool collapse_volume_fraction_of_edge_tet = true;
  // Collapses and snaps (on and off the cut) also bound each material's change: per material
  // label, the volume of its tets in the star (a changed tet keeps its label, a dying tet's
  // volume goes) changes by at most collapse_volume_fraction of the reference below. Without
  // it a collapse or snap across the myoma/myometrium interface moves the interface while
  // keeping the total (the default scene turned ~200 mm3 of myoma into myometrium that way).
  //   Off:     no per-material limit (the total's limit only).
  //   OwnPart: that material's part of the star (or the edge tet, as above).
  //   Star:    the whole star (or the edge tet), as the total's limit: a small sliver of
  //            another material in the star does not block the operation.
  enum class MaterialLimit { Off, OwnPart, Star };
  MaterialLimit collapse_material_limit = MaterialLimit::OwnPart;
  double volume_budget = 5e-4;  // peeling + collapses change the mesh volume by at most this (relative)
  // Curved cuts: volume_budget and move_volume_budget bound the net change of the volume
  // (collapses and moves add and remove volume locally); the sum of the absolute changes
  // may reach this x the budget. Plane cuts: the sum of the absolute changes (as 1).
  double volume_churn_factor = 4.0;
  // Curved cuts, last: flaps (flap_peel.cpp). Tets below this q* with a node within
  // flap_rings edge steps of what the cut touched, connected through faces, are removed
  // together where the group touches the boundary, its volume is at most flap_group_volume x
  // a regular tet of the cut's local edge (all groups of one cut: flap_pass_volume x that),
  // the mesh stays manifold (a node whose star falls apart also loses its smaller pieces, up
  // to flap_max_tets tets in the group) and the group is no bridge between large parts. Thin
  // wedges the sweep leaves against an earlier cut or the boundary (a fan of flat tets around
  // a node a few hundredths of a millimetre off the cut, knife edges) that no move, collapse
  // or single-tet peel can repair; the loop vaporises such tissue. 0 disables.
  // The group limit covers a flat tet whose repair takes the smaller pieces of a pinched
  // star with it (default scene: 0.17 -> 2.7, 0.7 -> 3.2 and 0.4 -> 6.4 regular tets at the
  // myoma's base).
  // Last, tets still below flap_quality have their edges collapsed once more (the checks of
  // the collapses above), now letting a node of the removed tets whose star was already not
  // a manifold one (earlier cuts left two sheets of the boundary touching there; every
  // collapse at it was refused) stay so, no worse: no more pieces of its star, no more
  // boundary loops around it (default scene: a 0.055 mm edge on the cut, q* 0.0026 -> 0.032).
  // A group with no boundary face (poor tets inside a wedge whose every node is on the
  // boundary, the tets between them and the surface a little better) takes the layer of its
  // face neighbours that have a boundary face and q* below quality_target, and is removed
  // only if the grown group (repairs included) is at most flap_grow_factor x its own volume
  // (a wedge, not a poor tet in thick tissue); 0: such groups stay (chips-left course of the
  // default scene, pass 59: q* 0.0196 -> 0.0295).
  double flap_quality = 0.03;
  int flap_rings = 1;
  double flap_group_volume = 7.0;
  double flap_pass_volume = 8.0;
  int flap_max_tets = 24;
  double flap_grow_factor = 3.0;
  // Last: each material label's volume is brought back to what the cut's input had (peels,
  // flaps, collapses and boundary moves lose or gain some), by moving the region's boundary
  // nodes whose live tets all have that label along their volume gradients: the smallest
  // moves (least squares) that restore it, each refused where a tet would invert or the worst
  // q* around the node would fall below min(before, the region's worst q*), so the mesh's
  // worst q* does not fall. What one material gained from another goes back across
  // their interface first. Within keep_volume_tolerance of the mesh's volume; a node moves at
  // most keep_volume_step x the cut's local edge; the nodes that move lie off the cut, within
  // keep_volume_rings (then twice that) edge steps of the optimised region.
  bool keep_volume = true;
  double keep_volume_tolerance = 1e-7;
  double keep_volume_step = 0.1;
  int keep_volume_rings = 2;
};

struct Cut3DOptions {
  CutMethod method = CutMethod::Hybrid;
  // Hybrid: a crossing at a fraction t < snap_region of the edge from a node snaps that node.
  // Snap uses 0.5 (always the nearer node); Standard and Delete never snap.
  double snap_region = 0.45;
  double feature_angle_deg = 30.0;  // boundary nodes move only where their boundary is flatter
  double min_quality = 0.08;        // q* floor for snapping (see step 2), q* in [0, 1/3]
  double min_edge_fraction = 0.3;   // a snapped node's edges keep >= this fraction of their length
  // Hybrid, last resort: a crossing still within this fraction of the edge from a node after
  // snapping, the away move and ridge/feature sliding were all tried and refused (or could not
  // apply: a boundary node where the cut is nearly tangent to the boundary, a corner) is moved
  // into that node: the cut passes through the node, which keeps its place. This avoids tiny
  // edges and slivers; the cut surface is then approximated locally.
  // Validity rule with routing: a routed node lies at most fraction * |e| from the cut
  // (Cut3DReport::max_route_deviation_mm gives the largest distance), and only the elements
  // touching a routed node may straddle the cut, by at most that node's distance; so
  // countStraddling / countFacesSharedAcross hold with eps = max_route_deviation_mm (and exactly,
  // eps ~ 0, when routed_nodes == 0). Volume is unaffected (routed nodes do not move).
  // 0 (the default) disables it. Uterus mesh, 100 random planes each with seeds 7 / 11, with
  // the optimisation (peeling, collapses, moves): the worst q*_min ratio is 0.09 / 0.24 without
  // routing (3 + 1 of 200 planes below 0.25) and 0.45 / 0.34 with 0.1 (none below); the worst
  // min edge ratio 0.07 / 0.10 without, 0.33 / 0.38 with; routed nodes <= 0.41 mm off the
  // plane. What routing removes: cuts passing within a few percent of an edge of a corner
  // node of the boundary (a Gmsh geometry point), which neither snaps nor slides.
  double through_node_fraction = 0.0;
  // Hybrid, plane cuts: a node that could not be snapped and whose crossed edge is still cut
  // within away_fraction * |e| of it moves AWAY from the plane (interior node: along the
  // normal; flat boundary node: within its tangent plane; ridge node: along a ridge edge),
  // just far enough that every crossing on its edges lies at >= away_fraction of the edge
  // (or at 3/4 ... 1/4 of that if the full move is refused). Exact: the cut is still the plane.
  // The move passes the same guard as a snap. 0 disables it.
  double away_fraction = 0.2;
  // Hybrid: a feature node may slide along one of its feature edges (onto the cut, or away
  // from it), which keeps it on the feature lines: along a straight ridge as far as a
  // boundary node may, at a corner or a bent ridge at most this fraction of the edge. That
  // moves the corner, so the volume is no longer exact (~1e-4 on the uterus mesh); 0 keeps
  // corners and bent ridges fixed. Corners of flat facets
  // (every boundary face around the node coplanar with a neighbouring boundary face, as on a
  // box) never slide, so flat-sided meshes keep their volume exactly.
  double feature_slide_fraction = 0.15;
  double on_surface_tolerance = 1e-9;  // eps relative to the mesh bounding-box diagonal
  bool separate = true;             // duplicate the nodes on the cut
  Optimize3DOptions optimize;       // Hybrid only
  // Optional (hybrid): the nodes that hold the tissue in place. Given, the pieces the cut
  // cuts off (node-connected parts of the cut mesh with no anchored node, such as a chip
  // the caller removes) are left as the cut made them: the optimisation works on the rest
  // only, and its budgets are the rest's. They stay in the result, valid as the cut left
  // them. anchored_nodes: a flag per input node (missing entries: not anchored), for the
  // nodes the cut left where they were; anchored_at: for the nodes it made, moved or put on
  // the cut, by their position (unset: not anchored). A piece counts as cut off only when
  // the search has seen all of it; it gives up (and optimises the piece) after
  // free_piece_search_limit nodes in all, and does not look into the last piece left open.
  const std::vector<std::uint8_t>* anchored_nodes = nullptr;
  std::function<bool(const Eigen::Vector3d&)> anchored_at;
  int free_piece_search_limit = 20000;
};

// The paper's four rotationally invariant cases of a tet the cut passes through: after
// snapping, zero to three of its nodes lie on the cut and are separated there; the rest of
// the tet is subdivided (Cut3DReport::tets_by_case).
enum class TetCutCase : int { NoNodeSeparated = 0, OneNodeSeparated = 1, TwoNodesSeparated = 2, ThreeNodesSeparated = 3 };

// One material label's volume in the input and output mesh of a cut (Cut3DReport).
struct MaterialVolume {
  std::int32_t label = 0;  // TetMesh::material
  double before = 0, after = 0;
  double drift() const { return before - after; }
};

struct Cut3DReport {
  int crossed_edges = 0;      // before any snapping
  int crossed_elements = 0;   // tets with nodes strictly on both sides
  int snapped_nodes = 0;
  int boundary_snaps = 0;     // of which moved within the boundary surface
  int refused_snaps = 0;      // candidates refused by the quality/inversion guard
  int feature_skips = 0;      // boundary candidates not moved: at a feature, or cut ~parallel
  int away_moves = 0;         // unsnapped nodes moved away from the plane (away_fraction)
  int ridge_snaps = 0;        // feature nodes slid along a ridge edge onto the cut
  int routed_nodes = 0;       // unmoved nodes the cut was routed through (through_node_fraction)
  double max_route_deviation_mm = 0;  // largest distance of a routed node from the cut surface
  int split_edges = 0;        // new nodes on edges
  int split_elements = 0;     // original tets subdivided
  // Crossed tets the cut still passes through after snapping (an edge still crossed, or a
  // face on the cut), by TetCutCase; not counted for Delete.
  std::array<int, 4> tets_by_case{};
  int deleted_elements = 0;
  int duplicated_nodes = 0;
  int cut_faces = 0;          // interior faces on the cut (now separated)
  int optimized_nodes = 0;
  int collapsed_edges = 0;    // edges on the cut collapsed by the optimisation
  int late_snaps = 0;         // nodes near the cut the optimisation moved onto it
  int peeled_elements = 0;    // slivers removed by the optimisation
  double peeled_volume = 0;   // their volume
  double volume_restored = 0;  // volume the optimisation's last step put back (keep_volume)
  int volume_moves = 0;        // the boundary node moves that did it
  int flap_peeled = 0;        // of the peeled elements, those removed in flaps (flap_quality)
  int optimize_iterations = 0;
  int cut_off_pieces = 0;     // pieces left out of the optimisation (anchored_nodes)
  int cut_off_elements = 0;   // their tets
  double cut_off_volume = 0;  // their volume (in volume_after: they stay in the output)
  // Volume kept: the output holds every piece, detached ones included, so what the input
  // had and the output lacks is tissue the cut lost, peeled slivers and flaps included
  // (peeled_volume); positive: lost. Per material label, ascending by label.
  double volume_before = 0, volume_after = 0, volume_drift = 0;
  std::vector<MaterialVolume> material_volumes;
  double cut_ms = 0, optimize_ms = 0;
  // Wall time of the steps (ms), for profiling: classification (with the node -> tets lists
  // and the work arrays), snapping (with moving away and routing), subdivision, separation,
  // assembly (the output arrays, the node -> tets lists patched, the pieces cut off), the
  // compaction after the optimisation; and of the optimisation's edge collapses, late snaps,
  // move loop and volume kept (parts of optimize_ms).
  double classify_ms = 0, snap_ms = 0, subdivide_ms = 0, separate_ms = 0, assemble_ms = 0, compact_ms = 0;
  double collapse_ms = 0, late_snap_ms = 0, move_ms = 0, keep_volume_ms = 0;
};

struct Cut3DResult {
  TetMesh mesh;
  TopologyChange change;
  Cut3DReport report;
};

// Cuts a valid, positively oriented tet mesh. Unchanged tets keep their index; a subdivided
// tet's index is reused by one of its pieces (it is still listed as removed, and the piece
// as added); new nodes are appended. Delete compacts both arrays.
Result<Cut3DResult> cut3d(const TetMesh& mesh, const CutSurface& surface, const Cut3DOptions& options = {});

// Connected components through shared faces (all three node indices equal).
struct Components3D {
  Eigen::VectorXi label;        // #T component of each tet, 0..count-1
  int count = 0;
  std::vector<double> volume;   // per component
  std::vector<int> elements;    // per component
  std::vector<bool> free;       // per component: touches no anchored node (a detached piece)
};
// `anchored`: node indices held fixed (may be empty: then every component is free).
Components3D tetComponents(const TetMesh& mesh, const std::vector<int>& anchored = {});

double totalVolume(const TetMesh& mesh);
// Each material label's volume in two meshes (a cut's input and output), ascending by label;
// a label missing from one mesh has volume 0 there (material_volumes.cpp).
std::vector<MaterialVolume> materialVolumes(const TetMesh& before, const TetMesh& after);
// The same in steps: `before` of one mesh, then `after` of another added.
std::vector<MaterialVolume> materialVolumes(const TetMesh& before);
void addVolumesAfter(const TetMesh& after, std::vector<MaterialVolume>* volumes);

// Largest signed distance by which a tet has nodes strictly on both sides of a plane, as a
// check: returns the number of tets with a node > eps and a node < -eps.
int countStraddling(const TetMesh& mesh, const Eigen::Vector3d& point, const Eigen::Vector3d& normal, double eps);
// Number of interior faces (shared by two tets) whose tets lie on opposite sides of the plane.
int countFacesSharedAcross(const TetMesh& mesh, const Eigen::Vector3d& point, const Eigen::Vector3d& normal,
                           double eps);

}  // namespace hysim::cutting
