// SPDX-License-Identifier: MIT
// The mode bank file: see docs/bank-format.md. Little-endian, chunked, checksummed.
//
//   header: magic "STRKBANK", u32 format_version, u32 header_size (32; 40 in formats 3-4),
//           u64 payload_size, u64 payload_checksum (bankPayloadChecksum),
//           formats 3-4: u64 head_size (the checksum covers the payload's first head_size bytes)
//   payload: chunks, each: char[4] tag, u32 flags (0), u64 size, then `size` bytes.
//   format 3: the last chunk is MODV, whose shapes ([vertex][mode][xyz], f32) are the payload's
//   tail after head_size, in blocks of vertices with one checksum each (kept in the head), so a
//   reader verifies only the blocks it reads.
//   format 4: the same with MODQ instead of MODV: a f32 scale per mode after the eigenvalues and
//   the shapes as i16 (value = q * scale), half the bytes (`strike modes --compact`).
//   format 5: format 3 or 4 (MODV or MODQ) plus ACTF, the acoustic transfer of every mode
//   (acoustic_transfer.hpp), and the transfer's seconds at the end of PROV.
//   format 6: format 5 whose ACTF may hold the first modes only (the heard ones), or none (the
//   dipole alone).
//
// Unknown chunks are skipped, so a reader of the same major format can read files that carry
// more. Every read is bounds-checked: a hostile file can make decoding fail, never overrun.
#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <limits>

#include "strike/bank/bank.hpp"
#include "strike/core/hash.hpp"
#include "strike/core/read_file.hpp"

namespace strike {
namespace {

constexpr char kMagic[8] = {'S', 'T', 'R', 'K', 'B', 'A', 'N', 'K'};
constexpr uint32_t kHeaderSize = 32;    // formats 1 and 2
constexpr uint32_t kHeaderSizeV3 = 40;  // format 3 adds u64 head_size
// Format 3 shape blocks hold about this many bytes: 13 vertices of a 100-mode bank. A render
// touching a few hundred vertices then reads and verifies ~2% of a 14,000-vertex plate's shapes.
constexpr size_t kShapeBlockBytes = 16384;
// A bank larger than this is not a bank: refuse it before allocating (10^8 floats of shapes).
constexpr uint64_t kMaxBankBytes = uint64_t(1) << 31;

static_assert(sizeof(float) == 4 && sizeof(double) == 8, "IEEE-754 float and double required");

// --- writing ------------------------------------------------------------------------------

class ByteWriter {
 public:
  template <class T>
  void put(T value) {
    // Why: the format is little-endian; x86 and ARM Linux are, and we check it at compile time.
    static_assert(std::is_arithmetic_v<T>);
    uint8_t bytes[sizeof(T)];
    std::memcpy(bytes, &value, sizeof(T));
    data_.insert(data_.end(), bytes, bytes + sizeof(T));
  }
  template <class T>
  void putArray(const std::vector<T>& values) {
    const auto* bytes = reinterpret_cast<const uint8_t*>(values.data());
    data_.insert(data_.end(), bytes, bytes + values.size() * sizeof(T));
  }
  void putString(const std::string& text) {
    put<uint32_t>(static_cast<uint32_t>(text.size()));
    data_.insert(data_.end(), text.begin(), text.end());
  }
  /// Starts a chunk; returns where its size goes.
  size_t beginChunk(const char tag[4]) {
    data_.insert(data_.end(), tag, tag + 4);
    put<uint32_t>(0);
    const size_t size_at = data_.size();
    put<uint64_t>(0);
    return size_at;
  }
  void endChunk(size_t size_at) {
    const uint64_t size = data_.size() - (size_at + 8);
    std::memcpy(data_.data() + size_at, &size, 8);
  }
  std::vector<uint8_t>& data() { return data_; }

 private:
  std::vector<uint8_t> data_;
};

static_assert(__BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__, "the bank codec assumes a little-endian host");

// --- reading ------------------------------------------------------------------------------

class ByteReader {
 public:
  ByteReader(const uint8_t* data, size_t size) : data_(data), size_(size) {}
  bool failed() const { return failed_; }
  size_t remaining() const { return size_ - pos_; }

