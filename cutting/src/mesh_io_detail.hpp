#pragma once
// Internal to cutting/src: what the MSH and VTK readers share. Not installed, not API.
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "hysim/cutting/mesh.hpp"
#include "hysim/cutting/result.hpp"

namespace hysim::cutting::io_detail {

// What both readers produce. Node indices are 0-based rows of xyz.
struct RawMesh {
  std::vector<double> xyz;                // 3 * #N, node-major (x0 y0 z0 x1 ...)
  std::vector<std::int32_t> tets;         // 4 * #T node indices
  std::vector<std::int32_t> tetMaterial;  // #T
  std::vector<std::int32_t> tris;         // 3 * #F node indices
  std::vector<std::int32_t> triMaterial;  // #F
};

// Parsers over a whole file's text; `path` is only used in messages.
Result<RawMesh> parseMsh(const std::string& path, const std::string& text);
Result<RawMesh> parseVtk(const std::string& path, const std::string& text);

// "path:line: what" and "path: what".
Error errorAt(const std::string& path, long long line, const std::string& what);
Error errorIn(const std::string& path, const std::string& what);

std::string lowercase(std::string_view s);
inline bool isSpace(char c) {
  return c == ' ' || c == '\t' || c == '\r' || c == '\n' || c == '\v' || c == '\f';
}
std::string_view trim(std::string_view s);
// Splits on whitespace into views of `line` (cleared first).
void splitWhitespace(std::string_view line, std::vector<std::string_view>& tokens);
// Whole-token integer parse; a leading '+' is accepted (from_chars alone rejects it).
bool parseInteger(std::string_view token, long long& out);
// Whole-token floating-point parse. "nan" and "inf" parse (and are rejected later with a
// clearer message); values beyond double range are reported as not parsed.
bool parseReal(std::string_view token, double& out);
bool fitsInt32(long long v);
// File text shown in a message: cut short and with control characters (a stray '\r', binary
// bytes) replaced, so that a message stays one readable line.
std::string quoted(std::string_view s);
// "coordinate '<token>' beyond +-1e+30 mm ..." (kMaxCoordinateMm), for a coordinate the
// readers refuse because products of such values overflow in volumes and quality measures.
std::string coordinateTooLarge(std::string_view token);
// Untrusted counts must not drive huge allocations: no element or node can take less
// than two characters of the file.
std::size_t cappedReserve(long long count, std::size_t fileSize);

}  // namespace hysim::cutting::io_detail
