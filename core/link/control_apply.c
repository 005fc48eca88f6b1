/* The control surface's commands applied to a session between frames (fp_control_apply.h). */
#define _GNU_SOURCE
#include "fp_control_apply.h"

#include "facepuppet/plugin.h"
#include "fp_clock.h"

#include <errno.h>
#include <stdio.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>

void fp_control_session_init(fp_control_session *cs, fp_control *ctl, fp_session *s,
                             fp_session_take *take, const fp_plugin_path *path)
{
    memset(cs, 0, sizeof *cs);
    cs->ctl = ctl;
    cs->s = s;
    cs->take = take;
    cs->plugin_path = path;
    snprintf(cs->slate, sizeof cs->slate, "%s",
             take && take->opt.slate ? take->opt.slate : FP_TAKE_DEFAULT_SLATE);
}

void fp_control_session_status(fp_control_session *cs, int64_t now_ns, uint64_t frame,
                               fp_control_status *st)
{
    memset(st, 0, sizeof *st);
    const bool rec = cs->take && fp_session_take_recording(cs->take);
    fp_timecode tc;
    fp_take_rate rate = cs->take ? cs->take->opt.rate : (fp_take_rate){60, 1};
    if (!rec || fp_session_take_timecode(cs->take, now_ns, &tc)) {
        struct timespec rt;
        clock_gettime(CLOCK_REALTIME, &rt);
        fp_timecode_time_of_day(rt.tv_sec, rt.tv_nsec, rate, false, &tc);
    }
    fp_timecode_format(&tc, cs->tc_buf, sizeof cs->tc_buf);
    st->timecode = cs->tc_buf;
    st->recording = rec;
    st->slate = rec ? cs->take->header.slate : cs->slate;
    st->take = rec ? fp_take_recorder_take(cs->take->rec) : cs->next_take ? cs->next_take : cs->last_take;
    st->time_s = (double)(now_ns - cs->t0_ns) * 1e-9;
    st->frame = frame;
    const char *state = cs->state ? cs->state(cs->user, st) : NULL; /* (play's transport) */
    if (!state) {
        const fp_control_set *set = fp_session_control_set(cs->s);
        state = set && set->active ? "engaged" : fp_session_commits(cs->s) ? "committed" : "idle";
    }
    st->state = state;
}

static int record_start(fp_control_session *cs, const fp_control_cmd *c, int64_t now, char *msg,
                        size_t n)
{
    if (!cs->take || !cs->take->opt.dir)
        return snprintf(msg, n, "no take folder (give --take-dir DIR)"), -EINVAL;
    if (fp_session_take_recording(cs->take)) return snprintf(msg, n, "a take is recording already"), -EBUSY;
    snprintf(cs->rec_slate, sizeof cs->rec_slate, "%.63s", c->has_text ? c->text : cs->slate);
    uint32_t number = c->has_take ? c->take : cs->next_take;
    const char *old_slate = cs->take->opt.slate;
    cs->take->opt.slate = cs->rec_slate;
    cs->take->opt.recorder.writer.take = number;
    char err[1024];
    int rc = fp_session_take_start(cs->take, cs->s, now, err, sizeof err);
    cs->take->opt.recorder.writer.take = 0;
    if (rc) {
        cs->take->opt.slate = old_slate;
        snprintf(msg, n, "%.900s", err);
        return rc;
    }
    snprintf(cs->slate, sizeof cs->slate, "%s", cs->rec_slate); /* (LLF: the slate stays) */
    cs->next_take = 0;
    if (cs->on_take) cs->on_take(cs->user, cs->take, NULL, 0, "");
    return 0;
}

static int record_stop(fp_control_session *cs, char *msg, size_t n)
{
    if (!cs->take || !fp_session_take_recording(cs->take))
        return snprintf(msg, n, "no take is recording"), -EINVAL;
    fp_session_take_result res;
    char err[1024] = "";
    int rc = fp_session_take_stop(cs->take, &res, err, sizeof err);
    cs->last_take = res.take;
    if (cs->on_take) cs->on_take(cs->user, cs->take, &res, rc, err);
    if (rc) snprintf(msg, n, "the take was not written whole: %.900s", err);
    return rc;
}

/* /fp/take N: the next take's number, refused where the take folder holds that take of the
 * current slate already (a take is never overwritten: /fp/record/start would refuse it). */
static int next_take(fp_control_session *cs, uint32_t take, char *msg, size_t n)
{
    char name[FP_TAKE_SLATE_MAX + 32], path[4096];
    struct stat st;
    if (cs->take && cs->take->opt.dir && !fp_take_filename(cs->slate, take, name, sizeof name) &&
        (size_t)snprintf(path, sizeof path, "%s/%s", cs->take->opt.dir, name) < sizeof path &&
        lstat(path, &st) == 0) {
        uint32_t free_take = 0;
        char err[256];
        if (fp_take_next_number(cs->take->opt.dir, cs->slate, &free_take, err, sizeof err)) free_take = 0;
        snprintf(msg, n, "take %u of slate %s exists (%.600s; a take is never overwritten): the next free "
                 "number is %u", (unsigned)take, cs->slate, path, (unsigned)free_take);
        return -EEXIST;
    }
    cs->next_take = take;
    return 0;
}

