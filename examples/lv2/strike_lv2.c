/* SPDX-License-Identifier: MIT */
/* Strike as an LV2 instrument: MIDI in, stereo out, one sounding object from a mode bank.
 *
 *  - The bank is strike.modes in the bundle (replace it with any `strike modes` output).
 *  - Note number picks the strike point: surface vertex (note * 37) mod V, a fixed scatter
 *    over the surface so neighbouring keys hit different places (nodes and antinodes differ).
 *  - Velocity picks the impact speed v = 0.05 * 100^(velocity / 127) m/s (0.05 .. 5 m/s) of the
 *    library's default striker (strike_impact_desc_default(): a steel ball 5 mm in radius, as
 *    `strike hit`); it rebounds elastically, so the impulse is 2 m* v along the inward normal
 *    (m* the reduced mass), and the Hertz contact time falls as v^(-1/5): harder notes are
 *    louder AND brighter.
 *  - Level: the object is normalised when the plugin is instantiated, so that the loudest note
 *    at velocity 127 peaks at -6 dBFS (two such notes struck together cannot clip) whatever the
 *    bank: every note is struck once at velocity 127 in a private probe context and the peak of
 *    its first PROBE_SECONDS is measured. Velocity then spans 40 dB of impulse (a medium note,
 *    velocity 64, is about 20 dB below velocity 127) and the brightness of the Hertz contact.
 *    Without it the physical level of a 5 m/s steel ball 1 m away varies by orders of magnitude
 *    from one object to another (the hand-made plate of the tests peaked at +51 dBFS).
 *  - Control port "gain" (dB, default 0) on top of that.
 * Everything is allocated in instantiate(); run() only queues impacts and calls strike_render(),
 * which never allocates. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <lv2/atom/atom.h>
#include <lv2/atom/util.h>
#include <lv2/core/lv2.h>
#include <lv2/midi/midi.h>
#include <lv2/urid/urid.h>

#include "strike/strike.h"

#define STRIKE_LV2_URI "https://github.com/strike-synth/strike/lv2/instrument"
#define STRIKE_LV2_MAX_BLOCK 4096u
#define STRIKE_LV2_LOUDEST_NOTE_PEAK 0.5 /* -6 dBFS: the loudest note at velocity 127 */
#define STRIKE_LV2_NOTES 128
/* How long each probe note is rendered, s: at least 4 periods of the lowest mode (the peak of a
 * struck object comes within its first few periods), within these bounds. */
#define STRIKE_LV2_PROBE_MIN_S 0.02
#define STRIKE_LV2_PROBE_MAX_S 0.25
#define STRIKE_LV2_SPEED_OF_SOUND_M_S 343.0 /* libstrike's listener model (dry air, 20 C) */

enum { PORT_MIDI_IN = 0, PORT_OUT_L = 1, PORT_OUT_R = 2, PORT_GAIN = 3 };

typedef struct {
  const LV2_Atom_Sequence* midi_in;
  float* out[2];
  const float* gain_db;
  float last_gain_db;
  LV2_URID midi_event;
  strike_context ctx;
  strike_bank bank;
  strike_object_id object;
  uint32_t vertices;
  double mass_kg; /* the object's, for the striker's impulse */
} StrikeLv2;

static double loudest_note_peak(const strike_context_config* cfg, const char* bank_path,
                                const strike_object_config* ocfg_in);

