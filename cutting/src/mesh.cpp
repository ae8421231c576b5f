// Mesh validation, element sizes and tet-mesh boundary extraction.
//
// Manifoldness is checked on matched faces (tet_faces.hpp) and sorted edge keys rather than
// hashing: allocation-light and deterministic, and validate() runs after every cut in tests on
// 20k-tet meshes.
#include "hysim/cutting/mesh.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "hysim/cutting/tet_faces.hpp"

namespace hysim::cutting {

namespace {

std::string formatDouble(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.6g", v);
  return buf;
}

// One snprintf instead of chained `"(" + ...` concatenation, which also sidesteps GCC 12's
// false -Wrestrict positive on short string literals (GCC bug 105329).
std::string formatNode(const Positions& X, Eigen::Index i) {
  char buf[96];
  std::snprintf(buf, sizeof buf, "(%.6g, %.6g, %.6g)", X(i, 0), X(i, 1), X(i, 2));
  return buf;
}

// Messages are built only on failure; these two keep the hot loops free of string work.
std::string faceText(const std::array<std::int32_t, 3>& f) {
  char buf[48];
  std::snprintf(buf, sizeof buf, "(%d, %d, %d)", f[0], f[1], f[2]);
  return buf;
}

std::string edgeText(std::int32_t a, std::int32_t b) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "(%d, %d)", a, b);
  return buf;
}

Error makeError(std::string message) { return Error{std::move(message)}; }

// Shared by both mesh types: label array size and finite coordinates.
Status validateNodesAndLabels(const Positions& X, Eigen::Index numElements, const Labels& material,
                              const char* elementName) {
  if (material.rows() != numElements) {
    return makeError("material has " + std::to_string(material.rows()) + " labels but the mesh has " +
                     std::to_string(numElements) + " " + elementName + "s");
  }
  for (Eigen::Index i = 0; i < X.rows(); ++i) {
    if (!std::isfinite(X(i, 0)) || !std::isfinite(X(i, 1)) || !std::isfinite(X(i, 2))) {
      return makeError("node " + std::to_string(i) + ": non-finite coordinate " + formatNode(X, i));
    }
  }
  return Status::Ok();
}

// Index range and repeated-node check for one element row.
template <class Row>
Status validateElementIndices(const Row& row, Eigen::Index numNodes, const char* elementName,
                              Eigen::Index e) {
  const int n = static_cast<int>(row.size());
  for (int j = 0; j < n; ++j) {
    if (row(j) < 0 || row(j) >= numNodes) {
      return makeError(std::string(elementName) + " " + std::to_string(e) + ": node index " +
                       std::to_string(row(j)) + " out of range [0, " + std::to_string(numNodes) + ")");
    }
  }
  for (int j = 0; j < n; ++j) {
    for (int k = j + 1; k < n; ++k) {
      if (row(j) == row(k)) {
        return makeError(std::string(elementName) + " " + std::to_string(e) + ": node " +
                         std::to_string(row(j)) + " repeated");
      }
    }
  }
  return Status::Ok();
}

Status validateAllNodesUsed(Eigen::Index numNodes, const std::vector<char>& used) {
  for (Eigen::Index i = 0; i < numNodes; ++i) {
    if (!used[static_cast<std::size_t>(i)]) {
      return makeError("node " + std::to_string(i) + ": not used by any element");
    }
  }
  return Status::Ok();
}

double signedTriAreaXY(const Positions& X, const Tris& F, Eigen::Index f) {
  const Eigen::Vector3d a = X.row(F(f, 0));
  const Eigen::Vector3d b = X.row(F(f, 1));
  const Eigen::Vector3d c = X.row(F(f, 2));
  return 0.5 * ((b.x() - a.x()) * (c.y() - a.y()) - (b.y() - a.y()) * (c.x() - a.x()));
}

double unsignedTriArea(const Positions& X, const Tris& F, Eigen::Index f) {
  const Eigen::Vector3d a = X.row(F(f, 0));
  const Eigen::Vector3d b = X.row(F(f, 1));
  const Eigen::Vector3d c = X.row(F(f, 2));
  return 0.5 * (b - a).cross(c - a).norm();
}

}  // namespace

bool TriMesh::isPlanar() const {
  for (Eigen::Index i = 0; i < X.rows(); ++i) {
    if (X(i, 2) != 0.0) return false;
  }
  return true;
}

