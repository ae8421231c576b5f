// Legacy VTK ASCII unstructured-grid reader: classic CELLS and the VTK 5 OFFSETS /
// CONNECTIVITY layout, SCALARS and FIELD cell data (the "material" array, or meshio's
// "gmsh:physical"), METADATA blocks; other attribute arrays are checked and skipped.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>
#include <string_view>
#include <vector>

#include "mesh_io_detail.hpp"

namespace hysim::cutting::io_detail {

namespace {

// Whitespace-separated tokens with the line each starts on. VTK data may wrap lines
// anywhere, so numbers are read as a token stream, not line by line.
class TokenReader {
 public:
  explicit TokenReader(const std::string& text) : text_(text) {}

  bool next(std::string_view& token) {
    skipSpace();
    if (pos_ >= text_.size()) return false;
    tokenLine_ = line_;
    const std::size_t start = pos_;
    while (pos_ < text_.size() && !isSpace(text_[pos_])) ++pos_;
    token = std::string_view(text_).substr(start, pos_ - start);
    return true;
  }
  // Like next() without consuming; `line` (optional) receives the token's line.
  bool peek(std::string_view& token, long long* line = nullptr) {
    const std::size_t pos = pos_;
    const long long savedLine = line_, tokenLine = tokenLine_;
    const bool found = next(token);
    if (line) *line = tokenLine_;
    pos_ = pos;
    line_ = savedLine;
    tokenLine_ = tokenLine;
    return found;
  }
  // The rest of the current line (for the header's title and format lines).
  std::string_view restOfLine() {
    const std::size_t end = text_.find('\n', pos_);
    const std::size_t stop = end == std::string::npos ? text_.size() : end;
    std::string_view rest = std::string_view(text_).substr(pos_, stop - pos_);
    tokenLine_ = line_;
    if (end != std::string::npos) {
      pos_ = end + 1;
      ++line_;
    } else {
      pos_ = text_.size();
    }
    if (!rest.empty() && rest.back() == '\r') rest.remove_suffix(1);
    return rest;
  }
  // Skips the rest of the current line, then lines up to and including the first blank one
  // (how VTK 5 METADATA blocks end).
  void skipToBlankLine() {
    restOfLine();
    while (pos_ < text_.size()) {
      if (trim(restOfLine()).empty()) return;
    }
  }
  long long tokenLine() const { return tokenLine_; }  // line of the last token read

 private:
  void skipSpace() {
    while (pos_ < text_.size() && isSpace(text_[pos_])) {
      if (text_[pos_] == '\n') ++line_;
      ++pos_;
    }
  }
  const std::string& text_;
  std::size_t pos_ = 0;
  long long line_ = 1;
  long long tokenLine_ = 1;
};

// The cell type ids VTK defines (vtkCellType.h): linear cells 0-16, quadratic and cubic
// 21-37, convex point set and polyhedron 41-42, parametric 51-56, higher order 60-81.
bool isVtkCellType(long long type) {
  return (type >= 0 && type <= 16) || (type >= 21 && type <= 37) || type == 41 || type == 42 ||
         (type >= 51 && type <= 56) || (type >= 60 && type <= 81);
}

class VtkParser {
 public:
  VtkParser(const std::string& path, const std::string& text) : path_(path), text_(text), tokens_(text) {}

  Result<RawMesh> parse() {
    if (Status s = parseHeader(); !s) return Error{s.error()};
    std::string_view keyword;
    while (tokens_.next(keyword)) {
      keywordLine_ = tokens_.tokenLine();
      const std::string key = lowercase(keyword);
      Status s;
      if (key == "points") {
        s = parsePoints();
      } else if (key == "cells") {
        s = parseCells();
      } else if (key == "cell_types") {
        s = parseCellTypes();
      } else if (key == "cell_data" || key == "point_data") {
        s = parseAttributeStart(key == "cell_data");
      } else if (key == "scalars") {
        s = parseScalars();
      } else if (key == "field") {
        s = parseField();
      } else if (key == "vectors" || key == "normals" || key == "tensors" || key == "tensors6") {
        s = skipNamedArray(key == "tensors" ? 9 : key == "tensors6" ? 6 : 3, std::string(keyword));
      } else if (key == "texture_coordinates" || key == "color_scalars") {
        s = skipSizedArray(std::string(keyword));
      } else if (key == "lookup_table") {
        s = skipLookupTable();
      } else if (key == "metadata") {
        tokens_.skipToBlankLine();
      } else {
        s = failAtToken("unexpected " + quoted(keyword));
      }
      if (!s) return Error{s.error()};
    }
    return finish();
  }

