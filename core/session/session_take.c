/* Recording a session as a take; playing a take's frames back (fp_session_take.h). */
#define _GNU_SOURCE
#include "fp_session_take.h"

#include "fp_error.h"
#include "fp_mesh.h"

#include <errno.h>
#include <math.h>
#include <sched.h>
#include <stdio.h>
#include <string.h>
#include <time.h>

void fp_session_take_init(fp_session_take *t, const fp_session_take_options *opt,
                          const fp_session_options *so)
{
    memset(t, 0, sizeof *t);
    if (opt) t->opt = *opt;
    if (!t->opt.slate) t->opt.slate = FP_TAKE_DEFAULT_SLATE;
    if (!t->opt.rate.num || !t->opt.rate.den) t->opt.rate = (fp_take_rate){60, 1};
    t->so = so;
}

static void sink_push(fp_session_take *t, const fp_frame_record *r);

void fp_session_take_sink(void *user, const fp_frame_record *r)
{
    fp_session_take *t = user;
    int open = 0; /* (fp_session_take_seal: nothing once sealed) */
    if (!atomic_compare_exchange_strong_explicit(&t->gate, &open, 1, memory_order_acquire,
                                                 memory_order_relaxed))
        return;
    if (t->rec) sink_push(t, r);
    atomic_store_explicit(&t->gate, 0, memory_order_release);
}

void fp_session_take_seal(fp_session_take *t)
{
    for (;;) {
        int open = 0;
        if (atomic_compare_exchange_weak_explicit(&t->gate, &open, 2, memory_order_acquire,
                                                  memory_order_relaxed))
            return;
        if (open == 2) return; /* sealed already */
        sched_yield();         /* a sink call in progress: microseconds */
    }
}

/* The sink's work, inside its gate. */
static void sink_push(fp_session_take *t, const fp_frame_record *r)
{
    if (!t->have_first) {
        t->first_frame = r->frame;
        t->have_first = true;
    }
    fp_take_frame f = {r->frame, r->time_ns, r->events, r->event_count, r->requested,
                       r->controls};
    fp_take_recorder_push(t->rec, &f);
    t->frames++;
    for (size_t i = 0; i < r->reach_count && i < FP_FRAME_REACH_MAX; i++) {
        double b = floor((double)r->reach[i] * FP_SESSION_TAKE_REACH_STEPS + 0.5);
        size_t k = !(b > 0) ? 0 : b >= FP_SESSION_TAKE_REACH_BINS - 1 ? FP_SESSION_TAKE_REACH_BINS - 1 : (size_t)b;
        t->reach_bins[k]++;
        t->reach_vectors++;
    }
    if (r->reach_count && r->reach_asked_max > t->reach_asked_max) t->reach_asked_max = r->reach_asked_max;
    t->reach_held += r->reach_held;
}

/* The q-quantile of the reach histogram (the bin's value, 1/FP_SESSION_TAKE_REACH_STEPS apart):
 * the smallest bin whose running count reaches q of the whole, as fp_percentile's rank. */
static double reach_quantile(const fp_session_take *t, double q)
{
    uint64_t want = (uint64_t)floor(q * (double)(t->reach_vectors - 1)) + 1, run = 0;
    for (size_t k = 0; k < FP_SESSION_TAKE_REACH_BINS; k++)
        if ((run += t->reach_bins[k]) >= want) return (double)k / FP_SESSION_TAKE_REACH_STEPS;
    return (double)(FP_SESSION_TAKE_REACH_BINS - 1) / FP_SESSION_TAKE_REACH_STEPS;
}

bool fp_session_take_recording(const fp_session_take *t) { return t->rec != NULL; }

int fp_session_take_failed(const fp_session_take *t, char *err, size_t errlen)
{
    if (!t->rec) return 0;
    fp_take_recorder_status st;
    fp_take_recorder_status_get(t->rec, &st);
    if (!st.error) return 0;
    if (err && errlen) snprintf(err, errlen, "%s", fp_take_recorder_error(t->rec));
    return st.error;
}

/* The mapping's name and keys from its SPEC (NAME[,key=value...]) into h; the strings live
 * in *spec until fp_spec_clear. */
static int mapping_keys(const char *mapping, fp_spec *spec, fp_take_header *h, char *err,
                        size_t errlen)
{
    int rc = fp_spec_parse(mapping ? mapping : "anchored", spec, err, errlen);
    if (rc) return rc;
    h->mapping = spec->name;
    for (size_t i = 0; i < spec->nparams && i < FP_TAKE_MAX_KEYS; i++)
        h->mapping_keys[h->mapping_key_count++] = spec->params[i];
    return 0;
}

