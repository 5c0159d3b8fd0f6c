// SPDX-License-Identifier: MIT
// ModeBank: everything the synthesizer and the simulator need to know about one object's
// vibration, and its file format (docs/bank-format.md). Target strike_bank: C++ standard
// library only, so the plugin runtime can load banks.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "strike/transfer/acoustic_transfer.hpp"
#include "strike/core/hash.hpp"  // fnv1a64: bank checksums, and the cache keys of bank users
#include "strike/core/material.hpp"
#include "strike/core/result.hpp"

namespace strike {

/// The file format version this build writes. Readers accept versions <= this. Version 2 differs
/// from 1 only in the payload checksum (bankPayloadChecksum); version 3 stores the shapes by
/// vertex in separately checksummed blocks, so a render reads only the vertices it strikes
/// (docs/bank-format.md). Version 4 is version 3 with the shapes stored as 16-bit integers and a
/// scale per mode (ShapeEncoding::Int16, `strike modes --compact`): half the shape bytes, each
/// value within 1.54e-5 of its mode's largest surface amplitude (half a step, 1/65534, plus float
/// rounding). Version 5 adds the acoustic transfer (chunk ACTF) to either encoding, for every
/// mode. Version 6 is version 5 with the transfer of a prefix of the modes only (the heard ones:
/// ACTF's mode count may be below the bank's), and an ACTF of no mode holding the dipole alone.
constexpr uint32_t kBankFormatVersion = 6;
/// The newest version this build reads (it reads every older one).
constexpr uint32_t kBankFormatVersionMax = 6;

/// How a bank file stores its mode shapes.
enum class ShapeEncoding {
  Float32,  ///< chunk MODV (formats 3, 5): IEEE single precision, exact copies of the computed shapes
  Int16,    ///< chunk MODQ (formats 4, 5): round(value / scale_i), scale_i = (largest |value| of mode i) / 32767
};

struct ModeBank {
  uint32_t format_version = kBankFormatVersion;
  ShapeEncoding shape_encoding = ShapeEncoding::Float32;  ///< as read (a computed bank: Float32)

  Material material;

  // What it was computed from, so a cache can reuse it safely.
  uint64_t mesh_hash = 0;      ///< FNV-1a 64 of the mesh file bytes or primitive spec
  std::string mesh_source;     ///< the MESH argument as given (informational)
  uint32_t element_order = 1;  ///< 1 Tet4, 2 Tet10
  double target_edge_m = 0.0;  ///< resolution asked for (0 = automatic)
  uint32_t mesh_nodes = 0;
  uint32_t mesh_tets = 0;
  double max_freq_hz = 0.0;  ///< cut-off the modes were computed up to
  uint32_t max_modes = 0;

  // Mass properties of the solid (from the tet mesh).
  double mass_kg = 0.0;
  double volume_m3 = 0.0;
  std::array<double, 3> centre_m{};       ///< centre of mass, mesh frame
  std::array<double, 9> inertia_kg_m2{};  ///< row-major 3x3 about centre_m

  // Modes: eigenvalues lambda_i (rad^2/s^2) ascending; shapes are mass-normalized
  // (phi^T M phi = 1, units 1/sqrt(kg)) and sampled on surface vertices only.
  std::vector<double> eigenvalues;               ///< #modes
  std::vector<float> shapes;                     ///< #modes * #surface vertices * 3: [mode][vertex][xyz]
  std::vector<double> frequency_error_estimate;  ///< #modes relative error estimate, or empty
  /// #modes radiation strengths R_i (m^2 / sqrt(kg)) of the listener model (synth radiation.cpp),
  /// computed once with the modes so renders need not; empty in banks that predate it.
  std::vector<double> radiation_m2;
  /// Per-mode far field as a function of direction (acoustic_transfer.hpp) of the first
  /// transfer.modeCount() modes: every mode in format 5, the heard ones (at or below the band a
  /// render plays) in format 6. Empty in banks of formats 1-4 and solved without it; a mode
  /// without a transfer is heard through radiation_m2 (direction-averaged) instead.
  AcousticTransfer transfer;

  // The surface: collision shape and where impacts land.
  std::vector<double> surface_positions;     ///< #V * 3, metres, mesh frame
  std::vector<float> surface_normals;        ///< #V * 3, unit, outward (area-weighted vertex normals)
  std::vector<uint32_t> surface_triangles;   ///< #F * 3, indices into surface vertices, CCW from outside
  std::vector<uint32_t> surface_node_index;  ///< #V: which tet-mesh node each surface vertex is

  // Provenance: what the precompute cost.
  double meshing_seconds = 0.0, assembly_seconds = 0.0, factorize_seconds = 0.0, lanczos_seconds = 0.0,
         total_seconds = 0.0;
  double transfer_seconds = 0.0;  ///< the acoustic transfer's own phase (included in total_seconds)
  uint32_t rigid_modes_dropped = 0;
  uint32_t above_cutoff_dropped = 0;
  std::string tool_version;

