/*
 * fp_stack.h: stacks, performances built in passes (docs/stack.md).
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 *
 * A stack is a small JSON file, NAME.fpstack, holding an ordered list of layers. Each layer
 * is a take (core/take, a path relative to the stack's folder) plus: a region of the face it
 * acts on (a region of the rig, landmarks of the rig with a falloff, a vertex group of the
 * mesh given by indices, or rig channels such as "jaw.open"), a mode (replace or add), a time
 * range [in, out] on the stack's clock with cross-fades of `fade` seconds inside it, an
 * offset (where the take's first frame falls on the stack's clock), a gain, mute and solo.
 * Layer 0 is the base: the whole face, replace; its frames are the stack's clock.
 *
 * This module is the file: parse, check, write, the --layer REGION[:MODE] grammar of the
 * command line and the named regions (presets: "mouth", "brows", "jaw"). Playing a stack
 * (the composition) is core/session's fp_stack_player (fp_stack_player.h).
 *
 * Errors: 0 or a negative errno-style code (fp_error.h): -EINVAL (a bad argument or spec),
 * -EBADMSG (a malformed stack: "FILE: json.path: reason"), -ENOENT/-EACCES/-EIO (the file),
 * -EEXIST (fp_stack_save never overwrites), -ENOMEM; the message in a caller-owned err.
 * Nothing is printed. Threads: an fp_stack belongs to one thread at a time.
 */
#ifndef FP_STACK_H
#define FP_STACK_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

#define FP_STACK_EXTENSION ".fpstack"
#define FP_STACK_FORMAT_VERSION 1
#define FP_STACK_MAX_LAYERS 32
#define FP_STACK_MAX_NAMES 16      /* landmarks or channels of one region */
#define FP_STACK_NAME_MAX 32       /* bytes of a name, NUL included */
#define FP_STACK_PATH_MAX 4096
#define FP_STACK_MAX_GROUP 16777216u /* vertex indices of one vertex group, at most (each < 2^24) */

/** What a layer's region is made of. */
typedef enum fp_stack_region_kind {
    FP_STACK_REGION_ALL = 0,       /* the whole face (weight 1 everywhere) */
    FP_STACK_REGION_RIG = 1,       /* a region of the rig by name (names[0]) */
    FP_STACK_REGION_LANDMARKS = 2, /* rig landmarks by name, core + falloff about them */
    FP_STACK_REGION_VERTICES = 3,  /* a vertex group: mesh vertex indices */
    FP_STACK_REGION_CHANNELS = 4   /* rig channels by name (no vertices: per channel) */
} fp_stack_region_kind;

/** How a layer composes with the layers below it. */
typedef enum fp_stack_mode {
    FP_STACK_REPLACE = 0,          /* d = d + w (d_layer - d): the layer's pass shows */
    FP_STACK_ADD = 1               /* d = d + w d_layer: its displacement adds */
} fp_stack_mode;

/** A region of the face. The weight of a vertex at distance d (mesh units, on the neutral
 *  shape) from the region's vertices (members of a rig region or vertex group: d = 0; the
 *  landmarks' vertices for landmarks) is 1 for d <= core, 1 - smoothstep((d - core) / falloff)
 *  up to core + falloff (C1), 0 beyond; core and falloff in millimetres. */
typedef struct fp_stack_region {
    fp_stack_region_kind kind;
    char name[FP_STACK_NAME_MAX];  /* the preset it came from ("mouth"), "" when none */
    char names[FP_STACK_MAX_NAMES][FP_STACK_NAME_MAX]; /* rig region, landmarks, channels */
    size_t name_count;
    uint32_t *vertices;            /* FP_STACK_REGION_VERTICES: owned by the stack */
    size_t vertex_count;
    double core_mm, falloff_mm;    /* >= 0 each */
} fp_stack_region;

/** One layer. Times in seconds on the stack's clock (the base take's first frame is 0). */
typedef struct fp_stack_layer {
    char take[FP_STACK_PATH_MAX];  /* as in the file: relative to the stack's folder */
    fp_stack_region region;        /* layer 0: FP_STACK_REGION_ALL */
    fp_stack_mode mode;            /* layer 0: FP_STACK_REPLACE */
    double in_s, out_s;            /* the range; out_s INFINITY: to the end */
    double fade_s;                 /* cross-fade at both ends, inside the range; >= 0 */
    double offset_s;               /* the take's first frame on the stack's clock */
    double gain;                   /* 0..2, multiplies the region's weight */
    bool mute, solo;
} fp_stack_layer;

/** A stack as read from a file or being built. */
typedef struct fp_stack {
    size_t layer_count;
    fp_stack_layer layers[FP_STACK_MAX_LAYERS];
    char path[FP_STACK_PATH_MAX];  /* the file it was read from, "" when built */
} fp_stack;

/** True where `path` ends in .fpstack (any case). */
bool fp_stack_is_stack_path(const char *path);

/** A new empty stack (calloc'ed; fp_stack_free) or NULL when out of memory. */
fp_stack *fp_stack_create(void);

