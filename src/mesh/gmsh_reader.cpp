// SPDX-License-Identifier: MIT
// Gmsh .msh reader, ASCII formats 2.2 and 4.1. Only volume elements of type 4 (Tet4) and
// 11 (Tet10) are kept; points, lines, triangles and other element types are skipped. Node tags
// may be sparse and unordered, so they are mapped to 0-based rows in file order. Gmsh's Tet10
// node order is the one TetMesh uses, so it is copied as is.
#include <cmath>
#include <cstdint>
#include <sstream>
#include <string>
#include <string_view>
#include <unordered_map>
#include <vector>

#include "mesh_io.hpp"
#include "strike/core/format.hpp"
#include "strike/mesh/mesh.hpp"

namespace strike {

namespace {

using detail::at;
using detail::quoteToken;

constexpr int64_t kMaxNodes = 200'000'000;

class GmshParser {
 public:
  GmshParser(const std::string& text, const std::string& path) : tok_(text, false), path_(path) {}

  Result<TetMesh> parse() {
    bool have_format = false;
    bool have_nodes = false;
    while (!tok_.atEnd()) {
      const std::string_view section = tok_.next();
      if (section.empty() || section.front() != '$') {
        return fail("got " + quoteToken(section) +
                    ", expected a section header such as $MeshFormat, $Nodes or $Elements");
      }
      const std::string name(section.substr(1));
      if (name == "MeshFormat") {
        if (Status s = parseFormat(); !s) return s.error();
        have_format = true;
      } else if (name == "Nodes") {
        if (!have_format) return fail("$Nodes before $MeshFormat, expected $MeshFormat first");
        if (Status s = version_ == 2 ? parseNodes2() : parseNodes4(); !s) return s.error();
        have_nodes = true;
      } else if (name == "Elements") {
        if (!have_nodes) return fail("$Elements before $Nodes, expected the nodes first");
        if (Status s = version_ == 2 ? parseElements2() : parseElements4(); !s) return s.error();
      } else {
        // $PhysicalNames, $Entities, $NodeData, ...: not needed for the geometry.
        if (Status s = skipSection(name); !s) return s.error();
        continue;
      }
      if (Status s = expectEnd(name); !s) return s.error();
    }
    if (!have_format) return badInput(path_ + ": error: no $MeshFormat section, expected a Gmsh .msh file");
    if (tets_.empty()) {
      return badInput(path_ +
                      ": error: no tetrahedra (element type 4 or 11) found, expected a volume mesh "
                      "(was only the surface meshed? in Gmsh use Mesh > 3D)");
    }
    TetMesh mesh;
    mesh.order = tet_nodes_ == 10 ? 2 : 1;
    const Eigen::Index num_nodes = static_cast<Eigen::Index>(xyz_.size() / 3);
    mesh.nodes.resize(num_nodes, 3);
    for (Eigen::Index i = 0; i < num_nodes; ++i) {
      for (int c = 0; c < 3; ++c) mesh.nodes(i, c) = xyz_[static_cast<size_t>(3 * i + c)];
    }
    const Eigen::Index num_tets = static_cast<Eigen::Index>(tets_.size() / static_cast<size_t>(tet_nodes_));
    mesh.tets.resize(num_tets, tet_nodes_);
    for (Eigen::Index t = 0; t < num_tets; ++t) {
      for (int c = 0; c < tet_nodes_; ++c) mesh.tets(t, c) = tets_[static_cast<size_t>(t * tet_nodes_ + c)];
    }
    return mesh;
  }

 private:
  Error fail(const std::string& what) { return badInput(at(path_, tok_.line()) + what); }

  Status readInt(int64_t& value, const char* what, bool same_line) {
    const std::string_view t = same_line ? tok_.nextOnLine() : tok_.next();
    if (t.empty()) return fail(std::string("missing ") + what + (same_line ? " on this line" : " (truncated file?)"));
    if (!detail::parseInt64(t, value))
      return fail(std::string(what) + " is " + quoteToken(t) + ", expected an integer");
    return {};
  }

  Status readCoord(double& value) {
    const std::string_view t = tok_.nextOnLine();
    if (t.empty()) return fail("missing node coordinate, expected x y z");
    if (!detail::parseDouble(t, value)) return fail("node coordinate " + quoteToken(t) + " is not a number");
    if (!std::isfinite(value))
      return fail("node coordinate is " + formatNumber(value, 17) + ", expected a finite number");
    return {};
  }

  // A count read from the file must fit in the bytes that are left (each entry takes at least
  // `min_bytes`); this refuses "10^9 nodes" in a 1 kB file before anything is reserved.
  Status checkCount(int64_t count, int64_t min_bytes, const char* what) {
    if (count < 0 || count > static_cast<int64_t>(tok_.remainingBytes()) / min_bytes || count > kMaxNodes * 10) {
      return fail(std::string(what) + " count " + std::to_string(count) + " cannot fit in the " +
                  std::to_string(tok_.remainingBytes()) + " bytes left in the file (truncated or corrupt)");
    }
    return {};
  }