double tetVolume(const TetMesh& mesh, int t) {
  const Eigen::Vector3d x0 = mesh.X.row(mesh.T(t, 0));
  const Eigen::Vector3d x1 = mesh.X.row(mesh.T(t, 1));
  const Eigen::Vector3d x2 = mesh.X.row(mesh.T(t, 2));
  const Eigen::Vector3d x3 = mesh.X.row(mesh.T(t, 3));
  return (x1 - x0).dot((x2 - x0).cross(x3 - x0)) / 6.0;
}

double triArea(const TriMesh& mesh, int f) {
  // Planarity is decided per triangle (all three nodes at z == 0), not per mesh: checking
  // the whole mesh would make this O(#N) per call. For a planar mesh this is the same.
  const bool planar =
      mesh.X(mesh.F(f, 0), 2) == 0.0 && mesh.X(mesh.F(f, 1), 2) == 0.0 && mesh.X(mesh.F(f, 2), 2) == 0.0;
  return planar ? signedTriAreaXY(mesh.X, mesh.F, f) : unsignedTriArea(mesh.X, mesh.F, f);
}

namespace {

// Sorts three ids and reports whether the sorting permutation is even: two correctly
// oriented tets sharing a face see it with opposite parity.
inline bool sortThreeWithParity(std::array<std::int32_t, 3>& v) {
  bool even = true;
  if (v[0] > v[1]) {
    std::swap(v[0], v[1]);
    even = !even;
  }
  if (v[1] > v[2]) {
    std::swap(v[1], v[2]);
    even = !even;
  }
  if (v[0] > v[1]) {
    std::swap(v[0], v[1]);
    even = !even;
  }
  return even;
}

// Face `slot` (4 t + k) of a tet as sorted node ids; returns the parity of its orientation.
bool sortedFace(const Tets& T, int slot, std::array<std::int32_t, 3>& sorted) {
  const int t = slot / 4;
  const int* local = kTetFace[slot % 4];
  sorted = {T(t, local[0]), T(t, local[1]), T(t, local[2])};
  return sortThreeWithParity(sorted);
}

// Every face of at most two tets, of opposite orientation (indices already checked).
Status validateFaces(const TetMesh& mesh) {
  std::vector<int> next;
  matchFaces(mesh, next);
  for (int s = 0; s < static_cast<int>(next.size()); ++s) {
    const int p = next[s];
    if (p <= s) continue;  // boundary, or the last slot of its face's cycle
    std::array<std::int32_t, 3> face{}, other{};
    const bool even = sortedFace(mesh.T, s, face);
    if (next[p] != s) {
      return makeError("tet " + std::to_string(next[p] / 4) + ": face " + faceText(face) +
                       " is shared by more than 2 tets (" + std::to_string(s / 4) + ", " + std::to_string(p / 4) +
                       ", " + std::to_string(next[p] / 4) + "): non-manifold");
    }
    if (sortedFace(mesh.T, p, other) == even) {
      return makeError("tet " + std::to_string(p / 4) + ": face " + faceText(face) + " shared with tet " +
                       std::to_string(s / 4) +
                       " with the same orientation (inconsistent orientation or duplicate tet)");
    }
  }
  return Status::Ok();
}

}  // namespace

Status validate(const TetMesh& mesh, const ValidateOptions& options) {
  const Eigen::Index numNodes = mesh.X.rows();
  const Eigen::Index numTets = mesh.T.rows();
  if (Status s = validateNodesAndLabels(mesh.X, numTets, mesh.material, "tet"); !s) return s;

  std::vector<char> used(static_cast<std::size_t>(numNodes), 0);
  for (Eigen::Index t = 0; t < numTets; ++t) {
    if (Status s = validateElementIndices(mesh.T.row(t), numNodes, "tet", t); !s) return s;
    for (int j = 0; j < 4; ++j) used[static_cast<std::size_t>(mesh.T(t, j))] = 1;
  }
  for (Eigen::Index t = 0; t < numTets; ++t) {
    const double volume = tetVolume(mesh, static_cast<int>(t));
    if (!(volume > options.minSignedSize)) {
      return makeError("tet " + std::to_string(t) + ": " + (volume < 0 ? "inverted" : "degenerate") +
                       " (signed volume " + formatDouble(volume) +
                       " <= " + formatDouble(options.minSignedSize) + ")");
    }
  }

  if (Status s = validateFaces(mesh); !s) return s;

  if (options.requireAllNodesUsed) {
    if (Status s = validateAllNodesUsed(numNodes, used); !s) return s;
  }
  return Status::Ok();
}

