/*
 * fp_control_apply.h: the control surface's commands applied to a session between frames
 * (run, live, play). Record start and stop go through the same calls as `run --take-dir`
 * and live's T key (fp_session_take_start / _stop on the command's fp_session_take), with
 * the slate and take number the command names; engage, commit and cancel are requests for
 * the next frame as the keys' (fp_session_request); undo, reset, the radius, the mapping and
 * rig channels as the viewer's keys (fp_session_undo, _reset, _set_radius, _set_mapping,
 * _set_channel); play, stop and seek go to the command's transport (play's take), or are
 * answered "error: no transport" where there is none (run). Every command is answered with
 * the status after it (fp_control_reply); the status is pushed to subscribers when it
 * changes and once a second (fp_control_session_tick).
 *
 * Threads: the frame thread only, between fp_session_step calls.
 */
#ifndef FP_CONTROL_APPLY_H
#define FP_CONTROL_APPLY_H

#include "fp_control.h"
#include "fp_session.h"
#include "fp_session_take.h"

#ifdef __cplusplus
extern "C" {
#endif

/** A transport (play, stop, seek): returns 0 or a negative code with msg. */
typedef int (*fp_control_transport_fn)(void *user, const fp_control_cmd *cmd, char *msg, size_t n);
/** The transport's state word ("playing", "stopped"), or NULL: the session's. st holds the
 *  session's status, which the transport may overwrite: its time (seconds), frame, timecode,
 *  slate and take (play: the played take's at the playhead; strings it points to stay the
 *  transport's and valid until its next call). Called on the frame thread. */
typedef const char *(*fp_control_state_fn)(void *user, fp_control_status *st);
/** A take started (res NULL) or stopped (res: what was recorded, rc its code), for the
 *  command's own lines. */
typedef void (*fp_control_take_fn)(void *user, const fp_session_take *t,
                                   const fp_session_take_result *res, int rc, const char *err);

typedef struct fp_control_session {
    fp_control *ctl;
    fp_session *s;
    fp_session_take *take;            /* NULL: no take folder (record start refused) */
    const fp_plugin_path *plugin_path;/* for /fp/mapping */
    fp_control_transport_fn transport;/* NULL: play/stop/seek refused */
    fp_control_state_fn state;
    fp_control_take_fn on_take;
    void *user;
    int64_t t0_ns;                    /* the session's first frame (status time) */
    /* kept between commands */
    char slate[FP_TAKE_SLATE_MAX];    /* the next take's slate (/fp/slate, /Slate) */
    char rec_slate[FP_TAKE_SLATE_MAX];/* the recording take's (its options point here) */
    uint32_t next_take;               /* the next take's number (/fp/take, /Take); 0: free */
    uint32_t last_take;               /* the last take recorded */
    bool quit;                        /* /fp/quit received */
    uint64_t applied, failed;         /* commands applied; of those, answered with an error */
    /* the last pushed status, to push on a change */
    char pushed_key[160];
    int64_t pushed_ns;
    char tc_buf[32];
} fp_control_session;

/** Zero *cs and set its session, take (may be NULL), plugin path and the default slate. */
void fp_control_session_init(fp_control_session *cs, fp_control *ctl, fp_session *s,
                             fp_session_take *take, const fp_plugin_path *path);

/** Apply every queued command at frame time now_ns (the next frame's), each answered.
 *  Returns how many were applied. */
size_t fp_control_session_apply(fp_control_session *cs, int64_t now_ns, uint64_t frame);

/** After a frame: push the status to subscribers when it changed, or a second after the last
 *  push. */
void fp_control_session_tick(fp_control_session *cs, int64_t now_ns, uint64_t frame);

/** The status at now_ns into *st (its strings in cs, valid until the next call). */
void fp_control_session_status(fp_control_session *cs, int64_t now_ns, uint64_t frame,
                               fp_control_status *st);

#ifdef __cplusplus
}
#endif
#endif
