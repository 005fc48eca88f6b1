/* The session: fp_session_step as the frame's seven steps (shared/docs/design.md "One
 * frame"; each step is a module of its own), real-time memory, the queries and edits,
 * destruction. Opening: session_open.c; the mapping: session_mapping.c. */
#define _GNU_SOURCE
#include "session_internal.h"

#include "fp_vec.h"

#include "csrbf.h"
#include "fp_clock.h"
#include "fp_plugin_crash.h"
#include "step_commit.h"

#include <errno.h>
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#if defined(__GLIBC__)
#include <malloc.h> /* mallopt: fp_session_realtime_memory */
#endif
#include <sys/mman.h> /* madvise: fp_session_realtime_memory */

_Static_assert(FP_INTENTS_MAX_INPUTS == FP_SESSION_MAX_INPUTS, "one input limit");
_Static_assert(FP_HISTORY_LEVELS == FP_SESSION_UNDO_LEVELS, "one undo depth");

_Static_assert(FP_ENGINE_MAX_CONTROL >= FP_CONTROL_CAPACITY, "the engine takes a full control set");

/* ---- real-time memory ------------------------------------------------------------------ */

/* Real-time memory (fp_session.h). A page fault took about 10 us on the 2-core VM
 * (a first write to fresh anonymous pages, 64 at a time); before this the ICT replay's
 * renewing and committing frames took 1 to 9 each (the undo level's arrays growing, the
 * contact guard's renewed lists), and they were its slowest frames. glibc's malloc gives
 * freed memory back to the system (trim, munmap of large chunks) and maps new memory for
 * growth (brk, mmap, a thread's own arena); with these settings it keeps what it has, serves
 * large blocks from the heap and one arena, so the reserve touched here is what a frame's
 * allocations reuse. */
#define FP_RT_RESERVE_BASE (32u << 20)  /* bytes: the reserve, at least */
#define FP_RT_RESERVE_PER_VERTEX 32u    /* bytes a vertex more (an undo level of the whole
                                           mesh is 12 a vertex, with its pieces' list) */
#define FP_RT_BLOCK 4096u               /* bytes: the reserve's blocks */
#define FP_RT_STACK (512u << 10)        /* bytes of the calling thread's stack touched */

/* The process's code mapped in (MADV_POPULATE_READ, Linux 5.14, on every executable file
 * mapping: the program, the libraries, the plugins loaded): a code page first run in a frame
 * (a gesture's first contact check) faults otherwise. Best effort: without /proc or that
 * advice the first run of a page still faults. */
static void populate_code(void)
{
#if defined(MADV_POPULATE_READ)
    FILE *f = fopen("/proc/self/maps", "re");
    if (!f) return;
    char line[4352];
    while (fgets(line, sizeof line, f)) {
        unsigned long lo, hi;
        char perm[8];
        int path_at = 0;
        if (sscanf(line, "%lx-%lx %7s %*s %*s %*s %n", &lo, &hi, perm, &path_at) < 3 || !path_at) continue;
        if (strcmp(perm, "r-xp") || line[path_at] != '/' || hi <= lo) continue; /* a file's code */
        (void)madvise((void *)lo, hi - lo, MADV_POPULATE_READ);
    }
    fclose(f);
#endif
}

/* FP_RT_STACK bytes of this thread's stack below the caller's frame written (not inlined:
 * its array is the stack touched) */
static __attribute__((noinline)) void touch_stack(void)
{
    volatile unsigned char pad[FP_RT_STACK];
    for (size_t i = 0; i < sizeof pad; i += 1024) pad[i] = 0;
}

