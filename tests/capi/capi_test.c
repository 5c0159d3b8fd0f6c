/* SPDX-License-Identifier: MIT */
/* Drives the whole C API as a plain C program (built as C99 and, through capi_test_cpp.cpp, as
 * C++17): create, load a bank from a file and from memory, add an object, strike it, render
 * stereo blocks, check that the spectrum peaks at the bank's frequencies, remove, destroy.
 * Usage: capi_test BANK.modes (written by strike_make_test_bank). Exit 0 on success. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "strike/strike.h"

#define CAPI_PI 3.14159265358979323846
#define FRAMES 16384
#define BLOCK 512

static int g_failures = 0;

#define CHECK(cond)                                                            \
  do {                                                                         \
    if (!(cond)) {                                                             \
      fprintf(stderr, "%s:%d: check failed: %s\n", __FILE__, __LINE__, #cond); \
      ++g_failures;                                                            \
    }                                                                          \
  } while (0)

#define CHECK_OK(expr)                                                                                               \
  do {                                                                                                               \
    strike_status s_ = (expr);                                                                                       \
    if (s_ != STRIKE_OK) {                                                                                           \
      fprintf(stderr, "%s:%d: %s returned %d (%s)\n", __FILE__, __LINE__, #expr, (int)s_, strike_status_string(s_)); \
      ++g_failures;                                                                                                  \
    }                                                                                                                \
  } while (0)

/* |DFT| of a Hann-windowed signal at frequency f (Hz): a plain Goertzel-free sum, O(n). */
static double dft_magnitude(const float* x, size_t n, double f, double fs) {
  double re = 0.0, im = 0.0;
  size_t k;
  for (k = 0; k < n; ++k) {
    const double w = 0.5 - 0.5 * cos(2.0 * CAPI_PI * (double)k / (double)(n - 1));
    const double ph = 2.0 * CAPI_PI * f * (double)k / fs;
    re += w * x[k] * cos(ph);
    im -= w * x[k] * sin(ph);
  }
  return sqrt(re * re + im * im);
}

static unsigned char* read_file(const char* path, size_t* size) {
  FILE* f = fopen(path, "rb");
  unsigned char* data;
  long n;
  if (!f) return NULL;
  fseek(f, 0, SEEK_END);
  n = ftell(f);
  fseek(f, 0, SEEK_SET);
  data = (unsigned char*)malloc((size_t)n);
  if (data && fread(data, 1, (size_t)n, f) != (size_t)n) {
    free(data);
    data = NULL;
  }
  fclose(f);
  *size = (size_t)n;
  return data;
}

static void STRIKE_CALL log_to_stderr(void* user, int32_t level, const char* message) {
  int* count = (int*)user;
  ++*count;
  (void)level;
  (void)message;
}