  Status parseFormat() {
    const std::string_view v = tok_.next();
    if (v == "2" || v == "2.0" || v == "2.1" || v == "2.2") {
      version_ = 2;
    } else if (v == "4.1") {
      version_ = 4;
    } else {
      return fail("mesh format version " + quoteToken(v) +
                  ", expected 2.2 or 4.1 (re-export with Gmsh's -format msh22 or msh41)");
    }
    int64_t file_type = 0, data_size = 0;
    if (Status s = readInt(file_type, "file type", true); !s) return s;
    if (Status s = readInt(data_size, "data size", true); !s) return s;
    if (file_type != 0)
      return fail("file type " + std::to_string(file_type) + " (binary), expected 0 (ASCII); save the mesh as ASCII");
    return {};
  }

  Status expectEnd(const std::string& name) {
    const std::string_view t = tok_.next();
    if (t != "$End" + name) {
      return fail("got " + (t.empty() ? std::string("end of file") : quoteToken(t)) + ", expected $End" + name);
    }
    return {};
  }

  Status skipSection(const std::string& name) {
    const std::string end = "$End" + name;
    const int64_t start = tok_.line();
    while (!tok_.atEnd()) {
      if (tok_.next() == end) return {};
    }
    return badInput(at(path_, start) + "section $" + name + " has no " + end + " (truncated file?)");
  }

  Status addNode(int64_t tag, const double xyz[3]) {
    const int index = static_cast<int>(xyz_.size() / 3);
    if (!node_index_.emplace(tag, index).second) return fail("node tag " + std::to_string(tag) + " appears twice");
    xyz_.insert(xyz_.end(), xyz, xyz + 3);
    return {};
  }

  Status parseNodes2() {
    int64_t n = 0;
    if (Status s = readInt(n, "node count", false); !s) return s;
    if (Status s = checkCount(n, 8, "node"); !s) return s;
    xyz_.reserve(3 * static_cast<size_t>(n));
    node_index_.reserve(static_cast<size_t>(n));
    for (int64_t i = 0; i < n; ++i) {
      int64_t tag = 0;
      double xyz[3];
      if (Status s = readInt(tag, "node tag", false); !s) return s;
      for (double& c : xyz) {
        if (Status s = readCoord(c); !s) return s;
      }
      if (Status s = addNode(tag, xyz); !s) return s;
    }
    return {};
  }

  Status parseNodes4() {
    int64_t num_blocks = 0, n = 0, min_tag = 0, max_tag = 0;
    if (Status s = readInt(num_blocks, "node block count", false); !s) return s;
    if (Status s = readInt(n, "node count", true); !s) return s;
    if (Status s = readInt(min_tag, "minimum node tag", true); !s) return s;
    if (Status s = readInt(max_tag, "maximum node tag", true); !s) return s;
    if (Status s = checkCount(n, 8, "node"); !s) return s;
    if (Status s = checkCount(num_blocks, 8, "node block"); !s) return s;
    xyz_.reserve(3 * static_cast<size_t>(n));
    node_index_.reserve(static_cast<size_t>(n));
    std::vector<int64_t> tags;
    for (int64_t b = 0; b < num_blocks; ++b) {
      int64_t dim = 0, entity = 0, parametric = 0, in_block = 0;
      if (Status s = readInt(dim, "entity dimension", false); !s) return s;
      if (Status s = readInt(entity, "entity tag", true); !s) return s;
      if (Status s = readInt(parametric, "parametric flag", true); !s) return s;
      if (Status s = readInt(in_block, "nodes in block", true); !s) return s;
      if (dim < 0 || dim > 3) return fail("entity dimension " + std::to_string(dim) + ", expected 0..3");
      if (Status s = checkCount(in_block, 8, "nodes in block"); !s) return s;
      tags.resize(static_cast<size_t>(in_block));
      for (int64_t& tag : tags) {
        if (Status s = readInt(tag, "node tag", false); !s) return s;
      }
      for (int64_t tag : tags) {
        double xyz[3];
        if (tok_.atEnd())
          return fail("end of file in the coordinates of node " + std::to_string(tag) + " (truncated file)");
        const std::string_view first = tok_.next();
        if (!detail::parseDouble(first, xyz[0]))
          return fail("node coordinate " + quoteToken(first) + " is not a number");
        if (!std::isfinite(xyz[0]))
          return fail("node coordinate is " + formatNumber(xyz[0], 17) + ", expected a finite number");
        for (int c = 1; c < 3; ++c) {
          if (Status s = readCoord(xyz[c]); !s) return s;
        }
        if (parametric != 0) tok_.skipLine();  // u, v, w parametric coordinates
        if (Status s = addNode(tag, xyz); !s) return s;
      }
    }
    if (static_cast<int64_t>(xyz_.size() / 3) != n) {
      return fail("$Nodes header says " + std::to_string(n) + " nodes, the blocks hold " +
                  std::to_string(xyz_.size() / 3));
    }
    return {};
  }