int fp_session_realtime_memory(fp_session *s, size_t reserve_bytes, char *err, size_t errlen)
{
    if (!s) {
        if (err && errlen) snprintf(err, errlen, "real-time memory: no session");
        return -EINVAL;
    }
#if defined(__GLIBC__)
    if (!reserve_bytes) reserve_bytes = FP_RT_RESERVE_BASE + FP_RT_RESERVE_PER_VERTEX * s->n;
    if (!mallopt(M_TRIM_THRESHOLD, INT_MAX) || !mallopt(M_MMAP_MAX, 0) || !mallopt(M_ARENA_MAX, 1)) {
        if (err && errlen) snprintf(err, errlen, "real-time memory: the C library refused a malloc setting (mallopt)");
        return -ENOTSUP;
    }
    /* in blocks, so that free memory inside the heap that nothing wrote yet (calloc's fresh
     * pages, blocks freed untouched: glibc serves a request from those before its top) is
     * written too, then the top */
    size_t nb = (reserve_bytes + FP_RT_BLOCK - 1) / FP_RT_BLOCK, got = 0;
    volatile unsigned char **b = malloc(nb * sizeof *b);
    while (b && got < nb && (b[got] = malloc(FP_RT_BLOCK))) {
        b[got][0] = 0; /* a block spans two pages at most */
        b[got++][FP_RT_BLOCK - 1] = 0;
    }
    bool whole = b && got == nb;
    while (got > 0) free((void *)b[--got]);
    free(b);
    if (!whole) {
        if (err && errlen) snprintf(err, errlen, "real-time memory: out of memory for a reserve of %zu MiB", reserve_bytes >> 20);
        return -ENOMEM;
    }
    touch_stack();
    populate_code();
    return 0;
#else
    (void)reserve_bytes;
    if (err && errlen) snprintf(err, errlen, "real-time memory: not supported by this C library (glibc only)");
    return -ENOTSUP;
#endif
}

/* ---- one frame ------------------------------------------------------------------------- */

/* Every drained event: to the pose step (through its input's filter) and, raw, to the
 * frame's record. */
static void on_event(void *user, size_t input, const fp_event *ev)
{
    fp_session *s = user;
    size_t p = input < s->input_count ? s->performers.of_input[input] : 0; /* whose hands */
    int h = ev->header.hand;
    unsigned long jumps = h == FP_HAND_LEFT || h == FP_HAND_RIGHT ? s->pose[p].hands[h].jumps : 0;
    int64_t sample = h == FP_HAND_LEFT || h == FP_HAND_RIGHT ? s->pose[p].hands[h].time_ns : 0;
    fp_pose_take_event_filtered(&s->pose[p], ev, input < s->input_count ? &s->inputs[input].filter : NULL);
    if (p == 0 && (h == FP_HAND_LEFT || h == FP_HAND_RIGHT) && s->pose[0].hands[h].time_ns != sample)
        s->hand_since_ns[h] = !s->intents.clocked && input < s->input_count /* (its pop, just now) */
                                  ? s->inputs[input].queue.popped_since_ns : ev->header.time_ns;
    if ((h == FP_HAND_LEFT || h == FP_HAND_RIGHT) && s->pose[p].hands[h].jumps != jumps) {
        const char *src = input < s->input_count ? s->inputs[input].name : NULL;
        fp_slog_repeat_report(&s->jump_report, &s->log, FP_LOG_WARNING, src ? src : "input", -ERANGE,
                              "the %s hand jumped farther and faster than a hand moves (fp_pose.h "
                              "FP_POSE_JUMP_MM): taken as the tracker losing it and finding it "
                              "elsewhere, so a gesture it held let go there",
                              h == FP_HAND_LEFT ? "left" : "right");
    }
    fp_arrive_step_event(&s->arrive[p], ev); /* (raw: the placement's estimate is robust anyway) */
    fp_record_step_event(&s->record, ev);
    if (ev->header.type == FP_EVENT_CHANNEL) { /* an input drives a rig channel (ABI 1.2) */
        char name[sizeof ev->channel.name];
        snprintf(name, sizeof name, "%.*s", (int)sizeof name - 1, ev->channel.name);
        if (fp_rig_step_set_channel(&s->rig, name, ev->channel.value) && !s->channel_event_warned) {
            s->channel_event_warned = true;
            const char *src = input < s->input_count ? s->inputs[input].name : NULL;
            fp_slog_printf(&s->log, FP_LOG_WARNING, src ? src : "input",
                           "channel '%s' is not a channel of the session's rig (or there is no "
                           "rig): its events are ignored", name);
        }
    }
}

/* What changed where the contact guard's shape is shown now or was last frame (was). Each
 * shape shown differs from the reference (the posed base; its own changes are recorded where
 * they happen) only where it may: the guard's shape at its D_P (fp_cg_ranges), the engine's
 * output (or the rig's blend of it, or the reference) in the engine's ranges, which hold last
 * frame's too. So the change lies in the engine's ranges (added by the caller), the D_P now
 * when the guard's shape is shown and the one kept at its last showing (guard_dp). */
