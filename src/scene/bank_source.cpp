// SPDX-License-Identifier: MIT
// The bank source (bank_source.hpp): given banks, reading a bank file's shapes where its body was
// struck, and the strategy chosen for banks solved from meshes.
#include "bank_source.hpp"

#include <algorithm>
#include <cstdio>
#include <ctime>
#include <filesystem>

#include "bank_strategy.hpp"
#include "strike/cache/bank_cache.hpp"
#include "strike/core/atomic_file.hpp"
#include "strike/scene/render_session.hpp"

namespace strike {
namespace {

Result<uint64_t> meshHash(const std::string& spec) {
  if (isPrimitiveSpec(spec)) return fnv1a64(spec.data(), spec.size());
  Result<std::string> bytes = readWholeFile(spec, uint64_t(1) << 31);
  if (!bytes) return bytes.error();
  return fnv1a64(bytes->data(), bytes->size());
}

/// A bank given in the scene: opened now, its shapes read in phase 3.
Status openGivenBank(Body& body, RenderReport& report) {
  Result<BankFile> file = BankFile::open(body.object->bank);
  if (!file) return file.error();
  body.bank = file->sharedBank();
  body.file = std::move(*file);
  body.has_modes = true;
  ++report.banks_given;
  return {};
}

}  // namespace

std::string cachePath(const std::string& cache_dir, uint64_t key, const char* extension) {
  char hex[17];
  std::snprintf(hex, sizeof hex, "%016llx", static_cast<unsigned long long>(key));
  return cache_dir + "/" + hex + extension;
}

std::optional<BankFile> openCachedBank(const std::string& cache_dir, uint64_t key, uint64_t mesh_hash) {
  const std::string path = cachePath(cache_dir, key, ".modes");
  if (!std::filesystem::is_regular_file(path)) return std::nullopt;
  Result<BankFile> cached = BankFile::open(path);
  if (!cached || cached->bank().mesh_hash != mesh_hash) return std::nullopt;
  touchCacheEntry(path);
  return std::move(*cached);
}

double solveSeconds(const ModeBank& bank) {
  return std::max(bank.total_seconds, bank.factorize_seconds + bank.lanczos_seconds + bank.transfer_seconds);
}

// A bank opened from a file keeps its shapes there until the simulation has said where the body
// was struck: read them only at the vertices of those points' nearest triangles (the projector's
// locator finds the same vertices again when it projects). A render of 20 plates reads ~2% of
// their 340 MB of shapes this way.
Status readStruckShapes(BankContext& context, size_t index) {
  Body& body = context.bodies[index];
  RenderReport& report = context.report;
  RenderSession* session = context.settings.session;
  body.rows.reset();
  body.locator.reset();
  body.located_bank.reset();
  const ModeBank& bank = *body.bank;
  const bool has_radiation = bank.radiation_m2.size() == bank.modeCount();
  // With a session, the locator of this file's content built by an earlier render (and the bank
  // object it points into, that render's file's): the same grid, so the same vertices and bytes.
  RenderSession::BankSurface surface;
  if (session) surface = session->bankSurface(*body.file);
  std::shared_ptr<const SurfaceLocator> shared_locator =
      session ? surface.locator : std::make_shared<const SurfaceLocator>(bank);
  const SurfaceLocator& locator = *shared_locator;
  // A library that loads whole bank files (an output other than the engine, --via-library).
  const bool whole = bool(context.settings.output);
  if (!has_radiation || !locator.hasTriangles() || whole) {
    // Radiation strengths computed from every shape (banks written before the RADI chunk), no
    // triangles to locate on, or a library that loads whole bank files: the whole bank.
    Result<ModeBank> all = body.file->readAll();
    if (!all) return all.error();
    body.bank = std::make_shared<const ModeBank>(std::move(*all));
    body.file.reset();
    report.shape_vertices_read += body.bank->surfaceVertexCount();
    report.shape_vertices_total += body.bank->surfaceVertexCount();
    return {};
  }
  // The points where the body was struck; a bank with no mode in the band (a marble) needs no
  // shape anywhere, so none.
  std::vector<std::array<double, 3>> points;
  if (bank.modeCount() > 0)
    for (const ContactEvent& event : *context.events) {
      if (event.body_a == index) points.push_back(event.point_a_mesh);
      if (event.body_b == index) points.push_back(event.point_b_mesh);
    }
  std::sort(points.begin(), points.end());
  points.erase(std::unique(points.begin(), points.end()), points.end());
  std::vector<uint32_t> vertices;
  for (const std::array<double, 3>& point : points) {
    std::array<uint32_t, 3> nearest_vertices;
    std::array<double, 3> weights;
    locator.nearest(point.data(), nearest_vertices.data(), weights.data());
    vertices.insert(vertices.end(), nearest_vertices.begin(), nearest_vertices.end());
  }
  Result<ShapeRows> rows = body.file->readShapeRows(std::move(vertices));
  if (!rows) return rows.error();
  report.shape_vertices_read += rows->vertices.size();
  report.shape_vertices_total += bank.surfaceVertexCount();
  body.rows = std::move(*rows);
  body.locator = std::move(shared_locator);  // the voice projects with it (the same bank object)
  body.located_bank = std::move(surface.bank);
  return {};
}

BankSource::BankSource(const RenderSettings& settings, std::vector<Body>& bodies, RenderReport& report,
                       std::function<void(std::string)> warn)
    : context_{settings, bodies, report, std::move(warn)},
      strategy_(settings.similar_reuse ? makeSimilarBanks(context_) : makeDirectBanks(context_)) {}

BankSource::~BankSource() = default;

Status BankSource::prepare() {
  for (size_t i = 0; i < context_.bodies.size(); ++i) {
    Body& body = context_.bodies[i];
    if (!body.object->bank.empty()) {
      if (Status opened = openGivenBank(body, context_.report); !opened) return opened;
      continue;
    }
    Result<uint64_t> hash = meshHash(body.object->mesh);
    if (!hash) return hash.error();
    if (Status prepared = strategy_->prepare(i, *hash); !prepared) return prepared;
  }
  if (!context_.settings.cache_dir.empty()) {
    std::error_code ignored;
    std::filesystem::create_directories(context_.settings.cache_dir, ignored);
  }
  return {};
}

Status BankSource::provide(const std::vector<ContactEvent>& events) {
  context_.events = &events;
  for (size_t i = 0; i < context_.bodies.size(); ++i) {
    const Body& body = context_.bodies[i];
    if (!body.sounded) continue;
    // A bank given in the scene is used as it is; its file damaged is the user's to know.
    Status provided = body.object->bank.empty() ? strategy_->provide(i) : readStruckShapes(context_, i);
    if (!provided) return provided;
  }
  return strategy_->finish();
}

void BankSource::pruneCache() {
  const RenderSettings& settings = context_.settings;
  if (settings.cache_dir.empty() || settings.cache_max_bytes == 0) return;
  Result<PruneReport> pruned =
      strike::pruneCache(settings.cache_dir, settings.cache_max_bytes, -1.0, std::time(nullptr));
  if (pruned)
    context_.report.cache_pruned = pruned->removed, context_.report.cache_pruned_bytes = pruned->bytes_removed;
}

}  // namespace strike
