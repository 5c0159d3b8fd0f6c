// SPDX-License-Identifier: MIT
// TetGen .node/.ele reader. The first node index (0 or 1) sets the base for both files, as
// TetGen itself does. Tet10 files (written with -o2) list the mid-edge nodes in TetGen's own
// order, which differs from Gmsh's; they are permuted here (see kTetgenToGmsh).
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <sstream>
#include <string>
#include <string_view>
#include <vector>

#include "mesh_io.hpp"
#include "strike/core/format.hpp"
#include "strike/mesh/mesh.hpp"

namespace strike {

namespace {

using detail::at;
using detail::quoteToken;

constexpr int64_t kMaxNodes = 200'000'000;

// TetGen 1.5 -o2 writes the six extra nodes of a tet in the order of its internal edge table
// (edge2ver = {0,1,2,3,8,5} with the org/dest pivots of tetgen.cxx), which in terms of the tet's
// corners is: (2,3) (0,3) (0,1) (1,2) (1,3) (0,2). Gmsh (and TetMesh) wants
// (0,1) (1,2) (2,0) (3,0) (3,2) (3,1). Entry k is the TetGen column that goes to our column k.
// Checked against the installed libtet (mid-edge nodes at edge midpoints, see
// tests/unit/mesh/tetgen_reader_test.cpp).
constexpr int kTetgenToGmsh[10] = {0, 1, 2, 3, 6, 7, 9, 5, 4, 8};

struct Reader {
  detail::Tokenizer tok;
  const std::string& path;

  Error fail(const std::string& what) { return badInput(at(path, tok.line()) + what); }

  Status readInt(int64_t& value, const char* what, bool same_line) {
    const std::string_view t = same_line ? tok.nextOnLine() : tok.next();
    if (t.empty()) return fail(std::string("missing ") + what + (same_line ? " on this line" : " (truncated file?)"));
    if (!detail::parseInt64(t, value))
      return fail(std::string(what) + " is " + quoteToken(t) + ", expected an integer");
    return {};
  }

  // Optional header fields default to 0 when the line ends early.
  Status readOptionalInt(int64_t& value, const char* what) {
    const std::string_view t = tok.nextOnLine();
    if (t.empty()) {
      value = 0;
      return {};
    }
    if (!detail::parseInt64(t, value))
      return fail(std::string(what) + " is " + quoteToken(t) + ", expected an integer");
    return {};
  }