/** Parse `len` bytes of JSON (docs/stack.md); `name` starts messages and, as a file path,
 *  becomes stack->path. Checks the structure, types, unknown members, ranges (in <= out,
 *  fade, gain 0..2), one kind per region, a vertex group of at most FP_STACK_MAX_GROUP
 *  indices (counted by its spans' lengths before any is walked or allocated), layer 0 with no
 *  region and replace mode, at most FP_STACK_MAX_LAYERS, nothing but white space after the
 *  object. Returns 0 and *out (fp_stack_free) or -EBADMSG with
 *  "NAME: json.path: reason" ("NAME: byte N: reason" where the text is no JSON object), -ENOMEM. */
int fp_stack_parse(const char *json, size_t len, const char *name, fp_stack **out, char *err,
                   size_t errlen);

/** Read and parse the file at path (fp_stack_parse). Also -ENOENT, -EACCES, -EIO. */
int fp_stack_load(const char *path, fp_stack **out, char *err, size_t errlen);

/** Write s as JSON to path, created with O_EXCL (never over a file: -EEXIST), fsync'ed.
 *  Returns 0 or a negative errno with err naming the file. */
int fp_stack_save(const fp_stack *s, const char *path, char *err, size_t errlen);

/** The JSON text of s (malloc'ed, free() it) or NULL when out of memory. */
char *fp_stack_to_json(const fp_stack *s);

/** Layer i's take as a path to open: the file's "take" joined to the folder of s->path when
 *  relative. Returns 0, or -EINVAL (i out of range) / -ENAMETOOLONG. */
int fp_stack_take_path(const fp_stack *s, size_t i, char *buf, size_t n);

/** The next free DIR/SLATE_SNNN.fpstack (NNN one more than the largest of that slate's stacks
 *  in dir, from 1) into buf. Returns 0, -EINVAL (a bad slate), -ENAMETOOLONG. */
int fp_stack_next_path(const char *dir, const char *slate, char *buf, size_t n);

/** Append a layer (copied, its vertices too). Returns 0, -ENOSPC (FP_STACK_MAX_LAYERS),
 *  -ENOMEM, -EINVAL. */
int fp_stack_append(fp_stack *s, const fp_stack_layer *layer, char *err, size_t errlen);

/** A layer with the defaults: take path copied, region all, replace, in 0, out INFINITY,
 *  fade 0.05 s, offset 0, gain 1. */
void fp_stack_layer_init(fp_stack_layer *l, const char *take);

/** Parse the command line's REGION[:MODE] (`--layer`): REGION is a preset ("mouth",
 *  "brows": landmarks of the rig; "jaw": the channel jaw.open; "all"), rig:NAME,
 *  landmark:NAME[,NAME...], channels:NAME[,NAME...] or vertices:A[-B][,...], each optionally
 *  followed by @FALLOFF_MM (or @CORE_MM+FALLOFF_MM); MODE is replace (default) or add.
 *  Fills *region (its vertices malloc'ed: fp_stack_region_clear) and *mode. Returns 0 or
 *  -EINVAL with a message. */
int fp_stack_layer_spec(const char *spec, fp_stack_region *region, fp_stack_mode *mode,
                        char *err, size_t errlen);

/** Release a region's vertices (the struct itself is the caller's). */
void fp_stack_region_clear(fp_stack_region *region);

/** "mouth (6 landmarks, core 6 mm, falloff 14 mm)", "rig region face", "channels jaw.open",
 *  "all"... into buf. Returns buf. */
const char *fp_stack_region_text(const fp_stack_region *region, char *buf, size_t n);

/* ---- overdub: a new pass on top of a stack or a take (run/live --over) ----------------- */

/** The stack a pass goes over: `over` a .fpstack (loaded) or a take (checked that it opens;
 *  a stack of it alone, its path as given). Returns 0 and *out, or the loader's or reader's
 *  code with err. */
int fp_stack_over_open(const char *over, fp_stack **out, char *err, size_t errlen);

/** Layer i's take path of the stack opened from `over` (the path to open: as
 *  fp_stack_take_path for a stack, `over` itself for a take). Returns 0 or -ENAMETOOLONG. */
int fp_stack_over_take_path(const char *over, const fp_stack *s, size_t i, char *buf, size_t n);

/** Write the overdub's new stack: the layers of `old` (opened from `over`) with their takes'
 *  paths rewritten for dir (a take in dir by its name, others absolute), then `pass` with
 *  take_path, as dir/SLATE_SNNN.fpstack (the next free number; never over a file). path_out
 *  (n bytes) gets its path. Returns 0 or a negative errno with err (-ENOSPC too many layers,
 *  -ENOENT a take gone, the save's). */
int fp_stack_over_save(const char *over, const fp_stack *old, const fp_stack_layer *pass,
                       const char *dir, const char *take_path, const char *slate,
                       char *path_out, size_t n, char *err, size_t errlen);

/** Free the stack (its layers' vertices too) and set *s to NULL. NULL-safe. */
void fp_stack_free(fp_stack **s);

#ifdef __cplusplus
}
#endif
#endif