Status validate(const TriMesh& mesh, const ValidateOptions& options) {
  const Eigen::Index numNodes = mesh.X.rows();
  const Eigen::Index numTris = mesh.F.rows();
  if (Status s = validateNodesAndLabels(mesh.X, numTris, mesh.material, "triangle"); !s) return s;

  std::vector<char> used(static_cast<std::size_t>(numNodes), 0);
  for (Eigen::Index f = 0; f < numTris; ++f) {
    if (Status s = validateElementIndices(mesh.F.row(f), numNodes, "triangle", f); !s) return s;
    for (int j = 0; j < 3; ++j) used[static_cast<std::size_t>(mesh.F(f, j))] = 1;
  }
  // Planar meshes must be counter-clockwise seen from +z; surfaces in 3D have no preferred
  // side, so only their (unsigned) area is checked.
  const bool planar = mesh.isPlanar();
  for (Eigen::Index f = 0; f < numTris; ++f) {
    const double area = planar ? signedTriAreaXY(mesh.X, mesh.F, f) : unsignedTriArea(mesh.X, mesh.F, f);
    if (!(area > options.minSignedSize)) {
      return makeError("triangle " + std::to_string(f) + ": " +
                       (area < 0 ? "inverted (clockwise seen from +z)" : "degenerate") + " (signed area " +
                       formatDouble(area) + " <= " + formatDouble(options.minSignedSize) + ")");
    }
  }

  // Directed edge (a -> b) keyed by (min, max); `forward` is a < b.
  struct EdgeKey {
    std::int32_t lo, hi, tri;
    bool forward;
  };
  std::vector<EdgeKey> keys;
  keys.reserve(static_cast<std::size_t>(numTris) * 3);
  for (Eigen::Index f = 0; f < numTris; ++f) {
    for (int j = 0; j < 3; ++j) {
      const std::int32_t a = mesh.F(f, j);
      const std::int32_t b = mesh.F(f, (j + 1) % 3);
      keys.push_back({std::min(a, b), std::max(a, b), static_cast<std::int32_t>(f), a < b});
    }
  }
  std::sort(keys.begin(), keys.end(), [](const EdgeKey& a, const EdgeKey& b) {
    if (a.lo != b.lo) return a.lo < b.lo;
    if (a.hi != b.hi) return a.hi < b.hi;
    return a.tri < b.tri;
  });
  for (std::size_t i = 0; i < keys.size();) {
    std::size_t j = i + 1;
    while (j < keys.size() && keys[j].lo == keys[i].lo && keys[j].hi == keys[i].hi) ++j;
    if (j - i > 2) {
      return makeError("triangle " + std::to_string(keys[i + 2].tri) + ": edge " +
                       edgeText(keys[i].lo, keys[i].hi) + " is shared by more than 2 triangles (" +
                       std::to_string(keys[i].tri) + ", " + std::to_string(keys[i + 1].tri) + ", " +
                       std::to_string(keys[i + 2].tri) + "): non-manifold");
    }
    if (j - i == 2 && keys[i].forward == keys[i + 1].forward) {
      return makeError("triangle " + std::to_string(keys[i + 1].tri) + ": edge " +
                       edgeText(keys[i].lo, keys[i].hi) + " shared with triangle " +
                       std::to_string(keys[i].tri) +
                       " in the same direction (inconsistent orientation or duplicate triangle)");
    }
    i = j;
  }

  if (options.requireAllNodesUsed) {
    if (Status s = validateAllNodesUsed(numNodes, used); !s) return s;
  }
  return Status::Ok();
}

Tris boundaryFaces(const TetMesh& mesh, Eigen::VectorXi* faceTet) {
  // In tet order, which is stable under unrelated edits elsewhere in the mesh.
  std::vector<int> next;
  matchFacesOfAnyIds(mesh, next);
  std::vector<std::uint8_t> boundary(next.size());
  for (size_t s = 0; s < next.size(); ++s) boundary[s] = next[s] < 0;
  Tris faces;
  Eigen::VectorXi faceTetHere;
  boundaryFromSlots(mesh, boundary, faces, faceTetHere);
  if (faceTet) *faceTet = std::move(faceTetHere);
  return faces;
}

}  // namespace hysim::cutting