static LV2_Handle instantiate(const LV2_Descriptor* descriptor, double rate, const char* bundle_path,
                              const LV2_Feature* const* features) {
  const LV2_URID_Map* map = NULL;
  StrikeLv2* self;
  strike_context_config cfg;
  strike_object_config ocfg;
  strike_bank_info info;
  char path[4096];
  double loudest;
  int i;
  (void)descriptor;
  if (!bundle_path) {
    fprintf(stderr, "strike.lv2: the host gave no bundle path\n");
    return NULL;
  }
  for (i = 0; features && features[i]; ++i)
    if (strcmp(features[i]->URI, LV2_URID__map) == 0) map = (const LV2_URID_Map*)features[i]->data;
  if (!map) {
    fprintf(stderr, "strike.lv2: host does not provide urid:map\n");
    return NULL;
  }
  self = (StrikeLv2*)calloc(1, sizeof(StrikeLv2));
  if (!self) return NULL;
  self->midi_event = map->map(map->handle, LV2_MIDI__MidiEvent);
  self->last_gain_db = 0.0f;

  cfg = strike_context_config_default();
  cfg.sample_rate_hz = rate;
  cfg.max_block_frames = STRIKE_LV2_MAX_BLOCK;
  cfg.channels = 2;
  cfg.max_objects = 1;
  cfg.max_pending_impacts_per_object = 128;
  if (strike_context_create(&cfg, &self->ctx) != STRIKE_OK) {
    free(self);
    return NULL;
  }
  snprintf(path, sizeof path, "%s%sstrike.modes", bundle_path,
           (bundle_path[0] && bundle_path[strlen(bundle_path) - 1] == '/') ? "" : "/");
  if (strike_bank_load_file(self->ctx, path, &self->bank) != STRIKE_OK) {
    fprintf(stderr, "strike.lv2: %s\n", strike_context_last_error(self->ctx));
    strike_context_destroy(self->ctx);
    free(self);
    return NULL;
  }
  memset(&info, 0, sizeof info);
  info.struct_size = sizeof info; /* libstrike 0.3: writes no more than this */
  if (strike_bank_get_info(self->bank, &info) != STRIKE_OK) info.surface_vertex_count = 0;
  self->vertices = info.surface_vertex_count;
  self->mass_kg = info.mass_kg;
  ocfg = strike_object_config_default();
  ocfg.bank = self->bank;
  ocfg.position[1] = 1.0; /* 1 m in front of the listener */
  loudest = self->vertices > 0 ? loudest_note_peak(&cfg, path, &ocfg) : 0.0;
  if (!(loudest > 0.0)) {
    fprintf(stderr, "strike.lv2: %s: no note of this bank makes a sound\n", path);
    strike_bank_destroy(self->bank);
    strike_context_destroy(self->ctx);
    free(self);
    return NULL;
  }
  ocfg.gain = (float)(STRIKE_LV2_LOUDEST_NOTE_PEAK / loudest);
  if (strike_object_add(self->ctx, &ocfg, &self->object) != STRIKE_OK) {
    fprintf(stderr, "strike.lv2: %s\n", strike_context_last_error(self->ctx));
    strike_bank_destroy(self->bank);
    strike_context_destroy(self->ctx);
    free(self);
    return NULL;
  }
  return (LV2_Handle)self;
}

static void connect_port(LV2_Handle instance, uint32_t port, void* data) {
  StrikeLv2* self = (StrikeLv2*)instance;
  switch (port) {
    case PORT_MIDI_IN: self->midi_in = (const LV2_Atom_Sequence*)data; break;
    case PORT_OUT_L: self->out[0] = (float*)data; break;
    case PORT_OUT_R: self->out[1] = (float*)data; break;
    case PORT_GAIN: self->gain_db = (const float*)data; break;
    default: break;
  }
}

/* The impact of one note: the note picks the vertex, the velocity the speed of the ball. */
static strike_impact_desc note_impact(strike_bank bank, uint32_t vertices, double mass_kg, strike_object_id object,
                                      uint8_t note, uint8_t velocity, uint32_t frame) {
  strike_impact_desc hit = strike_impact_desc_default();
  double normal[3] = {0, 0, 1};
  const double speed = 0.05 * pow(100.0, (double)velocity / 127.0);
  const double striker_kg = hit.striker_mass_kg;
  const double impulse = 2.0 * striker_kg * mass_kg / (striker_kg + mass_kg) * speed;
  hit.object = object;
  hit.surface_vertex = (int32_t)(((uint32_t)note * 37u) % vertices);
  strike_bank_surface_vertex(bank, (uint32_t)hit.surface_vertex, NULL, normal);
  hit.impulse[0] = -impulse * normal[0]; /* into the surface */
  hit.impulse[1] = -impulse * normal[1];
  hit.impulse[2] = -impulse * normal[2];
  hit.normal_speed_m_s = speed;
  hit.sample_offset = frame;
  return hit;
}

static void note_on(StrikeLv2* self, uint8_t note, uint8_t velocity, uint32_t frame) {
  const strike_impact_desc hit =
      note_impact(self->bank, self->vertices, self->mass_kg, self->object, note, velocity, frame);
  (void)strike_impact(self->ctx, &hit); /* a full queue drops the note; counted in stats */
}

/* Peak output (either channel) of the loudest note at velocity 127, at object gain 1: each note
 * is struck alone on a fresh object in a probe context like the plugin's and rendered for
 * PROBE seconds. Main thread (instantiate) only: it allocates. Returns 0 on failure. */