static void changed_guard(fp_session *s, int was)
{
    if (was == SHOWN_OTHER) fp_changed_add(&s->shown_changed, s->guard_dp, s->guard_dp_n);
    if (s->shown_kind != SHOWN_OTHER) return;
    const uint32_t *gr = NULL;
    size_t ng = s->shown_changed.tracking ? fp_cg_ranges(&s->cg, NULL, 0, &gr) : SIZE_MAX;
    if (ng != SIZE_MAX && ng > s->guard_dp_cap) {
        uint32_t *grown = realloc(s->guard_dp, 2 * ng * sizeof *grown);
        if (grown) s->guard_dp = grown, s->guard_dp_cap = ng;
        else ng = SIZE_MAX; /* (anything: always correct) */
    }
    if (ng != SIZE_MAX && ng) memcpy(s->guard_dp, gr, 2 * ng * sizeof *gr);
    s->guard_dp_n = ng;
    fp_changed_add(&s->shown_changed, s->guard_dp, ng);
}

/* Step 5's shape: the engine's output through the rig's blend, checked by the contact guard
 * (step_contact.h), shown; what changed since the last frame (was: what it showed) */
static void show_deformed(fp_session *s, bool commit, int was, fp_frame_stats *st)
{
    const float *ref = s->shown; /* the posed base */
    const uint32_t *touched;
    int64_t t0 = fp_now_ns();
    size_t ntouched = fp_engine_step_touched(&s->engine, &touched);
    fp_sheet_bind_apply(&s->bind, ref, s->deformed, touched, ntouched);
    s->shown = fp_rig_step_finish(&s->rig, s->deformed, touched, ntouched);
    /* (shown is the rig's buffer or deformed: the session's own, writable) */
    fp_crack_apply(&s->crack, s->mesh->triangles, ref, (float *)s->shown);
    st->stage_ms[FP_STAGE_SHAPE] += (double)(fp_now_ns() - t0) / 1e6;
    const fp_cg_frame f = {.ref = ref, .shown = s->shown, .commit = commit, .rig = &s->rig, .base = s->base,
                           .deformed = s->deformed, .touched = touched, .ntouched = ntouched,
                           .radius = s->radius};
    s->shown = fp_cg_run(&s->cg, &f, &s->log, st);
    /* the output differs from the last only in the engine's ranges (blocks in a support now
     * or at its last run), and the guard's D_P where its shape is or was shown */
    s->shown_kind = fp_cg_shows(&s->cg, s->shown) ? SHOWN_OTHER : SHOWN_ENGINE;
    fp_changed_add(&s->shown_changed, touched, ntouched);
    if (s->shown_kind == SHOWN_OTHER || was == SHOWN_OTHER) changed_guard(s, was);
}

/* Every start point of cs lies on skin the rig keeps still: its nearest vertex (within
 * FP_REACH_TOUCH x R) has mobility under FP_SESSION_STILL_MOBILITY. False without a rig, an
 * empty set, or a start point off the skin (a grab the rig does not hold). */
static bool on_still_skin(const fp_session *s, const fp_control_set *cs)
{
    if (!s->rig.rig || !s->engine.points || csrbf_points_count(s->engine.points) != s->rig.n) return false;
    size_t n = cs->count < FP_ENGINE_MAX_CONTROL ? cs->count : FP_ENGINE_MAX_CONTROL;
    if (!n || !(cs->radius > 0)) return false;
    const float *mobility = fp_rig_mobility(s->rig.rig);
    float dist[FP_ENGINE_MAX_CONTROL];
    uint32_t idx[FP_ENGINE_MAX_CONTROL];
    if (!mobility || csrbf_points_nearest(s->engine.points, &cs->start[0][0], n,
                                          (float)(FP_REACH_TOUCH * cs->radius), dist, idx) < 0)
        return false;
    for (size_t i = 0; i < n; i++)
        if (idx[i] >= s->rig.n || !(mobility[idx[i]] < FP_SESSION_STILL_MOBILITY)) return false;
    return true;
}

/* Steps 5 and 6 on the control set the engine is given (after the rig's clamp), on the
 * posed base: evaluate, the rig's mobility blend, show, commit. Shared by fp_session_step
 * and fp_session_apply_controls (takes played back). */
/* cs: what the engine gets (the rig's clamped copy); asked: what the mapping asked for, the
 * reach's measure (the same start points) */