  // Reads the node tags of one tet and maps them to rows.
  Status readTet(int64_t element_tag, int nodes_per_tet) {
    if (tet_nodes_ != 0 && tet_nodes_ != nodes_per_tet) {
      return fail("element " + std::to_string(element_tag) + " is a " + (nodes_per_tet == 10 ? "Tet10" : "Tet4") +
                  " but earlier tets are " + (tet_nodes_ == 10 ? "Tet10" : "Tet4") +
                  ", expected one element order per mesh");
    }
    tet_nodes_ = nodes_per_tet;
    for (int k = 0; k < nodes_per_tet; ++k) {
      int64_t tag = 0;
      if (Status s = readInt(tag, "element node tag", true); !s) return s;
      const auto it = node_index_.find(tag);
      if (it == node_index_.end()) {
        return fail("element " + std::to_string(element_tag) + " references node " + std::to_string(tag) +
                    ", which is not among the " + std::to_string(node_index_.size()) + " nodes in $Nodes");
      }
      tets_.push_back(it->second);
    }
    return {};
  }

  static int tetNodes(int64_t type) { return type == 4 ? 4 : type == 11 ? 10 : 0; }

  Status parseElements2() {
    int64_t n = 0;
    if (Status s = readInt(n, "element count", false); !s) return s;
    if (Status s = checkCount(n, 8, "element"); !s) return s;
    for (int64_t i = 0; i < n; ++i) {
      int64_t tag = 0, type = 0, num_tags = 0;
      if (Status s = readInt(tag, "element tag", false); !s) return s;
      if (Status s = readInt(type, "element type", true); !s) return s;
      const int nodes = tetNodes(type);
      if (nodes == 0) {
        tok_.skipLine();  // not a tet: points, lines, triangles, prisms...
        continue;
      }
      if (Status s = readInt(num_tags, "element tag count", true); !s) return s;
      if (num_tags < 0 || num_tags > 1000)
        return fail("element tag count " + std::to_string(num_tags) + ", expected 0..1000");
      for (int64_t k = 0; k < num_tags; ++k) {
        int64_t ignored = 0;
        if (Status s = readInt(ignored, "element tag", true); !s) return s;
      }
      if (Status s = readTet(tag, nodes); !s) return s;
    }
    return {};
  }

  Status parseElements4() {
    int64_t num_blocks = 0, n = 0, min_tag = 0, max_tag = 0;
    if (Status s = readInt(num_blocks, "element block count", false); !s) return s;
    if (Status s = readInt(n, "element count", true); !s) return s;
    if (Status s = readInt(min_tag, "minimum element tag", true); !s) return s;
    if (Status s = readInt(max_tag, "maximum element tag", true); !s) return s;
    if (Status s = checkCount(n, 4, "element"); !s) return s;
    if (Status s = checkCount(num_blocks, 8, "element block"); !s) return s;
    for (int64_t b = 0; b < num_blocks; ++b) {
      int64_t dim = 0, entity = 0, type = 0, in_block = 0;
      if (Status s = readInt(dim, "entity dimension", false); !s) return s;
      if (Status s = readInt(entity, "entity tag", true); !s) return s;
      if (Status s = readInt(type, "element type", true); !s) return s;
      if (Status s = readInt(in_block, "elements in block", true); !s) return s;
      if (Status s = checkCount(in_block, 4, "elements in block"); !s) return s;
      const int nodes = tetNodes(type);
      for (int64_t i = 0; i < in_block; ++i) {
        int64_t tag = 0;
        if (Status s = readInt(tag, "element tag", false); !s) return s;
        if (nodes == 0) {
          tok_.skipLine();
          continue;
        }
        if (Status s = readTet(tag, nodes); !s) return s;
      }
    }
    return {};
  }

  detail::Tokenizer tok_;
  const std::string& path_;
  int version_ = 0;
  std::vector<double> xyz_;
  std::unordered_map<int64_t, int> node_index_;
  std::vector<int> tets_;
  int tet_nodes_ = 0;
};

}  // namespace

Result<TetMesh> readGmsh(const std::string& path, std::vector<MeshWarning>* /*warnings*/) {
  Result<std::string> bytes = detail::readWholeFile(path);
  if (!bytes) return bytes.error();
  GmshParser parser(*bytes, path);
  return parser.parse();
}

}  // namespace strike
