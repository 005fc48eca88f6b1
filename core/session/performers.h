/*
 * performers.h: whose hands are whose (issue 55). Each input belongs to one performer: the
 * host's SPEC key `performer=NAME` (core/plugin, fp_input_instance.performer) names it, and
 * inputs without the key belong to the first performer (the first input's). Two right hands
 * from two performers are then two hands: the session keeps a pose state (hands, filters,
 * calibration) and a placement (step_arrive.h) per performer, and the mapping sees the first
 * performer's hands as fp_frame_input.hands and the others' as extra_hands (plugin.h).
 * With one performer (every session without the key) nothing changes: its hands are the
 * session's one pair, as before.
 *
 * Errors: fp_performers_assign returns -EINVAL beyond FP_PERFORMER_CAPACITY performers, the
 * message naming the input's SPEC. Threads: [main-thread] at the session's opening; the
 * lookups are pure. No allocation.
 */
#ifndef FP_PERFORMERS_H
#define FP_PERFORMERS_H

#include "fp_plugin_host.h"

#include <facepuppet/plugin.h>

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

typedef struct fp_performers {
    size_t count;                                          /* 1..FP_PERFORMER_CAPACITY */
    char names[FP_PERFORMER_CAPACITY][FP_PERFORMER_NAME_MAX + 1]; /* "": the unnamed first */
    uint8_t of_input[64];                                  /* each input's performer index */
} fp_performers;

/** Give each of the n inputs (n <= 64) its performer: the first input's performer is the first
 *  (index 0), inputs without a name join it, and each name met for the first time opens the
 *  next index. specs[i] (the inputs' SPEC texts, for the message; may be NULL) names the
 *  input that would open a performer beyond FP_PERFORMER_CAPACITY: -EINVAL, err says so.
 *  Returns 0 (count >= 1, also for n == 0). */
int fp_performers_assign(fp_performers *p, const fp_input_instance *inputs, size_t n,
                         const char *const *specs, char *err, size_t errlen);

/** How a message names performer i: "performer 'NAME'", or for an unnamed first performer
 *  "the first performer" (into buf, len bytes; returned). */
const char *fp_performers_label(const fp_performers *p, size_t i, char *buf, size_t len);

#ifdef __cplusplus
}
#endif
#endif