static void engine_and_history(fp_session *s, const fp_control_set *cs, const fp_control_set *asked,
                               fp_frame_stats *st)
{
    int was = s->shown_kind;
    const uint32_t *ranges;
    s->shown = fp_rig_step_posed(&s->rig, s->base);
    s->shown_kind = SHOWN_POSED;
    if (cs->active && cs->count > 0) {
        fp_engine_result er;
        int rc = fp_engine_step_run(&s->engine, cs, s->deformed, &er, &s->log);
        st->refactored = er.refactored;
        st->pairs = er.pairs;
        st->update_ms = er.update_ms;
        st->stage_ms[FP_STAGE_SOLVE] = er.update_ms - er.eval_ms;
        st->stage_ms[FP_STAGE_EVALUATE] = er.eval_ms;
        st->control_vectors = cs->count;
        st->guard_bound = er.bound;
        st->guard_clusters = er.clusters;
        st->guard_limited = er.clusters_limited;
        st->guard_substeps = er.substeps;
        st->guard_reached = er.reached;
        s->shown_substeps = er.substeps;
        st->min_det_j = er.min_det_j;
        if (rc) s->rig.shown_valid = false; /* the output buffer may have changed unseen */
        if (!rc) {
            st->active = true;
            const float *posed = s->shown;
            show_deformed(s, (cs->intents & FP_INTENT_COMMIT) != 0, was, st);
            /* how far the skin followed the fingertips (skin_reach.h) */
            int64_t t0 = fp_now_ns();
            const float *mobility = s->rig.rig && csrbf_points_count(s->engine.points) == s->rig.n
                                        ? fp_rig_mobility(s->rig.rig) : NULL;
            fp_skin_reach_frame(s->engine.points, posed, s->shown, asked, s->rig.rig ? cs : NULL, mobility,
                                st, &s->gesture_reach, &s->gesture_reach_allowed);
            st->stage_ms[FP_STAGE_SHAPE] += (double)(fp_now_ns() - t0) / 1e6;
            if (cs->intents & FP_INTENT_COMMIT) fp_commit_step_run(s, st);
        } else {
            fp_changed_all(&s->shown_changed); /* the posed base again, after an error */
            fp_cg_shown_ref(&s->cg); /* the engine failed: the posed base is shown */
        }
    } else {
        /* the posed base: where the engine's last output or the guard's shape differed
         * from it, if shown */
        if (was == SHOWN_OTHER)
            fp_changed_add(&s->shown_changed, s->guard_dp, s->guard_dp_n);
        else if (was == SHOWN_ENGINE)
            fp_changed_add(&s->shown_changed, ranges, fp_engine_step_touched(&s->engine, &ranges));
        fp_history_end_gesture(&s->history);
        fp_engine_step_end_gesture(&s->engine, &s->log);
        fp_skin_reach_gesture_end(&s->gesture_reach, &s->gesture_reach_allowed, s->head.mm_per_unit, &s->log);
        fp_cg_end_gesture(&s->cg, &s->log);
        if (s->flip_widened > 1.0)
            fp_slog_printf(&s->log, FP_LOG_INFO, FP_SLOG_CONTACT,
                           "contact guard widened the support %.3gx this gesture, so a long drag "
                           "turned the skin around less", s->flip_widened);
        s->flip_widened = 1.0;
        fp_cg_shown_ref(&s->cg);
    }
    s->engaged = cs->active && !(cs->intents & (FP_INTENT_COMMIT | FP_INTENT_CANCEL));
    s->engaged_still = s->engaged && on_still_skin(s, cs);
}

static void step_frame(fp_session *s, int64_t now_ns, fp_frame_stats *st);

/* fp_session_step's arguments, for the frame thread */
typedef struct frame_call {
    fp_session *s;
    int64_t now_ns;
    fp_frame_stats *st;
} frame_call;

static void frame_call_run(void *u)
{
    frame_call *f = u;
    step_frame(f->s, f->now_ns, f->st);
}

void fp_session_step(fp_session *s, int64_t now_ns, fp_frame_stats *st)
{
    fp_frame_stats local;
    if (!st) st = &local;
    frame_call f = {s, now_ns, st};
    bool there = fp_frame_thread_run(s->ft, frame_call_run, &f,
                                      s->frame_thread_opt == 2 ? 1000000000
                                                               : FP_FRAME_THREAD_GRACE_NS) == 1;
    st->frame_thread = there;
}

/* The face's frame a mapping is given (fp_frame_input.face_*): where the face is turned
 * (fp_calibration.face), the frame the hands are placed in and turned with (the rig's axes,
 * or --up/--facing, which win); else the rig's axes; else +x, +y, +z (fp_head.h). A mapping
 * that reads a hand's motion in the performer's axes (onehand) reads it along these. */
