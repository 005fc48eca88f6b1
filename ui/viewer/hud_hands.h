/* hud_hands.h: the HUD's hands line (live): whose hands are there with several performers,
 * and, with any number, a hand that was there and is gone (its input unplugged, its tracker
 * lost it, its sender quiet), with the input's last word on it, for as long as it is gone.
 * Internal to ui/. Threads: the viewer's (the session's log callback and the drawing, which
 * never run at once: viewer.c). */
#ifndef FP_UI_HUD_HANDS_H
#define FP_UI_HUD_HANDS_H

#include "hud.h"

#include <stdbool.h>
#include <stddef.h>

struct fp_session;

#define FP_HUD_HANDS_PERFORMERS 8   /* performers followed (the session has at most 4) */

typedef struct fp_hud_hands {
    bool seen[FP_HUD_HANDS_PERFORMERS][2];  /* a hand (fp_hand_side) shown at least once */
    char note[FP_HUD_MSG_LEN];              /* the inputs' latest warning, "" none */
    bool was_gone;                          /* a seen hand was absent at the last line */
} fp_hud_hands;

/** A session log line (fp_session_log_fn's level, source, message): kept as the note when it
 *  is a warning or an error (level <= FP_LOG_WARNING) of an input, i.e. source is the name of
 *  one of the input SPECs (inputs[0..n), "osc" for "osc:9000,bind=::"). */
void fp_hud_hands_log(fp_hud_hands *h, const char *const *inputs, size_t n, int level,
                      const char *source, const char *message);

/** The line for the HUD into buf (len bytes, starting "\n"; "" when there is nothing to
 *  say): with several performers "\nhands: first left right, B right"; a hand seen before
 *  and absent now adds "; gone: first left" (one performer: "\nhands: right; gone: left")
 *  and the note, "(osc: left hand: no data from ... for 1 s)". When every hand seen is back
 *  after one was gone, the note is forgotten. Marks the hands present now as seen. */
void fp_hud_hands_line(fp_hud_hands *h, const struct fp_session *s, char *buf, size_t len);

#endif