  template <class T>
  T get() {
    T value{};
    if (remaining() < sizeof(T)) {
      failed_ = true;
      return value;
    }
    std::memcpy(&value, data_ + pos_, sizeof(T));
    pos_ += sizeof(T);
    return value;
  }
  template <class T>
  bool getArray(std::vector<T>& values, uint64_t count) {
    if (count > remaining() / sizeof(T)) {  // checked before allocating
      failed_ = true;
      return false;
    }
    values.resize(count);
    // memcpy from/to a null pointer is undefined even for 0 bytes (an empty chunk; found by fuzz_bank).
    if (count > 0) std::memcpy(values.data(), data_ + pos_, count * sizeof(T));
    pos_ += count * sizeof(T);
    return true;
  }
  /// A reader over the next `count` bytes (no copy: a 17 MB MODE chunk is read in place), which
  /// this reader skips.
  ByteReader take(uint64_t count) {
    if (count > remaining()) {
      failed_ = true;
      return ByteReader(data_ + size_, 0);
    }
    ByteReader part(data_ + pos_, count);
    pos_ += count;
    return part;
  }
  /// Where the next byte is; skip() moves past `count` bytes.
  const uint8_t* here() const { return data_ + pos_; }
  bool skip(uint64_t count) {
    if (count > remaining()) return failed_ = true, false;
    pos_ += count;
    return true;
  }
  std::string getString() {
    const uint32_t length = get<uint32_t>();
    if (failed_ || length > remaining()) {
      failed_ = true;
      return {};
    }
    std::string text(reinterpret_cast<const char*>(data_ + pos_), length);
    pos_ += length;
    return text;
  }

