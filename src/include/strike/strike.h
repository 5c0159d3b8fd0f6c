/* SPDX-License-Identifier: MIT */
/**
 * @file strike.h
 * libstrike: the real-time-safe C API of Strike, for audio plugins and game engines.
 *
 * The only ABI-stable header of the project (C99, also valid C++). A host creates a context for
 * a sample rate and a maximum block size, loads mode banks (files written by `strike modes`),
 * adds sounding objects (a bank plus a pose), reports impacts from any thread, and pulls audio
 * from its audio callback with strike_render().
 *
 * Threads. Every function carries a tag:
 *  - [main-thread]: one thread at a time (the host's control thread); calls are not reentrant
 *    and must not overlap each other. They may allocate, do file I/O and log.
 *  - [any-thread]: any thread, concurrently with everything else; lock-free, never allocates.
 *  - [audio-thread]: the one thread that renders; never allocates, locks, logs, does I/O or
 *    throws. Only strike_render() and strike_impact() may be called from the audio callback.
 * Changes made on the main thread (objects, poses, gains, the listener) are handed to the audio
 * thread through a lock-free command queue and take effect at the start of the next
 * strike_render(); memory the audio thread no longer uses is freed later on the main thread.
 *
 * Units: SI everywhere (metres, seconds, kilograms, newton-seconds, hertz). Output samples are
 * sound pressure at the listener divided by the context's output_full_scale_pa, times the
 * object gain: by default 1.0 = 20 Pa (120 dB SPL), the convention of the `strike` tools, so a
 * float buffer from strike_render() and a WAV from `strike hit` or `strike render` have the
 * same level (see strike_context_config.output_full_scale_pa and strike_object_config.radiation).
 *
 * Status: EXPERIMENTAL (0.x). The ABI may change between minor versions until 1.0; the version
 * check in strike_context_create() refuses a header of another minor version.
 *
 * Changes in 0.4 (recompile: the soname is now libstrike.so.0.4):
 *  - What the listener hears (docs/listener.md): objects whose bank has an acoustic transfer
 *    (bank format 5) sound different in every direction, each impact heard along the direction
 *    from the object to the listener in the object's frame; free objects click when struck
 *    (acceleration noise: a 5 mm steel ball with no audible mode is heard); and a ground
 *    reflection (strike_context_config.ground_*, new, last fields; off by default).
 *  - Rolling, sliding and scraping (docs/contact.md): strike_contact gains, at its end,
 *    normal_force_n, slip_velocity_m_s, rolling_velocity_m_s, partner_point, patch_radius_m and
 *    the partner's roughness and restitution (read only when strike_step_desc.contact_size
 *    covers them); strike_object_config gains roughness_rms_m, roughness_correlation_m,
 *    roughness_seed and restitution (last fields). A contact with a normal force whose surfaces
 *    move over each other sounds while it moves; without them, contacts sound as in 0.3.
 *    strike_stats gains continuous_contacts and continuous_dropped (last fields).
 *
 * Changes in 0.3 (recompile: the soname is now libstrike.so.0.3; see src/capi/README.md):
 *  - One sound engine with `strike render`: the same contact scheduling, listener model and
 *    voices. strike_step() takes a physics step's body states and contacts (resting ones
 *    included) and decides what is an impact, what a steady load (silent) and what a change of
 *    load; `strike render --via-library` renders scenes through it.
 *  - The listener: level reference / max(distance, min_distance_m) from each object's centre of
 *    mass (new min_distance_m, default 0.05 m: objects nearer than reference_distance_m are now
 *    louder, as in the tools), and each contact is heard distance / 343 m/s after it happens.
 *  - Output structs (strike_stats, strike_bank_info) start with struct_size: set it to
 *    sizeof(the struct) and a newer library never writes past it.
 *  - New: strike_context_reset(), strike_step(), strike_bank_info's material and mass
 *    properties, strike_object_config.is_static, strike_context_config.min_distance_m,
 *    .contact_damping_per_s, .contact_queue_capacity. strike_context_create() logs the field
 *    and value it rejects.
 *
 * Changes in 0.2 (source-compatible; recompile: the soname is now libstrike.so.0.2):
 *  - strike_context_config.output_full_scale_pa (new, last field): the output level convention.
 *    Its default, 20 Pa, makes the default output 20 times (26 dB) lower than 0.1's pascals; set
 *    it to 1 to keep pascals. audibility_threshold is in output units, so its default 1e-6 is
 *    now 20 uPa (0 dB SPL, the threshold of hearing) rather than 1 uPa.
 *  - strike_context_create() refuses a config from a 0.1 header (STRIKE_ERR_VERSION): before
 *    1.0 every minor version may change the structs' layout.
 */
#ifndef STRIKE_STRIKE_H
#define STRIKE_STRIKE_H

#include <stddef.h>
#include <stdint.h>

/* ---- Export and calling convention ------------------------------------------------------ */
#if defined(STRIKE_STATIC)
#define STRIKE_API
#elif defined(_WIN32)
#if defined(STRIKE_BUILDING)
#define STRIKE_API __declspec(dllexport)
#else
#define STRIKE_API __declspec(dllimport)
#endif
#elif defined(__GNUC__)
#define STRIKE_API __attribute__((visibility("default")))
#else
#define STRIKE_API
#endif