/* One command; msg gets the error's words. Returns 0 or a negative code. */
static int apply_one(fp_control_session *cs, const fp_control_cmd *c, int64_t now, char *msg, size_t n)
{
    switch (c->kind) {
    case FP_CTL_RECORD_START: return record_start(cs, c, now, msg, n);
    case FP_CTL_RECORD_STOP: return record_stop(cs, msg, n);
    case FP_CTL_ENGAGE: fp_session_request(cs->s, FP_INTENT_ENGAGE); return 0;
    case FP_CTL_COMMIT: fp_session_request(cs->s, FP_INTENT_COMMIT); return 0;
    case FP_CTL_CANCEL: fp_session_request(cs->s, FP_INTENT_CANCEL); return 0;
    case FP_CTL_UNDO:
        return fp_session_undo(cs->s) ? 0 : (snprintf(msg, n, "nothing to undo"), -ENOENT);
    case FP_CTL_RESET: fp_session_reset(cs->s); return 0;
    case FP_CTL_RADIUS: {
        double lo, hi;
        fp_session_radius_range(cs->s, &lo, &hi);
        int rc = fp_session_set_radius(cs->s, c->value);
        if (rc) snprintf(msg, n, "radius %g outside [%g, %g] mesh units (a millionth to 10 times the mesh's "
                         "diagonal): the radius stays", c->value, lo, hi);
        return rc;
    }
    case FP_CTL_MAPPING: {
        char err[1024];
        int rc = cs->plugin_path ? fp_session_set_mapping(cs->s, cs->plugin_path, c->text, err, sizeof err)
                                 : (snprintf(err, sizeof err, "no mapping here"), -ENOTSUP);
        if (rc) snprintf(msg, n, "%.900s", err);
        return rc;
    }
    case FP_CTL_CHANNEL: {
        int rc = fp_session_set_channel(cs->s, c->text, c->value);
        if (rc) snprintf(msg, n, "channel %s: %s", c->text, rc == -ENOENT ? "no such channel (or no rig)" : "refused");
        return rc;
    }
    case FP_CTL_PLAY:
    case FP_CTL_STOP:
    case FP_CTL_SEEK:
        if (!cs->transport) return snprintf(msg, n, "no transport here (play has one)"), -ENOTSUP;
        return cs->transport(cs->user, c, msg, n);
    case FP_CTL_SUBSCRIBE:
    case FP_CTL_UNSUBSCRIBE: {
        int rc = fp_control_subscribe(cs->ctl, c, c->kind == FP_CTL_SUBSCRIBE);
        if (rc) snprintf(msg, n, rc == -ENOSPC ? "%d subscribers already" : "not subscribed",
                         FP_CONTROL_MAX_SUBSCRIBERS);
        return rc;
    }
    case FP_CTL_SLATE: snprintf(cs->slate, sizeof cs->slate, "%.63s", c->text); return 0;
    case FP_CTL_TAKE: return next_take(cs, c->take, msg, n);
    case FP_CTL_QUIT: cs->quit = true; return 0;
    case FP_CTL_STATUS:
    default: return 0;
    }
}

size_t fp_control_session_apply(fp_control_session *cs, int64_t now_ns, uint64_t frame)
{
    fp_control_cmd c;
    size_t k = 0;
    while (cs->ctl && fp_control_next(cs->ctl, &c)) {
        char msg[1000] = "", result[1100];
        int rc = apply_one(cs, &c, now_ns, msg, sizeof msg);
        snprintf(result, sizeof result, rc ? "error: %s" : "ok", msg);
        cs->applied++;
        cs->failed += rc != 0;
        fp_control_status st;
        fp_control_session_status(cs, now_ns, frame, &st);
        fp_control_reply(cs->ctl, &c, result, &st);
        k++;
    }
    return k;
}

void fp_control_session_tick(fp_control_session *cs, int64_t now_ns, uint64_t frame)
{
    if (!cs->ctl || !fp_control_subscribers(cs->ctl)) return;
    fp_control_status st;
    fp_control_session_status(cs, now_ns, frame, &st);
    char key[sizeof cs->pushed_key];
    snprintf(key, sizeof key, "%s|%s|%u|%d", st.state, st.slate, (unsigned)st.take, st.recording);
    int64_t wall = fp_now_ns();
    if (!strcmp(key, cs->pushed_key) && wall - cs->pushed_ns < 1000000000LL) return;
    snprintf(cs->pushed_key, sizeof cs->pushed_key, "%s", key);
    cs->pushed_ns = wall;
    fp_control_push(cs->ctl, &st);
}