int main(int argc, char** argv) {
  strike_context_config cfg;
  strike_context ctx = NULL;
  strike_bank bank = NULL, bank_mem = NULL;
  strike_bank_info info, info_mem;
  strike_object_config ocfg;
  strike_object_id obj;
  strike_impact_desc hit;
  strike_stats stats;
  float* left;
  float* right;
  float* out[2];
  unsigned char* bytes;
  size_t size = 0, n;
  uint32_t m;
  int log_count = 0;
  const double fs = 48000.0;

  if (argc != 2) {
    fprintf(stderr, "usage: %s BANK.modes\n", argv[0]);
    return 2;
  }
  CHECK(strike_get_version() == STRIKE_VERSION);
  CHECK(STRIKE_VERSION_GE(0, 1, 0));
  CHECK(strcmp(strike_status_string(STRIKE_OK), "ok") == 0);

  cfg = strike_context_config_default();
  cfg.sample_rate_hz = fs;
  cfg.max_block_frames = BLOCK;
  cfg.channels = 2;
  cfg.log = log_to_stderr;
  cfg.user = &log_count;
  CHECK_OK(strike_context_create(&cfg, &ctx));
  if (!ctx) return 1;

  CHECK_OK(strike_bank_load_file(ctx, argv[1], &bank));
  bytes = read_file(argv[1], &size);
  CHECK(bytes != NULL);
  CHECK_OK(strike_bank_load_memory(ctx, bytes, size, &bank_mem));
  CHECK(strike_bank_load_memory(ctx, bytes, size / 2, &bank_mem) == STRIKE_ERR_PARSE); /* truncated */
  CHECK(strlen(strike_context_last_error(ctx)) > 0);
  CHECK(log_count == 1);
  free(bytes);
  CHECK(strike_bank_load_file(ctx, "/nonexistent/x.modes", &bank_mem) == STRIKE_ERR_IO);
  /* Output structs carry their size (0.3): set it before the call. */
  memset(&info, 0, sizeof info);
  info.struct_size = sizeof info;
  info_mem = info;
  CHECK_OK(strike_bank_get_info(bank, &info));
  CHECK_OK(strike_bank_get_info(bank_mem, &info_mem));
  CHECK(info.struct_size == sizeof info);
  CHECK(info.mode_count == 4 && info_mem.mode_count == 4);
  CHECK(info.surface_vertex_count == 9);
  strike_bank_destroy(bank_mem);

  ocfg = strike_object_config_default();
  ocfg.bank = bank;
  ocfg.position[1] = 1.0; /* 1 m in front of the listener: centred */
  ocfg.radiation = STRIKE_RADIATION_UNIT;
  ocfg.gain = 1e-3f;
  CHECK_OK(strike_object_add(ctx, &ocfg, &obj));
  CHECK(strike_object_is_valid(ctx, obj) == 1);

  hit = strike_impact_desc_default();
  hit.object = obj;
  hit.surface_vertex = 4;
  hit.impulse[2] = 1e-2; /* N s */
  hit.normal_speed_m_s = 2.0;
  CHECK_OK(strike_impact(ctx, &hit));

  left = (float*)calloc(FRAMES, sizeof(float));
  right = (float*)calloc(FRAMES, sizeof(float));
  if (!left || !right) return 1;
  for (n = 0; n < FRAMES; n += BLOCK) {
    out[0] = left + n;
    out[1] = right + n;
    CHECK_OK(strike_render(ctx, out, 2, BLOCK));
  }
  memset(&stats, 0, sizeof stats);
  stats.struct_size = sizeof stats;
  CHECK_OK(strike_context_get_stats(ctx, &stats));
  CHECK(stats.impacts_queued == 1 && stats.impacts_scheduled == 1);
  CHECK(stats.frames_rendered == FRAMES);
  CHECK(fabs(left[1000]) > 0.0f);
  CHECK(fabs(left[1000] - right[1000]) <= 1e-6f * fabs(left[1000])); /* centred */

  /* The spectrum peaks at each mode (within 1.5 Hz, bin spacing 2.9 Hz) and stands 20 dB above
   * points between modes. */
  for (m = 0; m < info.mode_count; ++m) {
    double f0 = 0.0, best_f = 0.0, best = 0.0, df, floor_level;
    CHECK_OK(strike_bank_mode_frequency(bank, m, &f0));
    for (df = -20.0; df <= 20.0; df += 0.25) {
      const double a = dft_magnitude(left, FRAMES, f0 + df, fs);
      if (a > best) best = a, best_f = f0 + df;
    }
    floor_level = dft_magnitude(left, FRAMES, f0 * 1.17, fs);
    printf("mode %u: bank %.2f Hz, peak %.2f Hz, %.1f dB above %.0f Hz\n", (unsigned)m, f0, best_f,
           20.0 * log10(best / floor_level), f0 * 1.17);
    CHECK(fabs(best_f - f0) <= 1.5);
    CHECK(best > 10.0 * floor_level);
  }

  /* A physics step (0.3) from C: one contact approaching at 2 m/s is an impact. */
  {
    strike_contact contact = strike_contact_default();
    strike_step_desc step = strike_step_desc_default();
    strike_stats after;
    contact.object = obj;
    contact.impulse[2] = 1e-2;
    contact.normal_speed_m_s = 2.0;
    step.end_time_s = (double)FRAMES / fs;
    step.duration_s = 1.0 / 60.0;
    step.contacts = &contact;
    step.contact_count = 1;
    CHECK_OK(strike_step(ctx, &step));
    out[0] = left;
    out[1] = right;
    CHECK_OK(strike_render(ctx, out, 2, BLOCK));
    memset(&after, 0, sizeof after);
    after.struct_size = sizeof after;
    CHECK_OK(strike_context_get_stats(ctx, &after));
    CHECK(after.steps == 1 && after.contacts_queued == 1);
    CHECK(after.impacts_scheduled == stats.impacts_scheduled + 1);
    step.struct_size = 4; /* from no known version */
    CHECK(strike_step(ctx, &step) == STRIKE_ERR_INVALID_ARG);
  }

  /* Bad use gets status codes. */
  CHECK(strike_render(ctx, out, 2, BLOCK + 1) == STRIKE_ERR_TOO_MANY_FRAMES);
  CHECK(strike_render(ctx, out, 1, BLOCK) == STRIKE_ERR_INVALID_ARG);
  CHECK(strike_render(NULL, out, 2, BLOCK) == STRIKE_ERR_INVALID_ARG);
  CHECK(strike_impact(NULL, &hit) == STRIKE_ERR_INVALID_ARG);

  CHECK_OK(strike_object_remove(ctx, obj));
  CHECK(strike_object_is_valid(ctx, obj) == 0);
  CHECK(strike_impact(ctx, &hit) == STRIKE_ERR_STALE_ID);
  CHECK(strike_object_remove(ctx, obj) == STRIKE_ERR_STALE_ID);
  out[0] = left;
  out[1] = right;
  CHECK_OK(strike_render(ctx, out, 2, BLOCK));
  CHECK(left[BLOCK - 1] == 0.0f);
  CHECK_OK(strike_context_collect(ctx));

  strike_bank_destroy(bank);
  strike_context_destroy(ctx);
  strike_context_destroy(NULL);
  free(left);
  free(right);
  if (g_failures) {
    fprintf(stderr, "%d check(s) failed\n", g_failures);
    return 1;
  }
  printf("capi_test: all checks passed\n");
  return 0;
}
