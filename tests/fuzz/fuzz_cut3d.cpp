// Fuzz target: cut3d on small meshes and planes. The bytes give the method and options, a
// plane (a point and an integer normal, so planes through nodes, along edges and in face
// planes come often) and a displacement of every node of a 2x2x2-cube box (48 tets). A valid
// mesh must come out of the cut valid, or the cut must be refused with an error; anything
// else aborts, so libFuzzer reports the input.
#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>

#include "box_mesh.hpp"
#include "hysim/cutting/cut3d.hpp"

using namespace hysim::cutting;

namespace {

// Reads the input byte by byte; past its end, zeros.
struct ByteReader {
  const std::uint8_t* data;
  std::size_t size;
  std::size_t at = 0;
  std::uint8_t next() { return at < size ? data[at++] : 0; }
  double signedUnit() { return static_cast<std::int8_t>(next()) / 128.0; }  // [-1, 1)
};

Cut3DOptions optionsFrom(std::uint8_t flags) {
  static constexpr std::array<CutMethod, 4> kMethods = {CutMethod::Hybrid, CutMethod::Standard, CutMethod::Snap,
                                                         CutMethod::Delete};
  Cut3DOptions options;
  options.method = kMethods[flags & 3];
  options.separate = (flags & 4) == 0;
  if (flags & 8) options.through_node_fraction = 0.1;
  if (flags & 16) options.optimize.keep_volume = false;
  return options;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  ByteReader in{data, size};
  const Cut3DOptions options = optionsFrom(in.next());
  Eigen::Vector3d point, normal;
  for (int k = 0; k < 3; ++k) point[k] = in.next() / 64.0;  // [0, 4): the box is [0, 2]^3
  for (int k = 0; k < 3; ++k) normal[k] = static_cast<std::int8_t>(in.next());
  auto plane = CutSurface::plane(point, normal);
  if (!plane.ok()) return 0;

  TetMesh mesh = hysim::testing::boxTetMesh(2, 2, 2, 1.0);
  // Up to a quarter of the spacing, on a 1/512 grid, so nodes can land exactly on the plane.
  for (Eigen::Index i = 0; i < mesh.X.rows(); ++i)
    for (int k = 0; k < 3; ++k) mesh.X(i, k) += 0.25 * in.signedUnit();
  if (!validate(mesh).ok()) return 0;  // cut3d's precondition: a valid input mesh

  auto cut = cut3d(mesh, *plane, options);
  if (!cut.ok()) return 0;
  if (hysim::Status valid = validate(cut->mesh); !valid.ok()) {
    std::fprintf(stderr, "cut3d gave an invalid mesh: %s\n", valid.error().c_str());
    std::abort();
  }
  return 0;
}
