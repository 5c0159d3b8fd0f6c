// SPDX-License-Identifier: MIT
// The C API's documented error codes (strike.h), one cause each, and that a failed call leaves
// its out-parameter untouched.
#include <cstring>
#include <string>
#include <vector>

#include "check.hpp"
#include "struck_bank.hpp"

namespace {

using strike::runtime_test::bankBytes;

void contextCreation() {
  strike_context context = nullptr;
  CHECK_STATUS(strike_context_create(nullptr, &context), STRIKE_ERR_INVALID_ARG);
  strike_context_config config = strike_context_config_default();
  CHECK_STATUS(strike_context_create(&config, nullptr), STRIKE_ERR_INVALID_ARG);

  strike_context_config zeroed;
  std::memset(&zeroed, 0, sizeof zeroed);  // not from strike_context_config_default()
  CHECK_STATUS(strike_context_create(&zeroed, &context), STRIKE_ERR_NOT_INITIALIZED);

  config = strike_context_config_default();
  config.api_version += 1u << 16;  // a header of the next major version
  CHECK_STATUS(strike_context_create(&config, &context), STRIKE_ERR_VERSION);

  const auto rejects = [](void (*change)(strike_context_config&)) {
    strike_context_config c = strike_context_config_default();
    change(c);
    strike_context out = nullptr;
    const strike_status status = strike_context_create(&c, &out);
    if (out) strike_context_destroy(out);
    return status;
  };
  CHECK_STATUS(rejects([](strike_context_config& c) { c.sample_rate_hz = 7999.0; }), STRIKE_ERR_INVALID_ARG);
  CHECK_STATUS(rejects([](strike_context_config& c) { c.channels = 3; }), STRIKE_ERR_INVALID_ARG);
  CHECK_STATUS(rejects([](strike_context_config& c) { c.max_block_frames = 0; }), STRIKE_ERR_INVALID_ARG);
  CHECK_STATUS(rejects([](strike_context_config& c) { c.reference_distance_m = -1.0; }), STRIKE_ERR_INVALID_ARG);
  CHECK(context == nullptr);  // untouched by every failure
}

void bankLoading(strike_context context) {
  const std::vector<uint8_t> good = bankBytes({440.0}, 1e-9, 4.0);
  strike_bank bank = nullptr;
  CHECK_STATUS(strike_bank_load_memory(context, good.data(), good.size() / 2, &bank), STRIKE_ERR_PARSE);  // truncated
  const std::string foreign = "this is not a mode bank, just text of some length......";
  CHECK_STATUS(strike_bank_load_memory(context, foreign.data(), foreign.size(), &bank), STRIKE_ERR_PARSE);
  CHECK(std::strlen(strike_context_last_error(context)) > 0);  // the message says why
  std::vector<uint8_t> corrupt = good;
  corrupt[corrupt.size() - 1] ^= 0x55;  // one flipped byte fails a checksum
  CHECK_STATUS(strike_bank_load_memory(context, corrupt.data(), corrupt.size(), &bank), STRIKE_ERR_PARSE);
  std::vector<uint8_t> newer = good;
  newer[8] = 0xff;  // the format version (little-endian uint32 after the 8-byte magic)
  CHECK_STATUS(strike_bank_load_memory(context, newer.data(), newer.size(), &bank), STRIKE_ERR_VERSION);
  CHECK_STATUS(strike_bank_load_file(context, "/nonexistent/dir/x.modes", &bank), STRIKE_ERR_IO);
  CHECK_STATUS(strike_bank_load_memory(context, nullptr, 10, &bank), STRIKE_ERR_INVALID_ARG);
  CHECK_STATUS(strike_bank_load_memory(nullptr, good.data(), good.size(), &bank), STRIKE_ERR_INVALID_ARG);
  CHECK(bank == nullptr);
  CHECK_OK(strike_bank_load_memory(context, good.data(), good.size(), &bank));
  double f_hz = 0.0;
  CHECK_STATUS(strike_bank_mode_frequency(bank, 1, &f_hz), STRIKE_ERR_INVALID_ARG);  // one mode only
  strike_bank_destroy(bank);
}

void objectsImpactsAndRendering(strike_context context) {
  const std::vector<uint8_t> bytes = bankBytes({440.0}, 1e-9, 4.0);
  strike_bank bank = nullptr;
  CHECK_OK(strike_bank_load_memory(context, bytes.data(), bytes.size(), &bank));
  strike_object_config config = strike_object_config_default();
  CHECK_STATUS(strike_object_add(context, &config, nullptr), STRIKE_ERR_INVALID_ARG);
  strike_object_id object{}, second{};
  CHECK_STATUS(strike_object_add(context, &config, &object), STRIKE_ERR_INVALID_ARG);  // no bank
  config.bank = bank;
  CHECK_OK(strike_object_add(context, &config, &object));
  CHECK_STATUS(strike_object_add(context, &config, &second), STRIKE_ERR_CAPACITY);  // max_objects = 1

  strike_impact_desc hit = strike_impact_desc_default();
  hit.object = object;
  hit.surface_vertex = 4;
  hit.impulse[2] = 1e-2;
  hit.normal_speed_m_s = 1.0;
  strike_impact_desc bad = hit;
  bad.impulse[0] = std::nan("");
  CHECK_STATUS(strike_impact(context, &bad), STRIKE_ERR_INVALID_ARG);
  // The queue holds impact_queue_capacity (4) impacts; the fifth is dropped and counted.
  for (int i = 0; i < 4; ++i) CHECK_OK(strike_impact(context, &hit));
  CHECK_STATUS(strike_impact(context, &hit), STRIKE_ERR_QUEUE_FULL);
  strike_stats stats{};
  CHECK_STATUS(strike_context_get_stats(context, &stats), STRIKE_ERR_INVALID_ARG);  // struct_size not set
  stats.struct_size = sizeof stats;
  CHECK_OK(strike_context_get_stats(context, &stats));
  CHECK(stats.impacts_dropped_queue_full == 1);

  std::vector<float> left(64), right(64);
  float* mono[1] = {left.data()};
  float* stereo[2] = {left.data(), right.data()};
  CHECK_STATUS(strike_render(context, mono, 1, 65), STRIKE_ERR_TOO_MANY_FRAMES);  // max_block_frames = 64
  CHECK_STATUS(strike_render(context, stereo, 2, 64), STRIKE_ERR_INVALID_ARG);    // a mono context
  CHECK_STATUS(strike_render(context, nullptr, 1, 64), STRIKE_ERR_INVALID_ARG);
  CHECK_OK(strike_render(context, mono, 1, 64));

  CHECK_OK(strike_object_remove(context, object));
  CHECK_STATUS(strike_impact(context, &hit), STRIKE_ERR_STALE_ID);
  strike_object_id never{};  // generation 0: never valid
  CHECK_STATUS(strike_object_remove(context, never), STRIKE_ERR_STALE_ID);
  strike_bank_destroy(bank);
}

void statusStrings() {
  for (strike_status s = STRIKE_ERR_INTERNAL; s <= STRIKE_OK; ++s) {
    const char* text = strike_status_string(s);
    CHECK(text != nullptr && std::strlen(text) > 0);
  }
  CHECK(std::strcmp(strike_status_string(STRIKE_OK), "ok") == 0);
}

}  // namespace

int main() {
  contextCreation();
  strike_context_config config = strike_context_config_default();
  config.channels = 1;
  config.max_block_frames = 64;
  config.max_objects = 1;
  config.impact_queue_capacity = 4;
  strike_context context = nullptr;
  CHECK_OK(strike_context_create(&config, &context));
  if (!context) return strike::check::checkExitCode("errors_test");
  bankLoading(context);
  objectsImpactsAndRendering(context);
  strike_context_destroy(context);
  statusStrings();
  return strike::check::checkExitCode("errors_test");
}
