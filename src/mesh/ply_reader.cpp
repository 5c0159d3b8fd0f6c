// SPDX-License-Identifier: MIT
// PLY surface reader: ASCII and binary little and big endian. Every count in a file is checked
// against the bytes that are left before anything is reserved, so a hostile header cannot make
// us allocate gigabytes; every coordinate is checked for NaN/Inf and every index against the
// vertex count.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <sstream>
#include <string>
#include <string_view>
#include <vector>

#include "mesh_io.hpp"
#include "strike/mesh/mesh.hpp"
#include "triangle_soup.hpp"

namespace strike {

namespace {

using detail::at;
using detail::finishSurface;
using detail::kMaxVertices;
using detail::quoteToken;
using detail::Soup;

enum class PlyType { Int8, UInt8, Int16, UInt16, Int32, UInt32, Float32, Float64, Invalid };

PlyType plyType(std::string_view name) {
  if (name == "char" || name == "int8") return PlyType::Int8;
  if (name == "uchar" || name == "uint8") return PlyType::UInt8;
  if (name == "short" || name == "int16") return PlyType::Int16;
  if (name == "ushort" || name == "uint16") return PlyType::UInt16;
  if (name == "int" || name == "int32") return PlyType::Int32;
  if (name == "uint" || name == "uint32") return PlyType::UInt32;
  if (name == "float" || name == "float32") return PlyType::Float32;
  if (name == "double" || name == "float64") return PlyType::Float64;
  return PlyType::Invalid;
}

size_t plySize(PlyType t) {
  switch (t) {
    case PlyType::Int8:
    case PlyType::UInt8: return 1;
    case PlyType::Int16:
    case PlyType::UInt16: return 2;
    case PlyType::Int32:
    case PlyType::UInt32:
    case PlyType::Float32: return 4;
    case PlyType::Float64: return 8;
    case PlyType::Invalid: break;
  }
  return 0;
}

bool plyIsInteger(PlyType t) { return t != PlyType::Float32 && t != PlyType::Float64; }

struct PlyProperty {
  std::string name;
  PlyType type = PlyType::Invalid;
  bool is_list = false;
  PlyType count_type = PlyType::Invalid;
};

struct PlyElement {
  std::string name;
  int64_t count = 0;
  int64_t header_line = 0;
  std::vector<PlyProperty> props;
};

enum class PlyFormat { Ascii, BinaryLe, BinaryBe };

// Reads one scalar from a binary body; false at the end of the data.
class BinaryCursor {
 public:
  BinaryCursor(std::string_view data, size_t offset, bool big_endian)
      : data_(data), pos_(offset), big_endian_(big_endian) {}
  bool read(PlyType type, double& value) {
    const size_t n = plySize(type);
    if (n == 0 || data_.size() - pos_ < n) return false;
    unsigned char b[8];
    std::memcpy(b, data_.data() + pos_, n);
    pos_ += n;
    if (big_endian_) std::reverse(b, b + n);
    switch (type) {
      case PlyType::Int8: value = static_cast<int8_t>(b[0]); break;
      case PlyType::UInt8: value = b[0]; break;
      case PlyType::Int16: {
        int16_t v;
        std::memcpy(&v, b, 2);
        value = v;
        break;
      }
      case PlyType::UInt16: {
        uint16_t v;
        std::memcpy(&v, b, 2);
        value = v;
        break;
      }
      case PlyType::Int32: {
        int32_t v;
        std::memcpy(&v, b, 4);
        value = v;
        break;
      }
      case PlyType::UInt32: {
        uint32_t v;
        std::memcpy(&v, b, 4);
        value = v;
        break;
      }
      case PlyType::Float32: {
        float v;
        std::memcpy(&v, b, 4);
        value = v;
        break;
      }
      case PlyType::Float64: {
        double v;
        std::memcpy(&v, b, 8);
        value = v;
        break;
      }
      case PlyType::Invalid: return false;
    }
    return true;
  }
  size_t offset() const { return pos_; }
  size_t remaining() const { return data_.size() - pos_; }