 private:
  Error failAtToken(const std::string& what) const { return errorAt(path_, tokens_.tokenLine(), what); }
  // At end of file the last token's line is the last line with content.
  Error failAtEnd(const std::string& what) const {
    return errorAt(path_, tokens_.tokenLine(), "unexpected end of file: " + what);
  }

  Status parseHeader() {
    const std::string_view magic = trim(tokens_.restOfLine());
    if (lowercase(magic).rfind("# vtk datafile version", 0) != 0) {
      return failAtToken("expected '# vtk DataFile Version x.y', got " + quoted(magic));
    }
    if (Status s = checkVersion(magic); !s) return s;
    tokens_.restOfLine();  // title: free text
    const std::string_view format = trim(tokens_.restOfLine());
    if (lowercase(format) == "binary") {
      return failAtToken("binary VTK files are not supported (only legacy ASCII)");
    }
    if (lowercase(format) != "ascii") return failAtToken("expected ASCII, got " + quoted(format));
    std::string_view word;
    if (!tokens_.next(word)) return failAtEnd("expected DATASET");
    if (lowercase(word) != "dataset") return failAtToken("expected DATASET, got " + quoted(word));
    if (!tokens_.next(word)) return failAtEnd("expected dataset type");
    if (lowercase(word) != "unstructured_grid") {
      return failAtToken("unsupported dataset type " + quoted(word) + " (only UNSTRUCTURED_GRID)");
    }
    return Status::Ok();
  }

  // The legacy format's versions are 1.0 to 5.1; another number is another format, or a typo.
  Status checkVersion(std::string_view magic) {
    const std::string_view version = trim(magic.substr(std::string_view("# vtk DataFile Version").size()));
    const std::size_t dot = version.find('.');
    long long major = -1, minor = -1;
    const bool parsed = dot != std::string_view::npos && parseInteger(version.substr(0, dot), major) &&
                        parseInteger(version.substr(dot + 1), minor) && version.front() != '+' &&
                        version[dot + 1] != '+' && minor >= 0;
    if (!parsed || major < 1 || major > 5 || (major == 5 && minor > 1)) {
      return failAtToken("unsupported VTK version " + quoted(version) +
                         " (legacy VTK files are versions 1.0 to 5.1: '# vtk DataFile Version 3.0')");
    }
    return Status::Ok();
  }

  // `what` names the value in messages; `index` (when >= 0) is appended to it. Messages are
  // built only on failure: these run once per number in the file.
  static std::string describe(std::string_view what, long long index) {
    return index < 0 ? std::string(what) : std::string(what) + " " + std::to_string(index);
  }

  Status readInteger(std::string_view what, long long& value, long long index = -1) {
    std::string_view token;
    if (!tokens_.next(token)) return failAtEnd("expected " + describe(what, index));
    if (!parseInteger(token, value))
      return failAtToken("expected " + describe(what, index) + ", got " + quoted(token));
    return Status::Ok();
  }

  Status readCount(std::string_view what, long long& count, long long index = -1) {
    if (Status s = readInteger(what, count, index); !s) return s;
    if (count < 0) return failAtToken("expected " + describe(what, index) + ", got " + std::to_string(count));
    return Status::Ok();
  }

  // a * b for counts of values; no file can hold more values than it has characters.
  Status valueCount(long long a, long long b, long long& product) {
    const long long limit = static_cast<long long>(text_.size());
    if (a < 0 || b < 0 || (a > 0 && b > limit / a + 1)) {
      return failAtToken("value count " + std::to_string(a) + " x " + std::to_string(b) +
                         " exceeds the file size");
    }
    product = a * b;
    return Status::Ok();
  }

  Status readWord(const std::string& what, std::string_view& word) {
    if (!tokens_.next(word)) return failAtEnd("expected " + what);
    return Status::Ok();
  }