static double loudest_note_peak(const strike_context_config* cfg, const char* bank_path,
                                const strike_object_config* ocfg_in) {
  strike_context probe;
  strike_bank bank;
  strike_bank_info info;
  strike_object_config ocfg = *ocfg_in;
  double peak = 0.0, probe_s;
  uint32_t frames, note, vertices;
  float* buffers;
  if (strike_context_create(cfg, &probe) != STRIKE_OK) return 0.0;
  if (strike_bank_load_file(probe, bank_path, &bank) != STRIKE_OK) {
    strike_context_destroy(probe);
    return 0.0;
  }
  memset(&info, 0, sizeof info);
  info.struct_size = sizeof info;
  if (strike_bank_get_info(bank, &info) != STRIKE_OK) info.surface_vertex_count = 0;
  vertices = info.surface_vertex_count;
  probe_s = info.lowest_frequency_hz > 0 ? 4.0 / info.lowest_frequency_hz : STRIKE_LV2_PROBE_MAX_S;
  probe_s = probe_s < STRIKE_LV2_PROBE_MIN_S   ? STRIKE_LV2_PROBE_MIN_S
            : probe_s > STRIKE_LV2_PROBE_MAX_S ? STRIKE_LV2_PROBE_MAX_S
                                               : probe_s;
  /* Each note is heard distance / 343 m/s after it is struck (libstrike 0.3): add the delay of
   * the surface point farthest from the listener (at the origin), a corner of the bounds. */
  {
    double farthest = 0.0;
    int corner, k;
    for (corner = 0; corner < 8; ++corner) {
      double d2 = 0.0;
      for (k = 0; k < 3; ++k) {
        const double x = ocfg.position[k] + ((corner >> k) & 1 ? info.bounds_max_m[k] : info.bounds_min_m[k]);
        d2 += x * x;
      }
      if (d2 > farthest * farthest) farthest = sqrt(d2);
    }
    probe_s += farthest / STRIKE_LV2_SPEED_OF_SOUND_M_S;
  }
  frames = (uint32_t)ceil(probe_s * cfg->sample_rate_hz);
  buffers = (float*)malloc(2u * STRIKE_LV2_MAX_BLOCK * sizeof(float));
  ocfg.bank = bank;
  ocfg.gain = 1.0f;
  /* Notes that share a vertex sound alike: (note * 37) mod V repeats after V notes. */
  for (note = 0; buffers && vertices > 0 && note < STRIKE_LV2_NOTES && note < vertices; ++note) {
    strike_object_id id;
    strike_impact_desc hit;
    uint32_t done = 0, k;
    if (strike_object_add(probe, &ocfg, &id) != STRIKE_OK) break;
    hit = note_impact(bank, vertices, info.mass_kg, id, (uint8_t)note, 127, 0);
    (void)strike_impact(probe, &hit);
    while (done < frames) {
      float* out[2];
      const uint32_t n = frames - done < STRIKE_LV2_MAX_BLOCK ? frames - done : STRIKE_LV2_MAX_BLOCK;
      out[0] = buffers;
      out[1] = buffers + STRIKE_LV2_MAX_BLOCK;
      if (strike_render(probe, out, 2, n) != STRIKE_OK) break;
      for (k = 0; k < n; ++k) {
        if (fabs(out[0][k]) > peak) peak = fabs(out[0][k]);
        if (fabs(out[1][k]) > peak) peak = fabs(out[1][k]);
      }
      done += n;
    }
    strike_object_remove(probe, id);
    { /* lets the probe's render side drop the object, then frees it */
      float* out[2];
      out[0] = buffers;
      out[1] = buffers + STRIKE_LV2_MAX_BLOCK;
      (void)strike_render(probe, out, 2, 1);
      strike_context_collect(probe);
    }
  }
  free(buffers);
  strike_bank_destroy(bank);
  strike_context_destroy(probe);
  return peak;
}

static void run(LV2_Handle instance, uint32_t n_samples) {
  StrikeLv2* self = (StrikeLv2*)instance;
  uint32_t done = 0;
  if (self->gain_db && *self->gain_db != self->last_gain_db) {
    self->last_gain_db = *self->gain_db;
    /* strike_object_set_gain is [main-thread]; in this single-threaded example we fold the gain
       into the output instead (below). */
  }
  if (self->midi_in) {
    LV2_ATOM_SEQUENCE_FOREACH(self->midi_in, ev) {
      if (ev->body.type == self->midi_event && ev->body.size >= 3) {
        const uint8_t* msg = (const uint8_t*)(ev + 1);
        if (lv2_midi_message_type(msg) == LV2_MIDI_MSG_NOTE_ON && msg[2] > 0)
          note_on(self, msg[1], msg[2], (uint32_t)ev->time.frames);
      }
    }
  }
  while (done < n_samples) {
    const uint32_t n = n_samples - done < STRIKE_LV2_MAX_BLOCK ? n_samples - done : STRIKE_LV2_MAX_BLOCK;
    float* out[2];
    const float g = powf(10.0f, self->last_gain_db / 20.0f);
    uint32_t k;
    out[0] = self->out[0] + done;
    out[1] = self->out[1] + done;
    if (strike_render(self->ctx, out, 2, n) != STRIKE_OK) {
      memset(out[0], 0, n * sizeof(float));
      memset(out[1], 0, n * sizeof(float));
    }
    if (g != 1.0f)
      for (k = 0; k < n; ++k) out[0][k] *= g, out[1][k] *= g;
    done += n;
  }
}

static void cleanup(LV2_Handle instance) {
  StrikeLv2* self = (StrikeLv2*)instance;
  strike_bank_destroy(self->bank);
  strike_context_destroy(self->ctx);
  free(self);
}

static const LV2_Descriptor descriptor = {STRIKE_LV2_URI, instantiate, connect_port, NULL, run, NULL, cleanup, NULL};

LV2_SYMBOL_EXPORT const LV2_Descriptor* lv2_descriptor(uint32_t index) { return index == 0 ? &descriptor : NULL; }