static void frame_face_axes(const fp_session *s, fp_frame_input *in)
{
    double x[3] = {1, 0, 0}, y[3] = {0, 1, 0}, z[3] = {0, 0, 1}, l[3], u[3], f[3];
    if (s->canon) { /* (the face's frame is set) */
        fp_qrot(s->face, x, l);
        fp_qrot(s->face, y, u);
        fp_qrot(s->face, z, f);
        for (int i = 0; i < 3; i++)
            in->face_left[i] = (float)l[i], in->face_up[i] = (float)u[i], in->face_forward[i] = (float)f[i];
    } else if (s->rig.rig) {
        fp_rig_axes(s->rig.rig, in->face_up, in->face_forward, in->face_left);
    } else {
        in->face_up[1] = 1.f; /* the project's convention (fp_head.h) */
        in->face_forward[2] = 1.f;
        in->face_left[0] = 1.f;
    }
}

/* One frame (fp_session_step), on the frame thread or the caller's. */
static void step_frame(fp_session *s, int64_t now_ns, fp_frame_stats *st)
{
    memset(st, 0, sizeof *st);
    st->frame = s->frame;
    st->guard_reached = 1.0;
    st->min_det_j = NAN;
    st->collide_t = st->collide_kept = 1.0;

    int64_t tick = fp_now_ns(), tock;
#define FP_STAGE_END(stage)                                                                   \
    (tock = fp_now_ns(), st->stage_ms[stage] += (double)(tock - tick) / 1e6, tick = tock)
    /* 1: inputs and intents. */
    fp_record_step_begin(&s->record);
    st->events = s->intents.clocked
                     ? fp_intents_drain_until(&s->intents, s->inputs, s->input_count, now_ns,
                                              s->engaged, &s->log, on_event, s)
                     : fp_intents_drain(&s->intents, s->inputs, s->input_count, s->engaged,
                                        &s->log, on_event, s);
    for (size_t i = 0; i < s->input_count; i++) /* (one load each when none logged) */
        fp_input_instance_drain_log(&s->inputs[i]);
    FP_STAGE_END(FP_STAGE_EVENTS);
    /* 2: hand poses in mesh units, at the frame's time (a live input's placement refined
     * first). */
    fp__session_performers_build(s, now_ns); /* (each performer's) */
    FP_STAGE_END(FP_STAGE_HANDS);

    /* 3: the mapping. */
    fp_frame_input in;
    memset(&in, 0, sizeof in);
    in.size = sizeof in;
    in.time_ns = now_ns;
    in.frame = s->frame;
    in.events = s->intents.frame_events;
    in.event_count = s->intents.frame_event_count;
    in.mesh = &s->view;
    in.radius = s->radius;
    in.touch_radius = s->touch_radius;
    in.requested = fp_intents_take_requested(&s->intents);
    in.mm_per_unit = s->head.mm_per_unit;
    frame_face_axes(s, &in);
    in.rig = fp_rig_step_view(&s->rig);
    const float *surface = fp_rig_step_posed(&s->rig, s->base); /* what the fingers touch */
    s->view.base = surface;
    /* on its base (the posed surface), within the fingers' reach only (plugin.h); the index
     * first takes a commit of the last frame */
    fp_engine_step_sync(&s->engine);
    /* the hands and their distances: the first performer's, then the others' (extra_*) */
    fp__session_performers_frame(s, &in, (float)(FP_TIP_DISTANCE_REACH * fmax(s->radius, s->touch_radius)));
    FP_STAGE_END(FP_STAGE_DISTANCES);
    if (s->cs_asked_radius > 0) s->cs.radius = s->cs_asked_radius, s->cs_asked_radius = 0; /* (widened) */
    fp_mapping_step_run(&s->mapping_step, s->mapping, s->mapping_name, &in, &s->cs, &s->log);
    fp_mapping_host_drain_log(&s->mapping_host); /* (one load when it logged nothing) */
    fp__session_performers_check(s, now_ns, &in);
    st->engaged = s->cs.intents & FP_INTENT_ENGAGE;
    if (s->cs.intents & FP_INTENT_CANCEL) {
        st->cancelled = true;
        s->cs.active = false;
    }

    /* 4: the rig: channels pose the base; the engine works on the posed base. */
    if (fp_rig_step_update(&s->rig, &s->cs, s->base, &s->log)) {
        fp_engine_step_set_base(&s->engine, fp_rig_step_posed(&s->rig, s->base));
        fp_changed_all(&s->shown_changed);
        fp_cg_reference_changed(&s->cg, NULL, SIZE_MAX);
    }
    /* a gesture the guard held back for flips alone runs widened (step_contact.h); not on a
     * rig, whose clamp bounds each push toward a bone within the mapping's support */
    double asked_radius = s->cs.radius;
    if (s->cs.active && s->flip_widen > 1.0 && !s->rig.rig) {
        s->cs.radius = asked_radius * s->flip_widen;
        s->cs_asked_radius = asked_radius; /* (given back to the mapping before its next call) */
    }
    const fp_control_set *cs = fp_rig_step_run(&s->rig, &s->cs);
    FP_STAGE_END(FP_STAGE_MAPPING);

    /* 5: the engine. 6: history. The reach is measured against the mapping's own set: a rig's
     * clamp is part of what holds the skin back. */
    engine_and_history(s, cs, &s->cs, st);
    st->flip_widen = asked_radius > 0 ? s->cs.radius / asked_radius : 1.0;
    if (st->flip_widen > s->flip_widened) s->flip_widened = st->flip_widen;
    s->flip_widen = s->engaged && !s->rig.rig ? fp_cg_next_widen(s->flip_widen, st) : 1.0;

#undef FP_STAGE_END
    /* 7: the recorder. */
    fp_record_step_end(&s->record, s->frame, now_ns, in.requested | s->actions, cs, st, s->inputs,
                       s->input_count, &s->log);
    s->actions = 0;
    s->frame++;
}

