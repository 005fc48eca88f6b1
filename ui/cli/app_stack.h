/* Overdub (issue 54 item 2): `run --over STACK_OR_TAKE --layer REGION[:MODE] [--punch IN:OUT]`
 * records the new pass as a take, then writes a new stack (the old one kept) with the pass as
 * its top layer (core/take/fp_stack.h). The commands' side: the options checked before any
 * work, and the stack written after the take is closed. */
#ifndef FP_APP_STACK_H
#define FP_APP_STACK_H

#include "fp_stack.h"

#include <cjson/cJSON.h>

#include <stdbool.h>
#include <stddef.h>

struct fp_session;

/** --over, --layer, --punch as given (strings the caller's argv) and what they parse to. */
typedef struct fp_app_over {
    const char *over;              /* --over: a .fpstack or a take; NULL: no overdub */
    const char *layer;             /* --layer REGION[:MODE] (default mouth:replace) */
    const char *punch;             /* --punch IN:OUT seconds on the stack's clock, or NULL */
    fp_stack *stack;               /* the stack to extend (a take: a stack of it alone) */
    fp_stack_layer new_layer;      /* the pass's layer, take path filled at the end */
} fp_app_over;

/** Check the options before any work: --over needs --take-dir (take_dir), names a stack that
 *  loads or a take that opens; --layer parses; --punch is IN:OUT with 0 <= IN < OUT. Prints
 *  "CMD: ..." and returns the exit status (64 usage, 65 a damaged stack or take, 66 missing),
 *  or 0. --layer or --punch without --over is a usage error. */
int fp_app_over_check(fp_app_over *o, const char *cmd, const char *take_dir);

/** After the session opened: the base take's mesh is the session's (its checksum). Prints
 *  and returns 65 when not, else 0; the message names mesh_path (the session's mesh, as
 *  loaded; NULL: "the loaded mesh") and the take's own mesh. */
int fp_app_over_check_mesh(const fp_app_over *o, const char *cmd, const struct fp_session *s,
                           const char *mesh_path);

/** The pass was recorded as take_path: write DIR/SLATE_SNNN.fpstack (the next free number
 *  for the take's slate; never over a file) with the old layers and the pass on top, and say
 *  it on stderr ("CMD: stack PATH: N layers, top: REGION, MODE"). Returns 0 or the exit
 *  status (73 not written). Frees what o holds either way. */
int fp_app_over_finish(fp_app_over *o, const char *cmd, const char *take_dir,
                       const char *take_path, const char *slate);

/** As fp_app_over_finish without freeing o: one stack for each pass of a run that records
 *  several (run --control: each take started and stopped over OSC). Returns 0 or 73. */
int fp_app_over_save(const fp_app_over *o, const char *cmd, const char *take_dir,
                     const char *take_path, const char *slate);

/** `facepuppet info STACK`: the stack's layers, one a line (take, region, mode, range,
 *  fade, offset, gain, mute/solo, the take's frames and duration or why it cannot be read).
 *  Returns the exit status (65 a malformed stack, 66 missing). */
int fp_app_stack_info(const char *path);

/** `facepuppet takes DIR`: the stacks (*.fpstack) of dir after the takes' table, by name, each
 *  with its layers in one line ("NAME  N layers: TAKE (base); TAKE REGION MODE [IN-OUT]").
 *  Prints nothing when there are none. */
void fp_app_stack_list(const char *dir);

/** `facepuppet takes DIR --json`: the stacks of dir by name, a JSON array of {"kind":
 *  "stack", "path", "state": "ok"|"unreadable", "message", "layers": [{"take", "region",
 *  "mode", "in_s", "out_s" (null: to the end), "fade_s", "offset_s", "gain", "mute",
 *  "solo"}]} (the first layer's region "base"). NULL when out of memory; the caller's. */
cJSON *fp_app_stack_list_json(const char *dir);

/** The soundtrack's offset the base take of --over recorded (where it was made with
 *  --audio): the pass hears the line where the base did. true and *offset_s, else false
 *  (no --over, no soundtrack, a base take that cannot be read). Call after
 *  fp_app_over_check. */
bool fp_app_over_soundtrack_offset(const fp_app_over *o, double *offset_s);

/** Free what o holds (the stack, the layer's vertices). */
void fp_app_over_free(fp_app_over *o);

struct fp_stack_player;
/** After a stack's play or export (cmd "play", "export"): where the blend's fold bound held a
 *  layer back (fp_stack_player_limited: the layer then shows partly, not its frame bit for
 *  bit in its core, docs/stack.md), one line on stderr saying on how many layer frames.
 *  Nothing for NULL, none held back, or quiet. */
void fp_app_stack_limited_note(const char *cmd, const char *path, const struct fp_stack_player *sp, bool quiet);

#endif