 private:
  const uint8_t* data_;
  size_t size_;
  size_t pos_ = 0;
  bool failed_ = false;
};

/// The shapes chunk a file of `version` may have: MODE (1-2), MODV (3), MODQ (4), either (5).
bool isShapesTag(uint32_t version, const std::string& tag) {
  if (version <= 2) return tag == "MODE";
  if (version == 3) return tag == "MODV";
  if (version == 4) return tag == "MODQ";
  return tag == "MODV" || tag == "MODQ";
}

/// A spherical-harmonic order above this is not a mode's far field (ka = 200 would be a 1 m body
/// at 11 kHz): refuse it before allocating (201^2 coefficients per mode).
constexpr uint32_t kMaxTransferOrder = 200;

/// Reads an ACTF chunk (layout in docs/bank-format.md); empty on success, else the problem.
std::string readTransfer(ByteReader& r, AcousticTransfer& t) {
  const uint32_t modes = r.get<uint32_t>();
  r.get<uint32_t>();  // reserved
  for (double& v : t.centre_m) v = r.get<double>();
  t.air_density_kg_m3 = r.get<double>();
  t.speed_of_sound_m_s = r.get<double>();
  t.solve_seconds = r.get<double>();
  for (double& v : t.translation_dipole_m3) v = r.get<double>();
  t.method = r.getString();
  r.getArray(t.order, modes);
  r.getArray(t.relative_error, modes);
  if (r.failed()) return "shorter than its contents";
  t.offset.assign(1, 0);
  for (uint32_t n : t.order) {
    if (n > kMaxTransferOrder) return "order " + std::to_string(n) + " > " + std::to_string(kMaxTransferOrder);
    t.offset.push_back(t.offset.back() + uint64_t(n + 1) * (n + 1));
  }
  const uint64_t count = r.get<uint64_t>();
  if (count != t.offset.back())
    return std::to_string(count) + " coefficients, the orders need " + std::to_string(t.offset.back());
  r.getArray(t.coefficients, count);
  if (r.failed()) return "shorter than its contents";
  return t.checkConsistency(modes);
}

Error corrupt(const std::string& source, const std::string& what) {
  return badInput(source + ": error: not a valid mode bank: " + what);
}

/// Vertices per shape block for rows of `row_bytes` (modes x 3 x the value size).
uint32_t verticesPerBlock(size_t row_bytes, size_t vertices) {
  if (vertices == 0) return 1;
  if (row_bytes == 0) return static_cast<uint32_t>(std::min<size_t>(vertices, UINT32_MAX));
  return static_cast<uint32_t>(std::clamp<size_t>(kShapeBlockBytes / row_bytes, 1, vertices));
}

/// Block b of format 3 shapes (its `size` bytes): their bankPayloadChecksum, seeded into FNV-1a of
/// the block number so that two swapped blocks do not pass.
uint64_t shapeBlockChecksum(const uint8_t* bytes, size_t size, uint64_t block) {
  return fnv1a64(&block, sizeof block, bankPayloadChecksum(3, bytes, size));
}

/// Format 4's per-mode scale: the mode's largest |value| over the surface / 32767, so every value
/// is stored within scale / 2 = max / 65534 (1.53e-5 of the mode's largest amplitude).
std::vector<float> int16ShapeScales(const ModeBank& bank) {
  std::vector<float> scale(bank.modeCount(), 0.0f);
  for (size_t m = 0; m < bank.modeCount(); ++m) {
    float largest = 0.0f;
    for (size_t v = 0; v < bank.surfaceVertexCount(); ++v)
      for (int a = 0; a < 3; ++a) largest = std::max(largest, std::fabs(bank.shapeAt(m, v)[a]));
    scale[m] = largest / 32767.0f;
  }
  return scale;
}

}  // namespace

std::vector<uint8_t> encodeBank(const ModeBank& bank, ShapeEncoding encoding) {
  const bool int16 = encoding == ShapeEncoding::Int16;
  const uint32_t version = kBankFormatVersion;  // 6: MODV or MODQ, plus ACTF of a prefix of the modes
  ByteWriter w;
  w.data().insert(w.data().end(), kMagic, kMagic + 8);
  w.put<uint32_t>(version);
  w.put<uint32_t>(kHeaderSizeV3);
  w.put<uint64_t>(0);  // payload size, patched below
  w.put<uint64_t>(0);  // checksum, patched below
  w.put<uint64_t>(0);  // head size, patched below

  size_t at = w.beginChunk("MATL");
  w.putString(bank.material.name);
  w.put(bank.material.youngs_pa);
  w.put(bank.material.poisson);
  w.put(bank.material.density_kg_m3);
  w.put(bank.material.rayleigh_stiffness);
  w.put(bank.material.rayleigh_mass);
  w.endChunk(at);

  at = w.beginChunk("MESH");
  w.put<uint64_t>(bank.mesh_hash);
  w.putString(bank.mesh_source);
  w.put<uint32_t>(bank.element_order);
  w.put(bank.target_edge_m);
  w.put<uint32_t>(bank.mesh_nodes);
  w.put<uint32_t>(bank.mesh_tets);
  w.put(bank.max_freq_hz);
  w.put<uint32_t>(bank.max_modes);
  w.endChunk(at);

  at = w.beginChunk("MASS");
  w.put(bank.mass_kg);
  w.put(bank.volume_m3);
  for (double v : bank.centre_m) w.put(v);
  for (double v : bank.inertia_kg_m2) w.put(v);
  w.endChunk(at);

  at = w.beginChunk("SURF");
  w.put<uint32_t>(static_cast<uint32_t>(bank.surfaceVertexCount()));
  w.put<uint32_t>(static_cast<uint32_t>(bank.surface_triangles.size() / 3));
  w.put<uint32_t>(bank.surface_normals.empty() ? 0u : 1u);
  w.put<uint32_t>(bank.surface_node_index.empty() ? 0u : 1u);
  w.putArray(bank.surface_positions);
  w.putArray(bank.surface_normals);
  w.putArray(bank.surface_triangles);
  w.putArray(bank.surface_node_index);
  w.endChunk(at);

  if (!bank.frequency_error_estimate.empty()) {
    at = w.beginChunk("FERR");
    w.put<uint32_t>(static_cast<uint32_t>(bank.frequency_error_estimate.size()));
    w.putArray(bank.frequency_error_estimate);
    w.endChunk(at);
  }

  if (!bank.radiation_m2.empty()) {
    at = w.beginChunk("RADI");
    w.put<uint32_t>(static_cast<uint32_t>(bank.radiation_m2.size()));
    w.putArray(bank.radiation_m2);
    w.endChunk(at);
  }

  if (!bank.transfer.offset.empty()) {  // solved, if only its dipole (format 6: no mode heard)
    const AcousticTransfer& t = bank.transfer;
    at = w.beginChunk("ACTF");
    w.put<uint32_t>(static_cast<uint32_t>(t.modeCount()));
    w.put<uint32_t>(0);  // reserved
    for (double v : t.centre_m) w.put(v);
    w.put(t.air_density_kg_m3);
    w.put(t.speed_of_sound_m_s);
    w.put(t.solve_seconds);
    for (double v : t.translation_dipole_m3) w.put(v);
    w.putString(t.method);
    w.putArray(t.order);
    w.putArray(t.relative_error);
    w.put<uint64_t>(t.coefficients.size());
    w.putArray(t.coefficients);
    w.endChunk(at);
  }

  at = w.beginChunk("PROV");
  w.put(bank.meshing_seconds);
  w.put(bank.assembly_seconds);
  w.put(bank.factorize_seconds);
  w.put(bank.lanczos_seconds);
  w.put(bank.total_seconds);
  w.put<uint32_t>(bank.rigid_modes_dropped);
  w.put<uint32_t>(bank.above_cutoff_dropped);
  w.putString(bank.tool_version);
  w.put(bank.transfer_seconds);  // format 5
  w.endChunk(at);

  // MODV (MODQ in format 4) last: its shapes are the payload's tail, outside the head checksum.
  const size_t modes = bank.modeCount();
  const size_t vertices = bank.surfaceVertexCount();
  const size_t value_bytes = int16 ? sizeof(int16_t) : sizeof(float);
  const uint32_t per_block = verticesPerBlock(modes * 3 * value_bytes, vertices);
  const size_t blocks = per_block > 0 ? (vertices + per_block - 1) / per_block : 0;
  at = w.beginChunk(int16 ? "MODQ" : "MODV");
  w.put<uint32_t>(static_cast<uint32_t>(modes));
  w.put<uint32_t>(static_cast<uint32_t>(vertices));
  w.put<uint32_t>(per_block);
  w.put<uint32_t>(0);  // reserved
  w.putArray(bank.eigenvalues);
  std::vector<float> scale;
  if (int16) {
    scale = int16ShapeScales(bank);
    w.putArray(scale);
  }
  const size_t checksums_at = w.data().size();
  for (size_t b = 0; b < blocks; ++b) w.put<uint64_t>(0);  // patched below
  const size_t shapes_at = w.data().size();
  // Transposed from the in-memory [mode][vertex][xyz]: a vertex's row is contiguous in the file.
  std::vector<float> row(modes * 3);
  std::vector<int16_t> quantized(modes * 3);
  for (size_t v = 0; v < vertices; ++v) {
    for (size_t m = 0; m < modes; ++m) std::memcpy(&row[m * 3], bank.shapeAt(m, v), 3 * sizeof(float));
    if (!int16) {
      w.putArray(row);
      continue;
    }
    for (size_t k = 0; k < row.size(); ++k) {
      const float s_m = scale[k / 3];
      quantized[k] =
          s_m > 0 ? static_cast<int16_t>(std::clamp<long>(std::lround(double(row[k]) / double(s_m)), -32767, 32767))
                  : 0;
    }
    w.putArray(quantized);
  }
  w.endChunk(at);
  std::vector<uint8_t>& bytes = w.data();
  const size_t row_bytes = modes * 3 * value_bytes;
  for (size_t b = 0; b < blocks; ++b) {
    const size_t first = b * per_block, count = std::min<size_t>(per_block, vertices - first);
    const uint64_t checksum = shapeBlockChecksum(bytes.data() + shapes_at + first * row_bytes, count * row_bytes, b);
    std::memcpy(bytes.data() + checksums_at + 8 * b, &checksum, 8);
  }

  const uint64_t payload_size = bytes.size() - kHeaderSizeV3;
  const uint64_t head_size = shapes_at - kHeaderSizeV3;
  const uint64_t checksum = bankPayloadChecksum(version, bytes.data() + kHeaderSizeV3, head_size);
  std::memcpy(bytes.data() + 16, &payload_size, 8);
  std::memcpy(bytes.data() + 24, &checksum, 8);
  std::memcpy(bytes.data() + 32, &head_size, 8);
  return std::move(bytes);
}

uint64_t bankPayloadChecksum(uint32_t format_version, const uint8_t* payload, size_t size) {
  if (format_version < 2) return fnv1a64(payload, size);
  // Format 2: FNV-1a 64 steps on little-endian 64-bit words, word k into lane k mod 4, so four
  // independent multiply chains run at once (~16x the byte-wise speed, memory bound); then the
  // four lanes (32 bytes) and the tail of fewer than 32 bytes through byte-wise FNV-1a. Each step
  // is a bijection of the lane state, so any single changed word changes its lane.
  constexpr uint64_t kBasis = 0xcbf29ce484222325ull, kPrime = 0x100000001b3ull;
  uint64_t lanes[4] = {kBasis, kBasis, kBasis, kBasis};
  const size_t blocks = size / 32;
  for (size_t b = 0; b < blocks; ++b) {
    for (int k = 0; k < 4; ++k) {
      uint64_t word;
      std::memcpy(&word, payload + 32 * b + 8 * k, 8);  // little-endian host (static_assert above)
      lanes[k] = (lanes[k] ^ word) * kPrime;
    }
  }
  const uint64_t hash = fnv1a64(lanes, sizeof lanes);
  return fnv1a64(payload + 32 * blocks, size - 32 * blocks, hash);
}

/// A bank's bytes: all of them in memory, or an open file of which the first `resident` bytes (the
/// header and the checked head) are in memory and the rest is read with pread when asked.
struct BankFile::Source {
  std::string name;
  uint64_t size = 0;              ///< of the whole file
  const uint8_t* data = nullptr;  ///< its first `resident` bytes
  uint64_t resident = 0;
  std::string buffer;               ///< owns `data` when a file is read whole
  std::unique_ptr<uint8_t[]> head;  ///< owns `data` while a file's head is parsed
  int fd = -1;         ///< open while bytes after `resident` may be asked for
  Source() = default;
  Source(const Source&) = delete;
  Source& operator=(const Source&) = delete;
  ~Source() {
    if (fd >= 0) close(fd);
  }
  /// Bytes [offset, offset + count) into `to`; false if the file no longer has them.
  bool read(uint64_t offset, size_t count, uint8_t* to) const {
    if (count == 0) return true;
    if (offset <= resident && count <= resident - offset) {
      std::memcpy(to, data + offset, count);
      return true;
    }
    if (fd < 0) return false;
    while (count > 0) {
      const ssize_t got = pread(fd, to, count, static_cast<off_t>(offset));
      if (got < 0 && errno == EINTR) continue;
      if (got <= 0) return false;
      to += got, offset += static_cast<uint64_t>(got), count -= static_cast<size_t>(got);
    }
    return true;
  }
};

Result<BankFile> BankFile::parse(std::shared_ptr<const Source> source_ptr) {
  const Source& src = *source_ptr;
  const uint8_t* data = src.data;
  const uint64_t size = src.size;
  const std::string& source = src.name;
  if (src.resident < kHeaderSize || std::memcmp(data, kMagic, 8) != 0) {
    if (src.resident >= 8 && std::memcmp(data, kMagic, 8) == 0)
      return corrupt(source, "file is " + std::to_string(size) + " bytes, shorter than the 32-byte header (truncated)");
    return corrupt(source, "wrong magic number (expected a file written by `strike modes`)");
  }
  BankFile file;
  ModeBank bank;
  ByteReader header(data + 8, src.resident - 8);
  bank.format_version = header.get<uint32_t>();
  const uint32_t header_size = header.get<uint32_t>();
  const uint64_t payload_size = header.get<uint64_t>();
  const uint64_t checksum = header.get<uint64_t>();
  if (bank.format_version == 0 || bank.format_version > kBankFormatVersionMax)
    return badInput(source + ": error: mode bank format version " + std::to_string(bank.format_version) +
                    " is not supported by this build (reads versions 1 to " + std::to_string(kBankFormatVersionMax) +
                    "); recompute it with `strike modes` or update strike");
  const uint32_t expected_header = bank.format_version >= 3 ? kHeaderSizeV3 : kHeaderSize;
  if (header_size != expected_header)
    return corrupt(source,
                   "header size " + std::to_string(header_size) + ", expected " + std::to_string(expected_header));
  if (src.resident < header_size)
    return corrupt(source, "file is " + std::to_string(size) + " bytes, shorter than the " +
                               std::to_string(header_size) + "-byte header (truncated)");
  if (payload_size != size - header_size)
    return corrupt(source, "header says " + std::to_string(payload_size) + " payload bytes, file has " +
                               std::to_string(size - header_size) +
                               (payload_size > size - header_size ? " (truncated)" : ""));
  const uint64_t head_size = bank.format_version >= 3 ? header.get<uint64_t>() : payload_size;
  if (head_size > payload_size)
    return corrupt(source, "header says the checked head is " + std::to_string(head_size) + " bytes, the payload has " +
                               std::to_string(payload_size));
  if (src.resident - header_size < head_size) return corrupt(source, "the checked head is not all in memory");
  const uint8_t* payload_start = data + header_size;
  if (bankPayloadChecksum(bank.format_version, payload_start, head_size) != checksum)
    return corrupt(source, "checksum mismatch (the file is damaged)");
  const uint64_t key_parts[4] = {bank.format_version, payload_size, head_size, checksum};
  file.content_key_ = fnv1a64(key_parts, sizeof key_parts);

  // Chunks are read from what is in memory: all of a format 1-2 file, the head of a format 3 file
  // (whose last chunk, MODV, runs on into the shapes after it).
  ByteReader payload(payload_start, src.resident - header_size);
  bool seen_modes = false, seen_surface = false;
  uint32_t surface_vertices = 0, mode_vertices = 0;
  while (payload.remaining() > 0) {
    char tag_chars[4];
    for (char& c : tag_chars) c = static_cast<char>(payload.get<uint8_t>());
    payload.get<uint32_t>();  // flags, reserved
    const uint64_t chunk_size = payload.get<uint64_t>();
    const std::string tag(tag_chars, 4);
    const uint64_t chunk_offset = static_cast<uint64_t>(payload.here() - payload_start);  // of its contents
    const bool runs_past = !payload.failed() && chunk_size > payload.remaining();
    // Only MODV may run past what is in memory, and only to the end of the file.
    if (payload.failed() || (runs_past && (!isShapesTag(bank.format_version, tag) || tag == "MODE" ||
                                           chunk_size != payload_size - chunk_offset)))
      return corrupt(source, "chunk '" + tag + "' runs past the end of the file");
    ByteReader r = payload.take(runs_past ? payload.remaining() : chunk_size);
    if (tag == "MATL") {
      bank.material.name = r.getString();
      bank.material.youngs_pa = r.get<double>();
      bank.material.poisson = r.get<double>();
      bank.material.density_kg_m3 = r.get<double>();
      bank.material.rayleigh_stiffness = r.get<double>();
      bank.material.rayleigh_mass = r.get<double>();
    } else if (tag == "MESH") {
      bank.mesh_hash = r.get<uint64_t>();
      bank.mesh_source = r.getString();
      bank.element_order = r.get<uint32_t>();
      bank.target_edge_m = r.get<double>();
      bank.mesh_nodes = r.get<uint32_t>();
      bank.mesh_tets = r.get<uint32_t>();
      bank.max_freq_hz = r.get<double>();
      bank.max_modes = r.get<uint32_t>();
    } else if (tag == "MASS") {
      bank.mass_kg = r.get<double>();
      bank.volume_m3 = r.get<double>();
      for (double& v : bank.centre_m) v = r.get<double>();
      for (double& v : bank.inertia_kg_m2) v = r.get<double>();
    } else if (tag == "SURF") {
      surface_vertices = r.get<uint32_t>();
      const uint32_t triangles = r.get<uint32_t>();
      const bool has_normals = r.get<uint32_t>() != 0;
      const bool has_node_index = r.get<uint32_t>() != 0;
      r.getArray(bank.surface_positions, uint64_t(surface_vertices) * 3);
      if (has_normals) r.getArray(bank.surface_normals, uint64_t(surface_vertices) * 3);
      r.getArray(bank.surface_triangles, uint64_t(triangles) * 3);
      if (has_node_index) r.getArray(bank.surface_node_index, surface_vertices);
      seen_surface = true;
    } else if (tag == "MODE" || tag == "MODV" || tag == "MODQ") {
      const bool vertex_major = tag != "MODE";
      const bool int16 = tag == "MODQ";
      if (!isShapesTag(bank.format_version, tag))
        return corrupt(source, "a '" + tag + "' chunk in a format " + std::to_string(bank.format_version) + " file");
      if (seen_modes) return corrupt(source, "two '" + tag + "' chunks");
      const uint32_t modes = r.get<uint32_t>();
      mode_vertices = r.get<uint32_t>();
      uint64_t blocks = 0;
      if (vertex_major) {
        file.vertices_per_block_ = r.get<uint32_t>();
        r.get<uint32_t>();  // reserved
        if (!r.failed() && file.vertices_per_block_ == 0)
          return corrupt(source, "'" + tag + "' has 0 vertices per block");
        if (file.vertices_per_block_ > 0)
          blocks = (uint64_t(mode_vertices) + file.vertices_per_block_ - 1) / file.vertices_per_block_;
      }
      r.getArray(bank.eigenvalues, modes);
      if (int16) {
        r.getArray(file.shape_scale_, modes);
        for (float scale : file.shape_scale_)
          if (!r.failed() && !(std::isfinite(scale) && scale >= 0.0f))
            return corrupt(source, "a shape scale of 'MODQ' is not finite and >= 0");
      }
      file.int16_shapes_ = int16;
      bank.shape_encoding = int16 ? ShapeEncoding::Int16 : ShapeEncoding::Float32;
      if (vertex_major) r.getArray(file.block_checksums_, blocks);
      if (r.failed()) return corrupt(source, "chunk '" + tag + "' is shorter than its contents");
      // The shapes are not read here: readAll() or readShapeRows() read them when asked.
      const uint64_t shapes_offset = static_cast<uint64_t>(r.here() - payload_start);
      const uint64_t shape_bytes = chunk_offset + chunk_size - shapes_offset;  // what the chunk has left
      const uint64_t values = uint64_t(modes) * 3;
      const uint64_t value_bytes = int16 ? 2 : 4;
      if (mode_vertices != 0 && values > shape_bytes / value_bytes / mode_vertices)
        return corrupt(source, "chunk '" + tag + "' is shorter than its " + std::to_string(modes) + " modes x " +
                                   std::to_string(mode_vertices) + " vertices of shapes");
      // The shapes must be exactly the unchecked tail of a format 3 file: nothing after them
      // escapes both checksums.
      if (vertex_major && (shapes_offset != head_size || shape_bytes != values * mode_vertices * value_bytes ||
                           chunk_offset + chunk_size != payload_size))
        return corrupt(source, "the shapes of chunk '" + tag + "' are not the file's tail after the checked head");
      if (!runs_past) r.skip(values * mode_vertices * value_bytes);
      file.shapes_offset_ = header_size + shapes_offset;
      file.vertex_major_ = vertex_major;
      seen_modes = true;
    } else if (tag == "FERR") {
      const uint32_t count = r.get<uint32_t>();
      r.getArray(bank.frequency_error_estimate, count);
    } else if (tag == "RADI") {
      const uint32_t count = r.get<uint32_t>();
      r.getArray(bank.radiation_m2, count);
    } else if (tag == "ACTF" && bank.format_version >= 5) {
      const std::string problem = readTransfer(r, bank.transfer);
      if (!problem.empty()) return corrupt(source, "chunk 'ACTF': " + problem);
    } else if (tag == "PROV") {
      bank.meshing_seconds = r.get<double>();
      bank.assembly_seconds = r.get<double>();
      bank.factorize_seconds = r.get<double>();
      bank.lanczos_seconds = r.get<double>();
      bank.total_seconds = r.get<double>();
      bank.rigid_modes_dropped = r.get<uint32_t>();
      bank.above_cutoff_dropped = r.get<uint32_t>();
      bank.tool_version = r.getString();
      if (bank.format_version >= 5) bank.transfer_seconds = r.get<double>();
    }  // else: a chunk from a newer writer of the same version; skipped on purpose.
    if (r.failed()) return corrupt(source, "chunk '" + tag + "' is shorter than its contents");
  }
  if (!seen_modes || !seen_surface)
    return corrupt(source, std::string("missing the ") +
                               (seen_modes                 ? "SURF"
                                : bank.format_version >= 5 ? "MODV or MODQ"
                                : bank.format_version == 4 ? "MODQ"
                                : bank.format_version == 3 ? "MODV"
                                                           : "MODE") +
                               " chunk");
  if (mode_vertices != surface_vertices)
    return corrupt(source, "modes are sampled on " + std::to_string(mode_vertices) + " vertices, the surface has " +
                               std::to_string(surface_vertices));
  // Format 5 solved every mode; format 6 a prefix (ModeBank::checkConsistency: not more).
  if (bank.format_version == 5 && !bank.transfer.offset.empty() && bank.transfer.modeCount() != bank.modeCount())
    return corrupt(source, "chunk 'ACTF' has " + std::to_string(bank.transfer.modeCount()) + " modes, the bank " +
                               std::to_string(bank.modeCount()) + " (format 5 has the transfer of every mode)");
  const std::string problem = bank.checkConsistency(/*shapes_loaded=*/false);
  if (!problem.empty()) return corrupt(source, problem);
  file.bank_ = std::make_shared<const ModeBank>(std::move(bank));
  file.source_ = std::move(source_ptr);
  return file;
}

void BankFile::decodeRows(const uint8_t* bytes, size_t count, float* out) const {
  const size_t values = count * bank_->modeCount() * 3;
  if (values == 0) return;  // a bank with no modes: nothing to copy (and out may be null)
  if (!int16_shapes_) {
    std::memcpy(out, bytes, values * sizeof(float));
    return;
  }
  // The same float product the writer's error bound assumes: q * scale_mode.
  for (size_t k = 0; k < values; ++k) {
    int16_t q;
    std::memcpy(&q, bytes + 2 * k, 2);
    out[k] = static_cast<float>(q) * shape_scale_[(k / 3) % bank_->modeCount()];
  }
}

Status BankFile::readShapeBytes(size_t first, size_t count, std::vector<uint8_t>& to) const {
  const size_t row_bytes = bank_->modeCount() * 3 * shapeValueBytes();
  to.resize(count * row_bytes);
  if (!source_->read(shapes_offset_ + first * row_bytes, to.size(), to.data()))
    return corrupt(source_->name, "the file ended inside its mode shapes (was it truncated while open?)");
  return {};
}

Status BankFile::verifyBlock(size_t block, const uint8_t* bytes, size_t size) const {
  if (shapeBlockChecksum(bytes, size, block) == block_checksums_[block]) return {};
  const size_t first = block * vertices_per_block_;
  const size_t last = std::min<size_t>(first + vertices_per_block_, bank_->surfaceVertexCount()) - 1;
  return corrupt(source_->name, "checksum mismatch in the shapes of surface vertices " + std::to_string(first) +
                                    " to " + std::to_string(last) + " (the file is damaged)");
}

Result<ShapeRows> BankFile::readShapeRows(std::vector<uint32_t> vertices) const {
  const size_t modes = bank_->modeCount();
  const size_t nv = bank_->surfaceVertexCount();
  const size_t row_floats = modes * 3;
  std::sort(vertices.begin(), vertices.end());
  vertices.erase(std::unique(vertices.begin(), vertices.end()), vertices.end());
  if (!vertices.empty() && vertices.back() >= nv)
    return badInput(source_->name + ": error: surface vertex " + std::to_string(vertices.back()) +
                    " is out of range, the bank has " + std::to_string(nv));
  ShapeRows rows;
  rows.modes = modes;
  rows.values.resize(vertices.size() * row_floats);
  std::vector<uint8_t> bytes;
  size_t block_read = SIZE_MAX;  // format 3: the block in `bytes` (vertices come sorted)
  for (size_t i = 0; i < vertices.size(); ++i) {
    const size_t v = vertices[i];
    float* row = rows.values.data() + i * row_floats;
    if (vertex_major_) {
      // Read and verify the whole block, then take the row from the verified bytes.
      const size_t block = v / vertices_per_block_;
      const size_t first = block * vertices_per_block_;
      if (block != block_read) {
        Status read = readShapeBytes(first, std::min<size_t>(vertices_per_block_, nv - first), bytes);
        if (!read) return read.error();
        Status verified = verifyBlock(block, bytes.data(), bytes.size());
        if (!verified) return verified.error();
        block_read = block;
      }
      decodeRows(bytes.data() + (v - first) * row_floats * shapeValueBytes(), 1, row);
    } else {
      // Formats 1-2 are all in memory and verified: gather [mode][vertex][xyz].
      for (size_t m = 0; m < modes; ++m)
        if (!source_->read(shapes_offset_ + (m * nv + v) * 3 * sizeof(float), 3 * sizeof(float),
                           reinterpret_cast<uint8_t*>(row + m * 3)))
          return corrupt(source_->name, "the file ended inside its mode shapes");
    }
    for (size_t k = 0; k < row_floats; ++k)
      if (!std::isfinite(row[k])) return corrupt(source_->name, "a mode shape value is not finite");
  }
  rows.vertices = std::move(vertices);
  return rows;
}

Result<ModeBank> BankFile::readAll() const {
  ModeBank bank = *bank_;
  const size_t modes = bank.modeCount();
  const size_t nv = bank.surfaceVertexCount();
  bank.shapes.resize(modes * nv * 3);
  if (vertex_major_) {
    std::vector<uint8_t> bytes;
    Status read = readShapeBytes(0, nv, bytes);
    if (!read) return read.error();
    const size_t row_bytes = modes * 3 * shapeValueBytes();
    for (size_t b = 0; b < block_checksums_.size(); ++b) {
      const size_t first = b * vertices_per_block_, count = std::min<size_t>(vertices_per_block_, nv - first);
      Status verified = verifyBlock(b, bytes.data() + first * row_bytes, count * row_bytes);
      if (!verified) return verified.error();
    }
    // [vertex][mode][xyz] in the file, [mode][vertex][xyz] in memory.
    std::vector<float> row(modes * 3);
    for (size_t v = 0; v < nv; ++v) {
      decodeRows(bytes.data() + v * row_bytes, 1, row.data());
      for (size_t m = 0; m < modes; ++m)
        std::memcpy(bank.shapes.data() + (m * nv + v) * 3, &row[m * 3], 3 * sizeof(float));
    }
  } else if (!source_->read(shapes_offset_, bank.shapes.size() * sizeof(float),
                            reinterpret_cast<uint8_t*>(bank.shapes.data()))) {
    return corrupt(source_->name, "the file ended inside its mode shapes");
  }
  const std::string problem = bank.checkConsistency();
  if (!problem.empty()) return corrupt(source_->name, problem);
  return bank;
}

Result<BankFile> BankFile::openBytes(const uint8_t* data, size_t size, const std::string& source) {
  auto bytes = std::make_shared<Source>();
  bytes->name = source;
  bytes->data = data;
  bytes->size = bytes->resident = size;
  return parse(std::move(bytes));
}

Result<BankFile> BankFile::open(const std::string& path) {
  // A format 3 file is read up to the end of its checked head (about 1 MB of a 17 MB plate
  // bank) and kept open: its shapes are read with pread when asked. pread, not mmap: a file
  // truncated meanwhile by someone else then gives an error instead of a SIGBUS. Anything else
  // (formats 1-2, damaged headers, directories) is read whole, which also words the errors.
  auto bytes = std::make_shared<Source>();
  bytes->name = path;
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  struct stat info {};
  if (fd >= 0 && fstat(fd, &info) == 0 && S_ISREG(info.st_mode) && info.st_size >= kHeaderSizeV3 &&
      static_cast<uint64_t>(info.st_size) <= kMaxBankBytes) {
    bytes->fd = fd;
    bytes->size = static_cast<uint64_t>(info.st_size);
    uint8_t header[kHeaderSizeV3] = {};
    uint32_t version = 0, header_size = 0;
    uint64_t head_size = 0;
    if (bytes->read(0, sizeof header, header)) {
      std::memcpy(&version, header + 8, 4);
      std::memcpy(&header_size, header + 12, 4);
      std::memcpy(&head_size, header + 32, 8);
    }
    // Only the head of a well-formed format 3 header; everything otherwise.
    uint64_t wanted = bytes->size;
    if (std::memcmp(header, kMagic, 8) == 0 && version >= 3 && version <= kBankFormatVersionMax &&
        header_size == kHeaderSizeV3 && head_size <= bytes->size - kHeaderSizeV3)
      wanted = kHeaderSizeV3 + head_size;
    bytes->head.reset(new uint8_t[wanted]);  // not zeroed: the read fills it
    if (bytes->read(0, wanted, bytes->head.get())) {  // from the file
      bytes->data = bytes->head.get();
      bytes->resident = wanted;
      if (bytes->resident == bytes->size) {
        close(bytes->fd);
        bytes->fd = -1;
        return parse(std::move(bytes));
      }
      // The head is parsed into the bank and the shapes after it are read with pread when asked,
      // so its bytes (2-3 MB of a plate's bank, most of them the transfer) need not stay.
      const std::shared_ptr<Source> kept = bytes;
      Result<BankFile> parsed = parse(std::move(bytes));
      kept->head.reset();
      kept->data = nullptr;
      kept->resident = 0;
      return parsed;
    }
    bytes->head.reset();  // shorter than fstat said: the buffered path words it
  } else if (fd >= 0) {
    close(fd);
  }
  if (bytes->fd >= 0) {
    close(bytes->fd);
    bytes->fd = -1;
  }
  Result<std::string> read = readWholeFile(path, kMaxBankBytes);
  if (!read) return read.error();
  bytes->buffer = std::move(*read);
  bytes->data = reinterpret_cast<const uint8_t*>(bytes->buffer.data());
  bytes->size = bytes->resident = bytes->buffer.size();
  return parse(std::move(bytes));
}

Result<ModeBank> decodeBank(const uint8_t* data, size_t size, const std::string& source) {
  Result<BankFile> file = BankFile::openBytes(data, size, source);
  if (!file) return file.error();
  return file->readAll();
}

Result<ModeBank> readBank(const std::string& path) {
  Result<BankFile> file = BankFile::open(path);
  if (!file) return file.error();
  return file->readAll();
}

}  // namespace strike