int fp_session_take_start(fp_session_take *t, const fp_session *s, int64_t origin_ns,
                          char *err, size_t errlen)
{
    if (t->rec) return fp_errorf(err, errlen, -EBUSY, "a take is recording already");
    if (!t->opt.dir) return fp_errorf(err, errlen, -EINVAL, "no take folder (--take-dir)");
    const fp_session_options *so = t->so;
    fp_take_header *h = &t->header;
    memset(h, 0, sizeof *h);
    if (!fp_take_slate_valid(t->opt.slate))
        return fp_errorf(err, errlen, -EINVAL,
                         "slate '%s': use 1-63 of A-Z a-z 0-9 . _ - (not starting with '.')",
                         t->opt.slate);
    snprintf(h->slate, sizeof h->slate, "%s", t->opt.slate);
    h->rate = t->opt.rate;
    struct timespec rt;
    clock_gettime(CLOCK_REALTIME, &rt);
    /* the stage's timecode and the soundtrack's offset hold at stage_at_ns: carried on to a
     * take that starts later (run --control's /fp/record/start mid-run) */
    const int64_t later = t->opt.stage_at_given && origin_ns > t->opt.stage_at_ns
                              ? origin_ns - t->opt.stage_at_ns : 0;
    if (t->opt.have_timecode) { /* the stage's timecode (LTC) */
        uint64_t first;
        if (fp_timecode_to_frames(&t->opt.timecode_in, h->rate, &first) ||
            fp_timecode_from_frames(first + fp_take_frames_at(later, h->rate), h->rate,
                                    t->opt.timecode_in.drop, &h->timecode_in))
            return fp_errorf(err, errlen, -EINVAL, "the timecode in is not valid at %u/%u fps",
                             h->rate.num, h->rate.den);
    } else {
        /* drop-frame where the rate has it (29.97, 59.94): the time of day's timecode then
         * follows the clock; non-drop at 29.97 would be 3.6 s an hour behind it */
        fp_timecode_time_of_day(rt.tv_sec, rt.tv_nsec, h->rate, fp_timecode_drop_allowed(h->rate),
                                &h->timecode_in);
    }
    h->timecode_source = t->opt.timecode_source;
    h->soundtrack_path = t->opt.soundtrack_path;
    h->soundtrack_crc32 = t->opt.soundtrack_crc32;
    h->soundtrack_offset_s = t->opt.soundtrack_offset_s + (t->opt.soundtrack_path ? (double)later * 1e-9 : 0);
    h->audio_in_device = t->opt.audio_in_device;
    h->time_origin_ns = origin_ns;
    h->mesh_path = so->mesh_path;
    h->mesh_vertices = fp_session_vertex_count(s);
    h->mesh_crc32 = fp_take_crc32_positions(fp_session_loaded(s), h->mesh_vertices);
    h->mesh_crc_of = "positions";
    h->rig_path = t->opt.rig_path;
    if (!h->rig_path && fp_session_rig(s)) {   /* "PATH (how it was found)" */
        const char *how = fp_session_rig_how(s), *paren = strstr(how, " (");
        snprintf(t->rig_buf, sizeof t->rig_buf, "%.*s", paren ? (int)(paren - how) : (int)strlen(how), how);
        h->rig_path = t->rig_buf;
    }
    fp_spec spec;
    memset(&spec, 0, sizeof spec);
    int rc = mapping_keys(so->mapping, &spec, h, err, errlen);
    if (rc) return rc;
    for (size_t i = 0; i < so->input_count && i < FP_TAKE_MAX_INPUTS; i++)
        h->inputs[h->input_count++] = so->inputs[i];
    /* the first performer's placement per hand: its rotation as fp_pose applies it and
     * offset + that hand's offset */
    fp_calibration flat; /* (a face's frame folded in: the take holds device -> mesh) */
    fp_calibration_flatten(fp_session_calibration(s), &flat);
    const fp_calibration *c = &flat;
    for (int hand = 0; hand < FP_HANDS; hand++) {
        fp_take_calibration *tc = &h->calibration[hand];
        tc->present = true;
        tc->scale = c->scale;
        fp_calibration_rotation(c, tc->rotation);
        for (int i = 0; i < 3; i++) tc->offset[i] = c->offset[i] + c->hand_offset[hand][i];
    }
    /* 1.3: every performer's placement, whole (the array above keeps scale and offset) */
    h->performer_count = fp_session_performer_count(s);
    for (size_t p = 0; p < h->performer_count; p++) {
        fp_calibration pflat;
        fp_calibration_flatten(fp_session_performer_calibration(s, p), &pflat);
        const fp_calibration *pc = &pflat;
        fp_take_performer *tp = &h->performers[p];
        tp->name = fp_session_performer_name(s, p);
        tp->scale = pc->scale;
        memcpy(tp->rotation, pc->rotation, sizeof tp->rotation);
        memcpy(tp->offset, pc->offset, sizeof tp->offset);
        memcpy(tp->hand_offset, pc->hand_offset, sizeof tp->hand_offset);
    }
    float up[3], facing[3]; /* (1.4: where the face looks elsewhere than +z) */
    fp_session_face_axes(s, up, facing);
    if (up[1] < 1 || facing[2] < 1)
        for (int i = 0; i < 3; i++) h->face_up[i] = up[i], h->face_facing[i] = facing[i];
    h->radius = fp_session_radius(s);
    h->description = t->opt.description;
    t->have_first = false;
    t->frames = 0;
    memset(t->reach_bins, 0, sizeof t->reach_bins);
    t->reach_vectors = 0;
    t->reach_held = 0;
    t->reach_asked_max = 0;
    atomic_store(&t->gate, 0);
    t->mm_per_unit = fp_session_head(s)->mm_per_unit;
    t->origin_ns = origin_ns;
    rc = fp_take_recorder_start(t->opt.dir, h, &t->opt.recorder, &t->rec, err, errlen);
    fp_spec_clear(&spec);
    h->mapping = NULL;
    h->mapping_key_count = 0;
    if (rc) t->rec = NULL;
    else h->take = fp_take_recorder_take(t->rec);
    return rc;
}

