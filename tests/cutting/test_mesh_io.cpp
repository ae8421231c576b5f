// MSH 2.2 and legacy VTK reading/writing: exact round trips, files from other tools, and
// every reader error path with its file:line message.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <numbers>
#include <sstream>
#include <string>
#include <vector>

#include "../common/box_mesh.hpp"
#include "hysim/cutting/mesh_io.hpp"

namespace hysim::cutting {
namespace {

std::string outputPath(const std::string& name) {
  return std::string(HYSIM_TEST_OUTPUT_DIR) + "/cutting_io_" + name;
}

std::string dataPath(const std::string& name) {
  return std::string(HYSIM_TEST_DATA_DIR) + "/cutting/" + name;
}

// Writes `text` to the test output folder and returns the path.
std::string writeText(const std::string& name, const std::string& text) {
  const std::string path = outputPath(name);
  std::ofstream out(path, std::ios::binary);
  out << text;
  return path;
}

std::string readText(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream buffer;
  buffer << in.rdbuf();
  return buffer.str();
}

// Values that only survive a text round trip when printed with 17 significant digits.
TetMesh awkwardTetMesh() {
  TetMesh m;
  m.X.resize(6, 3);
  m.X << 1.0 / 3.0, -0.1, 1e-300,                          //
      1.0 + std::numeric_limits<double>::epsilon(), 0, 0,  //
      0, std::numbers::pi, 0,                              //
      -2.5e17, 0, 1,                                       //
      1, 1, 1.0 / 7.0,                                     //
      42, 42, 42;                                          // used by no tet: must be kept
  m.T.resize(2, 4);
  m.T << 0, 1, 2, 3,  //
      1, 2, 3, 4;
  m.material.resize(2);
  m.material << 3, 12;
  return m;
}

TriMesh awkwardTriMesh() {
  TriMesh m;
  m.X.resize(4, 3);
  m.X << 0.1, 0.2, 0,   //
      1.0 / 3.0, 0, 0,  //
      1, 2.0 / 3.0, 0,  //
      -1e-7, 1, 0;
  m.F.resize(2, 3);
  m.F << 0, 1, 2,  //
      0, 2, 3;
  m.material.resize(2);
  m.material << 0, 5;
  return m;
}

void expectSameMesh(const TetMesh& a, const TetMesh& b) {
  EXPECT_EQ(a.X, b.X);  // bitwise-equal doubles
  EXPECT_EQ(a.T, b.T);
  EXPECT_EQ(a.material, b.material);
}

void expectSameMesh(const TriMesh& a, const TriMesh& b) {
  EXPECT_EQ(a.X, b.X);
  EXPECT_EQ(a.F, b.F);
  EXPECT_EQ(a.material, b.material);
}

// --- round trips -----------------------------------------------------------------------

TEST(MeshIo, TetRoundTripIsExactInBothFormats) {
  const TetMesh original = awkwardTetMesh();
  for (const char* ext : {".msh", ".vtk"}) {
    SCOPED_TRACE(ext);
    const std::string path = outputPath(std::string("tet_roundtrip") + ext);
    const Status written = writeMesh(path, original);
    ASSERT_TRUE(written.ok()) << written.error();
    const Result<TetMesh> read = readTetMesh(path);
    ASSERT_TRUE(read.ok()) << read.error();
    expectSameMesh(*read, original);
  }
}

TEST(MeshIo, TriRoundTripIsExactInBothFormats) {
  const TriMesh original = awkwardTriMesh();
  for (const char* ext : {".msh", ".vtk"}) {
    SCOPED_TRACE(ext);
    const std::string path = outputPath(std::string("tri_roundtrip") + ext);
    const Status written = writeMesh(path, original);
    ASSERT_TRUE(written.ok()) << written.error();
    const Result<TriMesh> read = readTriMesh(path);
    ASSERT_TRUE(read.ok()) << read.error();
    expectSameMesh(*read, original);
  }
}

TEST(MeshIo, BoxMeshRoundTripStaysValid) {
  const TetMesh box = testing::boxTetMesh(4, 3, 2, 0.1, 9);
  for (const char* ext : {".msh", ".vtk"}) {
    SCOPED_TRACE(ext);
    const std::string path = outputPath(std::string("box") + ext);
    ASSERT_TRUE(writeMesh(path, box).ok());
    const Result<TetMesh> read = readTetMesh(path);
    ASSERT_TRUE(read.ok()) << read.error();
    expectSameMesh(*read, box);
    EXPECT_TRUE(validate(*read).ok());
  }
}

TEST(MeshIo, WindowsLineEndingsAreAccepted) {
  const TetMesh original = awkwardTetMesh();
  for (const char* ext : {".msh", ".vtk"}) {
    SCOPED_TRACE(ext);
    const std::string unixPath = outputPath(std::string("crlf_source") + ext);
    ASSERT_TRUE(writeMesh(unixPath, original).ok());
    std::string text;
    for (char c : readText(unixPath)) {
      if (c == '\n') text += '\r';
      text += c;
    }
    const Result<TetMesh> read = readTetMesh(writeText(std::string("crlf") + ext, text));
    ASSERT_TRUE(read.ok()) << read.error();
    expectSameMesh(*read, original);
  }
}

TEST(MshIo, WriterLayout) {
  TetMesh m = awkwardTetMesh();
  const std::string path = outputPath("layout.msh");
  ASSERT_TRUE(writeMesh(path, m).ok());
  const std::string text = readText(path);
  EXPECT_EQ(text.rfind(
                "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n6\n1 0.33333333333333331 -0.10000000000000001 "
                "1e-300\n2 1.0000000000000002 0 0\n",
                0),
            0u)
      << text;
  // id, type 4, 2 tags (physical = elementary = material), 1-based nodes.
  EXPECT_NE(text.find("$Elements\n2\n1 4 2 3 3 1 2 3 4\n2 4 2 12 12 2 3 4 5\n$EndElements\n"),
            std::string::npos)
      << text;
}

TEST(VtkIo, WriterLayout) {
  const std::string path = outputPath("layout.vtk");
  ASSERT_TRUE(writeMesh(path, awkwardTriMesh()).ok());
  const std::string text = readText(path);
  EXPECT_EQ(text.rfind("# vtk DataFile Version 3.0\n", 0), 0u);
  EXPECT_NE(
      text.find(
          "\nASCII\nDATASET UNSTRUCTURED_GRID\nPOINTS 4 double\n0.10000000000000001 0.20000000000000001 0\n"),
      std::string::npos)
      << text;
  EXPECT_NE(text.find("\nCELLS 2 8\n3 0 1 2\n3 0 2 3\nCELL_TYPES 2\n5\n5\n"
                      "CELL_DATA 2\nSCALARS material int 1\nLOOKUP_TABLE default\n0\n5\n"),
            std::string::npos)
      << text;
}

// --- files written by other tools ------------------------------------------------------

TEST(MshIo, ReadsNonContiguousIdsMixedElementsAndExtraSections) {
  const Result<TetMesh> tets = readTetMesh(dataPath("mixed_ids.msh"));
  ASSERT_TRUE(tets.ok()) << tets.error();
  ASSERT_EQ(tets->numNodes(), 5);  // node ids 10..50 mapped to rows 0..4 in file order
  EXPECT_EQ(tets->X.row(4), Eigen::RowVector3d(1, 1, 1));
  Tets expectedTets(2, 4);
  expectedTets << 0, 1, 2, 3,  //
      1, 2, 3, 4;
  EXPECT_EQ(tets->T, expectedTets);
  EXPECT_EQ(tets->material, (Labels(2) << 7, 8).finished());  // first tag (physical)

  const Result<TriMesh> tris = readTriMesh(dataPath("mixed_ids.msh"));
  ASSERT_TRUE(tris.ok()) << tris.error();
  Tris expectedTris(2, 3);
  expectedTris << 0, 2, 1,  //
      1, 2, 3;
  EXPECT_EQ(tris->F, expectedTris);
  EXPECT_EQ(tris->material, (Labels(2) << 11, 0).finished());  // no tags: material 0
}

TEST(MeshIo, ParsingTextInMemoryMatchesReadingTheFile) {
  const std::string path = dataPath("mixed_ids.msh");
  const Result<TetMesh> read = readTetMesh(path);
  const Result<TetMesh> parsed = parseTetMesh(path, readText(path));
  ASSERT_TRUE(read.ok() && parsed.ok());
  EXPECT_EQ(parsed->X, read->X);
  EXPECT_EQ(parsed->T, read->T);
  const Result<TriMesh> tris = parseTriMesh("memory.vtk", readText(dataPath("meshio_field.vtk")));
  ASSERT_TRUE(tris.ok()) << tris.error();
  EXPECT_EQ(tris->numTris(), 1);
  const Result<TetMesh> bad = parseTetMesh("memory.msh", "$MeshFormat\n9.9 0 8\n");
  ASSERT_FALSE(bad.ok());
  EXPECT_EQ(bad.error().rfind("memory.msh:", 0), 0u) << bad.error();
}

TEST(VtkIo, ReadsVersion51OffsetsLayoutWithMetadata) {
  const Result<TetMesh> m = readTetMesh(dataPath("vtk51_offsets.vtk"));
  ASSERT_TRUE(m.ok()) << m.error();
  ASSERT_EQ(m->numNodes(), 5);
  EXPECT_EQ(m->X.row(3), Eigen::RowVector3d(0, 0, 1));
  Tets expected(2, 4);
  expected << 0, 1, 2, 3,  //
      1, 2, 3, 4;
  EXPECT_EQ(m->T, expected);
  EXPECT_EQ(m->material, (Labels(2) << 5, 6).finished());  // the line cell is skipped
}

TEST(VtkIo, ReadsMeshioFieldData) {
  const Result<TetMesh> tets = readTetMesh(dataPath("meshio_field.vtk"));
  ASSERT_TRUE(tets.ok()) << tets.error();
  EXPECT_EQ(tets->material, (Labels(2) << 7, 8).finished());
  const Result<TriMesh> tris = readTriMesh(dataPath("meshio_field.vtk"));
  ASSERT_TRUE(tris.ok()) << tris.error();
  EXPECT_EQ(tris->F, (Tris(1, 3) << 0, 2, 1).finished());
  EXPECT_EQ(tris->material, (Labels(1) << 11).finished());
}

TEST(VtkIo, ReadsFloatMaterialAndOptionalLookupTable) {
  const std::string path =
      writeText("float_material.vtk",
                "# vtk DataFile Version 2.0\n\nascii\nDATASET UNSTRUCTURED_GRID\n"
                "POINTS 3 float\n0 0 0 1 0 0 0 1 0\nCELLS 1 4\n3 0 1 2\nCELL_TYPES 1\n5\n"
                "CELL_DATA 1\nSCALARS material float\n4.0\n");
  const Result<TriMesh> m = readTriMesh(path);
  ASSERT_TRUE(m.ok()) << m.error();
  EXPECT_EQ(m->material, (Labels(1) << 4).finished());
}

TEST(MeshIo, UnknownExtensionIsRecognisedByContent) {
  const std::string msh = readText(dataPath("mixed_ids.msh"));
  const Result<TetMesh> fromMsh = readTetMesh(writeText("content_sniff.mesh", msh));
  ASSERT_TRUE(fromMsh.ok()) << fromMsh.error();
  EXPECT_EQ(fromMsh->numTets(), 2);
  const std::string path = writeText("unknown.txt", "hello\n");
  EXPECT_EQ(readTetMesh(path).error(), path + ": unknown mesh format (expected a .msh or .vtk file)");
}

// --- MSH errors ------------------------------------------------------------------------

// A valid one-tet file; tests replace single lines (1-based) to break it.
//   1 $MeshFormat / 2 2.2 0 8 / 3 $EndMeshFormat / 4 $Nodes / 5 4 / 6-9 nodes /
//   10 $EndNodes / 11 $Elements / 12 1 / 13 the tet / 14 $EndElements
std::vector<std::string> goodMshLines() {
  return {"$MeshFormat", "2.2 0 8", "$EndMeshFormat", "$Nodes",    "4", "1 0 0 0",           "2 1 0 0",
          "3 0 1 0",     "4 0 0 1", "$EndNodes",      "$Elements", "1", "1 4 2 1 1 1 2 3 4", "$EndElements"};
}

std::string joinLines(const std::vector<std::string>& lines) {
  std::string text;
  for (const auto& line : lines) text += line + "\n";
  return text;
}

// A broken file and what readTetMesh said about it.
struct BadFile {
  std::string path;
  std::string error;
};

// Writes the good file with line `lineNumber` (1-based) replaced and reads it back.
BadFile mshWithLine(const std::string& name, int lineNumber, const std::string& replacement) {
  auto lines = goodMshLines();
  lines[static_cast<std::size_t>(lineNumber - 1)] = replacement;
  const std::string path = writeText(name + ".msh", joinLines(lines));
  const Result<TetMesh> r = readTetMesh(path);
  return {path, r.ok() ? std::string("(read ok)") : r.error()};
}

TEST(MshIo, GoodFileReads) {
  const Result<TetMesh> r = readTetMesh(writeText("good.msh", joinLines(goodMshLines())));
  ASSERT_TRUE(r.ok()) << r.error();
  EXPECT_EQ(r->numTets(), 1);
  EXPECT_TRUE(validate(*r).ok());
}

TEST(MshIo, ErrorMissingFile) {
  const std::string path = outputPath("does_not_exist.msh");
  EXPECT_EQ(readTetMesh(path).error(), "cannot open '" + path + "': No such file or directory");
  EXPECT_EQ(readTriMesh(path).error(), "cannot open '" + path + "': No such file or directory");
}

TEST(MshIo, ErrorDirectoryInsteadOfFile) {
  const std::string path = std::string(HYSIM_TEST_OUTPUT_DIR);
  EXPECT_EQ(readTetMesh(path).error(), "cannot read '" + path + "': Is a directory");
}

TEST(MshIo, ErrorTetWithThreeNodes) {
  const BadFile f = mshWithLine("tet3", 13, "1 4 2 1 1 1 2 3");
  EXPECT_EQ(f.error, f.path + ":13: expected 4 node indices for tetrahedron, got 3");
}

TEST(MshIo, ErrorTriangleWithTwoNodes) {
  const BadFile f = mshWithLine("tri2", 13, "1 2 2 1 1 1 2");
  EXPECT_EQ(f.error, f.path + ":13: expected 3 node indices for triangle, got 2");
}

TEST(MshIo, ErrorNonFiniteCoordinate) {
  BadFile f = mshWithLine("nan", 8, "3 nan 1 0");
  EXPECT_EQ(f.error, f.path + ":8: non-finite coordinate 'nan' for node 3");
  f = mshWithLine("inf", 9, "4 0 0 -inf");
  EXPECT_EQ(f.error, f.path + ":9: non-finite coordinate '-inf' for node 4");
  f = mshWithLine("overflow", 9, "4 0 0 1e999");
  EXPECT_EQ(f.error, f.path + ":9: bad coordinate '1e999' for node 4");
}

TEST(MshIo, ErrorBadNodeLines) {
  BadFile f = mshWithLine("badcoord", 8, "3 0 1 x");
  EXPECT_EQ(f.error, f.path + ":8: bad coordinate 'x' for node 3");
  f = mshWithLine("shortnode", 8, "3 0 1");
  EXPECT_EQ(f.error, f.path + ":8: expected 'id x y z' for a node, got 3 values");
  f = mshWithLine("dupnode", 9, "3 0 0 1");
  EXPECT_EQ(f.error, f.path + ":9: duplicate node id 3");
  f = mshWithLine("badcount", 5, "four");
  EXPECT_EQ(f.error, f.path + ":5: expected the number of nodes, got 'four'");
}

TEST(MshIo, ErrorUnknownNodeId) {
  const BadFile f = mshWithLine("unknown_node", 13, "1 4 2 1 1 1 2 3 99");
  EXPECT_EQ(f.error, f.path + ":13: element 1 references unknown node 99");
}

TEST(MshIo, ErrorBadElementLines) {
  BadFile f = mshWithLine("tags", 13, "1 4 9 1 1 1 2 3 4");
  EXPECT_EQ(f.error, f.path + ":13: element 1 has 9 tags but only 6 values follow");
  f = mshWithLine("float_node", 13, "1 4 2 1 1 1 2 3 4.5");
  EXPECT_EQ(f.error, f.path + ":13: expected an integer in element, got '4.5'");
  f = mshWithLine("short_element", 13, "1 4");
  EXPECT_EQ(f.error,
            f.path + ":13: expected 'id type number-of-tags tags... nodes...' for an element, got '1 4'");
}

TEST(MshIo, ErrorMissingEndNodes) {
  // File ends inside $Nodes.
  auto lines = goodMshLines();
  lines.resize(9);
  std::string path = writeText("no_endnodes_eof.msh", joinLines(lines));
  EXPECT_EQ(readTetMesh(path).error(), path + ":9: missing $EndNodes (end of file)");
  // $Elements where $EndNodes should be.
  const BadFile f = mshWithLine("no_endnodes", 10, "$Elements");
  EXPECT_EQ(f.error, f.path + ":10: expected $EndNodes after 4 nodes, got '$Elements'");
  // Fewer nodes than announced.
  const BadFile g = mshWithLine("few_nodes", 5, "5");
  EXPECT_EQ(g.error, g.path + ":10: expected 5 nodes, got 4 before '$EndNodes'");
}

TEST(MshIo, ErrorMissingEndElementsAndSections) {
  auto lines = goodMshLines();
  lines.pop_back();
  std::string path = writeText("no_endelements.msh", joinLines(lines));
  EXPECT_EQ(readTetMesh(path).error(), path + ":13: missing $EndElements (end of file)");
  lines = goodMshLines();
  lines.resize(10);
  path = writeText("no_elements.msh", joinLines(lines));
  EXPECT_EQ(readTetMesh(path).error(), path + ": no $Elements section");
  path = writeText("unterminated_section.msh", joinLines(goodMshLines()) + "$Comments\nhello\n");
  EXPECT_EQ(readTetMesh(path).error(), path + ":16: missing $EndComments (end of file)");
}

TEST(MshIo, ErrorUnsupportedVersionAndBinary) {
  BadFile f = mshWithLine("v41", 2, "4.1 0 8");
  EXPECT_EQ(f.error,
            f.path +
                ":2: unsupported MSH version 4.1 (only 2.2 ASCII is supported; in Gmsh: File > Export, "
                "'Version 2 ASCII')");
  f = mshWithLine("binary", 2, "2.2 1 8");
  EXPECT_EQ(f.error, f.path +
                         ":2: binary MSH files are not supported (only 2.2 ASCII; in Gmsh: File > Export, "
                         "'Version 2 ASCII')");
  f = mshWithLine("noheader", 1, "$Nodes");
  EXPECT_EQ(f.error,
            f.path + ":1: expected $MeshFormat, got '$Nodes' (only Gmsh MSH 2.2 ASCII is supported)");
  const std::string empty = writeText("empty.msh", "\n\n");
  EXPECT_EQ(readTetMesh(empty).error(), empty + ": empty file");
}

TEST(MshIo, ErrorNoTetrahedraOrTriangles) {
  const BadFile f = mshWithLine("only_tri", 13, "1 2 2 1 1 1 2 3");
  EXPECT_EQ(f.error, f.path + ": no tetrahedra (MSH element type 4) in file");
  const std::string tetOnly = writeText("tet_only.msh", joinLines(goodMshLines()));
  EXPECT_EQ(readTriMesh(tetOnly).error(), tetOnly + ": no triangles (MSH element type 2) in file");
}

// --- VTK errors ------------------------------------------------------------------------

// A valid two-tet file:
//   1 header / 2 title / 3 ASCII / 4 DATASET / 5 POINTS / 6-10 points / 11 CELLS /
//   12-13 cells / 14 CELL_TYPES / 15-16 types / 17 CELL_DATA / 18 SCALARS / 19 LOOKUP_TABLE /
//   20-21 materials
std::vector<std::string> goodVtkLines() {
  return {"# vtk DataFile Version 3.0",
          "two tets",
          "ASCII",
          "DATASET UNSTRUCTURED_GRID",
          "POINTS 5 double",
          "0 0 0",
          "1 0 0",
          "0 1 0",
          "0 0 1",
          "1 1 1",
          "CELLS 2 10",
          "4 0 1 2 3",
          "4 1 2 3 4",
          "CELL_TYPES 2",
          "10",
          "10",
          "CELL_DATA 2",
          "SCALARS material int 1",
          "LOOKUP_TABLE default",
          "1",
          "2"};
}

BadFile vtkWithLine(const std::string& name, int lineNumber, const std::string& replacement) {
  auto lines = goodVtkLines();
  lines[static_cast<std::size_t>(lineNumber - 1)] = replacement;
  const std::string path = writeText(name + ".vtk", joinLines(lines));
  const Result<TetMesh> r = readTetMesh(path);
  return {path, r.ok() ? std::string("(read ok)") : r.error()};
}

TEST(VtkIo, GoodFileReads) {
  const Result<TetMesh> r = readTetMesh(writeText("good.vtk", joinLines(goodVtkLines())));
  ASSERT_TRUE(r.ok()) << r.error();
  EXPECT_EQ(r->numTets(), 2);
  EXPECT_EQ(r->material, (Labels(2) << 1, 2).finished());
  EXPECT_TRUE(validate(*r).ok());
}

TEST(VtkIo, ErrorTetWithThreeNodes) {
  auto lines = goodVtkLines();
  lines[10] = "CELLS 2 9";
  lines[12] = "3 1 2 3";
  const std::string path = writeText("tet3.vtk", joinLines(lines));
  EXPECT_EQ(readTetMesh(path).error(),
            path + ":13: cell 1: expected 4 node indices for tetrahedron (cell type 10), got 3");
}

TEST(VtkIo, ErrorBinary) {
  const BadFile f = vtkWithLine("binary", 3, "BINARY");
  EXPECT_EQ(f.error, f.path + ":3: binary VTK files are not supported (only legacy ASCII)");
}

TEST(VtkIo, ErrorPointIndexOutOfRange) {
  const BadFile f = vtkWithLine("bad_index", 13, "4 1 2 3 7");
  EXPECT_EQ(f.error, f.path + ":13: cell 1 references point 7, but there are 5 points");
}

TEST(VtkIo, ErrorNonFiniteAndBadCoordinates) {
  BadFile f = vtkWithLine("nan", 8, "0 nan 0");
  EXPECT_EQ(f.error, f.path + ":8: non-finite coordinate 'nan' for point 2");
  f = vtkWithLine("badcoord", 8, "0 1 zero");
  EXPECT_EQ(f.error, f.path + ":8: bad coordinate 'zero' for point 2");
}

TEST(VtkIo, ErrorTruncatedPoints) {
  auto lines = goodVtkLines();
  lines.resize(7);
  const std::string path = writeText("truncated.vtk", joinLines(lines));
  EXPECT_EQ(readTetMesh(path).error(), path + ":7: unexpected end of file: expected 5 points, got 2");
}

TEST(VtkIo, ErrorHeaderAndDataset) {
  BadFile f = vtkWithLine("magic", 1, "hello");
  EXPECT_EQ(f.error, f.path + ":1: expected '# vtk DataFile Version x.y', got 'hello'");
  f = vtkWithLine("polydata", 4, "DATASET POLYDATA");
  EXPECT_EQ(f.error, f.path + ":4: unsupported dataset type 'POLYDATA' (only UNSTRUCTURED_GRID)");
  f = vtkWithLine("format", 3, "TEXT");
  EXPECT_EQ(f.error, f.path + ":3: expected ASCII, got 'TEXT'");
}

TEST(VtkIo, ErrorCountMismatches) {
  BadFile f = vtkWithLine("types_count", 14, "CELL_TYPES 3");
  EXPECT_EQ(f.error, f.path + ":14: CELL_TYPES has 3 entries but CELLS has 2");
  f = vtkWithLine("cells_size", 11, "CELLS 2 11");
  EXPECT_EQ(f.error, f.path + ":11: CELLS declares 11 values but its 2 cells have 10");
  f = vtkWithLine("celldata_count", 17, "CELL_DATA 3");
  EXPECT_EQ(f.error, f.path + ":17: CELL_DATA has 3 values but CELLS has 2 cells");
}

TEST(VtkIo, ErrorBadMaterialAndKeyword) {
  BadFile f = vtkWithLine("material", 21, "2.5");
  EXPECT_EQ(f.error, f.path + ":21: material '2.5' is not a 32-bit integer");
  f = vtkWithLine("keyword", 17, "FOO 2");
  EXPECT_EQ(f.error, f.path + ":17: unexpected 'FOO'");
}

TEST(VtkIo, ErrorNoTetrahedra) {
  const BadFile f = vtkWithLine("no_tets", 15, "5");  // first cell is now a "triangle" with 4 nodes
  EXPECT_EQ(f.error, f.path + ":12: cell 0: expected 3 node indices for triangle (cell type 5), got 4");
  auto lines = goodVtkLines();
  lines[14] = lines[15] = "12";  // hexahedra: ignored
  const std::string path = writeText("hex_only.vtk", joinLines(lines));
  EXPECT_EQ(readTetMesh(path).error(), path + ": no tetrahedra (VTK cell type 10) in file");
}

// --- writer errors ---------------------------------------------------------------------

TEST(MeshIo, WriterErrors) {
  std::string path = outputPath("mesh.obj");
  EXPECT_EQ(writeMesh(path, awkwardTetMesh()).error(),
            "cannot write '" + path + "': unknown mesh extension (expected .msh or .vtk)");
  path = outputPath("no_such_dir/mesh.msh");
  EXPECT_EQ(writeMesh(path, awkwardTetMesh()).error(),
            "cannot write '" + path + "': No such file or directory");
  TetMesh bad = awkwardTetMesh();
  bad.T(1, 3) = 9;
  path = outputPath("bad_index.vtk");
  EXPECT_EQ(writeMesh(path, bad).error(), "cannot write '" + path + "': tet 1 references node 9 of 6");
  bad = awkwardTetMesh();
  bad.X(2, 2) = std::nan("");
  EXPECT_EQ(writeMesh(path, bad).error(), "cannot write '" + path + "': node 2 has a non-finite coordinate");
  bad = awkwardTetMesh();
  bad.material.resize(3);
  EXPECT_EQ(writeMesh(path, bad).error(), "cannot write '" + path + "': 3 material labels for 2 tets");
}

// --- robustness ------------------------------------------------------------------------

// Every prefix of a valid file, and the file with single bytes replaced, must give a mesh
// or an error message: never a crash, a hang or an exception.
TEST(MeshIo, TruncatedAndCorruptedFilesNeverCrash) {
  const std::vector<std::pair<std::string, std::string>> sources = {
      {".msh", joinLines(goodMshLines())},
      {".vtk", joinLines(goodVtkLines())},
      {".msh", readText(dataPath("mixed_ids.msh"))},
      {".vtk", readText(dataPath("vtk51_offsets.vtk"))},
  };
  int failures = 0;
  for (const auto& [ext, text] : sources) {
    ASSERT_FALSE(text.empty());
    std::vector<std::string> variants;
    for (std::size_t n = 0; n < text.size(); ++n) variants.push_back(text.substr(0, n));
    for (std::size_t i = 0; i < text.size(); i += 4) {
      for (char c : {'\n', '9', '-', 'x'}) {
        std::string corrupted = text;
        corrupted[i] = c;
        variants.push_back(corrupted);
      }
    }
    const std::string path = outputPath("fuzz" + ext);
    for (const std::string& variant : variants) {
      writeText("fuzz" + ext, variant);
      const Result<TetMesh> tets = readTetMesh(path);
      const Result<TriMesh> tris = readTriMesh(path);
      for (const std::string* error : {&tets.error(), &tris.error()}) {
        if (!error->empty()) {
          ++failures;
          EXPECT_EQ(error->find('\n'), std::string::npos) << *error;  // one-line messages
          EXPECT_EQ(error->rfind(path, 0), 0u) << *error;             // naming the file
        }
      }
      if (tets.ok()) {
        EXPECT_EQ(tets->T.rows(), tets->material.rows());
        if (tets->T.size() > 0) {
          EXPECT_GE(tets->T.minCoeff(), 0);
          EXPECT_LT(tets->T.maxCoeff(), tets->numNodes());
        }
        EXPECT_TRUE(tets->X.allFinite());
      }
    }
  }
  EXPECT_GT(failures, 100);  // the corruptions were actually noticed
}

}  // namespace
}  // namespace hysim::cutting