void fp_session_apply_controls(fp_session *s, int64_t now_ns, const fp_control_set *cs,
                               uint32_t requested, fp_frame_stats *st)
{
    fp_frame_stats local;
    if (!st) st = &local;
    memset(st, 0, sizeof *st);
    st->frame = s->frame;
    st->collide_t = st->collide_kept = 1.0;
    st->flip_widen = 1.0; /* (the stored radius is the engine's) */
    fp_record_step_begin(&s->record);
    st->engaged = cs->intents & FP_INTENT_ENGAGE;
    st->cancelled = cs->intents & FP_INTENT_CANCEL;
    /* 4: the rig poses the base from the stored channels; the stored set is already the
     * one the rig's clamp returned, so it goes to the engine as it is. */
    if (fp_rig_step_update(&s->rig, cs, s->base, &s->log)) {
        fp_engine_step_set_base(&s->engine, fp_rig_step_posed(&s->rig, s->base));
        fp_changed_all(&s->shown_changed);
        fp_cg_reference_changed(&s->cg, NULL, SIZE_MAX);
    }
    /* the stored set is the rig's cut of what the fingertips asked: the reach is against it */
    s->gesture_reach.played = s->rig.rig != NULL;
    engine_and_history(s, cs, cs, st);
    fp_record_step_end(&s->record, s->frame, now_ns, requested | s->actions, cs, st, s->inputs,
                       s->input_count, &s->log);
    s->actions = 0;
    s->frame++;
}

/* ---- queries and edits ------------------------------------------------------------------ */

int fp_session_input_start(fp_session *s, int64_t *t0)
{
    return fp_intents_first_time(&s->intents, s->inputs, s->input_count, t0);
}

bool fp_session_inputs_ready(fp_session *s, int64_t t)
{
    return !s->intents.clocked || fp_intents_ready(&s->intents, s->inputs, s->input_count, t);
}

size_t fp_session_inputs_waiting(fp_session *s, int64_t t, char *names, size_t n)
{
    size_t count = 0, len = 0;
    if (n) names[0] = '\0';
    for (size_t i = 0; i < s->input_count; i++) {
        fp_input_instance_drain_log(&s->inputs[i]); /* (what it says while nothing steps) */
        if (!s->intents.clocked || fp_intents_input_ready(&s->intents, i, t)) continue;
        if (len < n) len += (size_t)snprintf(names + len, n - len, "%s'%s'", count ? ", " : "", s->inputs[i].name);
        count++;
    }
    return count;
}

bool fp_session_finished(const fp_session *s) { return fp_intents_all_ended(&s->intents, s->input_count); }

void fp_session_request(fp_session *s, uint32_t intents) { fp_intents_request(&s->intents, intents); }

unsigned fp_session_record_toggles(fp_session *s)
{
    unsigned n = s->intents.record_toggles;
    s->intents.record_toggles = 0;
    return n;
}
const float *fp_session_positions(const fp_session *s) { return s->shown; }
const float *fp_session_base(const fp_session *s) { return s->base; }

size_t fp_session_touched(fp_session *s, const uint32_t **ranges)
{
    return fp_changed_take(&s->shown_changed, ranges);
}

