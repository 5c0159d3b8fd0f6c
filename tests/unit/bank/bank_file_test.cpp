// SPDX-License-Identifier: MIT
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <random>

#include "strike/atomic_file.hpp"
#include "strike/bank.hpp"

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
  EXPECT_EQ(read->shapes, bank.shapes);
  EXPECT_EQ(read->surface_positions, bank.surface_positions);
  EXPECT_EQ(read->surface_normals, bank.surface_normals);
  EXPECT_EQ(read->surface_triangles, bank.surface_triangles);
  EXPECT_EQ(read->surface_node_index, bank.surface_node_index);
  EXPECT_EQ(read->frequency_error_estimate, bank.frequency_error_estimate);
  EXPECT_EQ(read->inertia_kg_m2, bank.inertia_kg_m2);
  EXPECT_EQ(read->rigid_modes_dropped, 6u);
  EXPECT_EQ(read->tool_version, "strike test");
  // Deterministic: encoding the decoded bank gives the same bytes.
  EXPECT_EQ(encodeBank(*read), bytes);
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
  const uint32_t version = kBankFormatVersion + 1;
  std::memcpy(newer.data() + 8, &version, 4);
  read = decodeBank(newer.data(), newer.size(), "new.modes");
  ASSERT_FALSE(read);
  EXPECT_NE(read.error().message.find("version " + std::to_string(version)), std::string::npos) << read.error().message;
}

// Format 1 (byte-wise FNV-1a checksum) is still read: the same payload under a version-1 header.
TEST(BankFile, ReadsFormatOneFiles) {
  std::vector<uint8_t> bytes = encodeBank(makeTestBank());
  const uint32_t version = 1;
  const uint64_t checksum = fnv1a64(bytes.data() + 32, bytes.size() - 32);
  EXPECT_NE(checksum, bankPayloadChecksum(2, bytes.data() + 32, bytes.size() - 32));
  std::memcpy(bytes.data() + 8, &version, 4);
  std::memcpy(bytes.data() + 24, &checksum, 8);
  Result<ModeBank> read = decodeBank(bytes.data(), bytes.size(), "v1.modes");
  ASSERT_TRUE(read) << read.error().message;
  EXPECT_EQ(read->format_version, 1u);
  EXPECT_EQ(read->eigenvalues, makeTestBank().eigenvalues);
}

TEST(BankFile, ChecksumCatchesEveryFlippedPayloadByte) {
  const std::vector<uint8_t> bytes = encodeBank(makeTestBank());
  for (size_t i = 32; i < bytes.size(); ++i) {
    std::vector<uint8_t> damaged = bytes;
    damaged[i] ^= 0x10;
    Result<ModeBank> read = decodeBank(damaged.data(), damaged.size(), "d.modes");
    ASSERT_FALSE(read) << "byte " << i;
    EXPECT_NE(read.error().message.find("checksum"), std::string::npos);
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
      const size_t at = 32 + random() % (mutated.size() - 32);
      mutated[at] = static_cast<uint8_t>(random() % 4 == 0 ? 0xff : random());
    }
    if (random() % 8 == 0) mutated.resize(32 + random() % (mutated.size() - 32));
    const uint64_t payload_size = mutated.size() - 32;
    const uint64_t checksum = bankPayloadChecksum(kBankFormatVersion, mutated.data() + 32, payload_size);
    std::memcpy(mutated.data() + 16, &payload_size, 8);
    std::memcpy(mutated.data() + 24, &checksum, 8);
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