  Status parsePoints() {
    if (seenPoints_) return failAtToken("second POINTS section");
    seenPoints_ = true;
    long long count = 0;
    std::string_view type;
    if (Status s = readCount("number of points", count); !s) return s;
    if (Status s = readWord("point data type", type); !s) return s;
    mesh_.xyz.reserve(3 * cappedReserve(count, text_.size()));
    std::string_view token;
    for (long long i = 0; i < count; ++i) {
      for (int axis = 0; axis < 3; ++axis) {
        if (!tokens_.next(token)) {
          return failAtEnd("expected " + std::to_string(count) + " points, got " + std::to_string(i));
        }
        double value = 0;
        if (!parseReal(token, value)) {
          return failAtToken("bad coordinate " + quoted(token) + " for point " + std::to_string(i));
        }
        if (!std::isfinite(value)) {
          return failAtToken("non-finite coordinate " + quoted(token) + " for point " + std::to_string(i));
        }
        if (std::abs(value) > kMaxCoordinateMm) {
          return failAtToken(coordinateTooLarge(token) + " for point " + std::to_string(i));
        }
        mesh_.xyz.push_back(value);
      }
    }
    numPoints_ = count;
    return Status::Ok();
  }

  // Reads one point index of a cell; range is checked in finish() since POINTS may follow.
  Status readPointIndex(std::string_view what, long long position, std::int32_t& index) {
    long long value = 0;
    if (Status s = readInteger(what, value, position); !s) return s;
    if (!fitsInt32(value)) return failAtToken("point index " + std::to_string(value) + " out of range");
    index = static_cast<std::int32_t>(value);
    return Status::Ok();
  }

  Status parseCells() {
    if (seenCells_) return failAtToken("second CELLS section");
    seenCells_ = true;
    long long first = 0, second = 0;
    if (Status s = readCount("number of cells", first); !s) return s;
    if (Status s = readCount("CELLS size", second); !s) return s;
    std::string_view next;
    if (tokens_.peek(next) && lowercase(next) == "offsets") return parseCellsOffsets(first, second);

    // Classic layout: `first` cells, each "k i0 ... i(k-1)", `second` integers in all.
    const long long numCells = first;
    cellStart_.reserve(cappedReserve(numCells, text_.size()) + 1);
    cellStart_.push_back(0);
    long long valuesRead = 0;
    for (long long c = 0; c < numCells; ++c) {
      long long size = 0;
      if (Status s = readCount("number of points of cell", size, c); !s) return s;
      cellLine_.push_back(tokens_.tokenLine());
      for (long long k = 0; k < size; ++k) {
        std::int32_t index = 0;
        if (Status s = readPointIndex("point index of cell", c, index); !s) return s;
        connectivity_.push_back(index);
      }
      cellStart_.push_back(static_cast<long long>(connectivity_.size()));
      valuesRead += 1 + size;
    }
    if (valuesRead != second) {
      return errorAt(path_, keywordLine_,
                     "CELLS declares " + std::to_string(second) + " values but its " +
                         std::to_string(numCells) + " cells have " + std::to_string(valuesRead));
    }
    numCells_ = numCells;
    return Status::Ok();
  }