size_t fp_session_base_touched(fp_session *s, const uint32_t **ranges)
{
    return fp_changed_take(&s->base_changed, ranges);
}
const float *fp_session_loaded(const fp_session *s) { return s->loaded; }
size_t fp_session_vertex_count(const fp_session *s) { return s->n; }
const struct fp_mesh *fp_session_mesh(const fp_session *s) { return s->mesh; }
double fp_session_radius(const fp_session *s) { return s->radius; }
const fp_calibration *fp_session_calibration(const fp_session *s) { return &s->pose[0].calib; }
const fp_calibration *fp_session_performer_calibration(const fp_session *s, size_t performer)
{
    return performer < s->performers.count ? &s->pose[performer].calib : NULL;
}
const fp_head *fp_session_head(const fp_session *s) { return &s->head; }

void fp_session_face_axes(const fp_session *s, float up[3], float facing[3])
{
    double y[3] = {0, 1, 0}, z[3] = {0, 0, 1}, a[3] = {0, 1, 0}, b[3] = {0, 0, 1};
    if (s->canon) { /* (the face's frame is set) */
        fp_qrot(s->face, y, a);
        fp_qrot(s->face, z, b);
    }
    for (int i = 0; i < 3; i++) up[i] = (float)a[i], facing[i] = (float)b[i];
}
const fp_control_set *fp_session_control_set(const fp_session *s) { return &s->cs; }

const struct csrbf_solver *fp_session_solver(const fp_session *s)
{
    /* not when the contact guard scaled the shape back: the solver's map is not what is shown */
    return s->shown != s->base && !fp_cg_shows(&s->cg, s->shown) && !s->rig.rig && s->shown_substeps <= 1
               ? fp_engine_step_solver(&s->engine) : NULL;
}

int fp_session_warp_parts(const fp_session *s, const float **surface, const struct csrbf_solver **solver)
{
    *surface = fp_rig_step_posed(&s->rig, s->base);
    *solver = NULL;
    if (s->shown == *surface) return 0;
    if (s->shown_kind != SHOWN_ENGINE) return -EAGAIN;
    if (s->shown_substeps > 1) return -ERANGE; /* one map's coefficients do not make it */
    *solver = fp_engine_step_solver(&s->engine);
    return *solver ? 0 : -EAGAIN;
}

int fp_session_surface_nearest(const fp_session *s, const float (*points)[3], size_t count,
                               float max_distance, fp_surface_hit *out)
{
    if (!s) return -EINVAL;
    return fp_engine_step_surface(&s->engine, fp_rig_step_posed(&s->rig, s->base), points, count,
                                  max_distance, out);
}

const struct fp_rig *fp_session_rig(const fp_session *s) { return s->rig.rig; }
const char *fp_session_rig_how(const fp_session *s) { return s->rig_how; }

int fp_session_set_channel(fp_session *s, const char *name, double value)
{
    return fp_rig_step_set_channel(&s->rig, name, (float)value);
}

double fp_session_channel(const fp_session *s, const char *name)
{
    return fp_rig_step_channel(&s->rig, name);
}

void fp_session_radius_range(const fp_session *s, double *lo, double *hi)
{
    *lo = FP_SESSION_RADIUS_MIN_DIAGONALS * s->diagonal;
    *hi = FP_SESSION_RADIUS_MAX_DIAGONALS * s->diagonal;
}

int fp_session_set_radius(fp_session *s, double radius)
{
    double lo, hi;
    fp_session_radius_range(s, &lo, &hi);
    if (!(radius >= lo && radius <= hi)) return -ERANGE; /* (NaN too) */
    s->radius = radius;
    return 0;
}

const fp_hand_pose *fp_session_hand(const fp_session *s, int hand)
{
    return fp_session_performer_hand(s, 0, hand);
}

int64_t fp_session_hand_since(const fp_session *s, int hand)
{
    return hand == FP_HAND_LEFT || hand == FP_HAND_RIGHT ? s->hand_since_ns[hand] : 0;
}

size_t fp_session_performer_count(const fp_session *s) { return s->performers.count; }

const char *fp_session_performer_name(const fp_session *s, size_t performer)
{
    return performer < s->performers.count ? s->performers.names[performer] : NULL;
}

const fp_hand_pose *fp_session_performer_hand(const fp_session *s, size_t performer, int hand)
{
    if (performer >= s->performers.count || hand < 0 || hand >= FP_HANDS) return NULL;
    const fp_hand_pose *p = &s->pose[performer].poses[hand];
    return p->present ? p : NULL;
}

/* After undo or reset: the mapping forgets its gesture, and so does the control set that
 * fp_session_control_set shows (no deformation until the next frame makes one). */
static void after_set_base(fp_session *s)
{
    fp_commit_step_base_changed(s);
    fp__session_reset_mapping(s);
    s->cs.active = false;
    s->cs.count = 0;
    s->cs.intents = 0;
    s->engaged = false;
    s->flip_widen = 1.0;
}

