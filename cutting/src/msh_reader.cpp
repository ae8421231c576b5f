// Gmsh MSH 2.2 ASCII reader. Node ids may be any integers (non-contiguous, unordered);
// they are mapped to rows in file order. Sections other than $MeshFormat, $Nodes and
// $Elements are skipped.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>
#include <string_view>
#include <unordered_map>
#include <vector>

#include "mesh_io_detail.hpp"

namespace hysim::cutting::io_detail {

namespace {

// Splits text into lines, counting them (1-based) for messages.
class LineReader {
 public:
  explicit LineReader(const std::string& text) : text_(text) {}
  bool next(std::string_view& line) {
    if (pos_ >= text_.size()) return false;
    const std::size_t end = text_.find('\n', pos_);
    const std::size_t stop = end == std::string::npos ? text_.size() : end;
    line = std::string_view(text_).substr(pos_, stop - pos_);
    pos_ = end == std::string::npos ? text_.size() : end + 1;
    ++lineNumber_;
    return true;
  }
  // Next line that is not blank, trimmed.
  bool nextNonBlank(std::string_view& line) {
    while (next(line)) {
      line = trim(line);
      if (!line.empty()) return true;
    }
    return false;
  }
  long long lineNumber() const { return lineNumber_; }

 private:
  const std::string& text_;
  std::size_t pos_ = 0;
  long long lineNumber_ = 0;
};

// Nodes of each element type the MSH 2.2 format defines (Gmsh reference manual, "MSH file
// format version 2"), or -1 for a number that is no MSH 2.2 element type.
int mshNodesPerElement(long long type) {
  static constexpr int kNodes[32] = {-1, 2,  3,  4,  4,  8,  6,  5,  3,  6,  9,  10, 27, 18, 14, 1,
                                     8,  20, 15, 13, 9,  10, 12, 15, 15, 21, 4,  5,  6,  20, 35, 56};
  if (type >= 1 && type <= 31) return kNodes[type];
  if (type == 92) return 64;   // 64-node third-order hexahedron
  if (type == 93) return 125;  // 125-node fourth-order hexahedron
  return -1;
}

class MshParser {
 public:
  MshParser(const std::string& path, const std::string& text) : path_(path), text_(text), lines_(text) {}

  Result<RawMesh> parse() {
    std::string_view line;
    if (!lines_.nextNonBlank(line)) return errorIn(path_, "empty file");
    if (line != "$MeshFormat") {
      return fail("expected $MeshFormat, got " + quoted(line) + " (only Gmsh MSH 2.2 ASCII is supported)");
    }
    if (Status s = parseMeshFormat(); !s) return Error{s.error()};
    while (lines_.nextNonBlank(line)) {
      if (line == "$Nodes") {
        if (seenNodes_) return fail("second $Nodes section");
        if (Status s = parseNodes(); !s) return Error{s.error()};
        seenNodes_ = true;
      } else if (line == "$Elements") {
        if (!seenNodes_) return fail("$Elements before $Nodes");
        if (seenElements_) return fail("second $Elements section");
        if (Status s = parseElements(); !s) return Error{s.error()};
        seenElements_ = true;
      } else if (line.front() == '$' && line.substr(0, 4) != "$End") {
        // Sections we do not use ($PhysicalNames, $NodeData, $Periodic, ...): skip.
        if (Status s = skipSection(line.substr(1)); !s) return Error{s.error()};
      } else {
        return fail("unexpected " + quoted(line) + " outside a section");
      }
    }
    if (!seenNodes_) return errorIn(path_, "no $Nodes section");
    if (!seenElements_) return errorIn(path_, "no $Elements section");
    return std::move(mesh_);
  }

 private:
  Error fail(const std::string& what) const { return errorAt(path_, lines_.lineNumber(), what); }

  // Reports EOF inside a section at the last line of the file.
  Error missingEnd(std::string_view section) const {
    return fail("missing $End" + std::string(section) + " (end of file)");
  }