  // VTK 5 layout: "CELLS n+1 m", "OFFSETS type" with n+1 offsets, "CONNECTIVITY type" with m indices.
  Status parseCellsOffsets(long long numOffsets, long long numIndices) {
    std::string_view word;
    tokens_.next(word);  // OFFSETS
    if (Status s = readWord("OFFSETS data type", word); !s) return s;
    if (numOffsets < 1) return failAtToken("CELLS in OFFSETS layout needs at least one offset");
    cellStart_.reserve(cappedReserve(numOffsets, text_.size()));
    for (long long i = 0; i < numOffsets; ++i) {
      long long offset = 0;
      if (Status s = readInteger("cell offset", offset, i); !s) return s;
      const long long previous = cellStart_.empty() ? 0 : cellStart_.back();
      if ((i == 0 && offset != 0) || offset < previous || offset > numIndices) {
        return failAtToken("bad cell offset " + std::to_string(offset) +
                           " (offsets start at 0, never decrease "
                           "and end at the CONNECTIVITY size " +
                           std::to_string(numIndices) + ")");
      }
      cellStart_.push_back(offset);
      if (i + 1 < numOffsets) cellLine_.push_back(tokens_.tokenLine());
    }
    if (cellStart_.back() != numIndices) {
      return failAtToken("last cell offset " + std::to_string(cellStart_.back()) +
                         " differs from the CONNECTIVITY size " + std::to_string(numIndices));
    }
    if (Status s = readWord("CONNECTIVITY", word); !s) return s;
    if (lowercase(word) != "connectivity") return failAtToken("expected CONNECTIVITY, got " + quoted(word));
    if (Status s = readWord("CONNECTIVITY data type", word); !s) return s;
    connectivity_.reserve(cappedReserve(numIndices, text_.size()));
    for (long long i = 0; i < numIndices; ++i) {
      std::int32_t index = 0;
      if (Status s = readPointIndex("CONNECTIVITY entry", i, index); !s) return s;
      connectivity_.push_back(index);
    }
    numCells_ = numOffsets - 1;
    return Status::Ok();
  }

  Status parseCellTypes() {
    if (seenCellTypes_) return failAtToken("second CELL_TYPES section");
    seenCellTypes_ = true;
    long long count = 0;
    if (Status s = readCount("number of cell types", count); !s) return s;
    if (!seenCells_) return failAtToken("CELL_TYPES before CELLS");
    if (count != numCells_) {
      return failAtToken("CELL_TYPES has " + std::to_string(count) + " entries but CELLS has " +
                         std::to_string(numCells_));
    }
    cellTypes_.reserve(cappedReserve(count, text_.size()));
    for (long long c = 0; c < count; ++c) {
      long long type = 0;
      if (Status s = readInteger("type of cell", type, c); !s) return s;
      cellTypes_.push_back(type);
      cellTypeLine_.push_back(tokens_.tokenLine());
    }
    return Status::Ok();
  }

  Status parseAttributeStart(bool cells) {
    long long count = 0;
    if (Status s = readCount(cells ? "CELL_DATA count" : "POINT_DATA count", count); !s) return s;
    if (cells && seenCells_ && count != numCells_) {
      return failAtToken("CELL_DATA has " + std::to_string(count) + " values but CELLS has " +
                         std::to_string(numCells_) + " cells");
    }
    if (!cells && seenPoints_ && count != numPoints_) {
      return failAtToken("POINT_DATA has " + std::to_string(count) + " values but POINTS has " +
                         std::to_string(numPoints_) + " points");
    }
    attributeIsCells_ = cells;
    attributeCount_ = count;
    seenAttributes_ = true;
    return Status::Ok();
  }

  // Reads `count` numbers; keeps them as labels when `labels` is non-null.
  Status readValues(long long count, const std::string& what, std::vector<std::int32_t>* labels) {
    if (labels) labels->reserve(cappedReserve(count, text_.size()));
    std::string_view token;
    for (long long i = 0; i < count; ++i) {
      if (!tokens_.next(token)) {
        return failAtEnd(what + " expects " + std::to_string(count) + " values, got " + std::to_string(i));
      }
      long long integer = 0;
      double real = 0;
      if (parseInteger(token, integer)) {
        real = static_cast<double>(integer);
      } else if (!parseReal(token, real)) {
        return failAtToken("bad value " + quoted(token) + " in " + what);
      }
      if (labels) {
        // Labels may be stored as floats by other tools; accept whole numbers only.
        if (!(real == std::floor(real)) || real < std::numeric_limits<std::int32_t>::min() ||
            real > std::numeric_limits<std::int32_t>::max()) {
          return failAtToken("material " + quoted(token) + " is not a 32-bit integer");
        }
        labels->push_back(static_cast<std::int32_t>(real));
      }
    }
    return Status::Ok();
  }

  Status requireAttributeSection(std::string_view keyword) {
    if (!seenAttributes_) return failAtToken(std::string(keyword) + " outside CELL_DATA or POINT_DATA");
    return Status::Ok();
  }

