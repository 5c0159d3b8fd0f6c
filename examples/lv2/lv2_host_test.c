/* SPDX-License-Identifier: MIT */
/* Loads the built strike.lv2 bundle with lilv (a real LV2 host library), instantiates it, sends
 * note-ons, runs it, and checks:
 *  - the output peaks at the bundled bank's frequencies;
 *  - a harder note is brighter (Hertz contact time);
 *  - the level: every note at velocity 127 stays under full scale and the loudest peaks at the
 *    plugin's stated -6 dBFS; a medium note (velocity 64) is well under 0 dBFS; the lowest mode's
 *    line grows with velocity as the impulse does (the plugin's velocity map: speed
 *    0.05 * 100^(velocity / 127) m/s, impulse 2 m* v); the gain port scales by its dB value.
 * Usage: lv2_host_test (LV2_PATH set to the directories holding strike.lv2, absolute or
 * relative to the working directory). Exit 0 on success. */
#define _XOPEN_SOURCE 700 /* realpath */
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <lilv/lilv.h>
#include <lv2/atom/atom.h>
#include <lv2/midi/midi.h>
#include <lv2/urid/urid.h>

#define URI "https://github.com/strike-synth/strike/lv2/instrument"
#define BLOCK 512
#define FRAMES 16384
#define PI 3.14159265358979323846
#define LOUDEST_NOTE_DBFS (-6.0) /* what strike_lv2.c promises for velocity 127 */

static char g_uris[64][256];
static uint32_t g_count = 0;

static LV2_URID map_uri(LV2_URID_Map_Handle handle, const char* uri) {
  uint32_t i;
  (void)handle;
  for (i = 0; i < g_count; ++i)
    if (strcmp(g_uris[i], uri) == 0) return i + 1;
  if (g_count == 64) return 0;
  snprintf(g_uris[g_count], sizeof g_uris[0], "%s", uri);
  return ++g_count;
}

static double dft(const float* x, size_t n, double f, double fs) {
  double re = 0, im = 0;
  size_t k;
  for (k = 0; k < n; ++k) {
    const double w = 0.5 - 0.5 * cos(2 * PI * (double)k / (double)(n - 1));
    re += w * x[k] * cos(2 * PI * f * (double)k / fs);
    im -= w * x[k] * sin(2 * PI * f * (double)k / fs);
  }
  return sqrt(re * re + im * im);
}

typedef struct {
  LV2_Atom_Sequence seq;
  LV2_Atom_Event ev;
  uint8_t msg[8];
} NoteSequence;

/* Renders FRAMES samples after one note-on at the given gain port value; writes the left
 * channel and returns the peak over both channels, or -1 on failure. */
static double play(const LilvPlugin* plugin, LV2_URID_Map* map, uint8_t note, uint8_t velocity, float gain_db,
                   float* left) {
  LV2_Feature map_feature = {LV2_URID__map, map};
  const LV2_Feature* features[] = {&map_feature, NULL};
  LilvInstance* inst = lilv_plugin_instantiate(plugin, 48000.0, features);
  NoteSequence seq;
  static float l[BLOCK], r[BLOCK];
  float gain = gain_db;
  double peak = 0;
  size_t n, k;
  if (!inst) return -1;
  memset(&seq, 0, sizeof seq);
  seq.seq.atom.type = map->map(map->handle, LV2_ATOM__Sequence);
  seq.seq.atom.size = (uint32_t)(sizeof(LV2_Atom_Sequence_Body) + sizeof(LV2_Atom_Event) + 8);
  seq.ev.time.frames = 0;
  seq.ev.body.type = map->map(map->handle, LV2_MIDI__MidiEvent);
  seq.ev.body.size = 3;
  seq.msg[0] = LV2_MIDI_MSG_NOTE_ON;
  seq.msg[1] = note;
  seq.msg[2] = velocity;
  lilv_instance_connect_port(inst, 0, &seq);
  lilv_instance_connect_port(inst, 1, l);
  lilv_instance_connect_port(inst, 2, r);
  lilv_instance_connect_port(inst, 3, &gain);
  lilv_instance_activate(inst);
  for (n = 0; n < FRAMES; n += BLOCK) {
    lilv_instance_run(inst, BLOCK);
    if (left) memcpy(left + n, l, sizeof l);
    for (k = 0; k < BLOCK; ++k) {
      if (fabs(l[k]) > peak) peak = fabs(l[k]);
      if (fabs(r[k]) > peak) peak = fabs(r[k]);
    }
    seq.seq.atom.size = sizeof(LV2_Atom_Sequence_Body); /* empty after the first block */
  }
  lilv_instance_deactivate(inst);
  lilv_instance_free(inst);
  return peak;
}