int fp_session_take_timecode(const fp_session_take *t, int64_t now_ns, fp_timecode *tc)
{
    if (!t->rec) return -EINVAL;
    uint64_t in;
    int rc = fp_timecode_to_frames(&t->header.timecode_in, t->header.rate, &in);
    if (rc) return rc;
    return fp_timecode_from_frames(in + fp_take_frames_in(now_ns - t->origin_ns, t->header.rate),
                                   t->header.rate, t->header.timecode_in.drop, tc);
}

int fp_session_take_stop(fp_session_take *t, fp_session_take_result *res, char *err,
                         size_t errlen)
{
    if (res) memset(res, 0, sizeof *res);
    if (!t->rec) return 0;
    if (res) {
        snprintf(res->path, sizeof res->path, "%s", fp_take_recorder_path(t->rec));
        res->take = fp_take_recorder_take(t->rec);
    }
    if (t->reach_vectors) {
        fp_take_reach reach = {t->reach_vectors, reach_quantile(t, 0.5), reach_quantile(t, 0.1),
                               t->mm_per_unit > 0 ? t->reach_asked_max * t->mm_per_unit : 0,
                               t->reach_held};
        fp_take_recorder_set_reach(t->rec, &reach);
    }
    fp_take_recorder_status st;
    int rc = fp_take_recorder_close(&t->rec, &st, err, errlen);
    t->rec = NULL;
    if (res) {
        res->frames = st.written;
        res->dropped = st.dropped;
        res->error = rc;
        res->timecode_in = t->header.timecode_in;
        /* The TAIL's timecode out: read it back (what a reader of the file will see). */
        fp_take_reader *r = NULL;
        char rerr[512];
        if (fp_take_reader_open(res->path, &r, rerr, sizeof rerr) == 0) {
            res->timecode_out = fp_take_reader_summary(r)->timecode_out;
            fp_take_reader_close(&r);
        } else {
            res->timecode_out = res->timecode_in;
        }
    }
    return rc;
}

int fp_session_take_check_mesh(const fp_session *s, const char *mesh_path,
                               const fp_take_header *h, char *err, size_t errlen)
{
    return fp_take_check_positions(fp_session_loaded(s), fp_session_vertex_count(s), mesh_path, h,
                                   err, errlen);
}

int fp_take_check_positions(const float *pos, size_t n, const char *mesh_path,
                            const fp_take_header *h, char *err, size_t errlen)
{
    uint32_t crc = fp_take_crc32_positions(pos, n);
    if (h->mesh_crc_of && strcmp(h->mesh_crc_of, "positions"))
        return fp_errorf(err, errlen, -ENOTSUP, "the take's mesh checksum is of its %s, not of "
                         "its positions: cannot check %s", h->mesh_crc_of, mesh_path);
    if (crc != h->mesh_crc32 || n != h->mesh_vertices)
        return fp_errorf(err, errlen, -EBADMSG,
                         "mesh %s (%zu vertices, crc32 %08x) is not the take's mesh %s "
                         "(%llu vertices, crc32 %08x)", mesh_path, n, crc,
                         h->mesh_path ? h->mesh_path : "(unnamed)",
                         (unsigned long long)h->mesh_vertices, h->mesh_crc32);
    return 0;
}

void fp_session_play_frame(fp_session *s, const fp_take_frame *f, fp_frame_stats *st)
{
    if (f->requested & FP_SESSION_ACTION_RESET) fp_session_reset(s);
    if (f->requested & FP_SESSION_ACTION_UNDO) fp_session_undo(s);
    static const fp_control_set none = {.size = sizeof none};
    fp_session_apply_controls(s, f->time_ns, f->control ? f->control : &none,
                              f->requested & ~(FP_SESSION_ACTION_UNDO | FP_SESSION_ACTION_RESET),
                              st);
}
