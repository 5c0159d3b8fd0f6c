/* SPDX-License-Identifier: MIT */
/* The smallest libstrike program: tap an object once and write what a listener 1 m away hears.
 *
 *   tap BANK.modes VERTEX OUT.wav
 *
 * BANK.modes comes from `strike modes`; VERTEX is a surface vertex of it (`strike info BANK.modes
 * --vertices` lists them with their normals). The tap is the library's default striker (a 5 mm
 * steel ball) giving 0.01 N s into the surface along its normal, heard 1 m away along the mesh
 * frame's -y: the tap of `strike hit BANK.modes -o OUT.wav --vertex VERTEX --listener 0,-1,0
 * --duration 1`, which sounds the same. (Plain `strike hit` puts the listener on the side struck
 * instead; a bank with an acoustic transfer sounds different in every direction.)
 * OUT.wav is mono 32-bit float at 48 kHz, 1.0 = 20 Pa (the tools' level).
 *
 * Build against an installed libstrike:  cc tap.c $(pkg-config --cflags --libs strike) -o tap */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>

#include "strike/strike.h"

enum { kRate = 48000, kBlock = 512, kFrames = kRate }; /* one second */

/* A WAV file of 32-bit float samples (format 3), little-endian as on x86. */
static int writeWav(const char* path, const float* samples, uint32_t frames) {
  FILE* f = fopen(path, "wb");
  if (!f) return 0;
  const uint32_t data_bytes = frames * 4, rate = kRate, byte_rate = kRate * 4, fmt_size = 16;
  const uint16_t format = 3, channels = 1, block_align = 4, bits = 32;
  const uint32_t riff_size = 36 + data_bytes;
  int ok = fwrite("RIFF", 1, 4, f) == 4 && fwrite(&riff_size, 4, 1, f) == 1 && fwrite("WAVEfmt ", 1, 8, f) == 8 &&
           fwrite(&fmt_size, 4, 1, f) == 1 && fwrite(&format, 2, 1, f) == 1 && fwrite(&channels, 2, 1, f) == 1 &&
           fwrite(&rate, 4, 1, f) == 1 && fwrite(&byte_rate, 4, 1, f) == 1 && fwrite(&block_align, 2, 1, f) == 1 &&
           fwrite(&bits, 2, 1, f) == 1 && fwrite("data", 1, 4, f) == 4 && fwrite(&data_bytes, 4, 1, f) == 1 &&
           fwrite(samples, 4, frames, f) == frames;
  return fclose(f) == 0 && ok;
}

int main(int argc, char** argv) {
  if (argc != 4) {
    fprintf(stderr, "usage: tap BANK.modes VERTEX OUT.wav\n");
    return 1;
  }
  /* A mono context at 48 kHz; every other setting is the library's default. */
  strike_context_config config = strike_context_config_default();
  config.sample_rate_hz = kRate;
  config.channels = 1;
  config.max_block_frames = kBlock;
  strike_context context = NULL;
  if (strike_context_create(&config, &context) != STRIKE_OK) return 2;

  strike_bank bank = NULL;
  if (strike_bank_load_file(context, argv[1], &bank) != STRIKE_OK) {
    fprintf(stderr, "tap: %s\n", strike_context_last_error(context));
    strike_context_destroy(context);
    return 1;
  }
  /* The object 1 m in front of the listener (the listener is at the origin by default), so the
   * listener is at (0, -1, 0) in the object's mesh frame. */
  strike_object_config object = strike_object_config_default();
  object.bank = bank;
  object.position[1] = 1.0;
  strike_object_id id;
  if (strike_object_add(context, &object, &id) != STRIKE_OK) return 2;

  /* The impact: which object, where (a surface vertex), and the impulse (N s). Every other
   * field (the striker, its speed, the contact time) is the default tap's. */
  const uint32_t vertex = (uint32_t)strtoul(argv[2], NULL, 10);
  double normal[3];
  if (strike_bank_surface_vertex(bank, vertex, NULL, normal) != STRIKE_OK) {
    fprintf(stderr, "tap: vertex %s is not a surface vertex of %s\n", argv[2], argv[1]);
    return 1;
  }
  strike_impact_desc impact = strike_impact_desc_default();
  impact.object = id;
  impact.surface_vertex = (int32_t)vertex;
  for (int axis = 0; axis < 3; ++axis) impact.impulse[axis] = -0.01 * normal[axis]; /* into the surface */
  if (strike_impact(context, &impact) != STRIKE_OK) return 2;

  /* Render one second, a block at a time, as an audio callback would. */
  static float samples[kFrames];
  for (uint32_t done = 0; done < kFrames; done += kBlock) {
    float* channel = samples + done;
    const uint32_t frames = kFrames - done < kBlock ? kFrames - done : kBlock;
    if (strike_render(context, &channel, 1, frames) != STRIKE_OK) return 2;
  }
  strike_bank_destroy(bank);
  strike_context_destroy(context);
  if (!writeWav(argv[3], samples, kFrames)) {
    fprintf(stderr, "tap: cannot write %s\n", argv[3]);
    return 1;
  }
  return 0;
}