/* lilv 0.24 crashes in lilv_world_load_bundle on a relative LV2_PATH entry (it makes an invalid
 * file URI of it), so every entry is made absolute here and handed to lilv as an option. */
static int set_absolute_lv2_path(LilvWorld* world) {
  const char* env = getenv("LV2_PATH");
  char joined[8192] = "";
  char resolved[PATH_MAX];
  const char* p = env;
  if (!env || !*env) return 1; /* lilv's default search path */
  while (*p) {
    const char* end = strchr(p, ':');
    const size_t len = end ? (size_t)(end - p) : strlen(p);
    char entry[PATH_MAX];
    if (len > 0 && len < sizeof entry) {
      memcpy(entry, p, len);
      entry[len] = '\0';
      if (realpath(entry, resolved)) {
        if (joined[0]) strncat(joined, ":", sizeof joined - strlen(joined) - 1);
        strncat(joined, resolved, sizeof joined - strlen(joined) - 1);
      } else {
        fprintf(stderr, "LV2_PATH entry '%s' does not exist; skipped\n", entry);
      }
    }
    p += len;
    if (*p == ':') ++p;
  }
  if (!joined[0]) {
    fprintf(stderr, "LV2_PATH='%s' names no existing directory\n", env);
    return 0;
  }
  {
    LilvNode* path = lilv_new_string(world, joined);
    lilv_world_set_option(world, LILV_OPTION_LV2_PATH, path);
    lilv_node_free(path);
  }
  return 1;
}

