/*
 * step_record.h: step 7 of the frame (docs/architecture.md): the recorder. After the frame,
 * its record (the raw events drained this frame, the requested intents, the control set
 * used, the time and the frame number) goes to the optional sink of fp_session_options (the
 * take recorder of the takes issue pushes it into its lock-free queue). The sink is called on
 * the session thread and must not block or do I/O.
 *
 * The record=FILE recordings of inputs (fp_record.h in core/plugin) are written by threads
 * of their own; this step only watches them: the first error of a recording (a failed
 * write, events dropped) is logged once per input with the input's name as source.
 *
 * Threads: the session thread. The event buffer grows (realloc) until it holds the largest
 * frame seen; nothing else allocates.
 */
#ifndef FP_STEP_RECORD_H
#define FP_STEP_RECORD_H

#include "fp_plugin_host.h"
#include "session_log.h"

struct fp_frame_stats; /* fp_session.h */

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/** One frame as the recorder sees it. Pointers valid during the sink's call only. */
typedef struct fp_frame_record {
    uint64_t frame;                  /* frame number since the session began */
    int64_t time_ns;                 /* the frame's host time (fp_now_ns clock) */
    const fp_event *events;          /* every event drained this frame, in drain order */
    size_t event_count;
    size_t events_lost;              /* events drained but not kept (out of memory) */
    uint32_t requested;              /* fp_intent bits requested (keys, pedal) this frame */
    const fp_control_set *controls;  /* the control set the engine was given (after the rig) */
    const float *reach;              /* the frame's reach per touching vector (skin_reach.h) */
    size_t reach_count;
    double reach_asked_max;          /* their longest ask, mesh units */
    size_t reach_held;               /* of them, those a rig keeps still (the skull, the jaw) */
} fp_frame_record;

/** The sink: called once per frame on the session thread after the frame; must not block,
 *  lock or do I/O. */
typedef void (*fp_frame_record_fn)(void *user, const fp_frame_record *record);

typedef struct fp_record_step {
    fp_frame_record_fn sink;         /* NULL: no frame records are kept */
    void *user;
    fp_event *events;                /* this frame's events (only with a sink) */
    size_t count, capacity, lost;
    bool reported[8];                /* input i's recording error was logged */
} fp_record_step;

/** Start with the sink (may be NULL) and its user pointer. */
void fp_record_step_init(fp_record_step *r, fp_frame_record_fn sink, void *user);
void fp_record_step_free(fp_record_step *r);

/** Forget the last frame's events (start of a frame). */
void fp_record_step_begin(fp_record_step *r);

/** Keep one drained event for this frame's record (nothing without a sink). */
void fp_record_step_event(fp_record_step *r, const fp_event *ev);

/** End of the frame: hand the record to the sink (if any; with the frame's reach from st,
 *  none where st is NULL),
 *  and log the first error of each input's record=FILE recording (n inputs). */
void fp_record_step_end(fp_record_step *r, uint64_t frame, int64_t time_ns, uint32_t requested,
                        const fp_control_set *controls, const struct fp_frame_stats *st,
                        fp_input_instance *inputs, size_t n, const fp_slog *log);

#ifdef __cplusplus
}
#endif
#endif