  size_t modeCount() const { return eigenvalues.size(); }
  size_t surfaceVertexCount() const { return surface_positions.size() / 3; }
  /// Undamped natural frequency sqrt(lambda)/2pi, Hz.
  double frequencyHz(size_t mode) const;
  /// Rayleigh damping c = a1 lambda + a2 (1/s); an under-damped mode decays as exp(-c t / 2).
  double dampingCoefficient(size_t mode) const;
  /// Amplitude decay rate c/2 (1/s), `decay_per_s` of `strike info --json` (docs/cli.md).
  double decayPerS(size_t mode) const { return 0.5 * dampingCoefficient(mode); }
  /// Mode shape at surface vertex v: 3 floats.
  const float* shapeAt(size_t mode, size_t vertex) const {
    return shapes.data() + (mode * surfaceVertexCount() + vertex) * 3;
  }
  /// Empty when consistent, else a description of the first inconsistency. With
  /// `shapes_loaded` false, `shapes` must be empty and is not checked (BankFile::bank()).
  std::string checkConsistency(bool shapes_loaded = true) const;
};

/// Mode shapes at some of a bank's surface vertices: what a render reads of a cached bank (its
/// contacts touch a few hundred of a plate's 14,000 vertices).
struct ShapeRows {
  size_t modes = 0;
  std::vector<uint32_t> vertices;  ///< ascending, no repeats
  std::vector<float> values;       ///< per vertex of `vertices`: #modes x 3 ([mode][xyz])
  /// The #modes x 3 shape values at `vertex`, or nullptr when they were not read.
  const float* row(uint32_t vertex) const;
};

/// A bank file opened to be read in parts. open() reads and verifies everything but the mode
/// shapes (about 1 MB of a 17 MB plate bank); readShapeRows() reads the shapes at chosen
/// vertices, verifying each block of the file they lie in against its own checksum. The file
/// stays open and is read with pread, not mapped: a file truncated by someone else meanwhile
/// gives an error, not a SIGBUS. Files of formats 1 and 2 (one checksum over everything) are
/// read and verified whole at open. Copies share the open file.
class BankFile {
 public:
  static Result<BankFile> open(const std::string& path);
  /// The same over bytes in memory (not copied: they must outlive the BankFile).
  static Result<BankFile> openBytes(const uint8_t* data, size_t size, const std::string& source);

  /// Everything but the shapes (`shapes` is empty).
  const ModeBank& bank() const { return *bank_; }
  /// The same bank, shared rather than copied: a render keeps it for the body and its voice
  /// (a plate's transfer is 2 MB) while the file reads the shapes.
  std::shared_ptr<const ModeBank> sharedBank() const { return bank_; }
  /// A key of the file's content: its format version, sizes and the checksum of its head (which,
  /// from format 3, holds the checksums of the shape blocks). Equal keys: the same bank.
  uint64_t contentKey() const { return content_key_; }
  /// The shapes at `vertices` (any order, repeats allowed). Fails, naming the file, on a damaged
  /// block, a non-finite value, a vertex out of range or a file that has become shorter.
  Result<ShapeRows> readShapeRows(std::vector<uint32_t> vertices) const;
  /// The whole bank, shapes included, every block verified.
  Result<ModeBank> readAll() const;

 private:
  struct Source;
  BankFile() = default;
  std::shared_ptr<const Source> source_;  ///< the file (or bytes) and its name
  std::shared_ptr<const ModeBank> bank_;  ///< never null once parsed
  bool vertex_major_ = false;       ///< format 3-4 (MODV, MODQ) or 1-2 (MODE, [mode][vertex][xyz])
  bool int16_shapes_ = false;       ///< format 4 (MODQ): values are int16 times shape_scale_[mode]
  std::vector<float> shape_scale_;  ///< format 4: per mode
  size_t shapeValueBytes() const { return int16_shapes_ ? 2 : 4; }
  /// Rows of `count` vertices as stored (f32 or i16) -> floats.
  void decodeRows(const uint8_t* bytes, size_t count, float* out) const;
  uint32_t vertices_per_block_ = 0;
  std::vector<uint64_t> block_checksums_;  ///< format 3: one per block of vertices
  uint64_t shapes_offset_ = 0;             ///< where the f32 shapes start in the file
  uint64_t content_key_ = 0;
  static Result<BankFile> parse(std::shared_ptr<const Source> source);
  /// Reads the shape bytes of vertices [first, first + count) into `to`.
  Status readShapeBytes(size_t first, size_t count, std::vector<uint8_t>& to) const;
  Status verifyBlock(size_t block, const uint8_t* bytes, size_t size) const;
};

/// Writes atomically: to PATH.tmp-XXXX in the same directory, then rename(). Defined in
/// strike_bank_writer (links strike_output), not strike_bank, so libstrike has no atomic writer.
Status writeBank(const std::string& path, const ModeBank& bank, ShapeEncoding shapes = ShapeEncoding::Float32);
/// Serializes to bytes (what writeBank writes).
std::vector<uint8_t> encodeBank(const ModeBank& bank, ShapeEncoding shapes = ShapeEncoding::Float32);
/// Reads and verifies magic, version, size and checksums; errors name the file and the problem.
/// BankFile::open(path) then readAll().
Result<ModeBank> readBank(const std::string& path);
/// Parses bytes; `source` names them in messages.
Result<ModeBank> decodeBank(const uint8_t* data, size_t size, const std::string& source);

/// The header's payload checksum for a file of `format_version`: 1, FNV-1a 64 of the bytes; 2 and 3,
/// the faster word-lane variant (docs/bank-format.md; format 3 checksums the head and each shape
/// block with it). Byte-wise FNV-1a is one serial multiply per byte, ~20 ms for a 17 MB bank.
uint64_t bankPayloadChecksum(uint32_t format_version, const uint8_t* payload, size_t size);

}  // namespace strike