unsigned long fp_session_commits(const fp_session *s) { return s->history.gestures; }

bool fp_session_undo(fp_session *s)
{
    if (!fp_history_undo(&s->history)) return false;
    after_set_base(s);
    s->actions |= FP_SESSION_ACTION_UNDO;
    return true;
}

void fp_session_reset(fp_session *s)
{
    fp_history_reset(&s->history, s->loaded);
    fp_rig_step_neutral(&s->rig);
    after_set_base(s);
    s->actions |= FP_SESSION_ACTION_RESET;
}

unsigned fp_session_input_errors(const fp_session *s, const char **last)
{
    if (last) *last = s->intents.last_error;
    return s->intents.input_errors;
}

unsigned long fp_session_dropped(const fp_session *s)
{
    unsigned long n = 0;
    for (size_t i = 0; i < s->input_count; i++)
        n += (unsigned long)fp_input_instance_dropped(&s->inputs[i]);
    return n;
}

int fp_session_save(const fp_session *s, const char *path, char *err, size_t errlen)
{
    return fp_session_save_ex(s, path, NULL, err, errlen);
}

int fp_session_save_ex(const fp_session *s, const char *path, unsigned *dropped, char *err,
                       size_t errlen)
{
    fp_mesh out = *s->mesh;
    size_t bytes = s->n * 3 * sizeof(float);
    out.positions = (float *)s->shown;
    out.normals = malloc(bytes);
    if (!out.normals) {
        snprintf(err, errlen, "%s: out of memory", path);
        return -ENOMEM;
    }
    fp_mesh_compute_normals(&out);
    int rc = fp_mesh_save_ex(&out, path, dropped, err, errlen);  /* its code, unchanged */
    free(out.normals);
    return rc;
}

int fp_session_stop(fp_session *s, char *err, size_t errlen)
{
    int first = 0;
    if (s->stopped) return 0;
    s->stopped = true;
    for (size_t i = 0; i < s->input_count; i++) {
        char msg[512] = "";
        int rc = fp_input_instance_close_record(&s->inputs[i], msg, sizeof msg);
        fp_input_instance_drain_log(&s->inputs[i]);
        if (rc) {
            fp_slog_printf(&s->log, FP_LOG_ERROR, s->inputs[i].name, "record: %s", msg);
            if (!first) {
                first = rc;
                snprintf(err, errlen, "input '%s': record: %s", s->inputs[i].name, msg);
            }
        }
    }
    return first;
}

void fp_session_destroy(fp_session **sp)
{
    fp_session *s = *sp;
    if (!s) return;
    fp_frame_thread_destroy(&s->ft); /* (between frames: no call in progress) */
    char msg[8];
    fp_session_stop(s, msg, sizeof msg);
    for (size_t p = 0; p < s->performers.count; p++) fp_arrive_step_finish(&s->arrive[p], &s->log);
    fp_mapping_step_flush(&s->mapping_step, &s->log);
    fp_engine_step_flush(&s->engine, &s->log);
    fp_skin_reach_gesture_end(&s->gesture_reach, &s->gesture_reach_allowed, s->head.mm_per_unit, &s->log);
    fp_cg_end_gesture(&s->cg, &s->log);
    fp_slog_repeat_flush(&s->jump_report, &s->log);
    for (size_t i = 0; i < s->input_count; i++) fp_input_instance_close(&s->inputs[i]);
    fp__session_destroy_mapping(s, s->mapping, s->mapping_name);
    fp_mapping_host_drain_log(&s->mapping_host);
    fp_log_relay_destroy(&s->mapping_relay);
    fp_plugin_unload(&s->mapping_plugin);
    fp_engine_step_free(&s->engine);
    fp_cg_free(&s->cg);
    fp_sheet_bind_free(&s->bind);
    fp_crack_free(&s->crack);
    fp_changed_free(&s->shown_changed);
    free(s->guard_dp);
    fp_changed_free(&s->base_changed);
    fp_rig_step_free(&s->rig);
    fp_history_free(&s->history);
    fp_intents_free(&s->intents);
    fp_record_step_free(&s->record);
    for (size_t p = 0; p < FP_PERFORMER_CAPACITY; p++) fp_arrive_step_free(&s->arrive[p]);
    free(s->loaded);
    free(s->canon);
    free(s->used);
    free(s->base);
    free(s->deformed);
    fp_mesh_free(&s->mesh);
    free(s);
    *sp = NULL;
}
