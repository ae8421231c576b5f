// Mesh file dispatch and writers, and the text helpers the readers share.
//
// Both readers (msh_reader.cpp, vtk_reader.cpp) parse into one intermediate (RawMesh:
// nodes, tets, triangles) and the public functions pick the element kind they need. Every
// count in a file is untrusted: reservations are capped by the file size and every index
// is checked, so bad input ends in an error message naming file and line, never in a
// crash or an exception.
#include "hysim/cutting/mesh_io.hpp"

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <limits>
#include <string>
#include <string_view>
#include <vector>

#include "hysim/cutting/input_file.hpp"
#include "mesh_io_detail.hpp"

namespace hysim::cutting::io_detail {

Error errorAt(const std::string& path, long long line, const std::string& what) {
  return Error{path + ":" + std::to_string(line) + ": " + what};
}

Error errorIn(const std::string& path, const std::string& what) { return Error{path + ": " + what}; }

std::string lowercase(std::string_view s) {
  std::string out(s);
  for (char& c : out) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return out;
}

std::string_view trim(std::string_view s) {
  while (!s.empty() && isSpace(s.front())) s.remove_prefix(1);
  while (!s.empty() && isSpace(s.back())) s.remove_suffix(1);
  return s;
}

void splitWhitespace(std::string_view line, std::vector<std::string_view>& tokens) {
  tokens.clear();
  std::size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && isSpace(line[i])) ++i;
    const std::size_t start = i;
    while (i < line.size() && !isSpace(line[i])) ++i;
    if (i > start) tokens.push_back(line.substr(start, i - start));
  }
}

bool parseInteger(std::string_view token, long long& out) {
  if (!token.empty() && token.front() == '+') token.remove_prefix(1);
  if (token.empty()) return false;
  const auto [end, ec] = std::from_chars(token.data(), token.data() + token.size(), out);
  return ec == std::errc() && end == token.data() + token.size();
}

bool parseReal(std::string_view token, double& out) {
  if (!token.empty() && token.front() == '+') token.remove_prefix(1);
  if (token.empty()) return false;
  const auto [end, ec] = std::from_chars(token.data(), token.data() + token.size(), out);
  return ec == std::errc() && end == token.data() + token.size();
}

bool fitsInt32(long long v) {
  return v >= std::numeric_limits<std::int32_t>::min() && v <= std::numeric_limits<std::int32_t>::max();
}

std::string quoted(std::string_view s) {
  constexpr std::size_t kMaxShown = 40;
  std::string out = "'";
  for (std::size_t i = 0; i < s.size() && i < kMaxShown; ++i) {
    const auto c = static_cast<unsigned char>(s[i]);
    out += (c < 0x20 || c == 0x7f) ? '?' : s[i];
  }
  out += s.size() > kMaxShown ? "...'" : "'";
  return out;
}

std::string coordinateTooLarge(std::string_view token) {
  char bound[32];
  std::snprintf(bound, sizeof bound, "%g", kMaxCoordinateMm);
  return "coordinate " + quoted(token) + " beyond +-" + bound + " mm (larger values overflow volumes)";
}

std::size_t cappedReserve(long long count, std::size_t fileSize) {
  return static_cast<std::size_t>(std::clamp<long long>(count, 0, static_cast<long long>(fileSize / 2 + 1)));
}

}  // namespace hysim::cutting::io_detail

