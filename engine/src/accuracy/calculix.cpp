#include "hysim/engine/accuracy/calculix.hpp"

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <algorithm>
#include <cstdint>
#include <map>
#include <sstream>

namespace hysim::engine::accuracy {
namespace {

// Mid-edge nodes of quadratic tets (C3D10): one per tet edge, numbered after the mesh's
// nodes in the order they are first met. A mid node belongs to a node set when both its
// ends do.
struct MidNodes {
  std::map<std::pair<int, int>, int> index;  // sorted edge -> 0-based node index
  std::vector<std::pair<int, int>> edges;
  int at(int a, int b, int base) {
    const auto key = std::minmax(a, b);
    auto [it, added] = index.emplace(key, base + static_cast<int>(edges.size()));
    if (added) edges.push_back(key);
    return it->second;
  }
};

// C3D10 order: corners 1-4, then the mid nodes of edges 1-2, 2-3, 3-1, 1-4, 2-4, 3-4.
constexpr int kQuadEdges[6][2] = {{0, 1}, {1, 2}, {2, 0}, {0, 3}, {1, 3}, {2, 3}};

void writeNodesAndElements(std::ostringstream& out, const AccuracyCase& c, bool quadratic, MidNodes& mid) {
  const int n = c.mesh.numNodes();
  std::map<int, std::vector<int>> by_label;
  for (int t = 0; t < c.mesh.numTets(); ++t) by_label[c.mesh.material[t]].push_back(t);
  if (quadratic)
    for (int t = 0; t < c.mesh.numTets(); ++t)
      for (const auto& e : kQuadEdges) mid.at(c.mesh.T(t, e[0]), c.mesh.T(t, e[1]), n);
  out << "*NODE, NSET=NALL\n";
  char line[160];
  auto node = [&](int id, const Eigen::Vector3d& p) {
    std::snprintf(line, sizeof line, "%d, %.12g, %.12g, %.12g\n", id + 1, p.x(), p.y(), p.z());  // ccx fields <= 20 chars
    out << line;
  };
  for (int i = 0; i < n; ++i) node(i, c.mesh.X.row(i).transpose());
  for (size_t k = 0; k < mid.edges.size(); ++k)
    node(n + static_cast<int>(k), 0.5 * (c.mesh.X.row(mid.edges[k].first) + c.mesh.X.row(mid.edges[k].second)).transpose());
  for (const auto& [label, tets] : by_label) {
    out << "*ELEMENT, TYPE=" << (quadratic ? "C3D10" : "C3D4") << ", ELSET=M" << label << "\n";
    for (int t : tets) {
      out << t + 1;
      for (int k = 0; k < 4; ++k) out << ", " << c.mesh.T(t, k) + 1;
      if (quadratic)
        for (const auto& e : kQuadEdges) out << ", " << mid.at(c.mesh.T(t, e[0]), c.mesh.T(t, e[1]), n) + 1;
      out << "\n";
    }
  }
}

// `nodes` plus the mid nodes whose two ends are in it.
std::vector<int> withMidNodes(const std::vector<int>& nodes, const MidNodes& mid, int num_nodes) {
  std::vector<std::uint8_t> in(num_nodes, 0);
  for (int i : nodes) in[i] = 1;
  std::vector<int> out = nodes;
  for (size_t k = 0; k < mid.edges.size(); ++k)
    if (in[mid.edges[k].first] && in[mid.edges[k].second]) out.push_back(num_nodes + static_cast<int>(k));
  return out;
}

void writeNodeSet(std::ostringstream& out, const std::string& name, const std::vector<int>& nodes) {
  out << "*NSET, NSET=" << name << "\n";
  for (size_t k = 0; k < nodes.size(); ++k) out << nodes[k] + 1 << ((k % 12 == 11 || k + 1 == nodes.size()) ? "\n" : ", ");
}

void writeMaterials(std::ostringstream& out, const AccuracyCase& c, double poisson) {
  std::map<int, bool> used;
  for (int t = 0; t < c.mesh.numTets(); ++t) used[c.mesh.material[t]] = true;
  for (const sim::Material& m : c.materials) {
    if (!used.count(m.label)) continue;
    out << "*MATERIAL, NAME=MAT" << m.label << "\n*ELASTIC\n" << m.young_modulus_pa << ", " << poisson
        << "\n*DENSITY\n" << m.density_g_mm3 << "\n*SOLID SECTION, ELSET=M" << m.label << ", MATERIAL=MAT" << m.label
        << "\n";
  }
}

void writeStep(std::ostringstream& out, const AccuracyCase& c, const FeOptions& o) {
  if (o.frequencies > 0) {
    out << "*STEP\n*FREQUENCY\n" << o.frequencies << "\n" << (c.fixed.empty() ? "" : "*BOUNDARY\nFIXED, 1, 3\n") << "*END STEP\n";
    return;
  }
  // Increments of at most 1/increments (cut back when a nonlinear one does not converge): the
  // indenter's reaction is printed at each.
  out << (o.nlgeom ? "*STEP, NLGEOM, INC=1000\n" : "*STEP, INC=1000\n") << "*STATIC\n" << 1.0 / o.increments
      << ", 1.0, 1e-3, " << 1.0 / o.increments << "\n";
  if (!c.fixed.empty()) out << "*BOUNDARY\nFIXED, 1, 3\n";
  if (o.hold_indenter && !c.indenter.empty()) {
    out << "*BOUNDARY\n";
    for (int d = 0; d < 3; ++d) out << "INDENTER, " << d + 1 << ", " << d + 1 << ", " << o.indent_mm * c.indent_direction[d] << "\n";
  }
  const double g = c.gravity.norm();
  if (o.gravity && g > 0.0) {
    out << "*DLOAD\n";
    for (const sim::Material& m : c.materials)
      if ((c.mesh.material.array() == m.label).any())  // only element sets the deck has
        out << "M" << m.label << ", GRAV, " << g << ", " << c.gravity.x() / g << ", " << c.gravity.y() / g << ", "
          << c.gravity.z() / g << "\n";
  }
  out << "*NODE PRINT, NSET=NALL\nU\n";
  if (o.hold_indenter && !c.indenter.empty()) out << "*NODE PRINT, NSET=INDENTER, TOTALS=ONLY\nRF\n";
  out << "*END STEP\n";
}

// The numbers on a line, or an empty vector when a token is not a number.
std::vector<double> numbersOf(const std::string& line) {
  std::istringstream in(line);
  std::vector<double> v;
  std::string tok;
  while (in >> tok) {
    char* end = nullptr;
    const double x = std::strtod(tok.c_str(), &end);
    if (end == tok.c_str() || *end != '\0') return {};
    v.push_back(x);
  }
  return v;
}

}  // namespace

std::string calculixDeck(const AccuracyCase& c, const FeOptions& o) {
  std::ostringstream out;
  out << "*HEADING\nhysim accuracy study: " << c.name << " (units mm, g, s: forces in uN, stresses in Pa)\n";
  MidNodes mid;
  writeNodesAndElements(out, c, o.quadratic, mid);
  const int n = c.mesh.numNodes();
  if (!c.fixed.empty()) writeNodeSet(out, "FIXED", withMidNodes(c.fixed, mid, n));
  if (o.hold_indenter && !c.indenter.empty()) writeNodeSet(out, "INDENTER", withMidNodes(c.indenter, mid, n));
  writeMaterials(out, c, o.poisson);
  writeStep(out, c, o);
  return out.str();
}

Result<FeSolution> parseCalculixDat(const std::string& text, int num_nodes) {
  FeSolution s;
  s.u = Eigen::MatrixX3d::Zero(num_nodes, 3);
  std::istringstream in(text);
  std::string line;
  enum class Block { None, Displacements, Total, Eigen } block = Block::None;
  int line_no = 0, rows = 0;
  while (std::getline(in, line)) {
    ++line_no;
    if (line.find("displacements (vx,vy,vz)") != std::string::npos) { block = Block::Displacements; rows = 0; continue; }
    if (line.find("total force") != std::string::npos) {
      block = Block::Total;
      const size_t at = line.find("time");
      s.increment_times.push_back(at == std::string::npos ? 1.0 : std::strtod(line.c_str() + at + 4, nullptr));
      continue;
    }
    if (line.find("P A R T I C I P A T I O N") != std::string::npos) { block = Block::None; continue; }
    if (line.find("E I G E N V A L U E   O U T P U T") != std::string::npos) { block = Block::Eigen; s.frequencies_hz.clear(); continue; }
    const std::vector<double> v = numbersOf(line);
    if (v.empty()) continue;
    if (block == Block::Displacements && v.size() == 4) {
      const int node = static_cast<int>(v[0]) - 1;
      if (node < 0) return Error{"ccx .dat line " + std::to_string(line_no) + ": node " + std::to_string(node + 1) + " out of range"};
      if (node < num_nodes) s.u.row(node) = Eigen::RowVector3d(v[1], v[2], v[3]);  // mid-edge nodes are not ours
      ++rows;
    } else if (block == Block::Total && v.size() == 3) {
      s.indenter_force = Eigen::Vector3d(v[0], v[1], v[2]);
      s.indenter_forces.push_back(s.indenter_force);
      block = Block::None;
    } else if (block == Block::Eigen && v.size() >= 4) {
      s.frequencies_hz.push_back(v[3]);  // mode, eigenvalue, rad/time, cycles/time, ...
    }
  }
  if (rows == 0 && s.frequencies_hz.empty()) return Error{"ccx .dat: no displacement or eigenvalue table"};
  return s;
}

bool calculixAvailable(const std::string& program) {
  const std::string cmd = "command -v " + program + " > /dev/null 2>&1";
  return std::system(cmd.c_str()) == 0;
}

Result<FeSolution> solveCalculix(const AccuracyCase& c, const FeOptions& o, const std::string& dir,
                                 const std::string& job) {
  namespace fs = std::filesystem;
  std::error_code ec;
  fs::create_directories(dir, ec);
  const fs::path inp = fs::path(dir) / (job + ".inp");
  {
    std::ofstream out(inp);
    out << calculixDeck(c, o);
    if (!out) return Error{inp.string() + ": cannot write the CalculiX deck"};
  }
  const fs::path dat = fs::path(dir) / (job + ".dat");
  fs::remove(dat, ec);  // a failed run must not leave an earlier run's results to be read
  const auto t0 = std::chrono::steady_clock::now();
  const std::string cmd = "cd '" + dir + "' && OMP_NUM_THREADS=1 '" + o.program + "' -i '" + job + "' > '" + job + ".log' 2>&1";
  const int rc = std::system(cmd.c_str());
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::ifstream in(dat);
  const std::string failed = o.program + " failed on " + inp.string() + " (exit " + std::to_string(rc) + "; see " + job + ".log)";
  if (!in) return Error{failed};
  std::stringstream text;
  text << in.rdbuf();
  auto s = parseCalculixDat(text.str(), c.mesh.numNodes());
  // A nonlinear run that diverged part-way still printed the increments it reached.
  if (rc != 0 && (!s.ok() || s->increment_times.empty())) return Error{failed};
  if (!s.ok()) return Error{dat.string() + ": " + s.error()};
  s->completed = rc == 0;
  s->seconds = seconds;
  return s;
}

}  // namespace hysim::engine::accuracy
