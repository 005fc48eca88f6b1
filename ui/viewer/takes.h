/* takes.h: takes in the live viewer (internal to ui/viewer): T (or the pedal's middle
 * button) starts and stops recording (optional countdown), the HUD's red REC with the running
 * timecode and take number, and the review of the last take on a timeline strip at the
 * bottom of the window (takes of this session as blocks, a playhead; P play/pause, the mouse
 * on the strip scrubs, , and . step a frame). Stopping a take leaves the live face and hands
 * shown: the review opens only when asked (V, or P, , . and the strip, which open it too)
 * and is left with V again, Esc or the next engage (fp_vtakes_leave). The review plays the take's stored control
 * sets through a second session on the same mesh (fp_session_play_frame, as `facepuppet
 * play`), so the live session goes on untouched.
 *
 * Once a take is written its review's session is made on a thread of its own (a session of
 * the mesh file takes about half a second, which V used to cost as one frame); V joins it.
 *
 * Threads: the viewer's (the session thread), and that opener's, which touches only its own
 * fp_vtakes_opener until joined. Recording: core/session/fp_session_take.h. */
#ifndef FP_UI_TAKES_H
#define FP_UI_TAKES_H

#include "fp_session_take.h"
#include "fp_viewer.h"
#include "render.h"

#include <pthread.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#define FP_VTAKES_BLOCKS 64

/* The review's session being made on a thread of its own once a take is written (takes.c). */
typedef struct fp_vtakes_opener {
    pthread_t thread;
    bool running;                 /* started and not joined */
    char mesh_path[4096], take_path[4096];
    const fp_plugin_path *plugin_path;
    fp_take_reader *reader;       /* what it made (the thread's until joined) */
    fp_session *rs;
    int rc;
    char err[1100];
} fp_vtakes_opener;

typedef struct fp_vtakes {
    bool enabled;                 /* a take folder was given */
    fp_session_take take;
    double countdown_s;
    int64_t countdown_until;      /* > 0 while counting down to a start */
    /* the review: the last take, played through its own session */
    fp_take_reader *reader;
    fp_session *rs;
    size_t frames, applied;       /* frames in the take; frames applied to rs so far */
    long playhead;                /* frame shown (-1: the live session is shown) */
    bool playing;
    int64_t play_start_ns, play_origin_ns;   /* host time and take time playing began at */
    struct { uint32_t take; uint64_t frames; } blocks[FP_VTAKES_BLOCKS];
    size_t nblocks;
    uint32_t review_take;
    fp_session_take_result last;  /* the last take written, reviewed when asked */
    bool have_last;               /* last holds a take with frames (not found unreadable) */
    char slate[FP_TAKE_SLATE_MAX];
    const fp_viewer_sound *sound; /* the take hooks (fp_viewer.h), or NULL */
    int64_t origin_ns;            /* the take recording's (or the last one's) start */
    fp_vtakes_opener opener;      /* the last take's review, being opened */
    int failed;                   /* the first take not written whole (its write failed: a
                                     full disk, its file deleted): its code, what was said */
    char failed_msg[1200];
} fp_vtakes;

/** Set up: the options' take folder, slate, countdown; puts the record sink into *so (the
 *  session options the viewer creates sessions from). */
void fp_vtakes_init(fp_vtakes *t, const char *dir, const char *slate, double countdown_s,
                    fp_session_options *so);
void fp_vtakes_free(fp_vtakes *t);

/** T or the middle pedal: start (after the countdown) or stop the take; msg gets a line for
 *  the HUD ("" when none). Returns 0 or the recorder's code (msg says why). */
int fp_vtakes_toggle(fp_vtakes *t, fp_session *s, int64_t now, char *msg, size_t n);
/** Each frame before the session's step: a take whose write failed (a full disk, its file
 *  deleted) is stopped at once, msg saying so (fp_vtakes_stop); a countdown that ran out
 *  starts the take; a review that plays advances with the clock. Returns 0 or the failed
 *  take's code. */
int fp_vtakes_tick(fp_vtakes *t, fp_session *s, int64_t now, char *msg, size_t n);
/** Stop a take recording (end of the run). One not written whole is kept in t->failed
 *  (the first such take of the session). */
int fp_vtakes_stop(fp_vtakes *t, fp_session *s, char *msg, size_t n);
/** The first take of the session not written whole: its code (-ENOSPC, -EIO...; a file
 *  deleted while recording: -EIO, an output lost) with its message in err, else 0. The run's
 *  end fails with it (73). */
int fp_vtakes_failed(const fp_vtakes *t, char *err, size_t errlen);

/** The review's shape to show, or NULL (show the live session). */
const float *fp_vtakes_shown(const fp_vtakes *t);
/** Review: P (play/pause), frame step by delta (, and .), scrub to a fraction of the take;
 *  each opens the last take's review first if it is not open. */
void fp_vtakes_play_pause(fp_vtakes *t, int64_t now);
void fp_vtakes_step(fp_vtakes *t, long delta);
void fp_vtakes_scrub(fp_vtakes *t, double fraction);
/** V: open the last take's review paused on its first frame, or leave it when it is shown.
 *  Returns 0, or -ENOENT (no take to review, or it cannot be read). */
int fp_vtakes_review(fp_vtakes *t);
/** Whether a take's frame is shown (fp_vtakes_shown non-NULL). */
bool fp_vtakes_reviewing(const fp_vtakes *t);
/** Leave the review (show the live session again). */
void fp_vtakes_leave(fp_vtakes *t);

/** The strip's rectangle in a w x h framebuffer (pixels from the top left). */
void fp_vtakes_strip_rect(int w, int h, float *x, float *y, float *sw, float *sh);
/** Draw REC / countdown / take number (top right, right of x = left: the badge's row, whose
 *  badge ends there; where the whole line does not fit, a shorter one, "slate take N" or
 *  "take N" when recording, "T: record" else, or none) and the strip (bottom). */
void fp_vtakes_draw(fp_vtakes *t, fp_render *r, int w, int h, int64_t now, float left);

#endif
