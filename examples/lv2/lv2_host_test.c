/* SPDX-License-Identifier: MIT */
/* Loads the built strike.lv2 bundle with lilv (a real LV2 host library), instantiates it, sends
 * a note-on, runs it, and checks that the output peaks at the bundled bank's frequencies and
 * that a harder note is brighter (Hertz contact time). Usage: lv2_host_test (LV2_PATH set to
 * the directory holding strike.lv2). Exit 0 on success. */
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

/* Renders FRAMES samples after one note-on; returns 0 on failure. */
static int play(const LilvPlugin* plugin, LV2_URID_Map* map, uint8_t note, uint8_t velocity, float* left) {
  LV2_Feature map_feature = {LV2_URID__map, map};
  const LV2_Feature* features[] = {&map_feature, NULL};
  LilvInstance* inst = lilv_plugin_instantiate(plugin, 48000.0, features);
  NoteSequence seq;
  static float l[BLOCK], r[BLOCK];
  float gain = 0.0f;
  size_t n;
  if (!inst) return 0;
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
    memcpy(left + n, l, sizeof l);
    seq.seq.atom.size = sizeof(LV2_Atom_Sequence_Body); /* empty after the first block */
  }
  lilv_instance_deactivate(inst);
  lilv_instance_free(inst);
  return 1;
}

int main(void) {
  static const double freqs[4] = {440.0, 1000.0, 2500.0, 5200.0};
  static float soft[FRAMES], hard[FRAMES];
  LV2_URID_Map map = {NULL, map_uri};
  LilvWorld* world = lilv_world_new();
  LilvNode* uri;
  const LilvPlugin* plugin;
  int failures = 0, m;
  double ratio_soft, ratio_hard;
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
  if (!play(plugin, &map, 60, 20, soft) || !play(plugin, &map, 60, 127, hard)) {
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
  printf("5200/440 Hz level: velocity 20 %.1f dB, velocity 127 %.1f dB (harder is brighter)\n",
         20 * log10(ratio_soft), 20 * log10(ratio_hard));
  if (!(ratio_hard > ratio_soft * 1.05)) ++failures;
  if (!(dft(hard, FRAMES, 440, 48000) > dft(soft, FRAMES, 440, 48000))) ++failures;
  lilv_node_free(uri);
  lilv_world_free(world);
  if (failures) fprintf(stderr, "%d failure(s)\n", failures);
  return failures ? 1 : 0;
}
