// SPDX-License-Identifier: MIT
#include <gtest/gtest.h>

#include <cmath>

#include "strike/precompute/materials.hpp"

namespace strike {
namespace {

TEST(Materials, BuiltinTableHasTheIssueListWithSources) {
  const MaterialTable& table = builtinMaterials();
  for (const char* name : {"steel", "aluminium", "brass", "copper", "iron", "glass", "ceramic", "porcelain", "wood",
                           "plastic", "abs", "polycarbonate", "rubber", "concrete", "stone"}) {
    Result<Material> m = table.find(name);
    ASSERT_TRUE(m) << name;
    EXPECT_TRUE(validateMaterial(*m, name).ok()) << name;
    ASSERT_TRUE(table.sources.count(name)) << name << " has no source";
    EXPECT_GT(table.sources.at(name).size(), 10u);
  }
  EXPECT_TRUE(table.find("STEEL").ok()) << "lookup is case-insensitive";
}

TEST(Materials, UnknownNameListsKnownOnes) {
  Result<Material> m = builtinMaterials().find("vibranium");
  ASSERT_FALSE(m);
  EXPECT_NE(m.error().message.find("unknown material 'vibranium'"), std::string::npos);
  EXPECT_NE(m.error().message.find("aluminium"), std::string::npos);
}

TEST(Materials, RayleighFitGivesTheLossFactorAtBothBandEdges) {
  // xi(w) = a2 / (2 w) + a1 w / 2 must equal eta / 2 at 500 Hz and 5 kHz.
  double a1 = 0, a2 = 0;
  const double eta = 3e-4;
  rayleighFromLossFactor(eta, 500.0, 5000.0, a1, a2);
  for (double f : {500.0, 5000.0}) {
    const double w = 2 * M_PI * f;
    EXPECT_NEAR(a2 / (2 * w) + a1 * w / 2, eta / 2, 1e-15);
  }
  const Material steel = *builtinMaterials().find("steel");
  EXPECT_NEAR(steel.rayleigh_stiffness, a1, 1e-20);
  EXPECT_NEAR(steel.rayleigh_mass, a2, 1e-12);
}

TEST(Materials, ValidationNamesFieldAndValue) {
  Material m{"x", 2e11, 0.5, 7850, 0, 0};
  Status s = validateMaterial(m, "objects[1].material");
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.error().message.find("objects[1].material: poisson = 0.5"), std::string::npos) << s.error().message;
  m.poisson = 0.3;
  m.density_kg_m3 = NAN;
  s = validateMaterial(m, "m");
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.error().message.find("density_kg_m3 = nan"), std::string::npos) << s.error().message;
}

TEST(Materials, MalformedTablesAreRefused) {
  EXPECT_FALSE(parseMaterialTable("{", "t.json").ok());
  EXPECT_FALSE(parseMaterialTable("{\"materials\": {}}", "t.json").ok());
  Result<MaterialTable> t = parseMaterialTable(
      "{\"materials\": {\"x\": {\"youngs_pa\": 1e9, \"poisson\": 0.3, \"density_kg_m3\": 1000, \"loss_factor\": 0.01, "
      "\"colour\": \"red\"}}}",
      "t.json");
  ASSERT_FALSE(t);
  EXPECT_NE(t.error().message.find("unknown key 'colour'"), std::string::npos) << t.error().message;
}

}  // namespace
}  // namespace strike