  Status checkCount(int64_t count, int64_t min_bytes, const char* what) {
    if (count < 0 || count > static_cast<int64_t>(tok.remainingBytes()) / min_bytes || count > kMaxNodes) {
      return fail(std::string(what) + " count " + std::to_string(count) + " cannot fit in the " +
                  std::to_string(tok.remainingBytes()) + " bytes left in the file (truncated or corrupt)");
    }
    return {};
  }
};

struct Stem {
  std::string node, ele;
};

Stem stemPaths(const std::string& path) {
  const std::string ext = detail::lowerExtension(path);
  std::string stem = path;
  if (ext == ".node" || ext == ".ele") stem = path.substr(0, path.size() - ext.size());
  return {stem + ".node", stem + ".ele"};
}

}  // namespace

Result<TetMesh> readTetgen(const std::string& path, std::vector<MeshWarning>* /*warnings*/) {
  const Stem files = stemPaths(path);
  Result<std::string> node_bytes = detail::readWholeFile(files.node);
  if (!node_bytes) return node_bytes.error();
  Result<std::string> ele_bytes = detail::readWholeFile(files.ele);
  if (!ele_bytes) return ele_bytes.error();

  TetMesh mesh;
  int64_t first_index = 0;
  {
    Reader r{detail::Tokenizer(*node_bytes, true), files.node};
    int64_t n = 0, dim = 0, num_attr = 0, num_markers = 0;
    if (Status s = r.readInt(n, "node count", false); !s) return s.error();
    if (Status s = r.readOptionalInt(dim, "dimension"); !s) return s.error();
    if (Status s = r.readOptionalInt(num_attr, "attribute count"); !s) return s.error();
    if (Status s = r.readOptionalInt(num_markers, "boundary marker flag"); !s) return s.error();
    if (dim != 3) return r.fail("dimension " + std::to_string(dim) + ", expected 3");
    if (num_attr < 0 || num_attr > 1000)
      return r.fail("attribute count " + std::to_string(num_attr) + ", expected 0..1000");
    if (num_markers != 0 && num_markers != 1)
      return r.fail("boundary marker flag " + std::to_string(num_markers) + ", expected 0 or 1");
    if (Status s = r.checkCount(n, 8, "node"); !s) return s.error();
    if (n == 0) return r.fail("node count 0, expected at least 4 nodes");
    mesh.nodes.resize(n, 3);
    for (int64_t i = 0; i < n; ++i) {
      int64_t index = 0;
      if (Status s = r.readInt(index, "node index", false); !s) return s.error();
      if (i == 0) {
        if (index != 0 && index != 1) return r.fail("first node index " + std::to_string(index) + ", expected 0 or 1");
        first_index = index;
      }
      if (index != first_index + i) {
        return r.fail("node index " + std::to_string(index) + ", expected " + std::to_string(first_index + i) +
                      " (consecutive indices)");
      }
      for (int c = 0; c < 3; ++c) {
        const std::string_view t = r.tok.nextOnLine();
        double x = 0;
        if (t.empty())
          return r.fail("node " + std::to_string(index) + " has " + std::to_string(c) + " coordinates, expected 3");
        if (!detail::parseDouble(t, x))
          return r.fail("node " + std::to_string(index) + " coordinate " + quoteToken(t) + " is not a number");
        if (!std::isfinite(x))
          return r.fail("node " + std::to_string(index) + " coordinate is " + formatNumber(x, 17) +
                        ", expected a finite number");
        mesh.nodes(i, c) = x;
      }
      r.tok.skipLine();  // attributes and boundary marker
    }
  }
  {
    Reader r{detail::Tokenizer(*ele_bytes, true), files.ele};
    int64_t n = 0, nodes_per_tet = 0, num_attr = 0;
    if (Status s = r.readInt(n, "tetrahedron count", false); !s) return s.error();
    if (Status s = r.readOptionalInt(nodes_per_tet, "nodes per tetrahedron"); !s) return s.error();
    if (Status s = r.readOptionalInt(num_attr, "attribute count"); !s) return s.error();
    if (nodes_per_tet == 0) nodes_per_tet = 4;
    if (nodes_per_tet != 4 && nodes_per_tet != 10) {
      return r.fail("nodes per tetrahedron " + std::to_string(nodes_per_tet) + ", expected 4 or 10");
    }
    if (Status s = r.checkCount(n, 2 * (nodes_per_tet + 1), "tetrahedron"); !s) return s.error();
    if (n == 0) return r.fail("tetrahedron count 0, expected a volume mesh");
    const int64_t num_nodes = mesh.nodes.rows();
    mesh.order = nodes_per_tet == 10 ? 2 : 1;
    mesh.tets.resize(n, nodes_per_tet);
    int file_row[10];
    for (int64_t t = 0; t < n; ++t) {
      int64_t index = 0;
      if (Status s = r.readInt(index, "tetrahedron index", false); !s) return s.error();
      for (int64_t k = 0; k < nodes_per_tet; ++k) {
        int64_t node = 0;
        if (Status s = r.readInt(node, "tetrahedron node", true); !s) return s.error();
        const int64_t row = node - first_index;
        if (row < 0 || row >= num_nodes) {
          return r.fail("tet " + std::to_string(index) + " references node " + std::to_string(node) + ", mesh has " +
                        std::to_string(num_nodes) + " nodes numbered from " + std::to_string(first_index));
        }
        file_row[k] = static_cast<int>(row);
      }
      for (int k = 0; k < nodes_per_tet; ++k) mesh.tets(t, k) = file_row[nodes_per_tet == 10 ? kTetgenToGmsh[k] : k];
      r.tok.skipLine();  // region attributes
    }
  }
  return mesh;
}

}  // namespace strike
