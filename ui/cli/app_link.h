/* app_link.h: `--control osc:PORT` and `--stream osc:HOST:PORT` for run, live and play
 * (core/link: fp_control.h, fp_control_apply.h, fp_stream.h; docs/osc.md). The command's frame
 * loop calls fp_app_link_before before each frame (the queued commands applied and answered)
 * and fp_app_link_after after it (status pushed, the frame streamed). Programs print: the
 * lines go to stderr prefixed "facepuppet CMD: ". Built without liblo, both options exit 69. */
#ifndef FP_APP_LINK_H
#define FP_APP_LINK_H

#include "fp_session.h"
#include "fp_session_take.h"

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

typedef struct fp_app_link fp_app_link;

/** What the link is given by the command. Strings are the caller's, kept while it lives. */
typedef struct fp_app_link_options {
    const char *cmd;                   /* "run", "live", "play" */
    const char *control;               /* --control SPEC or NULL */
    const char *stream;                /* --stream SPEC or NULL */
    fp_session *s;
    const char *mesh_path;             /* the session's mesh (the stream's info names it) */
    fp_session_take *take;             /* NULL: no takes (record start answered with an error) */
    const fp_plugin_path *plugin_path; /* /fp/mapping's */
    double fps;                        /* the frame rate (the stream's keyframe period) */
    bool touched;                      /* the stream may read fp_session_touched (no other
                                          caller: run, play; not live, whose viewer does) */
    bool quiet;
} fp_app_link_options;

/** Check the SPECs' syntax before any work: 0 or the exit status (64; 69 without liblo). */
int fp_app_link_check(const char *cmd, const char *control, const char *stream);

/** Open what was asked (a NULL *out when nothing was). Returns 0 or the exit status (said). */
int fp_app_link_open(const fp_app_link_options *o, fp_app_link **out);

/** The session's first frame time (the status's time origin). */
void fp_app_link_origin(fp_app_link *l, int64_t t0_ns);

/** Before frame `frame` at time now_ns: apply and answer the queued commands. */
void fp_app_link_before(fp_app_link *l, int64_t now_ns, uint64_t frame);
/** After the frame: push the status to subscribers, stream the frame. */
void fp_app_link_after(fp_app_link *l, int64_t now_ns, uint64_t frame);
/** The same with the frame's positions (n x 3 floats, mesh units; play: the stack's composite)
 *  and timecode (NULL: the take recording's, else none) given. */
void fp_app_link_after_frame(fp_app_link *l, int64_t now_ns, uint64_t frame, const float *pos,
                             const char *timecode);
/** While no frame is made (play stopped): the status pushed to subscribers when due. */
void fp_app_link_idle(fp_app_link *l, int64_t now_ns, uint64_t frame);
/** The session the commands and the stream read from now on (play's seek reopens it); the
 *  same vertex count. */
void fp_app_link_set_session(fp_app_link *l, fp_session *s);
/** Another session on another mesh (live: a mesh dropped on the window): the control surface
 *  stays as it is (its socket, port and subscribers; its commands and status from now on on
 *  s and take), the stream is closed (its line said) and opened again on s's mesh, named
 *  mesh_path (the caller's, kept), its frame times from t0_ns: a receiver sees a new stream
 *  (seq 0, an info and a keyframe). Returns 0 or the exit status of the stream's opening
 *  (said; the stream is then gone). NULL l: 0. */
int fp_app_link_reopen(fp_app_link *l, fp_session *s, fp_session_take *take, const char *mesh_path,
                       int64_t t0_ns);
/** True once /fp/quit was received. */
bool fp_app_link_quit(const fp_app_link *l);

enum { FP_APP_LINK_PLAY, FP_APP_LINK_STOP, FP_APP_LINK_SEEK };
/** play's transport: fn answers play, stop and seek; state gives its state word and the
 *  playhead: the played take's time (seconds since its first frame), frame (0 at its first),
 *  timecode (NULL: the session's) and slate and take number (NULL slate: the session's),
 *  which the control surface's status reports (docs/osc.md). Strings stay the transport's. */
typedef struct fp_app_link_playhead {
    double time_s;
    uint64_t frame;
    const char *timecode, *slate;
    uint32_t take;
} fp_app_link_playhead;
typedef int (*fp_app_link_transport_fn)(void *user, int kind /* FP_APP_LINK_* */, double seek_s, char *msg, size_t n);
typedef const char *(*fp_app_link_state_fn)(void *user, fp_app_link_playhead *at);
void fp_app_link_set_transport(fp_app_link *l, fp_app_link_transport_fn fn, fp_app_link_state_fn state,
                               void *user);

/** A take the control surface started (res NULL) or stopped (res: what was written): called
 *  after the command's own line, on the frame thread (run: the microphone's WAV beside it). */
typedef void (*fp_app_link_take_fn)(void *user, const fp_session_take *t,
                                    const fp_session_take_result *res);
/** Set (fn NULL: clear) the hook above. NULL l: nothing. */
void fp_app_link_set_take_hook(fp_app_link *l, fp_app_link_take_fn fn, void *user);

/** Close: a line with what the control surface and the stream did (unless quiet). NULL ok. */
void fp_app_link_close(fp_app_link **l);

#endif