  // The material array: "material" wins; "gmsh:physical" (meshio's name for the physical
  // tag) is used when no "material" array exists.
  void offerLabels(std::string_view name, std::vector<std::int32_t>&& labels) {
    if (name == "material") {
      material_ = std::move(labels);
      materialIsFinal_ = true;
    } else if (!materialIsFinal_) {
      material_ = std::move(labels);
    }
  }

  bool wantsLabels(std::string_view name, long long components) const {
    return attributeIsCells_ && components == 1 && (name == "material" || name == "gmsh:physical");
  }

  Status parseScalars() {
    if (Status s = requireAttributeSection("SCALARS"); !s) return s;
    std::string_view name, type;
    if (Status s = readWord("SCALARS name", name); !s) return s;
    if (Status s = readWord("SCALARS data type", type); !s) return s;
    long long components = 1;
    std::string_view next;
    long long nextLine = 0;
    // The component count is optional: present when a number follows on the same line.
    if (tokens_.peek(next, &nextLine) && nextLine == tokens_.tokenLine() && parseInteger(next, components)) {
      tokens_.next(next);
      if (components < 1 || components > 4) return failAtToken("SCALARS component count must be 1..4");
    }
    if (tokens_.peek(next) && lowercase(next) == "lookup_table") {
      tokens_.next(next);
      if (Status s = readWord("LOOKUP_TABLE name", next); !s) return s;
    }
    const std::string what = "SCALARS " + quoted(name);
    if (wantsLabels(name, components)) {
      std::vector<std::int32_t> labels;
      if (Status s = readValues(attributeCount_, what, &labels); !s) return s;
      offerLabels(name, std::move(labels));
      return Status::Ok();
    }
    long long total = 0;
    if (Status s = valueCount(attributeCount_, components, total); !s) return s;
    return readValues(total, what, nullptr);
  }

  Status parseField() {
    std::string_view fieldName;
    long long numArrays = 0;
    if (Status s = readWord("FIELD name", fieldName); !s) return s;
    if (Status s = readCount("FIELD array count", numArrays); !s) return s;
    for (long long a = 0; a < numArrays; ++a) {
      std::string_view name, type, next;
      long long components = 0, tuples = 0;
      if (Status s = readWord("FIELD array name", name); !s) return s;
      if (Status s = readCount("component count of " + quoted(name), components); !s) return s;
      if (Status s = readCount("tuple count of " + quoted(name), tuples); !s) return s;
      if (Status s = readWord("data type of " + quoted(name), type); !s) return s;
      const std::string what = "FIELD array " + quoted(name);
      if (seenAttributes_ && wantsLabels(name, components) && tuples == attributeCount_) {
        std::vector<std::int32_t> labels;
        if (Status s = readValues(tuples, what, &labels); !s) return s;
        offerLabels(name, std::move(labels));
      } else {
        long long total = 0;
        if (Status s = valueCount(components, tuples, total); !s) return s;
        if (Status s = readValues(total, what, nullptr); !s) return s;
      }
      // VTK 5 writers may follow each array with a METADATA block.
      if (tokens_.peek(next) && lowercase(next) == "metadata") {
        tokens_.next(next);
        tokens_.skipToBlankLine();
      }
    }
    return Status::Ok();
  }

  Status skipNamedArray(long long components, const std::string& keyword) {
    if (Status s = requireAttributeSection(keyword); !s) return s;
    std::string_view name, type;
    if (Status s = readWord(keyword + " name", name); !s) return s;
    if (Status s = readWord(keyword + " data type", type); !s) return s;
    long long total = 0;
    if (Status s = valueCount(attributeCount_, components, total); !s) return s;
    return readValues(total, keyword + " " + quoted(name), nullptr);
  }

  // TEXTURE_COORDINATES name dim type / COLOR_SCALARS name nValues.
  Status skipSizedArray(const std::string& keyword) {
    if (Status s = requireAttributeSection(keyword); !s) return s;
    std::string_view name, type;
    long long components = 0;
    if (Status s = readWord(keyword + " name", name); !s) return s;
    if (Status s = readCount(keyword + " component count", components); !s) return s;
    if (lowercase(keyword) == "texture_coordinates") {
      if (Status s = readWord(keyword + " data type", type); !s) return s;
    }
    long long total = 0;
    if (Status s = valueCount(attributeCount_, components, total); !s) return s;
    return readValues(total, keyword + " " + quoted(name), nullptr);
  }