namespace hysim::cutting {

namespace {

using namespace io_detail;

Status writeWholeFile(const std::string& path, const std::string& text) {
  std::FILE* file = std::fopen(path.c_str(), "wb");
  if (!file) return Error{"cannot write '" + path + "': " + std::strerror(errno)};
  const std::size_t written = std::fwrite(text.data(), 1, text.size(), file);
  const int writeErrno = errno;
  const bool closed = std::fclose(file) == 0;
  if (written != text.size() || !closed) {
    return Error{"cannot write '" + path +
                 "': " + std::strerror(written != text.size() ? writeErrno : errno)};
  }
  return Status::Ok();
}

// ".msh" or ".vtk" (lowercase), or "" when the name has no extension.
std::string extensionOf(const std::string& path) {
  const std::size_t slash = path.find_last_of('/');
  const std::size_t dot = path.find_last_of('.');
  if (dot == std::string::npos || (slash != std::string::npos && dot < slash)) return "";
  return lowercase(std::string_view(path).substr(dot));
}

enum class Format { Msh, Vtk };

Result<Format> formatForReading(const std::string& path, const std::string& text) {
  const std::string ext = extensionOf(path);
  if (ext == ".msh") return Format::Msh;
  if (ext == ".vtk") return Format::Vtk;
  // Unknown extension: recognise the content by its first line.
  const std::string_view head = trim(std::string_view(text).substr(0, 64));
  if (head.rfind("$MeshFormat", 0) == 0) return Format::Msh;
  if (lowercase(head).rfind("# vtk datafile", 0) == 0) return Format::Vtk;
  return errorIn(path, "unknown mesh format (expected a .msh or .vtk file)");
}

// Parses a file's text; `format` receives the format it was read as.
Result<RawMesh> parseRaw(const std::string& path, const std::string& text, Format& format) {
  Result<Format> detected = formatForReading(path, text);
  if (!detected) return Error{detected.error()};
  format = *detected;
  return format == Format::Msh ? parseMsh(path, text) : parseVtk(path, text);
}

Positions toPositions(const std::vector<double>& xyz) {
  const Eigen::Index n = static_cast<Eigen::Index>(xyz.size() / 3);
  Positions X(n, 3);
  for (Eigen::Index i = 0; i < n; ++i) {
    for (int axis = 0; axis < 3; ++axis) X(i, axis) = xyz[static_cast<std::size_t>(3 * i + axis)];
  }
  return X;
}

template <class Elements>
Elements toElements(const std::vector<std::int32_t>& flat) {
  const Eigen::Index cols = Elements::ColsAtCompileTime;
  const Eigen::Index n = static_cast<Eigen::Index>(flat.size()) / cols;
  Elements E(n, cols);
  for (Eigen::Index e = 0; e < n; ++e) {
    for (Eigen::Index j = 0; j < cols; ++j) E(e, j) = flat[static_cast<std::size_t>(e * cols + j)];
  }
  return E;
}

Labels toLabels(const std::vector<std::int32_t>& values) {
  Labels L(static_cast<Eigen::Index>(values.size()));
  for (std::size_t i = 0; i < values.size(); ++i) L(static_cast<Eigen::Index>(i)) = values[i];
  return L;
}

// ---------------------------------------------------------------------------------------
// Writing

// Appends printf-formatted text; every call here formats a bounded number of values.
template <class... Args>
void appendf(std::string& out, const char* format, Args... args) {
  char buffer[256];
  const int n = std::snprintf(buffer, sizeof buffer, format, args...);
  if (n > 0) out.append(buffer, static_cast<std::size_t>(std::min<int>(n, sizeof buffer - 1)));
}

// What a writer needs from either mesh type: elements with `cols` nodes and their labels.
template <class Elements>
Status checkWritable(const std::string& path, const Positions& X, const Elements& E, const Labels& material,
                     const char* elementName) {
  if (material.rows() != 0 && material.rows() != E.rows()) {
    return Error{"cannot write '" + path + "': " + std::to_string(material.rows()) + " material labels for " +
                 std::to_string(E.rows()) + " " + elementName + "s"};
  }
  for (Eigen::Index i = 0; i < X.rows(); ++i) {
    if (!X.row(i).allFinite()) {
      return Error{"cannot write '" + path + "': node " + std::to_string(i) + " has a non-finite coordinate"};
    }
  }
  for (Eigen::Index e = 0; e < E.rows(); ++e) {
    for (Eigen::Index j = 0; j < E.cols(); ++j) {
      if (E(e, j) < 0 || E(e, j) >= X.rows()) {
        return Error{"cannot write '" + path + "': " + elementName + " " + std::to_string(e) +
                     " references node " + std::to_string(E(e, j)) + " of " + std::to_string(X.rows())};
      }
    }
  }
  return Status::Ok();
}

// %.17g prints every double so that reading it back gives the same bits.
void appendPoint(std::string& out, const Positions& X, Eigen::Index i) {
  appendf(out, "%.17g %.17g %.17g", X(i, 0), X(i, 1), X(i, 2));
}

template <class Elements>
std::string formatMsh(const Positions& X, const Elements& E, const Labels& material, int mshType) {
  std::string out;
  out.reserve(static_cast<std::size_t>(X.rows()) * 64 + static_cast<std::size_t>(E.rows()) * 48 + 128);
  out += "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n";
  appendf(out, "%lld\n", static_cast<long long>(X.rows()));
  for (Eigen::Index i = 0; i < X.rows(); ++i) {
    appendf(out, "%lld ", static_cast<long long>(i + 1));
    appendPoint(out, X, i);
    out += '\n';
  }
  out += "$EndNodes\n$Elements\n";
  appendf(out, "%lld\n", static_cast<long long>(E.rows()));
  for (Eigen::Index e = 0; e < E.rows(); ++e) {
    const int label = material.rows() == 0 ? 0 : material(e);
    // Two tags: physical group (the material) and elementary entity (also the material).
    appendf(out, "%lld %d 2 %d %d", static_cast<long long>(e + 1), mshType, label, label);
    for (Eigen::Index j = 0; j < E.cols(); ++j) appendf(out, " %d", E(e, j) + 1);
    out += '\n';
  }
  out += "$EndElements\n";
  return out;
}

template <class Elements>
std::string formatVtk(const Positions& X, const Elements& E, const Labels& material, int vtkType) {
  std::string out;
  out.reserve(static_cast<std::size_t>(X.rows()) * 64 + static_cast<std::size_t>(E.rows()) * 48 + 256);
  out += "# vtk DataFile Version 3.0\nhysim mesh\nASCII\nDATASET UNSTRUCTURED_GRID\n";
  appendf(out, "POINTS %lld double\n", static_cast<long long>(X.rows()));
  for (Eigen::Index i = 0; i < X.rows(); ++i) {
    appendPoint(out, X, i);
    out += '\n';
  }
  const long long cols = E.cols();
  appendf(out, "CELLS %lld %lld\n", static_cast<long long>(E.rows()),
          static_cast<long long>(E.rows()) * (cols + 1));
  for (Eigen::Index e = 0; e < E.rows(); ++e) {
    appendf(out, "%lld", cols);
    for (Eigen::Index j = 0; j < E.cols(); ++j) appendf(out, " %d", E(e, j));
    out += '\n';
  }
  appendf(out, "CELL_TYPES %lld\n", static_cast<long long>(E.rows()));
  for (Eigen::Index e = 0; e < E.rows(); ++e) appendf(out, "%d\n", vtkType);
  appendf(out, "CELL_DATA %lld\nSCALARS material int 1\nLOOKUP_TABLE default\n",
          static_cast<long long>(E.rows()));
  for (Eigen::Index e = 0; e < E.rows(); ++e) appendf(out, "%d\n", material.rows() == 0 ? 0 : material(e));
  return out;
}

template <class Elements>
Status writeAny(const std::string& path, const Positions& X, const Elements& E, const Labels& material,
                const char* elementName, int mshType, int vtkType) {
  const std::string ext = extensionOf(path);
  if (ext != ".msh" && ext != ".vtk") {
    return Error{"cannot write '" + path + "': unknown mesh extension (expected .msh or .vtk)"};
  }
  if (Status s = checkWritable(path, X, E, material, elementName); !s) return s;
  return writeWholeFile(
      path, ext == ".msh" ? formatMsh(X, E, material, mshType) : formatVtk(X, E, material, vtkType));
}

}  // namespace

Result<TetMesh> readTetMesh(const std::string& path) {
  Result<std::string> text = readInputFile(path, kMaxMeshFileBytes, "mesh");
  if (!text) return Error{text.error()};
  return parseTetMesh(path, *text);
}

Result<TriMesh> readTriMesh(const std::string& path) {
  Result<std::string> text = readInputFile(path, kMaxMeshFileBytes, "mesh");
  if (!text) return Error{text.error()};
  return parseTriMesh(path, *text);
}

Result<TetMesh> parseTetMesh(const std::string& path, const std::string& text) {
  Format format = Format::Msh;
  Result<RawMesh> raw = parseRaw(path, text, format);
  if (!raw) return Error{raw.error()};
  if (raw->tets.empty()) {
    return errorIn(path, format == Format::Msh ? "no tetrahedra (MSH element type 4) in file"
                                               : "no tetrahedra (VTK cell type 10) in file");
  }
  TetMesh mesh;
  mesh.X = toPositions(raw->xyz);
  mesh.T = toElements<Tets>(raw->tets);
  mesh.material = toLabels(raw->tetMaterial);
  return mesh;
}

Result<TriMesh> parseTriMesh(const std::string& path, const std::string& text) {
  Format format = Format::Msh;
  Result<RawMesh> raw = parseRaw(path, text, format);
  if (!raw) return Error{raw.error()};
  if (raw->tris.empty()) {
    return errorIn(path, format == Format::Msh ? "no triangles (MSH element type 2) in file"
                                               : "no triangles (VTK cell type 5) in file");
  }
  TriMesh mesh;
  mesh.X = toPositions(raw->xyz);
  mesh.F = toElements<Tris>(raw->tris);
  mesh.material = toLabels(raw->triMaterial);
  return mesh;
}

Status writeMesh(const std::string& path, const TetMesh& mesh) {
  return writeAny(path, mesh.X, mesh.T, mesh.material, "tet", 4, 10);
}

Status writeMesh(const std::string& path, const TriMesh& mesh) {
  return writeAny(path, mesh.X, mesh.F, mesh.material, "triangle", 2, 5);
}

}  // namespace hysim::cutting