  Status parseMeshFormat() {
    std::string_view line;
    if (!lines_.nextNonBlank(line)) return missingEnd("MeshFormat");
    splitWhitespace(line, tokens_);
    if (tokens_.size() != 3) {
      return fail("expected 'version file-type data-size' in $MeshFormat, got " + quoted(line));
    }
    double version = 0;
    long long fileType = 0;
    if (!parseReal(tokens_[0], version)) return fail("bad MSH version " + quoted(tokens_[0]));
    if (!parseInteger(tokens_[1], fileType)) return fail("bad MSH file type " + quoted(tokens_[1]));
    if (version != 2.2) {
      return fail("unsupported MSH version " + std::string(tokens_[0]) +
                  " (only 2.2 ASCII is supported; in Gmsh: File > Export, 'Version 2 ASCII')");
    }
    if (fileType != 0) {
      return fail(
          "binary MSH files are not supported (only 2.2 ASCII; in Gmsh: File > Export, "
          "'Version 2 ASCII')");
    }
    if (!lines_.nextNonBlank(line)) return missingEnd("MeshFormat");
    if (line != "$EndMeshFormat") return fail("expected $EndMeshFormat, got " + quoted(line));
    return Status::Ok();
  }

  // Reads the count line that opens $Nodes and $Elements.
  Status parseCount(std::string_view section, long long& count) {
    std::string_view line;
    if (!lines_.nextNonBlank(line)) return missingEnd(section);
    if (!parseInteger(line, count) || count < 0) {
      return fail("expected the number of " + std::string(section == "Nodes" ? "nodes" : "elements") +
                  ", got " + quoted(line));
    }
    return Status::Ok();
  }

  // After `count` entries, the next line must close the section.
  Status expectEnd(std::string_view section, long long count) {
    std::string_view line;
    if (!lines_.nextNonBlank(line)) return missingEnd(section);
    const std::string end = "$End" + std::string(section);
    if (line != end) {
      return fail("expected " + end + " after " + std::to_string(count) + " " + lowercase(section) +
                  ", got " + quoted(line));
    }
    return Status::Ok();
  }

  Status parseNodes() {
    long long count = 0;
    if (Status s = parseCount("Nodes", count); !s) return s;
    mesh_.xyz.reserve(3 * cappedReserve(count, text_.size()));
    nodeIndexById_.reserve(cappedReserve(count, text_.size()));
    std::string_view line;
    for (long long i = 0; i < count; ++i) {
      if (!lines_.nextNonBlank(line)) return missingEnd("Nodes");
      if (line.front() == '$') {
        return fail("expected " + std::to_string(count) + " nodes, got " + std::to_string(i) + " before " +
                    quoted(line));
      }
      splitWhitespace(line, tokens_);
      if (tokens_.size() != 4) {
        return fail("expected 'id x y z' for a node, got " + std::to_string(tokens_.size()) + " values");
      }
      long long id = 0;
      if (!parseInteger(tokens_[0], id)) return fail("bad node id " + quoted(tokens_[0]));
      for (int axis = 0; axis < 3; ++axis) {
        const std::string_view token = tokens_[1 + axis];
        double value = 0;
        if (!parseReal(token, value)) {
          return fail("bad coordinate " + quoted(token) + " for node " + std::to_string(id));
        }
        if (!std::isfinite(value)) {
          return fail("non-finite coordinate " + quoted(token) + " for node " + std::to_string(id));
        }
        if (std::abs(value) > kMaxCoordinateMm) {
          return fail(coordinateTooLarge(token) + " for node " + std::to_string(id));
        }
        mesh_.xyz.push_back(value);
      }
      if (!fitsInt32(i)) return fail("too many nodes for 32-bit indices");
      if (!nodeIndexById_.emplace(id, static_cast<std::int32_t>(i)).second) {
        return fail("duplicate node id " + std::to_string(id));
      }
    }
    return expectEnd("Nodes", count);
  }

