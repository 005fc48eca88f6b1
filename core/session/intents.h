/*
 * intents.h: step 1 of the frame (docs/architecture.md): the inputs' events and the intents.
 * Drains every input's queue (the lock-free MPSC queues of core/plugin), binds pedal buttons
 * to intents (left engages, or commits an engaged deformation; right cancels; middle is
 * reserved for takes and does nothing yet), collects key requests (fp_session_request) into
 * intent bits for the mapping, and turns status events into counts (end of stream per input,
 * errors) and log lines (errors, warnings, disconnects) naming the input's SPEC name.
 * Every drained event is handed to a callback (the session gives it to the pose step and the
 * recorder); button and status events are also kept for the mapping's fp_frame_input.
 *
 * Threads: the session thread only. No allocation, no I/O (log lines go to the callback).
 */
#ifndef FP_INTENTS_H
#define FP_INTENTS_H

#include "fp_plugin_host.h"
#include "session_log.h"

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

#define FP_INTENTS_MAX_INPUTS 8         /* = FP_SESSION_MAX_INPUTS */
#define FP_INTENTS_MAX_FRAME_EVENTS 64
#define FP_INTENTS_HOLD_MAX_NS 50000000 /* 50 ms: a live event stamped later than that is taken */  /* button/status events kept per frame for the mapping */

/** Events taken from an input's queue but not yet consumed (the input clock's lookahead). */
typedef struct fp_intents_ahead {
    fp_event *ev;       /* ring of cap events, malloc()ed on demand */
    size_t head, len, cap;
    bool eos;           /* an END_OF_STREAM status is among them (or was consumed) */
} fp_intents_ahead;

typedef struct fp_intents {
    bool clocked;                           /* consume by time: fp_intents_drain_until */
    bool waited[FP_INTENTS_MAX_INPUTS];     /* inputs on the input clock (recordings) */
    fp_intents_ahead ahead[FP_INTENTS_MAX_INPUTS];
    bool started;                           /* fp_intents_first_time has fixed t0 and the shifts */
    int64_t t0;                             /* the recordings' common time zero */
    int64_t shift[FP_INTENTS_MAX_INPUTS];   /* added to a waited input's times (time zeros aligned) */
    uint32_t requested;                     /* fp_intent bits for the next mapping call */
    bool ended[FP_INTENTS_MAX_INPUTS];      /* input i reported FP_STATUS_END_OF_STREAM */
    unsigned input_errors;                  /* FP_STATUS_ERROR events seen */
    char last_error[128];                   /* the latest one's text */
    fp_event frame_events[FP_INTENTS_MAX_FRAME_EVENTS];  /* this frame's buttons, statuses */
    size_t frame_event_count;
    unsigned record_toggles;                /* middle pedal presses: start/stop a take */
} fp_intents;

/** Called for every drained event, in queue order per input, inputs in index order. */
typedef void (*fp_intents_event_fn)(void *user, size_t input, const fp_event *ev);

/** Zero the state (no request, no input ended). */
void fp_intents_init(fp_intents *it);

/** Request intents (fp_intent bits) for the next mapping call; bits accumulate. */
void fp_intents_request(fp_intents *it, uint32_t intents);

/** The pedal binding for one button event: on a press, left requests COMMIT when `engaged`
 *  (a deformation is active) and ENGAGE otherwise; right requests CANCEL; middle counts a
 *  record toggle (start/stop a take: fp_session_record_toggles); FP_BUTTON_REQUEST requests
 *  its mask's fp_intent bits (a take performed again); releases request nothing. */
void fp_intents_bind_button(fp_intents *it, const fp_event_button *b, bool engaged);

/** Take one event from input `input` named `name`: buttons through the binding, statuses
 *  into the counts (END_OF_STREAM marks the input ended; ERROR counts and keeps its text) and
 *  a log line for ERROR (FP_LOG_ERROR), WARNING and DISCONNECTED (FP_LOG_WARNING) with the
 *  status text and source `name`. Buttons and statuses are kept for the frame (up to
 *  FP_INTENTS_MAX_FRAME_EVENTS; later ones are not kept). Other events are ignored here. */
void fp_intents_take(fp_intents *it, size_t input, const char *name, const fp_event *ev,
                     bool engaged, const fp_slog *log);

/** One frame's step 1: forget the last frame's kept events, then pop every event of the n
 *  inputs (fp_input_instance_poll), take each (fp_intents_take) and hand it to each(user,
 *  input, event) when each is not NULL. Returns the number of events drained. */
size_t fp_intents_drain(fp_intents *it, fp_input_instance *inputs, size_t n, bool engaged,
                        const fp_slog *log, fp_intents_event_fn each, void *user);

/** The input clock (a headless run): like fp_intents_drain, but from each input only the
 *  events stamped at or before t (time_ns) are consumed, in order; the first later one stays
 *  in the lookahead for a later frame. For an input not waited for (live), an event stamped
 *  more than FP_INTENTS_HOLD_MAX_NS beyond the host clock now is taken at once (its clock is
 *  not the host's), and what it has not queued yet is not waited for.
 *  Returns the number of events consumed. Allocation: the lookahead grows as needed (an
 *  event that finds no memory stays in its queue). */
size_t fp_intents_drain_until(fp_intents *it, fp_input_instance *inputs, size_t n, int64_t t,
                              bool engaged, const fp_slog *log, fp_intents_event_fn each, void *user);

/** True when every waited input has ended or has delivered an event stamped later than t, so
 *  that fp_intents_drain_until(t) misses nothing whatever the inputs' pacing. Moves queued
 *  events into the lookahead (consumes none). */
bool fp_intents_ready(fp_intents *it, fp_input_instance *inputs, size_t n, int64_t t);

/** Whether waited input i has ended or delivered past t, as fp_intents_ready last found
 *  (it fetches; this does not). True for an input not waited for. */
bool fp_intents_input_ready(const fp_intents *it, size_t i, int64_t t);

/** The recordings' common time zero: once each waited input has delivered its first event
 *  (or ended), the earliest of those first events' times, 1 and *t0; 0 while one has not yet;
 *  -1 when none is waited for (or all ended empty). A recording's first event marks its time
 *  zero (plugin.h, FP_EXT_INPUT_CLOCK: a replay's start status): from then on each waited
 *  input's event times are shifted so that its time zero is *t0, so several recordings (and
 *  one forwarded from another session) start together whatever the order and latency their
 *  threads started with (a run is then the same whichever input started first). */
int fp_intents_first_time(fp_intents *it, fp_input_instance *inputs, size_t n, int64_t *t0);

/** Free the lookahead buffers. */
void fp_intents_free(fp_intents *it);

/** Hand the requested intents to the mapping: returns them and clears the request. */
uint32_t fp_intents_take_requested(fp_intents *it);

/** True when n > 0 and every one of the n inputs has ended. */
bool fp_intents_all_ended(const fp_intents *it, size_t n);

#ifdef __cplusplus
}
#endif
#endif
