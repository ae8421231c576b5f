// Inputs checked where they enter: what is not a regular file, or is larger than the stated
// limit, is refused before it is read; unknown element types, unknown VTK versions and
// coordinates whose products would overflow are refused with file and line; text that is
// not UTF-8 is found; a cut plane's normal is normalised without overflow.
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "../common/box_mesh.hpp"
#include "hysim/cutting/cut3d.hpp"
#include "hysim/cutting/cut_surface.hpp"
#include "hysim/cutting/input_file.hpp"
#include "hysim/cutting/mesh_io.hpp"
#include "hysim/cutting/mesh_stats.hpp"

namespace hysim::cutting {
namespace {

namespace fs = std::filesystem;

std::string outputPath(const std::string& name) {
  return std::string(HYSIM_TEST_OUTPUT_DIR) + "/input_checks_" + name;
}

std::string writeText(const std::string& name, const std::string& text) {
  const std::string path = outputPath(name);
  std::ofstream(path, std::ios::binary) << text;
  return path;
}

std::string joinLines(const std::vector<std::string>& lines) {
  std::string text;
  for (const auto& line : lines) text += line + "\n";
  return text;
}

// One tet; line 13 is the element, lines 6-9 the nodes.
std::vector<std::string> goodMsh() {
  return {"$MeshFormat", "2.2 0 8", "$EndMeshFormat", "$Nodes",    "4", "1 0 0 0",           "2 1 0 0",
          "3 0 1 0",     "4 0 0 1", "$EndNodes",      "$Elements", "1", "1 4 2 1 1 1 2 3 4", "$EndElements"};
}

// Two tets; line 1 is the version line, lines 6-10 the points, 15-16 the cell types.
std::vector<std::string> goodVtk() {
  return {"# vtk DataFile Version 3.0", "two tets", "ASCII", "DATASET UNSTRUCTURED_GRID", "POINTS 5 double",
          "0 0 0", "1 0 0", "0 1 0", "0 0 1", "1 1 1", "CELLS 2 10", "4 0 1 2 3", "4 1 2 3 4", "CELL_TYPES 2",
          "10", "10"};
}

// The file with line `line` (1-based) replaced, its path and what readTetMesh says.
struct Read {
  std::string path, error;
};
Read readWithLine(std::vector<std::string> lines, const std::string& name, int line, const std::string& text) {
  lines[static_cast<std::size_t>(line - 1)] = text;
  const std::string path = writeText(name, joinLines(lines));
  const Result<TetMesh> r = readTetMesh(path);
  return {path, r.ok() ? std::string("(read ok)") : r.error()};
}

// --- files that must not be read ---------------------------------------------------------

// Reading /dev/zero never ends: the test would hang (and time out) without the check.
TEST(InputFile, DeviceIsRefusedBeforeReading) {
  const std::string expected =
      "cannot read '/dev/zero': not a regular file (a device, FIFO or socket), refused as a mesh file";
  EXPECT_EQ(readTetMesh("/dev/zero").error(), expected);
  EXPECT_EQ(readTriMesh("/dev/zero").error(), expected);
}

// Opening a FIFO without a writer blocks forever: refused before it is opened.
TEST(InputFile, FifoIsRefusedBeforeOpening) {
  const std::string path = outputPath("fifo.msh");
  fs::remove(path);
  ASSERT_EQ(mkfifo(path.c_str(), 0600), 0);
  EXPECT_EQ(readTetMesh(path).error(),
            "cannot read '" + path + "': not a regular file (a device, FIFO or socket), refused as a mesh file");
  fs::remove(path);
}

// A sparse file one byte over the 1 GiB limit takes no disk space and is refused unread.
TEST(InputFile, MeshOverTheLimitIsRefusedUnread) {
  const std::string path = writeText("huge.msh", "");
  fs::resize_file(path, kMaxMeshFileBytes + 1);
  EXPECT_EQ(readTetMesh(path).error(),
            "cannot read '" + path + "': 1073741825 bytes, more than the 1 GiB limit for a mesh file");
  fs::remove(path);
}

TEST(InputFile, LimitIsInclusive) {
  const std::string path = writeText("hundred.txt", std::string(100, 'x'));
  const Result<std::string> at = readInputFile(path, 100, "scene");
  ASSERT_TRUE(at.ok()) << at.error();
  EXPECT_EQ(*at, std::string(100, 'x'));
  EXPECT_EQ(readInputFile(path, 99, "scene").error(),
            "cannot read '" + path + "': 100 bytes, more than the 99 bytes limit for a scene file");
  EXPECT_EQ(byteSizeText(kMaxYamlFileBytes), "16 MiB");
}

// --- UTF-8 ---------------------------------------------------------------------------------

TEST(Utf8, FirstInvalidByte) {
  const std::size_t none = std::string_view::npos;
  EXPECT_EQ(firstInvalidUtf8(""), none);
  EXPECT_EQ(firstInvalidUtf8("plain ascii"), none);
  EXPECT_EQ(firstInvalidUtf8("caf\xc3\xa9 \xe2\x82\xac \xf0\x9f\x98\x80"), none);  // é € and an emoji
  EXPECT_EQ(firstInvalidUtf8("caf\xe9"), 3u);                                     // Latin-1 é
  EXPECT_EQ(firstInvalidUtf8("ab\xc3"), 2u);                                      // cut short
  EXPECT_EQ(firstInvalidUtf8("a\x80"), 1u);                                       // lone continuation
  EXPECT_EQ(firstInvalidUtf8("\xc0\xaf"), 0u);                                    // overlong '/'
  EXPECT_EQ(firstInvalidUtf8("\xe0\x80\xaf"), 0u);                                // overlong, 3 bytes
  EXPECT_EQ(firstInvalidUtf8("x\xed\xa0\x80"), 1u);                               // a surrogate
  EXPECT_EQ(firstInvalidUtf8("\xf4\x90\x80\x80"), 0u);                            // past U+10FFFF
  EXPECT_EQ(firstInvalidUtf8("\xff"), 0u);
}

// --- element types and versions ------------------------------------------------------------

TEST(MshInput, UnknownElementTypeNamesLine) {
  const Read r = readWithLine(goodMsh(), "type99.msh", 13, "1 99 2 1 1 1 2 3 4");
  EXPECT_EQ(r.error, r.path + ":13: element 1 has unknown element type 99 (MSH 2.2 defines types 1-31, 92 and 93)");
}

TEST(MshInput, IgnoredTypesAreCheckedToo) {
  // A 2-node line (type 1) given three nodes: the line is misread, whatever its type.
  auto lines = goodMsh();
  lines[11] = "2";
  lines.insert(lines.begin() + 13, "2 1 2 1 1 1 2 3");
  const std::string path = writeText("line3.msh", joinLines(lines));
  EXPECT_EQ(readTetMesh(path).error(), path + ":14: expected 2 node indices for element type 1, got 3");
  // With two nodes it is a line, ignored by the tet reader.
  lines[13] = "2 1 2 1 1 1 2";
  const Result<TetMesh> ok = readTetMesh(writeText("line2.msh", joinLines(lines)));
  ASSERT_TRUE(ok.ok()) << ok.error();
  EXPECT_EQ(ok->numTets(), 1);
}

TEST(VtkInput, VersionLineIsChecked) {
  Read r = readWithLine(goodVtk(), "v9.vtk", 1, "# vtk DataFile Version 9.0");
  EXPECT_EQ(r.error, r.path +
                         ":1: unsupported VTK version '9.0' (legacy VTK files are versions 1.0 to 5.1: "
                         "'# vtk DataFile Version 3.0')");
  r = readWithLine(goodVtk(), "vx.vtk", 1, "# vtk DataFile Version three");
  EXPECT_NE(r.error.find(":1: unsupported VTK version 'three'"), std::string::npos) << r.error;
  r = readWithLine(goodVtk(), "vnone.vtk", 1, "# vtk DataFile Version");
  EXPECT_NE(r.error.find(":1: unsupported VTK version ''"), std::string::npos) << r.error;
  for (const char* version : {"2.0", "4.2", "5.1"}) {
    r = readWithLine(goodVtk(), "vok.vtk", 1, std::string("# vtk DataFile Version ") + version);
    EXPECT_EQ(r.error, "(read ok)") << version;
  }
}

TEST(VtkInput, UnknownCellTypeNamesLine) {
  const Read r = readWithLine(goodVtk(), "cell99.vtk", 16, "99");
  EXPECT_EQ(r.error, r.path +
                         ":16: cell 1 has unknown cell type 99 (VTK cell types are 0-16, 21-37, 41, 42, 51-56 "
                         "and 60-81)");
}

// --- coordinates ---------------------------------------------------------------------------

TEST(MeshInput, CoordinatesBeyondTheBoundNameLine) {
  Read r = readWithLine(goodMsh(), "far.msh", 7, "2 1e200 0 0");
  EXPECT_EQ(r.error, r.path + ":7: coordinate '1e200' beyond +-1e+30 mm (larger values overflow volumes) for node 2");
  r = readWithLine(goodVtk(), "far.vtk", 8, "0 -1.5e30 0");
  EXPECT_EQ(r.error,
            r.path + ":8: coordinate '-1.5e30' beyond +-1e+30 mm (larger values overflow volumes) for point 2");
}

// At the bound the statistics stay finite (no inf volume, no NaN quality) and equal the
// unit tet's, since q and angles do not depend on scale.
TEST(MeshInput, StatisticsAtTheBoundAreFinite) {
  const std::string path =
      writeText("at_bound.msh", joinLines({"$MeshFormat", "2.2 0 8", "$EndMeshFormat", "$Nodes", "4",
                                           "1 -1e30 -1e30 -1e30", "2 1e30 -1e30 -1e30", "3 -1e30 1e30 -1e30",
                                           "4 -1e30 -1e30 1e30", "$EndNodes", "$Elements", "1",
                                           "1 4 2 1 1 1 2 3 4", "$EndElements"}));
  const Result<TetMesh> far = readTetMesh(path);
  ASSERT_TRUE(far.ok()) << far.error();
  const MeshStats s = computeStats(*far);
  for (double v : {s.size_min, s.size_mean, s.edge_min, s.edge_mean, s.q_min, s.q_mean, s.dihedral_min_deg}) {
    EXPECT_TRUE(std::isfinite(v)) << v;
  }
  EXPECT_NEAR(s.size_min, 8e90 / 6.0, 1e78);
  const Result<TetMesh> unit = readTetMesh(writeText("unit.msh", joinLines(goodMsh())));
  ASSERT_TRUE(unit.ok()) << unit.error();
  EXPECT_NEAR(s.q_min, computeStats(*unit).q_min, 1e-12);
  EXPECT_NEAR(s.dihedral_min_deg, computeStats(*unit).dihedral_min_deg, 1e-9);
}

// --- cut planes ----------------------------------------------------------------------------

TEST(CutPlane, NormalIsNormalisedWithoutOverflow) {
  const Eigen::Vector3d p(0.5, 0.5, 0.5);
  for (const Eigen::Vector3d& n : {Eigen::Vector3d(0, 0, 1e300), Eigen::Vector3d(0, 0, 1e-300),
                                   Eigen::Vector3d(0, 0, 4.9e-324)}) {
    const auto plane = CutSurface::plane(p, n);
    ASSERT_TRUE(plane.ok()) << plane.error();
    EXPECT_EQ(plane->planeNormal(), Eigen::Vector3d(0, 0, 1)) << n.transpose();
  }
  const auto big = CutSurface::plane(p, Eigen::Vector3d(1e300, 1e300, 0));
  ASSERT_TRUE(big.ok());
  EXPECT_NEAR(big->planeNormal().x(), std::sqrt(0.5), 1e-15);
  // An ordinary normal gives the plain quotient, bit for bit, as before.
  const Eigen::Vector3d n(0.15, 0.1, 1.0);
  EXPECT_EQ(CutSurface::plane(p, n)->planeNormal(), Eigen::Vector3d(n / n.norm()));
  EXPECT_EQ(CutSurface::plane(p, Eigen::Vector3d::Zero()).error(), "cut plane: zero normal");
  EXPECT_EQ(CutSurface::plane(Eigen::Vector3d(2e30, 0, 0), n).error(),
            "cut plane: point coordinate beyond +-1e30 mm (larger values overflow distances)");
}

// The reported defect: a normal whose squared length overflows cut every tet free. Now it
// is the same cut as with the unit normal.
TEST(CutPlane, HugeNormalCutsLikeTheUnitNormal) {
  const TetMesh box = testing::boxTetMesh(4, 4, 4, 0.25);
  const Eigen::Vector3d p(0.5, 0.5, 0.43);
  const auto unit = cut3d(box, *CutSurface::plane(p, Eigen::Vector3d(0, 0, 1)), {});
  const auto huge = cut3d(box, *CutSurface::plane(p, Eigen::Vector3d(0, 0, 1e300)), {});
  ASSERT_TRUE(unit.ok()) << unit.error();
  ASSERT_TRUE(huge.ok()) << huge.error();
  EXPECT_EQ(huge->mesh.X, unit->mesh.X);
  EXPECT_EQ(huge->mesh.T, unit->mesh.T);
  EXPECT_EQ(tetComponents(huge->mesh).count, 2);
}

}  // namespace
}  // namespace hysim::cutting