  Status parseElements() {
    long long count = 0;
    if (Status s = parseCount("Elements", count); !s) return s;
    std::string_view line;
    for (long long i = 0; i < count; ++i) {
      if (!lines_.nextNonBlank(line)) return missingEnd("Elements");
      if (line.front() == '$') {
        return fail("expected " + std::to_string(count) + " elements, got " + std::to_string(i) + " before " +
                    quoted(line));
      }
      splitWhitespace(line, tokens_);
      if (tokens_.size() < 3) {
        return fail("expected 'id type number-of-tags tags... nodes...' for an element, got " + quoted(line));
      }
      values_.resize(tokens_.size());
      for (std::size_t k = 0; k < tokens_.size(); ++k) {
        if (!parseInteger(tokens_[k], values_[k])) {
          return fail("expected an integer in element, got " + quoted(tokens_[k]));
        }
      }
      const long long id = values_[0];
      const long long type = values_[1];
      const long long numTags = values_[2];
      if (numTags < 0 || numTags > static_cast<long long>(tokens_.size()) - 3) {
        return fail("element " + std::to_string(id) + " has " + std::to_string(numTags) + " tags but only " +
                    std::to_string(tokens_.size() - 3) + " values follow");
      }
      const std::size_t firstNode = 3 + static_cast<std::size_t>(numTags);
      const std::size_t numNodes = tokens_.size() - firstNode;
      // Gmsh's first tag is the physical group: that is the material.
      const long long material = numTags >= 1 ? values_[3] : 0;
      if (!fitsInt32(material)) return fail("physical tag " + std::to_string(material) + " out of range");

      // Node ids are resolved for every element, also the ignored kinds (lines, points,
      // quads): a file that references missing nodes is broken either way.
      resolved_.clear();
      for (std::size_t k = firstNode; k < tokens_.size(); ++k) {
        const auto found = nodeIndexById_.find(values_[k]);
        if (found == nodeIndexById_.end()) {
          return fail("element " + std::to_string(id) + " references unknown node " +
                      std::to_string(values_[k]));
        }
        resolved_.push_back(found->second);
      }
      // Every element's node count is checked against its type, also for the kinds that are
      // ignored: a count that does not match means the line is misread.
      const int expected = mshNodesPerElement(type);
      if (expected < 0) {
        return fail("element " + std::to_string(id) + " has unknown element type " + std::to_string(type) +
                    " (MSH 2.2 defines types 1-31, 92 and 93)");
      }
      if (numNodes != static_cast<std::size_t>(expected)) {
        const std::string kind =
            type == 4 ? "tetrahedron" : type == 2 ? "triangle" : "element type " + std::to_string(type);
        return fail("expected " + std::to_string(expected) + " node indices for " + kind + ", got " +
                    std::to_string(numNodes));
      }
      if (type == 4) {  // 4-node tetrahedron
        mesh_.tets.insert(mesh_.tets.end(), resolved_.begin(), resolved_.end());
        mesh_.tetMaterial.push_back(static_cast<std::int32_t>(material));
      } else if (type == 2) {  // 3-node triangle
        mesh_.tris.insert(mesh_.tris.end(), resolved_.begin(), resolved_.end());
        mesh_.triMaterial.push_back(static_cast<std::int32_t>(material));
      }
    }
    return expectEnd("Elements", count);
  }

  Status skipSection(std::string_view name) {
    const std::string end = "$End" + std::string(name);
    std::string_view line;
    while (lines_.nextNonBlank(line)) {
      if (line == end) return Status::Ok();
    }
    return missingEnd(name);
  }

  const std::string& path_;
  const std::string& text_;
  LineReader lines_;
  RawMesh mesh_;
  std::unordered_map<long long, std::int32_t> nodeIndexById_;  // file node id -> row of xyz
  std::vector<std::string_view> tokens_;
  std::vector<long long> values_;
  std::vector<std::int32_t> resolved_;
  bool seenNodes_ = false;
  bool seenElements_ = false;
};

}  // namespace

Result<RawMesh> parseMsh(const std::string& path, const std::string& text) {
  return MshParser(path, text).parse();
}

}  // namespace hysim::cutting::io_detail
