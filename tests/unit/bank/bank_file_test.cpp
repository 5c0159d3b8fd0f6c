// SPDX-License-Identifier: MIT
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <random>

#include "common/same_bytes.hpp"
#include "strike/core/atomic_file.hpp"
#include "strike/bank/bank.hpp"

namespace strike {
namespace {

// A small but complete bank: 3 modes on a 4-vertex tetrahedron surface.
ModeBank makeTestBank() {
  ModeBank bank;
  bank.material = Material{"steel", 2.0e11, 0.29, 7850.0, 1e-8, 2.0};
  bank.mesh_hash = 0x1234567890abcdefull;
  bank.mesh_source = "box:0.3,0.02,0.02";
  bank.element_order = 2;
  bank.target_edge_m = 0.005;
  bank.mesh_nodes = 4;
  bank.mesh_tets = 1;
  bank.max_freq_hz = 20000.0;
  bank.max_modes = 200;
  bank.mass_kg = 0.942;
  bank.volume_m3 = 1.2e-4;
  bank.centre_m = {0.1, 0.2, 0.3};
  bank.inertia_kg_m2 = {1, 0, 0, 0, 2, 0, 0, 0, 3};
  bank.surface_positions = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1};
  bank.surface_normals = {0, 0, -1, 1, 0, 0, 0, 1, 0, 0, 0, 1};
  bank.surface_triangles = {0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3};
  bank.surface_node_index = {0, 1, 2, 3};
  bank.eigenvalues = {std::pow(2 * M_PI * 1000, 2), std::pow(2 * M_PI * 2000, 2), std::pow(2 * M_PI * 5000, 2)};
  for (int i = 0; i < 3 * 4 * 3; ++i) bank.shapes.push_back(0.01f * static_cast<float>(i - 18));
  bank.frequency_error_estimate = {1e-3, 2e-3, 4e-3};
  bank.total_seconds = 1.5;
  bank.rigid_modes_dropped = 6;
  bank.tool_version = "strike test";
  return bank;
}

TEST(ModeBank, DerivedFrequencyAndDecay) {
  const ModeBank bank = makeTestBank();
  EXPECT_NEAR(bank.frequencyHz(0), 1000.0, 1e-9);
  const double lambda = bank.eigenvalues[1];
  EXPECT_DOUBLE_EQ(bank.decayPerS(1), 0.5 * (1e-8 * lambda + 2.0));
  EXPECT_EQ(bank.checkConsistency(), "");
}

TEST(BankFile, RoundTripIsExact) {
  const ModeBank bank = makeTestBank();
  const std::vector<uint8_t> bytes = encodeBank(bank);
  Result<ModeBank> read = decodeBank(bytes.data(), bytes.size(), "mem");
  ASSERT_TRUE(read) << read.error().message;
  EXPECT_EQ(read->material.name, "steel");
  EXPECT_EQ(read->material.youngs_pa, bank.material.youngs_pa);
  EXPECT_EQ(read->mesh_hash, bank.mesh_hash);
  EXPECT_EQ(read->mesh_source, bank.mesh_source);
  EXPECT_EQ(read->element_order, 2u);
  EXPECT_EQ(read->eigenvalues, bank.eigenvalues);
  EXPECT_TRUE(test::sameValues(read->shapes, bank.shapes));
  EXPECT_EQ(read->surface_positions, bank.surface_positions);
  EXPECT_EQ(read->surface_normals, bank.surface_normals);
  EXPECT_EQ(read->surface_triangles, bank.surface_triangles);
  EXPECT_EQ(read->surface_node_index, bank.surface_node_index);
  EXPECT_EQ(read->frequency_error_estimate, bank.frequency_error_estimate);
  EXPECT_EQ(read->inertia_kg_m2, bank.inertia_kg_m2);
  EXPECT_EQ(read->rigid_modes_dropped, 6u);
  EXPECT_EQ(read->tool_version, "strike test");
  // Deterministic: encoding the decoded bank gives the same bytes.
  EXPECT_TRUE(test::sameValues(encodeBank(*read), bytes));
}

TEST(BankFile, WriteIsAtomicAndReadable) {
  const std::string dir = testing::TempDir() + "/bank_atomic";
  std::filesystem::create_directories(dir);
  const std::string path = dir + "/a.modes";
  ASSERT_TRUE(writeBank(path, makeTestBank()).ok());
  Result<ModeBank> read = readBank(path);
  ASSERT_TRUE(read) << read.error().message;
  int entries = 0;
  for ([[maybe_unused]] const auto& entry : std::filesystem::directory_iterator(dir)) ++entries;
  EXPECT_EQ(entries, 1) << "a temporary file was left behind";
  // Writing into a directory that does not exist fails cleanly and names the path.
  Status failed = writeBank(dir + "/missing/b.modes", makeTestBank());
  ASSERT_FALSE(failed.ok());
  EXPECT_NE(failed.error().message.find("missing/b.modes"), std::string::npos);
}

TEST(BankFile, RefusesTruncatedFiles) {
  const std::vector<uint8_t> bytes = encodeBank(makeTestBank());
  for (size_t size : {size_t(0), size_t(7), size_t(8), size_t(31), size_t(32), bytes.size() / 2, bytes.size() - 1}) {
    Result<ModeBank> read = decodeBank(bytes.data(), size, "cut.modes");
    ASSERT_FALSE(read) << "size " << size;
    EXPECT_EQ(read.error().kind, ErrorKind::BadInput);
    EXPECT_NE(read.error().message.find("cut.modes"), std::string::npos) << read.error().message;
  }
  Result<ModeBank> half = decodeBank(bytes.data(), bytes.size() / 2, "cut.modes");
  EXPECT_NE(half.error().message.find("truncated"), std::string::npos) << half.error().message;
}

TEST(BankFile, RefusesForeignAndNewerFiles) {
  std::vector<uint8_t> bytes = encodeBank(makeTestBank());
  std::vector<uint8_t> foreign = bytes;
  std::memcpy(foreign.data(), "RIFF", 4);
  Result<ModeBank> read = decodeBank(foreign.data(), foreign.size(), "x.wav");
  ASSERT_FALSE(read);
  EXPECT_NE(read.error().message.find("magic"), std::string::npos) << read.error().message;

  std::vector<uint8_t> newer = bytes;
  const uint32_t version = kBankFormatVersionMax + 1;
  std::memcpy(newer.data() + 8, &version, 4);
  read = decodeBank(newer.data(), newer.size(), "new.modes");
  ASSERT_FALSE(read);
  EXPECT_NE(read.error().message.find("version " + std::to_string(version)), std::string::npos) << read.error().message;
}

// The format 3 header: 40 bytes, u64 head_size at 32; the head checksum covers payload bytes
// [0, head_size), the shapes after it are checked per block.
constexpr size_t kHeaderV3 = 40;
uint64_t headSize(const std::vector<uint8_t>& bytes) {
  uint64_t head = 0;
  std::memcpy(&head, bytes.data() + 32, 8);
  return head;
}
/// Recomputes the head checksum (payload size and head size as they are in the header).
void repairHeadChecksum(std::vector<uint8_t>& bytes) {
  const uint64_t head = std::min<uint64_t>(headSize(bytes), bytes.size() - kHeaderV3);
  const uint64_t checksum = bankPayloadChecksum(3, bytes.data() + kHeaderV3, head);
  std::memcpy(bytes.data() + 24, &checksum, 8);
}

// A bank with many shape blocks: 40 modes on 1,000 vertices (34 vertices per 16 KiB block).
ModeBank makeBigBank() {
  ModeBank bank = makeTestBank();
  bank.surface_positions.clear();
  bank.surface_normals.clear();
  bank.surface_node_index.clear();
  bank.surface_triangles.clear();
  for (uint32_t v = 0; v < 1000; ++v) {
    bank.surface_positions.insert(bank.surface_positions.end(), {0.001 * v, 0.002 * (v % 7), 0.0});
    if (v + 2 < 1000) bank.surface_triangles.insert(bank.surface_triangles.end(), {v, v + 1, v + 2});
  }
  bank.eigenvalues.clear();
  for (int m = 0; m < 40; ++m) bank.eigenvalues.push_back(std::pow(2 * M_PI * (500.0 + 100.0 * m), 2));
  bank.shapes.clear();
  for (size_t i = 0; i < 40 * 1000 * 3; ++i)
    bank.shapes.push_back(static_cast<float>(std::sin(0.37 * static_cast<double>(i))));
  bank.frequency_error_estimate.clear();
  return bank;
}

/// The bank as a format 1 or 2 file: SURF and MODE ([mode][vertex][xyz] shapes) chunks, a
/// 32-byte header and one checksum over the whole payload (docs/bank-format.md).
std::vector<uint8_t> legacyFile(const ModeBank& bank, uint32_t version) {
  std::vector<uint8_t> out = {'S', 'T', 'R', 'K', 'B', 'A', 'N', 'K'};
  auto put = [](std::vector<uint8_t>& to, const void* p, size_t n) {
    to.insert(to.end(), static_cast<const uint8_t*>(p), static_cast<const uint8_t*>(p) + n);
  };
  const uint32_t header[2] = {version, 32};
  const uint64_t sizes[2] = {0, 0};
  put(out, header, 8);
  put(out, sizes, 16);
  auto chunk = [&](const char* tag, const std::vector<uint8_t>& body) {
    const uint32_t flags = 0;
    const uint64_t size = body.size();
    put(out, tag, 4), put(out, &flags, 4), put(out, &size, 8);
    put(out, body.data(), body.size());
  };
  std::vector<uint8_t> body;
  const uint32_t nv = static_cast<uint32_t>(bank.surfaceVertexCount());
  const uint32_t surf[4] = {nv, static_cast<uint32_t>(bank.surface_triangles.size() / 3), 0, 0};
  put(body, surf, 16);
  put(body, bank.surface_positions.data(), 8 * bank.surface_positions.size());
  put(body, bank.surface_triangles.data(), 4 * bank.surface_triangles.size());
  chunk("SURF", body);
  body.clear();
  const uint32_t mode[2] = {static_cast<uint32_t>(bank.modeCount()), nv};
  put(body, mode, 8);
  put(body, bank.eigenvalues.data(), 8 * bank.eigenvalues.size());
  put(body, bank.shapes.data(), 4 * bank.shapes.size());
  chunk("MODE", body);
  const uint64_t payload = out.size() - 32;
  const uint64_t checksum =
      version == 1 ? fnv1a64(out.data() + 32, payload) : bankPayloadChecksum(2, out.data() + 32, payload);
  std::memcpy(out.data() + 16, &payload, 8);
  std::memcpy(out.data() + 24, &checksum, 8);
  return out;
}

// Formats 1 (byte-wise FNV-1a checksum) and 2 (word lanes) are still read, whole or in rows.
TEST(BankFile, ReadsFormatOneAndTwoFiles) {
  const ModeBank bank = makeBigBank();
  for (uint32_t version : {1u, 2u}) {
    const std::vector<uint8_t> bytes = legacyFile(bank, version);
    Result<ModeBank> read = decodeBank(bytes.data(), bytes.size(), "old.modes");
    ASSERT_TRUE(read) << read.error().message;
    EXPECT_EQ(read->format_version, version);
    EXPECT_EQ(read->eigenvalues, bank.eigenvalues);
    EXPECT_TRUE(test::sameValues(read->shapes, bank.shapes));
    Result<BankFile> file = BankFile::openBytes(bytes.data(), bytes.size(), "old.modes");
    ASSERT_TRUE(file) << file.error().message;
    Result<ShapeRows> rows = file->readShapeRows({999, 3, 3});
    ASSERT_TRUE(rows) << rows.error().message;
    ASSERT_EQ(rows->vertices, (std::vector<uint32_t>{3, 999}));
    for (uint32_t v : rows->vertices)
      for (size_t m = 0; m < bank.modeCount(); ++m)
        for (int c = 0; c < 3; ++c) ASSERT_EQ(rows->row(v)[m * 3 + c], bank.shapeAt(m, v)[c]);
    std::vector<uint8_t> damaged = bytes;
    damaged[damaged.size() - 5] ^= 1;  // in the shapes: formats 1 and 2 check everything at open
    EXPECT_FALSE(BankFile::openBytes(damaged.data(), damaged.size(), "old.modes"));
  }
  // The committed fuzz seed, written by an early strike (format 1).
  Result<ModeBank> seed = readBank(std::string(STRIKE_SOURCE_DIR) + "/tests/fuzz/corpus/bank/tiny.modes");
  ASSERT_TRUE(seed) << seed.error().message;
  EXPECT_EQ(seed->format_version, 1u);
  EXPECT_GT(seed->surfaceVertexCount(), 0u);
}

// A BankFile opens without reading shapes, then reads rows equal to the whole bank's, and checks
// only the blocks it reads: damage in one block is found when (and only when) that block is read.
// A body too small or stiff to ring below its cut-off has a bank with no modes: reading it whole
// (what `strike render --via-library` does) gives the surface and no shapes, without touching a
// null buffer (UBSan found memcpy(nullptr, ..., 0) here).
TEST(BankFile, ABankWithNoModesReadsWhole) {
  ModeBank bank = makeTestBank();
  bank.eigenvalues.clear();
  bank.shapes.clear();
  bank.frequency_error_estimate.clear();
  for (ShapeEncoding encoding : {ShapeEncoding::Float32, ShapeEncoding::Int16}) {
    const std::vector<uint8_t> bytes = encodeBank(bank, encoding);
    Result<BankFile> file = BankFile::openBytes(bytes.data(), bytes.size(), "silent.modes");
    ASSERT_TRUE(file) << file.error().message;
    Result<ModeBank> all = file->readAll();
    ASSERT_TRUE(all) << all.error().message;
    EXPECT_EQ(all->modeCount(), 0u);
    EXPECT_TRUE(all->shapes.empty());
    EXPECT_EQ(all->surface_positions, bank.surface_positions);
  }
}

TEST(BankFile, ReadsShapeRowsCheckingOnlyTheirBlocks) {
  const ModeBank bank = makeBigBank();
  const std::vector<uint8_t> bytes = encodeBank(bank);
  Result<BankFile> file = BankFile::openBytes(bytes.data(), bytes.size(), "big.modes");
  ASSERT_TRUE(file) << file.error().message;
  EXPECT_TRUE(file->bank().shapes.empty());
  EXPECT_EQ(file->bank().eigenvalues, bank.eigenvalues);
  EXPECT_EQ(file->bank().surface_positions, bank.surface_positions);
  Result<ShapeRows> rows = file->readShapeRows({500, 0, 999, 500});
  ASSERT_TRUE(rows) << rows.error().message;
  ASSERT_EQ(rows->vertices, (std::vector<uint32_t>{0, 500, 999}));
  for (uint32_t v : rows->vertices)
    for (size_t m = 0; m < bank.modeCount(); ++m)
      for (int c = 0; c < 3; ++c) ASSERT_EQ(rows->row(v)[m * 3 + c], bank.shapeAt(m, v)[c]) << v << " " << m;
  EXPECT_EQ(rows->row(1), nullptr);
  EXPECT_FALSE(file->readShapeRows({1000})) << "vertex out of range";

  // Damage one value of vertex 700: the head still verifies, rows elsewhere read, vertex 700 fails.
  const size_t row_bytes = bank.modeCount() * 3 * sizeof(float);
  std::vector<uint8_t> damaged = bytes;
  damaged[kHeaderV3 + headSize(bytes) + 700 * row_bytes + 17] ^= 0x40;
  Result<BankFile> opened = BankFile::openBytes(damaged.data(), damaged.size(), "d.modes");
  ASSERT_TRUE(opened) << opened.error().message;
  EXPECT_TRUE(opened->readShapeRows({0, 500, 999}));
  Result<ShapeRows> bad = opened->readShapeRows({700});
  ASSERT_FALSE(bad);
  EXPECT_NE(bad.error().message.find("checksum mismatch in the shapes"), std::string::npos) << bad.error().message;
  EXPECT_NE(bad.error().message.find("d.modes"), std::string::npos);
  EXPECT_FALSE(opened->readAll());
  EXPECT_FALSE(decodeBank(damaged.data(), damaged.size(), "d.modes"));

  // Two blocks swapped: each block's checksum is seeded with its number.
  std::vector<uint8_t> swapped = bytes;
  const uint32_t per_block = static_cast<uint32_t>(16384 / row_bytes);  // docs/bank-format.md
  uint8_t* shapes = swapped.data() + kHeaderV3 + headSize(bytes);
  std::swap_ranges(shapes, shapes + per_block * row_bytes, shapes + per_block * row_bytes);
  Result<BankFile> swapped_file = BankFile::openBytes(swapped.data(), swapped.size(), "s.modes");
  ASSERT_TRUE(swapped_file);
  EXPECT_FALSE(swapped_file->readShapeRows({0}));
  EXPECT_FALSE(swapped_file->readShapeRows({per_block}));
}

// A BankFile keeps the file open and reads shapes with pread: a file truncated (or replaced by
// rename) after open gives an error or the old contents, never a crash (a mapping would SIGBUS).
TEST(BankFile, ReadsFromAFileTruncatedOrReplacedAfterOpenFailCleanly) {
  const std::string dir = testing::TempDir() + "/bank_truncated";
  std::filesystem::create_directories(dir);
  const std::string path = dir + "/big.modes";
  const ModeBank bank = makeBigBank();
  ASSERT_TRUE(writeBank(path, bank).ok());
  Result<BankFile> file = BankFile::open(path);
  ASSERT_TRUE(file) << file.error().message;
  const uintmax_t full = std::filesystem::file_size(path);
  EXPECT_TRUE(file->readShapeRows({999}));

  // Replaced by rename (what writers do): the open file still reads its old, intact contents.
  ModeBank other = bank;
  for (float& v : other.shapes) v = -v;
  ASSERT_TRUE(writeBank(path, other).ok());
  Result<ShapeRows> old_rows = file->readShapeRows({999});
  ASSERT_TRUE(old_rows) << old_rows.error().message;
  EXPECT_EQ(old_rows->row(999)[0], bank.shapeAt(0, 999)[0]);

  // Truncated in place under the reader: rows past the end fail naming the file.
  Result<BankFile> reopened = BankFile::open(path);
  ASSERT_TRUE(reopened);
  std::filesystem::resize_file(path, full / 2);
  EXPECT_TRUE(reopened->readShapeRows({0})) << "the first block is still there";
  Result<ShapeRows> cut = reopened->readShapeRows({999});
  ASSERT_FALSE(cut);
  EXPECT_NE(cut.error().message.find(path), std::string::npos) << cut.error().message;
  EXPECT_NE(cut.error().message.find("ended"), std::string::npos) << cut.error().message;
  EXPECT_FALSE(reopened->readAll());
}

// Only the shapes escape the head checksum: a file whose head size stops short of them, or that
// carries bytes after them, is refused even with a repaired head checksum.
TEST(BankFile, NothingButTheShapesIsOutsideTheHeadChecksum) {
  const std::vector<uint8_t> bytes = encodeBank(makeBigBank());
  std::vector<uint8_t> short_head = bytes;
  const uint64_t shorter = headSize(bytes) - 100;
  std::memcpy(short_head.data() + 32, &shorter, 8);
  repairHeadChecksum(short_head);
  EXPECT_FALSE(decodeBank(short_head.data(), short_head.size(), "h.modes"));

  std::vector<uint8_t> trailing = bytes;
  const uint8_t chunk[16] = {'X', 'T', 'R', 'A', 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0};
  trailing.insert(trailing.end(), chunk, chunk + 16);
  const uint64_t payload = trailing.size() - kHeaderV3;
  std::memcpy(trailing.data() + 16, &payload, 8);
  repairHeadChecksum(trailing);
  Result<ModeBank> read = decodeBank(trailing.data(), trailing.size(), "t.modes");
  ASSERT_FALSE(read);
  EXPECT_NE(read.error().message.find("tail"), std::string::npos) << read.error().message;
}

TEST(BankFile, ChecksumCatchesEveryFlippedPayloadByte) {
  const std::vector<uint8_t> bytes = encodeBank(makeTestBank());
  for (size_t i = 32; i < bytes.size(); ++i) {
    std::vector<uint8_t> damaged = bytes;
    damaged[i] ^= 0x10;
    Result<ModeBank> read = decodeBank(damaged.data(), damaged.size(), "d.modes");
    ASSERT_FALSE(read) << "byte " << i;
    // Bytes 32-39 are the head size: a changed one moves what the checksum covers.
    if (i >= kHeaderV3) {
      EXPECT_NE(read.error().message.find("checksum"), std::string::npos) << read.error().message;
    }
  }
}

// Hostile payloads with a valid checksum: the decoder must fail cleanly, never overrun or
// allocate what the counts claim. Fixed seed, 2000 mutations.
TEST(BankFile, MutatedPayloadsWithValidChecksumNeverCrash) {
  const std::vector<uint8_t> bytes = encodeBank(makeTestBank());
  std::mt19937_64 random(12345);
  int refused = 0;
  for (int trial = 0; trial < 2000; ++trial) {
    std::vector<uint8_t> mutated = bytes;
    const int flips = 1 + static_cast<int>(random() % 4);
    for (int f = 0; f < flips; ++f) {
      const size_t at = kHeaderV3 + random() % (mutated.size() - kHeaderV3);
      mutated[at] = static_cast<uint8_t>(random() % 4 == 0 ? 0xff : random());
    }
    if (random() % 8 == 0) mutated.resize(kHeaderV3 + random() % (mutated.size() - kHeaderV3));
    const uint64_t payload_size = mutated.size() - kHeaderV3;
    std::memcpy(mutated.data() + 16, &payload_size, 8);
    repairHeadChecksum(mutated);
    Result<ModeBank> read = decodeBank(mutated.data(), mutated.size(), "m.modes");
    if (!read) {
      ++refused;
      EXPECT_EQ(read.error().kind, ErrorKind::BadInput);
    } else {
      EXPECT_EQ(read->checkConsistency(), "");
    }
  }
  EXPECT_GT(refused, 100);
}

TEST(BankFile, ReadNamesMissingFilesAndDirectories) {
  Result<ModeBank> read = readBank("/nonexistent/x.modes");
  ASSERT_FALSE(read);
  EXPECT_NE(read.error().message.find("/nonexistent/x.modes"), std::string::npos);
  read = readBank(testing::TempDir());
  ASSERT_FALSE(read);
  EXPECT_NE(read.error().message.find("directory"), std::string::npos) << read.error().message;
}

TEST(Fnv1a64, MatchesPublishedVectors) {
  // Test vectors from the FNV reference (Noll): "" and "a".
  EXPECT_EQ(fnv1a64("", 0), 0xcbf29ce484222325ull);
  EXPECT_EQ(fnv1a64("a", 1), 0xaf63dc4c8601ec8cull);
  EXPECT_EQ(fnv1a64("foobar", 6), 0x85944171f73967e8ull);
}

}  // namespace
}  // namespace strike