  // A standalone lookup table: "LOOKUP_TABLE name size" then size RGBA tuples.
  Status skipLookupTable() {
    std::string_view name;
    long long size = 0;
    if (Status s = readWord("LOOKUP_TABLE name", name); !s) return s;
    if (Status s = readCount("LOOKUP_TABLE size", size); !s) return s;
    long long total = 0;
    if (Status s = valueCount(4, size, total); !s) return s;
    return readValues(total, "LOOKUP_TABLE " + quoted(name), nullptr);
  }

  Result<RawMesh> finish() {
    if (!seenPoints_) return errorIn(path_, "no POINTS section");
    if (!seenCells_) return errorIn(path_, "no CELLS section");
    if (!seenCellTypes_) return errorIn(path_, "no CELL_TYPES section");
    if (!material_.empty() && static_cast<long long>(material_.size()) != numCells_) {
      return errorIn(path_, "material array has " + std::to_string(material_.size()) +
                                " values but CELLS has " + std::to_string(numCells_) + " cells");
    }
    for (long long c = 0; c < numCells_; ++c) {
      const auto cell = static_cast<std::size_t>(c);
      const long long begin = cellStart_[cell];
      const long long size = cellStart_[cell + 1] - begin;
      const long long line = cellLine_[cell];
      for (long long k = 0; k < size; ++k) {
        const std::int32_t index = connectivity_[static_cast<std::size_t>(begin + k)];
        if (index < 0 || index >= numPoints_) {
          return errorAt(path_, line,
                         "cell " + std::to_string(c) + " references point " + std::to_string(index) +
                             ", but there are " + std::to_string(numPoints_) + " points");
        }
      }
      const long long type = cellTypes_[cell];
      if (!isVtkCellType(type)) {
        return errorAt(path_, cellTypeLine_[cell],
                       "cell " + std::to_string(c) + " has unknown cell type " + std::to_string(type) +
                           " (VTK cell types are 0-16, 21-37, 41, 42, 51-56 and 60-81)");
      }
      const std::int32_t material = material_.empty() ? 0 : material_[cell];
      const auto first = connectivity_.begin() + begin;
      if (type == 10) {  // VTK_TETRA
        if (size != 4) {
          return errorAt(path_, line,
                         "cell " + std::to_string(c) +
                             ": expected 4 node indices for tetrahedron (cell type 10), got " +
                             std::to_string(size));
        }
        mesh_.tets.insert(mesh_.tets.end(), first, first + 4);
        mesh_.tetMaterial.push_back(material);
      } else if (type == 5) {  // VTK_TRIANGLE
        if (size != 3) {
          return errorAt(path_, line,
                         "cell " + std::to_string(c) +
                             ": expected 3 node indices for triangle (cell type 5), got " +
                             std::to_string(size));
        }
        mesh_.tris.insert(mesh_.tris.end(), first, first + 3);
        mesh_.triMaterial.push_back(material);
      }
    }
    return std::move(mesh_);
  }

  const std::string& path_;
  const std::string& text_;
  TokenReader tokens_;
  RawMesh mesh_;
  long long numPoints_ = 0;
  long long numCells_ = 0;
  std::vector<long long> cellStart_;        // #cells + 1 offsets into connectivity_
  std::vector<long long> cellLine_;         // #cells: line where each cell starts (messages)
  std::vector<std::int32_t> connectivity_;  // point indices of all cells, concatenated
  std::vector<long long> cellTypes_;        // #cells VTK cell type ids
  std::vector<long long> cellTypeLine_;     // #cells: line of each cell's type (messages)
  std::vector<std::int32_t> material_;      // #cells labels, or empty
  bool materialIsFinal_ = false;
  bool seenPoints_ = false, seenCells_ = false, seenCellTypes_ = false, seenAttributes_ = false;
  bool attributeIsCells_ = false;
  long long attributeCount_ = 0;
  long long keywordLine_ = 0;  // line of the section keyword being parsed
};

}  // namespace

Result<RawMesh> parseVtk(const std::string& path, const std::string& text) {
  return VtkParser(path, text).parse();
}

}  // namespace hysim::cutting::io_detail
