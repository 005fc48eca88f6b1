/* overdub.h: a new pass over a stack in the live viewer (internal to ui/viewer; issue 54
 * item 2; docs/stack.md). With `live --over STACK_OR_TAKE --layer REGION[:MODE]`, a take
 * started with T plays the stack from its start under the performer (pre-roll): the window
 * shows the stack's composite with the live session composed on top as the new layer
 * (fp_stack_blend: the region's weights, the mode, the fold bound). I (or the pedal's middle
 * switch while the take records) punches in, again punches out, cross-faded over the
 * layer's fade; T (or the pedal once punched out) stops the take, and a new stack
 * SLATE_SNNN.fpstack is written beside it (fp_stack_over_save; the old one kept) with the
 * pass on top over [in, out] (the whole take when it was never punched in). Lanes above the
 * take strip show each layer (its take, region, range, mute/solo), the pass with its punch
 * points, and the playhead. A channel pass (--layer jaw) shows the live session as it is.
 *
 * Threads: the viewer's. Errors: 0 or a negative errno with a message. */
#ifndef FP_UI_OVERDUB_H
#define FP_UI_OVERDUB_H

#include "fp_stack_player.h"
#include "fp_take_player.h"
#include "render.h"
#include "takes.h"
#include "wave.h"

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

typedef struct fp_voverdub {
    bool enabled;
    const char *over;              /* --over (the caller's string) */
    fp_stack *stack;               /* the stack under (a take: a stack of it alone) */
    fp_stack_layer pass;           /* the pass's region and mode; in/out from the punches */
    fp_take_player *player;        /* while recording: the stack playing under */
    fp_stack_weights wt;           /* the pass's region on the live session's loaded shape */
    float *under, *shown;          /* the stack's frame at the playhead; the composite */
    size_t n;
    bool recording, pending, ended, have_under;
    fp_take_frame next;            /* the player's next frame (pending), not yet due */
    int64_t t0, first_ns;          /* host time the pass began; the stack's first frame time */
    int punch;                     /* 0 pre-roll, 1 punched in, 2 punched out */
    double t, stack_s;             /* playhead and the stack's length, seconds */
    char written[4200];            /* the last stack written ("" none) */
    size_t selected;               /* the layer L selected for M and O (0: none yet) */
} fp_voverdub;

/** Set up from --over and --layer (NULL over: disabled, returns 0). Returns 0, or the stack
 *  loader's / --layer's code with err. */
int fp_voverdub_init(fp_voverdub *o, const char *over, const char *layer, char *err,
                     size_t errlen);
/** Close the playback and free the stack and the pass's region. */
void fp_voverdub_free(fp_voverdub *o);

/** Each frame after the session's step (and once after the last take stopped): a take that
 *  began starts the playback under it; one that ended writes the new stack; while one
 *  records, the stack advances to the playhead and the composite is made. msg gets a line
 *  for the HUD ("" none). */
void fp_voverdub_frame(fp_voverdub *o, fp_vtakes *takes, fp_session *s,
                       const fp_plugin_path *plugins, int64_t now, char *msg, size_t n);

/** I, or the pedal's middle switch while a pass records and is not yet punched out: punch
 *  in, then out. Returns true when it acted (msg says what), false when the pedal should
 *  start or stop the take instead. */
bool fp_voverdub_punch(fp_voverdub *o, int64_t now, char *msg, size_t n);

/** L selects the next layer of the stack (1 .. its top, again from 1), M mutes or unmutes
 *  it, O solos or unsolos it: the stack under the pass plays so from the next frame (while
 *  a take records) and the new stack is written with those states. Returns true when it
 *  acted (msg says what), false without an overdub. */
bool fp_voverdub_layer_key(fp_voverdub *o, char key, char *msg, size_t n);

/** The composite to show while a pass records, else NULL. */
const float *fp_voverdub_shown(const fp_voverdub *o);

/** The lanes above the take strip, one a layer (its range lit, dimmed when muted or off for
 *  another's solo, tagged M / S, its in and out points as white ticks, the selected one
 *  outlined), the pass's with its punch points, and under them the soundtrack's waveform
 *  (wave, when on) on the same time axis. Returns false (nothing drawn) when disabled. */
bool fp_voverdub_draw(const fp_voverdub *o, fp_render *r, int w, int h, const fp_vwave *wave);

/** The top (pixels from the window's top, w x h) of what the bottom of the window holds
 *  now: the take strip with its line of text above (t: when it has a take), the lanes of o
 *  (fp_voverdub_draw) or the soundtrack's lane alone (fp_vwave_draw_lane), and the "? keys"
 *  line under them all; the HUD's messages stop above it. */
float fp_voverdub_bottom_top(const fp_voverdub *o, const fp_vtakes *t, const fp_vwave *wave,
                             int w, int h);

#endif
