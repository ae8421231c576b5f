// `hysim cut` on tetrahedral meshes (--plane / --surface) and `hysim tables --table 2`, run as
// a user would: outputs read back and validated, stats JSON, one-line errors on bad input.
#include <gtest/gtest.h>

#include "read_json.hpp"
#include "run_hysim.hpp"

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "hysim/cutting/cut3d.hpp"
#include "hysim/cutting/mesh_io.hpp"
#include "hysim/render/image.hpp"

namespace {

namespace fs = std::filesystem;

using hysim::testing::Output;

Output hysim(const std::string& args) { return hysim::testing::runHysim(args); }

std::string outDir(const std::string& name) { return hysim::testing::freshOutputDir("cli_cut3d", name); }

using hysim::testing::readJson;

std::string readText(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

// The Table-2 ellipsoid (semi-axes 20, 15, 12 mm, 135 tets) and the Table-2 plane A.
const std::string kMesh = "tests/data/cutting/table2_ellipsoid.msh";
const std::string kPlane = "--plane 0.5,0.3,0.2,0.15,0.1,1";

const char* const kStatsKeys[] = {"nodes",    "elements",  "size_min", "size_mean", "size_std", "edge_min",
                                  "edge_mean", "edge_std", "q_min",    "q_mean",    "q_std",    "dihedral_min_deg"};

// The output mesh reads back, is valid, and `hysim stats --json` gives the stats file's numbers.
void checkOutput(const std::string& mesh_path, const nlohmann::json& stats) {
  auto m = hysim::cutting::readTetMesh(mesh_path);
  ASSERT_TRUE(m.ok()) << m.error();
  const auto valid = hysim::cutting::validate(*m);
  EXPECT_TRUE(valid.ok()) << valid.error();
  EXPECT_EQ(m->numTets(), stats["elements"].get<int>());
  EXPECT_EQ(m->numNodes(), stats["nodes"].get<int>());
  EXPECT_EQ(hysim::cutting::tetComponents(*m).count, stats["components"].get<int>());
  const Output s = hysim("stats " + mesh_path + " --json");
  ASSERT_EQ(s.exit_code, 0) << s.text;
  const auto js = nlohmann::json::parse(s.text, nullptr, false);
  ASSERT_FALSE(js.is_discarded()) << s.text;
  for (const char* key : kStatsKeys) {
    ASSERT_TRUE(js.contains(key)) << key;
    EXPECT_NEAR(js[key].get<double>(), stats[key].get<double>(), 1e-6 * (1 + std::abs(js[key].get<double>()))) << key;
  }
}

nlohmann::json checkStats(const std::string& path) {
  const auto j = readJson(path);
  EXPECT_FALSE(j.is_discarded()) << path;
  if (j.is_discarded()) return j;
  for (const char* key : kStatsKeys) EXPECT_TRUE(j.contains(key)) << key;
  for (const char* key : {"time_ms", "components", "method", "volume_before", "volume_after", "volume_drift",
                          "material_volumes"})
    EXPECT_TRUE(j.contains(key)) << key;
  EXPECT_GT(j.value("time_ms", 0.0), 0.0);
  return j;
}

TEST(CliCut3D, PlaneCutEveryMethod) {
  for (const std::string method : {"hybrid", "standard", "snap", "delete"}) {
    SCOPED_TRACE(method);
    const std::string dir = outDir("plane_" + method);
    const Output o =
        hysim("cut " + kMesh + " " + kPlane + " --method " + method + " --out " + dir + "/cut.msh --stats " + dir + "/s.json");
    ASSERT_EQ(o.exit_code, 0) << o.text;
    EXPECT_NE(o.text.find(method + " cut"), std::string::npos) << o.text;
    const auto j = checkStats(dir + "/s.json");
    ASSERT_FALSE(j.is_discarded());
    EXPECT_EQ(j["method"], method);
    EXPECT_GE(j["components"].get<int>(), 2);  // the plane passes through the middle: two pieces
    const double v0 = j["volume_before"].get<double>(), v1 = j["volume_after"].get<double>();
    EXPECT_NEAR(j["volume_drift"].get<double>(), v0 - v1, 1e-12 * v0);
    if (method == "standard") {
      EXPECT_NEAR(v1, v0, 1e-9 * v0);
    } else if (method == "hybrid") {
      // No quality bound here: with the CLI's default 30 degree feature angle every boundary
      // node of this coarse ellipsoid (~35 degree dihedrals) is a feature and stays, so a few
      // slivers remain (q*_min ~0.002); `hysim tables --table 2` uses 60 degrees.
      EXPECT_NEAR(v1, v0, 1e-2 * v0);
    } else if (method == "delete") {
      EXPECT_LT(v1, v0);
    }
    checkOutput(dir + "/cut.msh", j);
  }
}

TEST(CliCut3D, VtkOutput) {
  const std::string dir = outDir("vtk");
  const Output o = hysim("cut " + kMesh + " " + kPlane + " --out " + dir + "/cut.vtk --stats " + dir + "/s.json");
  ASSERT_EQ(o.exit_code, 0) << o.text;
  const auto j = checkStats(dir + "/s.json");
  ASSERT_FALSE(j.is_discarded());
  checkOutput(dir + "/cut.vtk", j);
}

// A curved strip z = 1 + 0.02 x^2 - 0.01 y^2 over [-24, 24] x [-18, 18], which covers the
// ellipsoid's outline: a complete cut into two pieces.
struct Strip {
  std::vector<Eigen::Vector3d> v;
  std::vector<std::array<int, 3>> f;
};
Strip curvedStrip() {
  Strip s;
  const int nx = 12, ny = 9;
  for (int j = 0; j <= ny; ++j)
    for (int i = 0; i <= nx; ++i) {
      const double x = -24 + 48.0 * i / nx, y = -18 + 36.0 * j / ny;
      s.v.emplace_back(x, y, 1 + 0.02 * x * x - 0.01 * y * y);
    }
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      const int a = j * (nx + 1) + i, b = a + 1, c = a + nx + 1, d = c + 1;
      s.f.push_back({a, b, d});
      s.f.push_back({a, d, c});
    }
  return s;
}

void writeObj(const std::string& path, const Strip& s) {
  std::ofstream o(path);
  o << "# curved strip\n";
  for (const auto& p : s.v) o << "v " << p.x() << " " << p.y() << " " << p.z() << "\n";
  for (const auto& f : s.f) o << "f " << f[0] + 1 << " " << f[1] + 1 << " " << f[2] + 1 << "\n";
}

void writeStl(const std::string& path, const Strip& s) {
  std::ofstream o(path);
  o << "solid strip\n";
  for (const auto& f : s.f) {
    const Eigen::Vector3d n = (s.v[f[1]] - s.v[f[0]]).cross(s.v[f[2]] - s.v[f[0]]).normalized();
    o << " facet normal " << n.x() << " " << n.y() << " " << n.z() << "\n  outer loop\n";
    for (int k = 0; k < 3; ++k) o << "   vertex " << s.v[f[k]].x() << " " << s.v[f[k]].y() << " " << s.v[f[k]].z() << "\n";
    o << "  endloop\n endfacet\n";
  }
  o << "endsolid strip\n";
}

void writeMshTriangles(const std::string& path, const Strip& s) {
  std::ofstream o(path);
  o << "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n" << s.v.size() << "\n";
  for (size_t i = 0; i < s.v.size(); ++i) o << i + 1 << " " << s.v[i].x() << " " << s.v[i].y() << " " << s.v[i].z() << "\n";
  o << "$EndNodes\n$Elements\n" << s.f.size() << "\n";
  for (size_t i = 0; i < s.f.size(); ++i)
    o << i + 1 << " 2 2 1 1 " << s.f[i][0] + 1 << " " << s.f[i][1] + 1 << " " << s.f[i][2] + 1 << "\n";
  o << "$EndElements\n";
}

TEST(CliCut3D, SurfaceCutFromObjStlAndMsh) {
  const std::string dir = outDir("surface");
  const Strip strip = curvedStrip();
  writeObj(dir + "/strip.obj", strip);
  writeStl(dir + "/strip.stl", strip);
  writeMshTriangles(dir + "/strip.msh", strip);
  std::vector<int> elements;
  for (const std::string file : {"strip.obj", "strip.stl", "strip.msh"}) {
    for (const std::string method : {"hybrid", "standard"}) {
      SCOPED_TRACE(file + " " + method);
      const std::string out = dir + "/cut_" + method + "_" + file + ".msh", stats = dir + "/s_" + method + "_" + file + ".json";
      const Output o = hysim("cut " + kMesh + " --surface " + dir + "/" + file + " --method " + method + " --out " + out +
                             " --stats " + stats);
      ASSERT_EQ(o.exit_code, 0) << o.text;
      const auto j = checkStats(stats);
      ASSERT_FALSE(j.is_discarded());
      EXPECT_EQ(j["components"].get<int>(), 2) << o.text;
      checkOutput(out, j);
      if (method == "standard") elements.push_back(j["elements"].get<int>());
    }
  }
  // The three files hold the same surface (OBJ/STL through the engine's loader, .msh through
  // the mesh reader): the same cut.
  ASSERT_EQ(elements.size(), 3u);
  EXPECT_EQ(elements[0], elements[1]);
  EXPECT_EQ(elements[0], elements[2]);
}

// An error: exit status 1 (not a crash), one line "hysim: ..." naming `names`.
void expectOneLineError(const Output& o, const std::string& names) {
  EXPECT_EQ(o.exit_code, 1) << o.text;
  EXPECT_NE(o.text.find(names), std::string::npos) << o.text;
  std::string text = o.text;
  while (!text.empty() && text.back() == '\n') text.pop_back();
  EXPECT_EQ(text.find('\n'), std::string::npos) << "not one line:\n" << o.text;
  EXPECT_EQ(text.rfind("hysim: ", 0), 0u) << o.text;
}

TEST(CliCut3D, BadInputGivesAOneLineMessageAndKeepsTheOutput) {
  const std::string dir = outDir("bad");
  const std::string out = dir + "/keep.msh";
  const std::string sentinel = "not a mesh: must survive failed cuts\n";
  { std::ofstream(out) << sentinel; }
  const std::string tail = " --out " + out + " --stats " + dir + "/s.json";
  struct Case {
    std::string args, names;
  };
  std::ofstream(dir + "/points.obj") << "v 0 0 0\nv 1 0 0\nv 0 1 0\n";                 // no faces
  std::ofstream(dir + "/flat.obj") << "v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\n";          // degenerate only
  std::ofstream(dir + "/empty.stl") << "solid nothing\nendsolid nothing\n";
  const std::vector<Case> cases = {
      {"cut " + dir + "/missing.msh " + kPlane + tail, dir + "/missing.msh"},
      {"cut " + kMesh + " --plane 1,2,3" + tail, "'1,2,3'"},
      {"cut " + kMesh + " --plane 1,2,3,4,5,6,7" + tail, "'1,2,3,4,5,6,7'"},
      {"cut " + kMesh + " --plane 0,0,0,nan,0,1" + tail, "'0,0,0,nan,0,1'"},
      {"cut " + kMesh + " --plane 0,0,0,0,0,inf" + tail, "'0,0,0,0,0,inf'"},
      {"cut " + kMesh + " --plane 0,0,x,0,0,1" + tail, "'0,0,x,0,0,1'"},
      {"cut " + kMesh + " --plane 0,0,0,0,0,0" + tail, "'0,0,0,0,0,0'"},
      {"cut " + kMesh + " " + kPlane + " --method laser" + tail, "'laser'"},
      {"cut " + kMesh + " " + kPlane + " --surface " + dir + "/points.obj" + tail, "--plane"},
      {"cut " + kMesh + " --surface " + dir + "/points.obj" + tail, dir + "/points.obj"},
      {"cut " + kMesh + " --surface " + dir + "/flat.obj" + tail, dir + "/flat.obj"},
      {"cut " + kMesh + " --surface " + dir + "/empty.stl" + tail, dir + "/empty.stl"},
      {"cut " + kMesh + " --surface " + dir + "/missing.obj" + tail, dir + "/missing.obj"},
      {"cut " + kMesh + " --surface assets/uterus_myoma.msh" + tail, "assets/uterus_myoma.msh"},  // tets only
  };
  for (const auto& c : cases) {
    SCOPED_TRACE(c.args);
    const Output o = hysim(c.args);
    expectOneLineError(o, c.names);
    EXPECT_EQ(readText(out), sentinel);
    EXPECT_FALSE(fs::exists(dir + "/s.json"));
  }
  EXPECT_EQ(readText(out), sentinel);
}

TEST(CliCut3D, Table2PicturesArePngsOfTheMeshes) {
  const std::string dir = outDir("table2");
  const Output o = hysim("tables --table 2 --repeats 1 --json " + dir + "/t2.json --pictures " + dir + "/pics");
  ASSERT_EQ(o.exit_code, 0) << o.text;
  const auto j = readJson(dir + "/t2.json");
  ASSERT_FALSE(j.is_discarded());
  EXPECT_EQ(j["table2"].size(), 4u);
  std::vector<hysim::render::Image> images;
  for (const char* name : {"table2_initial", "table2_standard", "table2_hybrid_a", "table2_hybrid_b"}) {
    SCOPED_TRACE(name);
    const auto img = hysim::render::readPng(dir + "/pics/" + name + ".png");
    ASSERT_TRUE(img.ok()) << img.error();
    EXPECT_EQ(img->width, 640);
    EXPECT_EQ(img->height, 480);
    // The mesh covers a good part of the picture; the cut surface (red, r > 2 g) shows only
    // after a cut, and white background shows between the two pieces.
    int drawn = 0, cut = 0;
    for (int y = 0; y < img->height; ++y)
      for (int x = 0; x < img->width; ++x) {
        const auto* p = img->pixel(x, y);
        if (p[0] < 250 || p[1] < 250 || p[2] < 250) ++drawn;
        if (p[0] > 60 && p[0] > 2 * p[1]) ++cut;
      }
    const int total = img->width * img->height;
    EXPECT_GT(drawn, total / 10);
    EXPECT_LT(drawn, total * 9 / 10);
    if (std::string(name) == "table2_initial") {
      EXPECT_EQ(cut, 0);
    } else {
      EXPECT_GT(cut, total / 100);
    }
    images.push_back(*img);
  }
  // Standard and Hybrid A cut the same mesh with the same plane, so they differ only in the
  // elements near the cut.
  ASSERT_EQ(images.size(), 4u);
  EXPECT_NE(images[1].rgba, images[2].rgba);
  EXPECT_NE(images[2].rgba, images[3].rgba);
}

}  // namespace