int main(void) {
  static const double freqs[4] = {440.0, 1000.0, 2500.0, 5200.0};
  static const uint8_t velocities[3] = {1, 64, 127};
  static float soft[FRAMES], hard[FRAMES], medium[FRAMES];
  LV2_URID_Map map = {NULL, map_uri};
  LilvWorld* world = lilv_world_new();
  LilvNode* uri;
  const LilvPlugin* plugin;
  int failures = 0, m, v, note, loudest_note = 0, clipping_notes = 0;
  double ratio_soft, ratio_hard, peak[3], loudest = 0, attenuated, line_ratio, impulse_ratio;
  if (!set_absolute_lv2_path(world)) return 1;
  lilv_world_load_all(world);
  uri = lilv_new_uri(world, URI);
  plugin = lilv_plugins_get_by_uri(lilv_world_get_all_plugins(world), uri);
  if (!plugin) {
    fprintf(stderr, "lilv does not find %s (LV2_PATH=%s)\n", URI, getenv("LV2_PATH") ? getenv("LV2_PATH") : "");
    return 1;
  }
  if (!lilv_plugin_verify(plugin)) {
    fprintf(stderr, "lilv_plugin_verify failed\n");
    ++failures;
  }
  if (lilv_plugin_get_num_ports(plugin) != 4) ++failures;
  if (play(plugin, &map, 60, 20, 0.0f, soft) < 0 || play(plugin, &map, 60, 127, 0.0f, hard) < 0) {
    fprintf(stderr, "instantiation failed\n");
    return 1;
  }
  for (m = 0; m < 4; ++m) {
    double best = 0, best_f = 0, df;
    for (df = -20; df <= 20; df += 0.5) {
      const double a = dft(hard, FRAMES, freqs[m] + df, 48000.0);
      if (a > best) best = a, best_f = freqs[m] + df;
    }
    printf("mode %d: %.1f Hz expected, peak at %.1f Hz, %.1f dB over %.0f Hz\n", m, freqs[m], best_f,
           20 * log10(best / dft(hard, FRAMES, freqs[m] * 1.17, 48000.0)), freqs[m] * 1.17);
    if (fabs(best_f - freqs[m]) > 1.0 || best < 10 * dft(hard, FRAMES, freqs[m] * 1.17, 48000.0)) ++failures;
  }
  ratio_soft = dft(soft, FRAMES, 5200, 48000) / dft(soft, FRAMES, 440, 48000);
  ratio_hard = dft(hard, FRAMES, 5200, 48000) / dft(hard, FRAMES, 440, 48000);
  printf("5200/440 Hz level: velocity 20 %.1f dB, velocity 127 %.1f dB (harder is brighter)\n", 20 * log10(ratio_soft),
         20 * log10(ratio_hard));
  if (!(ratio_hard > ratio_soft * 1.05)) ++failures;
  if (!(dft(hard, FRAMES, 440, 48000) > dft(soft, FRAMES, 440, 48000))) ++failures;

  /* Level per velocity, note 60 (issue 15 item 1: it peaked at 2.7, 34 and 367). */
  for (v = 0; v < 3; ++v) {
    peak[v] = play(plugin, &map, 60, velocities[v], 0.0f, velocities[v] == 64 ? medium : NULL);
    printf("note 60 velocity %3d: peak %.4g (%+.1f dBFS)\n", velocities[v], peak[v], 20 * log10(peak[v]));
  }
  if (!(peak[0] < peak[1] && peak[1] < peak[2])) {
    fprintf(stderr, "FAIL: the level does not grow with velocity\n");
    ++failures;
  }
  if (!(peak[1] < pow(10.0, -12.0 / 20))) {
    fprintf(stderr, "FAIL: a medium note (velocity 64) peaks at %.1f dBFS, not well under 0 (<= -12)\n",
            20 * log10(peak[1]));
    ++failures;
  }
  /* The 440 Hz line is far below the contact pulse's corner (< 0.1 ms contacts), so its amplitude
   * follows the impulse 2 m* v: the ratio of the velocity map's speeds, 100^(63/127) = 9.83. */
  impulse_ratio = pow(100.0, (127.0 - 64.0) / 127.0);
  line_ratio = dft(hard, FRAMES, 440, 48000) / dft(medium, FRAMES, 440, 48000);
  printf("440 Hz line, velocity 127 / 64: %.3f (impulse ratio %.3f)\n", line_ratio, impulse_ratio);
  if (fabs(line_ratio / impulse_ratio - 1.0) > 0.03) {
    fprintf(stderr, "FAIL: the 440 Hz line does not follow the impulse (within 3%%)\n");
    ++failures;
  }
  /* Every note at velocity 127 under full scale; the loudest at the promised level. */
  for (note = 0; note < 128; ++note) {
    const double p = play(plugin, &map, (uint8_t)note, 127, 0.0f, NULL);
    if (p > loudest) loudest = p, loudest_note = note;
    if (!(p < 1.0)) ++clipping_notes;
  }
  if (clipping_notes) {
    fprintf(stderr, "FAIL: %d notes at velocity 127 reach full scale (the loudest, note %d, peaks at %.3g)\n",
            clipping_notes, loudest_note, loudest);
    ++failures;
  }
  printf("loudest note at velocity 127: %+.2f dBFS (promised %+.1f)\n", 20 * log10(loudest), LOUDEST_NOTE_DBFS);
  if (fabs(20 * log10(loudest) - LOUDEST_NOTE_DBFS) > 0.5) {
    fprintf(stderr, "FAIL: the loudest note is not at %.1f dBFS (within 0.5 dB)\n", LOUDEST_NOTE_DBFS);
    ++failures;
  }
  /* The gain port, in dB. */
  attenuated = play(plugin, &map, 60, 127, -20.0f, NULL);
  printf("gain port -20 dB: peak %.4g (%.2f dB re 0 dB)\n", attenuated, 20 * log10(attenuated / peak[2]));
  if (fabs(20 * log10(attenuated / peak[2]) + 20.0) > 0.01) {
    fprintf(stderr, "FAIL: the gain port at -20 dB does not give -20 dB\n");
    ++failures;
  }
  lilv_node_free(uri);
  lilv_world_free(world);
  if (failures) fprintf(stderr, "%d failure(s)\n", failures);
  return failures ? 1 : 0;
}
