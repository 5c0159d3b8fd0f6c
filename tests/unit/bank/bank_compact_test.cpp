// SPDX-License-Identifier: MIT
// Bank format 4 (`strike modes --compact`): shapes as 16-bit integers with a scale per mode.
// Half the shape bytes; every value within scale / 2 = max|phi_i| / 65534.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <filesystem>

#include <unistd.h>

#include "strike/bank/bank.hpp"

namespace strike {
namespace {

/// 40 modes on 1000 vertices, values of every sign and size (a mode's amplitude varies 1000x).
ModeBank bigBank() {
  ModeBank bank;
  bank.material = Material{"steel", 2.0e11, 0.29, 7850.0, 1e-8, 2.0};
  bank.mesh_source = "test";
  bank.mass_kg = 1.0;
  bank.volume_m3 = 1e-4;
  for (uint32_t v = 0; v < 1000; ++v) {
    bank.surface_positions.insert(bank.surface_positions.end(), {0.001 * v, 0.002 * (v % 7), 0.0});
    if (v + 2 < 1000) bank.surface_triangles.insert(bank.surface_triangles.end(), {v, v + 1, v + 2});
  }
  for (int m = 0; m < 40; ++m) bank.eigenvalues.push_back(std::pow(2 * M_PI * (500.0 + 100.0 * m), 2));
  for (size_t i = 0; i < 40 * 1000 * 3; ++i) {
    const double mode_scale = std::pow(10.0, static_cast<double>(i / 3000) / 13.0 - 1.5);  // 0.03 to 30 1/sqrt(kg)
    bank.shapes.push_back(static_cast<float>(mode_scale * std::sin(0.37 * static_cast<double>(i))));
  }
  bank.radiation_m2.assign(40, 1e-3);
  return bank;
}

TEST(CompactBank, ShapesRoundTripWithinTheStatedErrorAtHalfTheBytes) {
  const ModeBank bank = bigBank();
  const std::vector<uint8_t> f32 = encodeBank(bank, ShapeEncoding::Float32);
  const std::vector<uint8_t> i16 = encodeBank(bank, ShapeEncoding::Int16);
  // 40 modes x 1000 vertices x 3 values x 2 bytes saved; format 4 adds one f32 scale per mode and
  // has fewer blocks (so fewer u64 checksums): 16 KiB holds 68 vertices of 240-byte i16 rows, 34 of f32.
  const long saved = static_cast<long>(f32.size()) - static_cast<long>(i16.size());
  const long blocks_f32 = (1000 + 33) / 34, blocks_i16 = (1000 + 67) / 68;
  EXPECT_EQ(saved, 40 * 1000 * 3 * 2 - 40 * 4 + 8 * (blocks_f32 - blocks_i16));
  Result<ModeBank> read = decodeBank(i16.data(), i16.size(), "compact.modes");
  ASSERT_TRUE(read) << read.error().message;
  EXPECT_EQ(read->format_version, kBankFormatVersion);
  EXPECT_EQ(read->shape_encoding, ShapeEncoding::Int16);
  EXPECT_EQ(read->eigenvalues, bank.eigenvalues);
  EXPECT_EQ(read->surface_positions, bank.surface_positions);
  EXPECT_EQ(read->radiation_m2, bank.radiation_m2);
  double worst_ratio = 0.0;  // |error| / (max |phi_i| / 65534), over every value
  for (size_t m = 0; m < bank.modeCount(); ++m) {
    double largest = 0.0;
    for (size_t v = 0; v < 1000; ++v)
      for (int a = 0; a < 3; ++a) largest = std::max(largest, double(std::fabs(bank.shapeAt(m, v)[a])));
    for (size_t v = 0; v < 1000; ++v)
      for (int a = 0; a < 3; ++a) {
        const double error = std::fabs(double(read->shapeAt(m, v)[a]) - double(bank.shapeAt(m, v)[a]));
        worst_ratio = std::max(worst_ratio, error / (largest / 65534.0));
      }
  }
  // The bound holds, plus float rounding (the scale and the product q * scale, each within 2^-24
  // of the mode's largest value), and it is what quantization costs: with 120,000 values the
  // worst comes close to half a step.
  EXPECT_LE(worst_ratio, 1.0 + 2.0 * 65534.0 * std::ldexp(1.0, -24));
  EXPECT_GT(worst_ratio, 0.9);
}

TEST(CompactBank, RowsReadFromTheFileEqualTheWholeReadAndDamageIsFound) {
  const ModeBank bank = bigBank();
  const std::string path = testing::TempDir() + "/compact-" + std::to_string(::getpid()) + ".modes";
  ASSERT_TRUE(writeBank(path, bank, ShapeEncoding::Int16));
  Result<ModeBank> whole = readBank(path);
  ASSERT_TRUE(whole) << whole.error().message;
  Result<BankFile> file = BankFile::open(path);
  ASSERT_TRUE(file) << file.error().message;
  EXPECT_TRUE(file->bank().shapes.empty());
  Result<ShapeRows> rows = file->readShapeRows({999, 0, 421});
  ASSERT_TRUE(rows) << rows.error().message;
  for (uint32_t v : rows->vertices)
    for (size_t m = 0; m < bank.modeCount(); ++m)
      for (int a = 0; a < 3; ++a) ASSERT_EQ(rows->row(v)[m * 3 + a], whole->shapeAt(m, v)[a]);
  // One flipped bit in vertex 421's stored row: its block fails, naming the vertices.
  std::vector<uint8_t> bytes = encodeBank(bank, ShapeEncoding::Int16);
  bytes[bytes.size() - (1000 - 421) * 40 * 3 * 2 + 5] ^= 0x10;
  Result<BankFile> damaged = BankFile::openBytes(bytes.data(), bytes.size(), "damaged.modes");
  ASSERT_TRUE(damaged) << damaged.error().message;
  EXPECT_TRUE(damaged->readShapeRows({0, 999}));
  Result<ShapeRows> bad = damaged->readShapeRows({421});
  ASSERT_FALSE(bad);
  EXPECT_NE(bad.error().message.find("checksum mismatch in the shapes of surface vertices 408 to 475"),
            std::string::npos)
      << bad.error().message;
  std::filesystem::remove(path);
}

}  // namespace
}  // namespace strike