 private:
  std::string_view data_;
  size_t pos_;
  bool big_endian_;
};

Result<SurfaceMesh> parsePly(const std::string& bytes, const std::string& path, std::vector<MeshWarning>* warnings) {
  // Header: text lines up to "end_header".
  size_t pos = 0;
  int64_t line = 0;
  std::vector<PlyElement> elements;
  PlyFormat format = PlyFormat::Ascii;
  bool have_format = false;
  bool have_end = false;
  auto nextHeaderLine = [&](std::string& out) {
    if (pos >= bytes.size()) return false;
    size_t end = bytes.find('\n', pos);
    if (end == std::string::npos) end = bytes.size();
    out.assign(bytes, pos, end - pos);
    if (!out.empty() && out.back() == '\r') out.pop_back();
    pos = std::min(bytes.size(), end + 1);
    ++line;
    return true;
  };
  std::string text;
  if (!nextHeaderLine(text) || text != "ply") {
    return badInput(at(path, 1) + "first line is " + quoteToken(text) + ", expected \"ply\"");
  }
  while (nextHeaderLine(text)) {
    std::istringstream ls(text);
    std::string key;
    ls >> key;
    if (key == "format") {
      std::string f, version;
      ls >> f >> version;
      if (f == "ascii")
        format = PlyFormat::Ascii;
      else if (f == "binary_little_endian")
        format = PlyFormat::BinaryLe;
      else if (f == "binary_big_endian")
        format = PlyFormat::BinaryBe;
      else {
        return badInput(at(path, line) + "format " + quoteToken(f) +
                        ", expected ascii, binary_little_endian or binary_big_endian");
      }
      have_format = true;
    } else if (key == "element") {
      PlyElement e;
      std::string count_text;
      ls >> e.name >> count_text;
      if (e.name.empty() || !detail::parseInt64(count_text, e.count) || e.count < 0) {
        return badInput(at(path, line) + "element count " + quoteToken(count_text) +
                        ", expected a non-negative integer");
      }
      e.header_line = line;
      elements.push_back(std::move(e));
    } else if (key == "property") {
      if (elements.empty()) return badInput(at(path, line) + "property before any element");
      PlyProperty p;
      std::string type_name;
      ls >> type_name;
      if (type_name == "list") {
        std::string count_type, item_type;
        ls >> count_type >> item_type >> p.name;
        p.is_list = true;
        p.count_type = plyType(count_type);
        p.type = plyType(item_type);
        if (p.count_type == PlyType::Invalid || !plyIsInteger(p.count_type) || p.type == PlyType::Invalid) {
          return badInput(at(path, line) + "list property types " + quoteToken(count_type) + " " +
                          quoteToken(item_type) + ", expected an integer count type and a scalar item type");
        }
      } else {
        p.type = plyType(type_name);
        ls >> p.name;
        if (p.type == PlyType::Invalid) {
          return badInput(at(path, line) + "property type " + quoteToken(type_name) +
                          ", expected char uchar short ushort int uint float double (or int8...float64)");
        }
      }
      elements.back().props.push_back(p);
    } else if (key == "end_header") {
      have_end = true;
      break;
    } else if (key == "comment" || key == "obj_info" || key.empty()) {
      continue;
    } else {
      return badInput(at(path, line) + "header keyword " + quoteToken(key) +
                      ", expected format, element, property, comment or end_header");
    }
  }
  if (!have_end) return badInput(at(path, line) + "header has no end_header line (truncated file?)");
  if (!have_format) return badInput(path + ": error: header has no format line");

  const PlyElement* vertex_element = nullptr;
  for (const PlyElement& e : elements) {
    if (e.name == "vertex") vertex_element = &e;
  }
  if (!vertex_element) return badInput(path + ": error: no \"element vertex\" in the header");
  int xyz_prop[3] = {-1, -1, -1};
  for (size_t k = 0; k < vertex_element->props.size(); ++k) {
    const PlyProperty& p = vertex_element->props[k];
    for (int c = 0; c < 3; ++c) {
      if (!p.is_list && p.name == std::string(1, static_cast<char>('x' + c))) xyz_prop[c] = static_cast<int>(k);
    }
  }
  for (int c = 0; c < 3; ++c) {
    if (xyz_prop[c] < 0) {
      return badInput(at(path, vertex_element->header_line) + "vertex element has no scalar property " +
                      std::string(1, static_cast<char>('x' + c)));
    }
  }
  if (vertex_element->count > kMaxVertices) {
    return badInput(at(path, vertex_element->header_line) + "vertex count " + std::to_string(vertex_element->count) +
                    ", expected at most " + std::to_string(kMaxVertices));
  }

  // Bounds on counts: every element needs at least this many bytes, so a count that cannot
  // fit in the rest of the file is refused before anything is allocated.
  const size_t body_bytes = bytes.size() - pos;
  for (const PlyElement& e : elements) {
    size_t min_bytes = 0;
    for (const PlyProperty& p : e.props) {
      min_bytes += format == PlyFormat::Ascii ? 2 : plySize(p.is_list ? p.count_type : p.type);
    }
    min_bytes = std::max<size_t>(min_bytes, 1);
    if (static_cast<uint64_t>(e.count) > body_bytes / min_bytes) {
      return badInput(at(path, e.header_line) + "element " + e.name + " count " + std::to_string(e.count) +
                      " cannot fit in the " + std::to_string(body_bytes) +
                      " bytes after the header (truncated or corrupt file)");
    }
  }

  Soup soup;
  int64_t num_vertices_read = 0;
  bool vertices_done = false;
  std::vector<int64_t> polygon;
  std::vector<double> scalar_values;

  // One reader for both encodings: yields the next value, or an Error naming where.
  detail::Tokenizer tok(std::string_view(bytes).substr(pos), false);
  BinaryCursor cursor(bytes, pos, format == PlyFormat::BinaryBe);
  const int64_t header_lines = line;
  auto location = [&]() {
    if (format == PlyFormat::Ascii) return at(path, header_lines + tok.line());
    return path + ": byte " + std::to_string(cursor.offset()) + ": error: ";
  };
  auto readValue = [&](PlyType type, double& value, const PlyElement& e, int64_t index) -> Status {
    if (format == PlyFormat::Ascii) {
      const std::string_view t = tok.next();
      if (t.empty()) {
        return badInput(at(path, header_lines + tok.line()) + "end of file in " + e.name + " " + std::to_string(index) +
                        " (truncated file), expected " + std::to_string(e.count) + " " + e.name + " elements");
      }
      if (!detail::parseDouble(t, value)) {
        return badInput(at(path, header_lines + tok.line()) + e.name + " " + std::to_string(index) + " value " +
                        quoteToken(t) + " is not a number");
      }
      return {};
    }
    if (!cursor.read(type, value)) {
      return badInput(path + ": byte " + std::to_string(cursor.offset()) + ": error: end of data in " + e.name + " " +
                      std::to_string(index) + " (truncated file), expected " + std::to_string(e.count) + " " + e.name +
                      " elements");
    }
    return {};
  };

  for (const PlyElement& e : elements) {
    const bool is_vertex = &e == vertex_element;
    const bool is_face = e.name == "face";
    int index_prop = -1;
    if (is_face) {
      for (size_t k = 0; k < e.props.size(); ++k) {
        if (e.props[k].is_list && (e.props[k].name == "vertex_indices" || e.props[k].name == "vertex_index")) {
          index_prop = static_cast<int>(k);
        }
      }
      if (index_prop < 0) {
        return badInput(at(path, e.header_line) + "face element has no list property vertex_indices or vertex_index");
      }
      if (!plyIsInteger(e.props[static_cast<size_t>(index_prop)].type)) {
        return badInput(at(path, e.header_line) + "face vertex_indices are floating point, expected an integer type");
      }
    }
    if (is_vertex) soup.xyz.reserve(3 * static_cast<size_t>(e.count));
    for (int64_t i = 0; i < e.count; ++i) {
      double xyz[3] = {0, 0, 0};
      for (size_t k = 0; k < e.props.size(); ++k) {
        const PlyProperty& p = e.props[k];
        if (p.is_list) {
          double count_value = 0;
          if (Status s = readValue(p.count_type, count_value, e, i); !s) return s.error();
          // Each item takes at least one byte (binary) or two (ASCII): bounded by the file.
          const double max_items = static_cast<double>(
              format == PlyFormat::Ascii ? tok.remainingBytes() / 2 + 1 : cursor.remaining() / plySize(p.type));
          if (!(count_value >= 0) || count_value != std::floor(count_value) || count_value > max_items) {
            return badInput(location() + e.name + " " + std::to_string(i) + " list " + p.name + " has count " +
                            formatNumber(count_value, 17) +
                            ", expected a non-negative integer that fits in the rest of the file (truncated file?)");
          }
          const int64_t count = static_cast<int64_t>(count_value);
          if (static_cast<int>(k) == index_prop) polygon.clear();
          for (int64_t j = 0; j < count; ++j) {
            double item = 0;
            if (Status s = readValue(p.type, item, e, i); !s) return s.error();
            if (static_cast<int>(k) == index_prop) {
              const int64_t limit = vertices_done ? num_vertices_read : kMaxVertices;
              if (item != std::floor(item) || item < 0 || item >= static_cast<double>(limit)) {
                return badInput(location() + "face " + std::to_string(i) + " references vertex " +
                                formatNumber(item, 17) + ", the file has " + std::to_string(vertex_element->count) +
                                " vertices (0-based indices)");
              }
              polygon.push_back(static_cast<int64_t>(item));
            }
          }
          if (static_cast<int>(k) == index_prop) {
            if (polygon.size() < 3) {
              return badInput(location() + "face " + std::to_string(i) + " has " + std::to_string(polygon.size()) +
                              " vertices, expected at least 3");
            }
            for (size_t m = 1; m + 1 < polygon.size(); ++m) {
              soup.tri.insert(soup.tri.end(), {static_cast<int>(polygon[0]), static_cast<int>(polygon[m]),
                                               static_cast<int>(polygon[m + 1])});
            }
          }
        } else {
          double value = 0;
          if (Status s = readValue(p.type, value, e, i); !s) return s.error();
          if (is_vertex) {
            for (int c = 0; c < 3; ++c) {
              if (static_cast<int>(k) == xyz_prop[c]) {
                if (!std::isfinite(value)) {
                  return badInput(location() + "vertex " + std::to_string(i) + " coordinate " + p.name + " is " +
                                  formatNumber(value, 17) + ", expected a finite number");
                }
                xyz[c] = value;
              }
            }
          }
        }
      }
      if (is_vertex) {
        soup.xyz.insert(soup.xyz.end(), xyz, xyz + 3);
        ++num_vertices_read;
      }
    }
    if (is_vertex) vertices_done = true;
  }
  // Faces stored before the vertices (legal, if unusual) were checked against kMaxVertices only.
  const int64_t nv = static_cast<int64_t>(soup.xyz.size() / 3);
  for (size_t t = 0; t < soup.tri.size(); ++t) {
    if (soup.tri[t] >= nv) {
      return badInput(path + ": error: face triangle " + std::to_string(t / 3) + " references vertex " +
                      std::to_string(soup.tri[t]) + ", the file has " + std::to_string(nv) + " vertices");
    }
  }
  if (soup.tri.empty()) return badInput(path + ": error: no faces, expected a closed triangle surface");
  return finishSurface(std::move(soup), path, true, warnings);
}

}  // namespace

Result<SurfaceMesh> readPly(const std::string& path, std::vector<MeshWarning>* warnings) {
  Result<std::string> bytes = detail::readWholeFile(path);
  if (!bytes) return bytes.error();
  return parsePly(*bytes, path, warnings);
}

}  // namespace strike