#if defined(_WIN32) && !defined(_WIN64)
#define STRIKE_CALL __cdecl
#else
#define STRIKE_CALL
#endif

#ifdef __cplusplus
extern "C" {
#endif

/* ---- Version ---------------------------------------------------------------------------- */
/* Kept equal to project(strike VERSION ...) in CMakeLists.txt (checked at configure time). */
#define STRIKE_VERSION_MAJOR 0
#define STRIKE_VERSION_MINOR 4
#define STRIKE_VERSION_PATCH 0
/** Packed version of this header: (major << 16) | (minor << 8) | patch. */
#define STRIKE_VERSION                                                                         \
  ((uint32_t)(((uint32_t)STRIKE_VERSION_MAJOR << 16) | ((uint32_t)STRIKE_VERSION_MINOR << 8) | \
              (uint32_t)STRIKE_VERSION_PATCH))
/** True when this header is at least version maj.min.rev. */
#define STRIKE_VERSION_GE(maj, min, rev)                                                              \
  (STRIKE_VERSION_MAJOR > (maj) || (STRIKE_VERSION_MAJOR == (maj) && STRIKE_VERSION_MINOR > (min)) || \
   (STRIKE_VERSION_MAJOR == (maj) && STRIKE_VERSION_MINOR == (min) && STRIKE_VERSION_PATCH >= (rev)))

/** Packed version of the library actually loaded (same layout as STRIKE_VERSION). [any-thread] */
STRIKE_API uint32_t STRIKE_CALL strike_get_version(void);

/* ---- Status codes ----------------------------------------------------------------------- */
/** 0 is success, negative values are errors. An int32_t, never a C enum (whose size varies). */
typedef int32_t strike_status;
enum {
  STRIKE_OK = 0,
  STRIKE_ERR_INVALID_ARG = -1,      /**< NULL handle or pointer, out-of-range or non-finite value */
  STRIKE_ERR_OUT_OF_MEMORY = -2,    /**< an allocation failed */
  STRIKE_ERR_VERSION = -3,          /**< header/library mismatch, or a bank of a newer format */
  STRIKE_ERR_IO = -4,               /**< a file could not be opened or read */
  STRIKE_ERR_PARSE = -5,            /**< not a valid mode bank (truncated, foreign, corrupt) */
  STRIKE_ERR_STALE_ID = -6,         /**< the object was removed (or never existed) */
  STRIKE_ERR_QUEUE_FULL = -7,       /**< a lock-free queue is full; the item was dropped and counted */
  STRIKE_ERR_CAPACITY = -8,         /**< a configured maximum (objects) is reached */
  STRIKE_ERR_TOO_MANY_FRAMES = -9,  /**< render asked for more frames than max_block_frames */
  STRIKE_ERR_NOT_INITIALIZED = -10, /**< a config struct that did not come from its _default() */
  STRIKE_ERR_INTERNAL = -11         /**< a bug in libstrike; the message says where */
};

/** Static English text for a status code ("unknown status" for other values). [any-thread] */
STRIKE_API const char* STRIKE_CALL strike_status_string(strike_status status);

/* ---- Handles and ids -------------------------------------------------------------------- */
/** A synthesis context: sample rate, objects, queues, and the audio-thread state. */
typedef struct strike_context_s* strike_context;
/** A loaded mode bank (immutable, shared by the objects that use it). */
typedef struct strike_bank_s* strike_bank;

/**
 * A sounding object. Ids are values: a removed object's id becomes stale (its generation no
 * longer matches) and is reported as STRIKE_ERR_STALE_ID, never mistaken for a newer object in
 * the same slot. {0, 0} is never a valid id.
 */
typedef struct strike_object_id {
  uint32_t index;      /**< slot, < max_objects */
  uint32_t generation; /**< >= 1 for a valid id */
} strike_object_id;

/* ---- Callbacks (owned by the context: no process globals) ------------------------------- */
enum { STRIKE_LOG_ERROR = 0, STRIKE_LOG_WARNING = 1, STRIKE_LOG_INFO = 2 };
/** Log sink. Called only from [main-thread] functions, never from the audio thread.
 *  @param message valid only during the call. */
typedef void(STRIKE_CALL* strike_log_fn)(void* user, int32_t level, const char* message);
/** Allocator: size bytes aligned to alignment (a power of two <= 64); NULL on failure.
 *  What it covers: the context and its queues, slots and sound engine; each bank handle; each
 *  object's record. What it does not: the engine's voice table and budget histogram and the
 *  list of removed objects awaiting collection (sized at creation by max_objects), the storage
 *  inside a loaded bank (its modes and shapes) and inside an object's oscillators, projector and
 *  contact state (sized by the bank's modes), which come from the C++ runtime's operator new,
 *  also on the main thread only (create, bank load, object add and remove, collect). Nothing is
 *  allocated on the audio thread, nor by strike_impact() or strike_step(). */
typedef void*(STRIKE_CALL* strike_alloc_fn)(void* user, size_t size, size_t alignment);
/** Frees what strike_alloc_fn returned (never called with NULL). */
typedef void(STRIKE_CALL* strike_free_fn)(void* user, void* pointer);

/* ---- Context ---------------------------------------------------------------------------- */
typedef struct strike_context_config {
  uint32_t api_version;      /**< STRIKE_VERSION of the caller's header (set by _default) */
  double sample_rate_hz;     /**< 8000 .. 768000; default 48000 */
  uint32_t max_block_frames; /**< largest strike_render() frames, 1 .. 16384; default 1024 */
  uint32_t channels;         /**< 1 (mono) or 2 (stereo, constant-power pan); default 2 */
  uint32_t max_objects;      /**< objects alive at once, 1 .. 65536; default 64 */
  /** Budget of ringing modes over all objects; when over it at the end of a render call, the
   *  quietest (at the listener) are put to sleep first. 0 = no budget. Default 100000. */
  uint32_t max_active_modes;
  /** Impacts in flight between strike_impact() and the next render, 2 .. 1048576, rounded up to
   *  a power of two; when full, strike_impact() drops and counts. Default 1024. */
  uint32_t impact_queue_capacity;
  /** Impacts per object whose contact pulse has not yet finished, 1 .. 4096; more are dropped
   *  and counted (impacts_dropped_capacity). Default 32. */
  uint32_t max_pending_impacts_per_object;
  /** Impacts prepared per strike_render() call at most; the rest wait in the queue for the next
   *  call (bounds the audio thread's work in a burst: preparing one impact costs about 0.5 us
   *  per mode of its object on a 2020s x86 core). 0 = no limit (one queue's worth). Default 64. */
  uint32_t max_impacts_per_render;
  double max_contact_duration_s; /**< longer contact pulses are shortened to this, s; default 0.005 */
  double min_freq_hz;            /**< modes below are not synthesized, Hz; default 20 */
  double max_freq_hz;            /**< modes above min(this, 0.45 fs) are not synthesized; default 20000 */
  /** Output amplitude (output units, before object gain) below which a mode sleeps; default 1e-6
   *  (with the default output_full_scale_pa, 20 uPa: 0 dB SPL). */
  double audibility_threshold;
  /** Distance at which the output is the bank's radiated pressure (over output_full_scale_pa),
   *  m (> 0). Gain = reference / max(distance, min_distance_m), distance from the object's
   *  centre of mass to the listener. Default 1. */
  double reference_distance_m;
  strike_log_fn log;     /**< NULL = no logging */
  strike_alloc_fn alloc; /**< NULL = aligned_alloc; alloc and free are both set or both NULL */
  strike_free_fn free;
  void* user;              /**< passed to log, alloc and free */
  int32_t internal_cookie; /**< set by strike_context_config_default(); do not touch */
  /** Output level convention (added in 0.2): the sound pressure at the listener, Pa, that
   *  strike_render() writes as sample value 1.0 (for STRIKE_RADIATION_PRESSURE objects; _UNIT
   *  objects are not scaled). Finite, > 0. Default 20: 1.0 = 20 Pa = 120 dB SPL, as the `strike`
   *  tools write WAVs, so ordinary impacts stay below full scale and the same impact has the
   *  same level in both. 1 gives pascals (libstrike 0.1's output). */
  double output_full_scale_pa;
  /** (0.3) Nearer than this the level stops growing as 1/distance, m (> 0). Default 0.05, as
   *  the tools. */
  double min_distance_m;
  /** (0.3) Extra decay of an object's modes while it is in sustained contact (resting, pressed),
   *  1/s of amplitude, >= 0: the energy it loses into what it touches. Default 0 (as the scene
   *  file's "contact_damping"). */
  double contact_damping_per_s;
  /** (0.3) Records in flight between strike_step() and the next render: one per body state and
   *  contact, plus two per step, 16 .. 1048576, rounded up to a power of two. Default 8192. */
  uint32_t contact_queue_capacity;
  /** (0.4) A flat ground that reflects sound: every object is also heard from the listener's
   *  mirror image in the plane ground_normal . x = ground_height_m, later by the longer path and
   *  weighted by ground_reflection (the pressure reflection coefficient, -1 .. 1; 1 = rigid, as
   *  concrete, wood and steel floors are to air). Only when the object and the listener are both
   *  above it. 0 = no reflection (default); 1 = on. ground_normal is normalized here (default
   *  0, 0, 1); `strike render` sets it from the scene's ground. */
  int32_t ground_reflects;
  double ground_normal[3];
  double ground_height_m;
  double ground_reflection;
} strike_context_config;

/** Defaults (see each field). [any-thread] */
STRIKE_API strike_context_config STRIKE_CALL strike_context_config_default(void);

/**
 * Creates a context; allocates everything the audio thread will need for max_objects objects.
 * Fails with STRIKE_ERR_VERSION when config->api_version has another major version or a newer
 * minor version than the library, or (before 1.0) another minor version at all,
 * STRIKE_ERR_NOT_INITIALIZED when config did not come from
 * strike_context_config_default(), STRIKE_ERR_INVALID_ARG for a value out of range. Each
 * refusal is logged through config->log (if set), naming the field and its value, e.g.
 * "strike_context_create: channels = 3 (must be 1 or 2)". [main-thread]
 * @param config read during the call only.
 * @param[out] out the new context on success; untouched on failure. Destroy with
 *             strike_context_destroy().
 */
STRIKE_API strike_status STRIKE_CALL strike_context_create(const strike_context_config* config, strike_context* out);

/** Output formats (docs/listener.md): how each path (the direct sound, the ground's image)
 *  reaches the channels of strike_render() from its direction of arrival in the listener's
 *  frame (+y forward, +x right, +z up; strike_listener_set_pose). */
enum {
  STRIKE_OUTPUT_MONO = 0,   /**< 1 channel: the level alone; both paths in one signal */
  STRIKE_OUTPUT_STEREO = 1, /**< 2 channels (left, right): constant-power pan by the direction's x */
  /** (N+1)^2 channels of Ambisonics of order N = 1, 2, 3 in the AmbiX convention: ACN channel
   *  order, SN3D normalisation, x forward, y left, z up. */
  STRIKE_OUTPUT_AMBIX1 = 2,
  STRIKE_OUTPUT_AMBIX2 = 3,
  STRIKE_OUTPUT_AMBIX3 = 4,
  /** (0.4, added later) 2 channels (left ear, right ear): each path through head-related impulse
   *  responses interpolated to its direction, which the host hands over in strike_output_desc's
   *  hrtf_* fields (read from a SOFA file, for example; libstrike reads no file). */
  STRIKE_OUTPUT_BINAURAL = 5
};

/** (0.4, added later) The output of a context, for strike_context_create_with_output(). Later versions
 *  add fields at its end; the library reads only struct_size bytes of it. */
typedef struct strike_output_desc {
  uint32_t struct_size; /**< sizeof(strike_output_desc); set by _default() */
  uint32_t format;      /**< a STRIKE_OUTPUT_* value; default STRIKE_OUTPUT_MONO */
  /** Air absorption on every path of every mode, per ISO 9613-1 (docs/listener.md): 1 on, 0 off
   *  (default). Read only when struct_size covers air_pressure_kpa. */
  int32_t air_absorption;
  double air_temperature_c;             /**< -50 .. 60; default 20 */
  double air_relative_humidity_percent; /**< 0 .. 100; default 50 */
  double air_pressure_kpa;              /**< 50 .. 200; default 101.325 */
  /** (0.4, added later) STRIKE_OUTPUT_BINAURAL's head-related impulse responses, measured in
   *  hrtf_count directions (at least 4), hrtf_length samples each at the context's sample rate
   *  (1 .. 16384). Read only for that format, and only when struct_size covers hrtf_right;
   *  copied during the call (the caller may free them after). Interpolated between the
   *  measured directions by modified Shepard weighting of the three nearest, aligned on their
   *  onsets (docs/listener.md). Defaults: 0 and NULL. */
  uint32_t hrtf_count;
  uint32_t hrtf_length;
  /** hrtf_count x 3 doubles: each measurement's source direction seen from the head's centre,
   *  in the SOFA frame (x forward, y left, z up; any non-zero length). */
  const double* hrtf_directions;
  const float* hrtf_left;  /**< hrtf_count x hrtf_length: the left ear's responses */
  const float* hrtf_right; /**< hrtf_count x hrtf_length: the right ear's responses */
} strike_output_desc;

/** Defaults (mono). [any-thread] */
STRIKE_API strike_output_desc STRIKE_CALL strike_output_desc_default(void);

/**
 * (0.4, added later) strike_context_create() with an output format: config->channels is ignored, and
 * strike_render() takes the format's channel count (1, 2, 4, 9 or 16; 2 for binaural). With a format that has
 * directions and a reflecting ground, the ground's image is rendered as a signal of its own
 * (twice the oscillators of the objects it reaches) and arrives from below. Refusals as
 * strike_context_create(), and STRIKE_ERR_INVALID_ARG for a NULL output, a struct_size too small
 * for `format`, an unknown format, air values out of range, or a binaural format without
 * valid responses (struct_size too small for them, a count, length or pointer missing, a
 * direction of no length, a value not finite) (logged). [main-thread]
 */
STRIKE_API strike_status STRIKE_CALL strike_context_create_with_output(const strike_context_config* config,
                                                                       const strike_output_desc* output,
                                                                       strike_context* out);

/**
 * Destroys the context, its objects and its queues. Banks loaded in it must be destroyed first
 * or after (a bank keeps its data alive on its own), but the context must outlive no audio
 * callback: stop rendering before. NULL is a no-op. [main-thread]
 */
STRIKE_API void STRIKE_CALL strike_context_destroy(strike_context context);

/**
 * The message of the last failed [main-thread] call on this context ("" if none), naming the
 * file, field or value. Also sent to the log callback. [main-thread]
 * @return owned by the context, valid until the next [main-thread] call on it.
 */
STRIKE_API const char* STRIKE_CALL strike_context_last_error(strike_context context);

/** Counters since creation. Read with relaxed atomics: consistent per field, not across fields. */
typedef struct strike_stats {
  /** Set to sizeof(strike_stats) before the call: the library writes no more than that, so a
   *  caller compiled against an older (smaller) struct is safe with a newer library. */
  uint32_t struct_size;
  uint64_t impacts_queued;             /**< accepted by strike_impact() */
  uint64_t impacts_dropped_queue_full; /**< refused by strike_impact(): the queue was full */
  uint64_t impacts_dropped_stale;      /**< their object was removed before they were rendered */
  uint64_t impacts_dropped_capacity;   /**< max_pending_impacts_per_object reached */
  uint64_t impacts_scheduled;          /**< reached the oscillators */
  uint64_t impacts_inaudible;          /**< changed no mode above the audibility threshold */
  uint64_t modes_culled;               /**< put to sleep by the max_active_modes budget */
  uint64_t frames_rendered;            /**< by successful strike_render() calls */
  uint32_t active_modes;               /**< ringing after the last render */
  uint32_t objects;                    /**< objects alive on the audio thread after the last render */
  /* 0.3 */
  uint64_t steps;                       /**< strike_step() calls rendered */
  uint64_t contacts_queued;             /**< contacts accepted by strike_step() */
  uint64_t contacts_dropped_queue_full; /**< body states and contacts refused: the queue was full */
  uint64_t contacts_dropped_stale;      /**< on an object that was not alive when rendered */
  uint64_t sustained_contacts;          /**< contacts slower than 5 cm/s: part of a load */
  uint64_t load_changes;                /**< changes of an object's load (force steps scheduled) */
  uint64_t load_holds;                  /**< steps a sleeping object's load was kept */
  uint64_t clock_frames;                /**< frames since creation or the last strike_context_reset() */
  /* 0.4 */
  uint64_t continuous_contacts; /**< rolling/sliding contacts whose roughness began to drive an object */
  uint64_t continuous_dropped;  /**< contact points of further partners not heard: the object already
                                     sounded with 4 (docs/contact.md) */
} strike_stats;

/** Copies the counters. [any-thread]
 *  @param[out] out its struct_size must be set; at most that many bytes are written on success.
 *  STRIKE_ERR_INVALID_ARG when struct_size is smaller than the 0.3 layout's first field. */
STRIKE_API strike_status STRIKE_CALL strike_context_get_stats(strike_context context, strike_stats* out);

/**
 * Frees memory the audio thread has released (removed objects). Every [main-thread] call does
 * this too; call it periodically if you rarely call anything else. [main-thread]
 */
STRIKE_API strike_status STRIKE_CALL strike_context_collect(strike_context context);

/**
 * Silences every object (modes, pending pulses, loads), drops the impacts and steps queued
 * before this call and restarts the context's clock at 0 at the next strike_render(); objects,
 * banks, poses and the listener stay. Impacts and steps reported after it returns are kept (on
 * the restarted clock). For a game loading a level or a plugin's transport jumping. [main-thread]
 */
STRIKE_API strike_status STRIKE_CALL strike_context_reset(strike_context context);

/* ---- Banks ------------------------------------------------------------------------------ */
/**
 * Loads a mode bank file (format: docs/bank-format.md). STRIKE_ERR_IO when it cannot be read,
 * STRIKE_ERR_VERSION when it is of a newer format, STRIKE_ERR_PARSE when it is truncated,
 * foreign or corrupt (strike_context_last_error() says which). [main-thread]
 * @param path UTF-8 file name, read during the call only.
 * @param[out] out the bank on success; untouched on failure. Destroy with strike_bank_destroy().
 */
STRIKE_API strike_status STRIKE_CALL strike_bank_load_file(strike_context context, const char* path, strike_bank* out);

/**
 * Same from bytes in memory (e.g. a bank bundled with a plugin). [main-thread]
 * @param data size bytes, read during the call only (copied).
 */
STRIKE_API strike_status STRIKE_CALL strike_bank_load_memory(strike_context context, const void* data, size_t size,
                                                             strike_bank* out);

/** Releases the handle. Objects using the bank keep its data alive until they are removed.
 *  NULL is a no-op. [main-thread] */
STRIKE_API void STRIKE_CALL strike_bank_destroy(strike_bank bank);

typedef struct strike_bank_info {
  /** Set to sizeof(strike_bank_info) before the call (see strike_stats.struct_size). */
  uint32_t struct_size;
  uint32_t mode_count;           /**< modes in the bank (some may be out of band) */
  uint32_t surface_vertex_count; /**< valid strike_impact_desc.surface_vertex values: 0 .. this-1 */
  uint32_t surface_triangle_count;
  double mass_kg;
  double lowest_frequency_hz; /**< of mode 0, 0 if no modes */
  double bounds_min_m[3];     /**< axis-aligned bounds of the surface, mesh frame */
  double bounds_max_m[3];
  /* 0.3: the object's physical data, for the physics engine (mass properties) and contacts */
  double volume_m3;
  double centre_of_mass_m[3]; /**< mesh frame */
  double inertia_kg_m2[9];    /**< about the centre of mass, mesh frame, row-major */
  double surface_area_m2;
  /** Radius of the sphere of the same volume, m: what `strike render` uses as the object's
   *  contact radius (strike_object_config.contact_radius_m). */
  double equal_volume_radius_m;
  char material_name[32]; /**< NUL-terminated, truncated */
  double youngs_pa;
  double poisson;
  double density_kg_m3;
  double rayleigh_stiffness_s; /**< a1 of C = a1 K + a2 M */
  double rayleigh_mass_per_s;  /**< a2 */
} strike_bank_info;

/** [any-thread] (banks are immutable) @param[out] out its struct_size must be set; at most that
 *  many bytes are written on success. */
STRIKE_API strike_status STRIKE_CALL strike_bank_get_info(strike_bank bank, strike_bank_info* out);

/** Undamped natural frequency of one mode, Hz. [any-thread] @param[out] out_hz written on success. */
STRIKE_API strike_status STRIKE_CALL strike_bank_mode_frequency(strike_bank bank, uint32_t mode, double* out_hz);

/** Position of a surface vertex in the mesh frame, m. [any-thread] */
STRIKE_API strike_status STRIKE_CALL strike_bank_surface_vertex(strike_bank bank, uint32_t vertex,
                                                                double out_position[3], double out_normal[3]);

/* ---- Objects ---------------------------------------------------------------------------- */
enum {
  /** Per-mode weights of a compact radiator: output is sound pressure at the reference distance
   *  in units of output_full_scale_pa (see radiation.cpp for the model and what it leaves out). */
  STRIKE_RADIATION_PRESSURE = 0,
  /** Weight 1 for every mode: output is the sum of modal accelerations (m/s^2 sqrt(kg)). */
  STRIKE_RADIATION_UNIT = 1
};

typedef struct strike_object_config {
  strike_bank bank;      /**< required; must come from the same context */
  double position[3];    /**< world position of the mesh-frame origin, m; default 0 */
  double orientation[4]; /**< unit quaternion w, x, y, z (world from mesh frame); default 1,0,0,0 */
  float gain;            /**< linear, >= 0; default 1 */
  int32_t radiation;     /**< STRIKE_RADIATION_*; default PRESSURE */
  /** Radius of curvature of the object's surface at contacts, m, for the Hertz contact time;
   *  0 = flat (a half-space). Default 0. */
  double contact_radius_m;
  /** (0.3) Non-zero: immovable (a table, a floor): infinite mass in the Hertz contact time,
   *  and it keeps carrying the load of objects that fall asleep on it. Default 0. */
  int32_t is_static;
  int32_t internal_cookie; /**< set by strike_object_config_default(); do not touch */
  /** (0.4) Its surface's roughness for rolling, sliding and scraping (strike_contact's
   *  normal_force_n): rms height R_q and correlation length of the profile, m; the materials'
   *  values are in assets/materials.json (`strike modes --list-materials`). rms 0 (default):
   *  smooth. The seed names the surface: the same seed, the same profile (default 0; give each
   *  object its own). */
  double roughness_rms_m;
  double roughness_correlation_m;
  uint64_t roughness_seed;
  double restitution; /**< of its material on itself: damps the contact's resonance; default 0.5 */
} strike_object_config;

/** Defaults (see each field). [any-thread] */
STRIKE_API strike_object_config STRIKE_CALL strike_object_config_default(void);

/**
 * Adds a sounding object; it can be struck from the next strike_render() on. Allocates its
 * oscillators and impact reserve here (never on the audio thread). STRIKE_ERR_CAPACITY when
 * max_objects are alive, STRIKE_ERR_QUEUE_FULL when the command queue is full (the audio thread
 * is not rendering). [main-thread]
 * @param[out] out the id on success; untouched on failure.
 */
STRIKE_API strike_status STRIKE_CALL strike_object_add(strike_context context, const strike_object_config* config,
                                                       strike_object_id* out);

/** Removes an object: it falls silent at the next render; pending impacts on it are dropped
 *  (impacts_dropped_stale). STRIKE_ERR_STALE_ID for an id that is not alive. [main-thread] */
STRIKE_API strike_status STRIKE_CALL strike_object_remove(strike_context context, strike_object_id object);

/** 1 if the id names a live object, else 0 (also for a NULL context). [any-thread] */
STRIKE_API int32_t STRIKE_CALL strike_object_is_valid(strike_context context, strike_object_id object);

/** Moves an object (world frame; see strike_object_config). [main-thread] */
STRIKE_API strike_status STRIKE_CALL strike_object_set_pose(strike_context context, strike_object_id object,
                                                            const double position[3], const double orientation[4]);

/** Sets the linear gain (>= 0), ramped over the next block. [main-thread] */
STRIKE_API strike_status STRIKE_CALL strike_object_set_gain(strike_context context, strike_object_id object,
                                                            float gain);

/**
 * Sets the listener pose (world frame). The listener faces its local +y, with +x to its right
 * and +z up; stereo pans by the direction's x component. Default: at the origin, identity.
 * [main-thread]
 */
STRIKE_API strike_status STRIKE_CALL strike_listener_set_pose(strike_context context, const double position[3],
                                                              const double orientation[4]);

/* ---- Impacts ---------------------------------------------------------------------------- */
enum { STRIKE_FRAME_OBJECT = 0, STRIKE_FRAME_WORLD = 1 };
enum { STRIKE_PULSE_HALF_SINE = 0, STRIKE_PULSE_BOX = 1 };

/** One contact on an object. A plain value: copied into the queue by strike_impact(). */
typedef struct strike_impact_desc {
  strike_object_id object;
  /** Frame of point and impulse: STRIKE_FRAME_OBJECT (the bank's mesh frame; default) or
   *  STRIKE_FRAME_WORLD (transformed by the object's pose at render time). */
  int32_t frame;
  /** >= 0: strike this surface vertex (point ignored; O(modes) on the audio thread). -1
   *  (default): the surface point nearest to `point` (O(triangles + modes) on the audio thread). */
  int32_t surface_vertex;
  double point[3];   /**< contact point, m */
  double impulse[3]; /**< impulse applied TO the object, N s */
  /** Relative normal speed at contact, m/s, for the Hertz contact time: faster is shorter, so
   *  harder hits are brighter. <= 0 (default): the speed at which the striker (of
   *  striker_mass_kg; immovable when 0) meets the object to give this impulse in an elastic
   *  rebound, J.n = 2 m* v with m* the reduced mass and n the surface normal where it strikes. */
  double normal_speed_m_s;
  /** < 0 (default): Hertz duration from normal_speed_m_s and the materials; 0: an ideal
   *  impulse; > 0: this duration, s. Always capped at max_contact_duration_s. */
  double contact_duration_s;
  /* The striker. The defaults (since 0.5) are the striker of `strike hit` and the Python
   * package's strike.hit(): a steel ball 5 mm in radius (E 200 GPa, nu 0.29, 7850 kg/m^3,
   * 4.11 g), so the same tap sounds the same from each. */
  double striker_radius_m;  /**< radius of the striking body at contact, m; 0 = flat. Default 0.005 */
  double striker_youngs_pa; /**< 0: same material as the object. Default 2e11 (steel) */
  double striker_poisson;   /**< used when striker_youngs_pa > 0; default 0.29 (steel) */
  double striker_mass_kg;   /**< 0: immovable (infinite mass). Default 4.11e-3 (the steel ball) */
  /** Frames after the start of the next strike_render() at which the contact begins
   *  (sample-accurate scheduling within or beyond that block). Default 0. */
  uint32_t sample_offset;
  int32_t pulse; /**< STRIKE_PULSE_HALF_SINE (default) or STRIKE_PULSE_BOX (sustained) */
} strike_impact_desc;

/** Defaults (see each field). [any-thread] */
STRIKE_API strike_impact_desc STRIKE_CALL strike_impact_desc_default(void);

/**
 * Queues an impact for the next strike_render(): lock-free, wait-free unless the queue is
 * contended, no allocation. The projection onto modes and the pulse integration happen on the
 * audio thread into preallocated storage. STRIKE_ERR_QUEUE_FULL when the queue is full (the
 * impact is dropped and counted in impacts_dropped_queue_full), STRIKE_ERR_STALE_ID when the id
 * is not alive now, STRIKE_ERR_INVALID_ARG for non-finite values. Does not set last_error.
 * [any-thread], including the audio callback.
 * @param impact read during the call only.
 */
STRIKE_API strike_status STRIKE_CALL strike_impact(strike_context context, const strike_impact_desc* impact);

/* ---- Physics steps (0.3) ---------------------------------------------------------------- */
/** Where a body is after a physics step. */
typedef struct strike_body_state {
  strike_object_id object;
  double position[3];    /**< world position of the mesh-frame origin, m */
  double orientation[4]; /**< unit quaternion w, x, y, z (world from mesh frame) */
  /** Non-zero when the physics engine has put it to sleep: it reports no contacts, but it still
   *  rests on its support, so its load is kept (not released as if it were lifted). */
  int32_t asleep;
} strike_body_state;

/** One object's side of one contact point during one physics step: report every contact the
 *  physics engine solved, resting ones included (a contact between two objects is two of these,
 *  one per object, each with its own point and impulse). */
typedef struct strike_contact {
  strike_object_id object; /**< the object heard */
  /** The other body, if it is an object; {0, 0} for the ground or anything else. */
  strike_object_id partner;
  int32_t frame;     /**< STRIKE_FRAME_OBJECT (default: object's mesh frame) or _WORLD */
  double point[3];   /**< contact point, m */
  double impulse[3]; /**< applied TO the object over the step (normal + friction), N s */
  /** Speed at which the surfaces approach along the normal, m/s (>= 0). Above 0.05 m/s an impact
   *  (a Hertz pulse); at or below, part of the object's load over the step. */
  double normal_speed_m_s;
  /** When, on the context's clock (seconds since creation or reset, see strike_stats.clock_frames):
   *  for an impact the moment the surfaces met. < 0: the step's start. Times already rendered
   *  sound at once. */
  double time_s;
  /** The other body's material, radius at the contact and mass for the Hertz contact time, when
   *  it is not an object (partner {0, 0}): 0 = the object's own material, flat, immovable. */
  double partner_youngs_pa;
  double partner_poisson;
  double partner_radius_m;
  double partner_mass_kg;
  /* (0.4) Continuous contact: rolling, sliding, scraping (docs/contact.md). Read only when the
   * step's contact_size covers them (a smaller, older element is read without them). A point
   * with normal_force_n > 0 whose surfaces move over each other drives the object's modes with
   * the force of their roughness (both objects need a roughness, or the partner's fields). */
  /** Mean normal force on this point over the step, N (>= 0). 0 (default): no continuous sound. */
  double normal_force_n;
  /** Velocity of the object's surface relative to the partner's at the point, in the tangent
   *  plane, m/s (0 while they stick: resting, rolling without slip). Same frame as point. */
  double slip_velocity_m_s[3];
  /** Velocity at which the contact point travels over the object's own surface, in the tangent
   *  plane, m/s: a ball rolling at v, v; a block sliding, 0. Only the lengths are used: the
   *  point travels |rolling| over the object and |rolling + slip| over the partner. */
  double rolling_velocity_m_s[3];
  /** The point in the partner's mesh frame (in the world for a partner {0, 0}), m: where the
   *  partner's roughness is read, so the same spot sounds the same. */
  double partner_point[3];
  /** Hertz contact radius, m; 0 (default): from the normal force. */
  double patch_radius_m;
  /** The partner's surface when it is not an object (partner {0, 0}); an object's come from its
   *  strike_object_config. rms 0 (default): smooth. The seed names the surface (0 default). */
  double partner_roughness_rms_m;
  double partner_roughness_correlation_m;
  uint64_t partner_roughness_seed;
  double partner_restitution; /**< damps the contact's resonance; default 0.5 */
} strike_contact;

/** Defaults (see each field). [any-thread] */
STRIKE_API strike_contact STRIKE_CALL strike_contact_default(void);

/** One physics step: what a game reports once per step, after stepping its physics. */
typedef struct strike_step_desc {
  uint32_t struct_size; /**< sizeof(strike_step_desc); set by _default() */
  /** End of the step on the context's clock, s. A game whose physics runs ahead of its audio
   *  passes its physics time; the step's sound is placed there (a time already rendered sounds
   *  at once). Render audio at least one step behind the physics for sample-accurate timing. */
  double end_time_s;
  double duration_s;               /**< the step, s (> 0) */
  const strike_body_state* states; /**< poses of the objects that moved (others keep theirs) */
  uint32_t state_count;
  uint32_t state_size; /**< sizeof(strike_body_state); set by _default() */
  const strike_contact* contacts;
  uint32_t contact_count;
  uint32_t contact_size; /**< sizeof(strike_contact); set by _default() */
} strike_step_desc;

/** Defaults: sizes set, no states or contacts. [any-thread] */
STRIKE_API strike_step_desc STRIKE_CALL strike_step_desc_default(void);

/**
 * Reports one physics step: its body states, then its contacts, copied into a lock-free queue
 * and applied, in order, at the next strike_render(). There the contact scheduler decides what
 * each contact is: an impact (a Hertz pulse from the two materials, radii, masses and the speed),
 * or part of the object's load over the step. A load that stays steady (a resting box, however
 * its contact points flicker) is silent; a change of load (landing, being pushed, lifted) is
 * heard; a sleeping object keeps its load. This is what `strike render` does with Bullet's
 * contacts. STRIKE_ERR_QUEUE_FULL when the queue filled: the rest of the step is dropped and
 * counted (contacts_dropped_queue_full). STRIKE_ERR_INVALID_ARG for NULL, a struct_size or
 * element size from no known version, or a non-finite value (nothing is queued). Lock-free, no
 * allocation. [any-thread], but one step at a time: steps from several threads must not overlap.
 */
STRIKE_API strike_status STRIKE_CALL strike_step(strike_context context, const strike_step_desc* step);

/* ---- Audio ------------------------------------------------------------------------------ */
/**
 * Renders the next `frames` samples of every object into planar buffers (overwrites them).
 * Applies queued commands, steps and impacts first, so an impact queued before this call sounds
 * in this block (at its sample_offset). Never allocates, locks, logs, does I/O or throws.
 * STRIKE_ERR_INVALID_ARG when channels differs from the context's or a pointer is NULL,
 * STRIKE_ERR_TOO_MANY_FRAMES when frames > max_block_frames (nothing is rendered). Does not set
 * last_error. [audio-thread]
 * @param out `channels` pointers to `frames` floats each, owned by the caller.
 */
STRIKE_API strike_status STRIKE_CALL strike_render(strike_context context, float* const* out, uint32_t channels,
                                                   uint32_t frames);

#ifdef __cplusplus
}
#endif

#endif /* STRIKE_STRIKE_H */
