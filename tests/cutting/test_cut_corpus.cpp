// Meshes from other meshers (issue 34): every corpus mesh (tests/data/corpus: TetGen, Gmsh,
// CGAL Mesh_3; tools/make-corpus) is there and valid, and a sample of the cuts bench/cut_corpus
// measures (the first 8 planes and 4 curved surfaces of each mesh: one of each surface kind)
// leaves a valid mesh whose pieces are separated: the properties that must hold for every
// cut. The quality bounds are measured, not asserted, by bench/cut_corpus (docs/cutting.md).
// Known open: partial curved cuts where the optimisation joins the two sides of the crack
// again (kOpenSeparation); there the cut without the optimisation must separate, and the
// test fails once the optimised one does too, so that the entry is removed.
#include <gtest/gtest.h>

#include <filesystem>
#include <set>
#include <string>

#include "cut_checks.hpp"
#include "hysim/cutting/mesh_io.hpp"

namespace hysim::cutting {
namespace {

std::string corpusPath(const testing::CorpusMesh& m) {
  return std::string(HYSIM_TEST_DATA_DIR) + "/corpus/" + m.file;
}

TEST(CutCorpus, MeshesExistAndAreValid) {
  for (const auto& m : testing::kCorpus) {
    SCOPED_TRACE(m.file);
    ASSERT_TRUE(std::filesystem::exists(corpusPath(m)));
    auto mesh = readTetMesh(corpusPath(m));
    ASSERT_TRUE(mesh.ok()) << mesh.error();
    EXPECT_TRUE(validate(*mesh).ok());
    EXPECT_GE(mesh->numTets(), 2000);
    EXPECT_LE(mesh->numTets(), 8000);
  }
}

// Partial curved cuts of the sample after which an edge of the result crosses the cut
// surface: the optimisation's collapses and moves
// near the crack reconnect its sides (docs/cutting.md, "Meshes from other meshers").
const std::set<std::string> kOpenSeparation = {"tetgen_ellipsoid_noq.msh surface:3", "gmsh_ellipsoid.msh surface:1"};

void expectValidAndSeparated(const TetMesh& mesh, const testing::MeshBaseline& base, const testing::CorpusCut& cut,
                             const std::string& what) {
  const auto r = testing::measureCut(mesh, base, cut);
  ASSERT_TRUE(r.error.empty()) << what << ": " << r.error;
  EXPECT_TRUE(r.invalid.empty()) << what << ": " << r.invalid;
  if (r.complete) {
    EXPECT_GE(r.components, 2) << what;
  }
  if (!kOpenSeparation.count(what)) {
    EXPECT_EQ(r.crossing_edges, 0) << what << ": deepest crossing " << r.max_depth << " mm";
    return;
  }
  EXPECT_GT(r.crossing_edges, 0) << what << " is separated now: remove it from kOpenSeparation";
  Cut3DOptions plain;
  plain.optimize.enabled = false;
  const auto bare = cut3d(mesh, testing::corpusCutSurface(cut), plain);
  ASSERT_TRUE(bare.ok()) << bare.error();
  int crossing = 0;
  double depth = 0;
  testing::detail::crossingEdges(bare->mesh, cut, testing::corpusCutSurface(cut),
                                 testing::separationTolerance(base, cut.kind == testing::CutKind::Plane), &crossing,
                                 &depth);
  EXPECT_EQ(crossing, 0) << what << " without the optimisation: deepest crossing " << depth << " mm";
}

TEST(CutCorpus, SampleCutsAreValidAndSeparated) {
  for (int i = 0; i < static_cast<int>(testing::kCorpus.size()); ++i) {
    const auto& m = testing::kCorpus[i];
    auto mesh = readTetMesh(corpusPath(m));
    ASSERT_TRUE(mesh.ok()) << mesh.error();
    const auto base = testing::meshBaseline(*mesh);
    for (int k = 0; k < 8; ++k)
      expectValidAndSeparated(*mesh, base, testing::corpusPlane(*mesh, i, k),
                              std::string(m.file) + " plane:" + std::to_string(k));
    for (int k = 0; k < 4; ++k)
      expectValidAndSeparated(*mesh, base, testing::corpusSurface(*mesh, i, k),
                              std::string(m.file) + " surface:" + std::to_string(k));
  }
}

}  // namespace
}  // namespace hysim::cutting
