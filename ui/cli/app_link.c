/* --control and --stream for run, live and play (app_link.h). */
#define _GNU_SOURCE
#include "app_link.h"
#include "app_util.h"
#include "command.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#ifdef FP_HAVE_LINK
#include "fp_control_apply.h"
#include "fp_stream.h"
#include "fp_rig.h"

struct fp_app_link {
    fp_app_link_options o;
    fp_control *ctl;
    fp_control_session cs;
    fp_stream *stream;
    const char *channels[FP_STREAM_MAX_CHANNELS];   /* the rig's, streamed */
    float values[FP_STREAM_MAX_CHANNELS];
    size_t nchannels;
    fp_app_link_transport_fn transport;
    fp_app_link_state_fn state;
    void *user;
    fp_app_link_take_fn take_hook;
    void *take_user;
};

int fp_app_link_check(const char *cmd, const char *control, const char *stream)
{
    char err[512];
    if (control && fp_control_spec_check(control, err, sizeof err)) {
        fprintf(stderr, "facepuppet %s: %s\n", cmd, err);
        return FP_EXIT_USAGE;
    }
    if (stream && fp_stream_spec_check(stream, err, sizeof err)) {
        fprintf(stderr, "facepuppet %s: --stream %s\n", cmd, err);
        return FP_EXIT_USAGE;
    }
    return 0;
}

static void on_take(void *user, const fp_session_take *t, const fp_session_take_result *res, int rc,
                    const char *err)
{
    fp_app_link *l = user;
    char prefix[64];
    snprintf(prefix, sizeof prefix, "facepuppet %s", l->o.cmd);
    if (!res) {
        if (!l->o.quiet)
            fprintf(stderr, "%s: --control: recording %s take %u\n", prefix, t->header.slate,
                    fp_take_recorder_take(t->rec));
    } else {
        if (rc) fprintf(stderr, "%s: the take was not written whole: %s\n", prefix, err);
        fp_app_print_take(stderr, prefix, res);
    }
    if (l->take_hook) l->take_hook(l->take_user, t, res);
}

void fp_app_link_set_take_hook(fp_app_link *l, fp_app_link_take_fn fn, void *user)
{
    if (!l) return;
    l->take_hook = fn;
    l->take_user = user;
}

static int transport(void *user, const fp_control_cmd *cmd, char *msg, size_t n)
{
    fp_app_link *l = user;
    int kind = cmd->kind == FP_CTL_PLAY ? FP_APP_LINK_PLAY : cmd->kind == FP_CTL_STOP ? FP_APP_LINK_STOP
                                                                                      : FP_APP_LINK_SEEK;
    return l->transport(l->user, kind, cmd->value, msg, n);
}

static const char *state(void *user, fp_control_status *st)
{
    fp_app_link *l = user;
    if (!l->state) return NULL;
    fp_app_link_playhead at = {.time_s = st->time_s, .frame = st->frame};
    const char *word = l->state(l->user, &at);
    st->time_s = at.time_s;
    st->frame = at.frame;
    if (at.timecode) st->timecode = at.timecode;
    if (at.slate) st->slate = at.slate, st->take = at.take;
    return word;
}

/* The stream of l->o.s's mesh (l->o.mesh_path names it), its rig's channels. 0 or the exit
 * status (said). */
static int stream_open(fp_app_link *l)
{
    const fp_app_link_options *o = &l->o;
    char err[1024];
    int rc;
    const struct fp_rig *rig = fp_session_rig(o->s);
    l->nchannels = 0;
    for (size_t i = 0; rig && i < fp_rig_channel_count(rig) && l->nchannels < FP_STREAM_MAX_CHANNELS; i++) {
        fp_rig_channel_desc d;
        if (!fp_rig_channel_get(rig, i, &d)) l->channels[l->nchannels++] = d.name;
    }
    const float *neutral = fp_session_loaded(o->s);
    size_t n = fp_session_vertex_count(o->s);
    fp_stream_options so = {.spec = o->stream, .neutral = neutral, .n = n,
                            .mm_per_unit = fp_session_head(o->s)->mm_per_unit,
                            .mesh_path = o->mesh_path,
                            .mesh_crc32 = fp_take_crc32_positions(neutral, n),
                            .channels = l->channels, .nchannels = l->nchannels, .fps = o->fps,
                            .wait = strcmp(o->cmd, "live") != 0};
    if ((rc = fp_stream_open(&so, &l->stream, err, sizeof err))) {
        fprintf(stderr, "facepuppet %s: --stream %s\n", o->cmd, err);
        return fp_app_exit_code(rc, FP_APP_OUTPUT);
    }
    if (!o->quiet) {
        fp_stream_describe(l->stream, err, sizeof err);
        fprintf(stderr, "facepuppet %s: --stream: %s\n", o->cmd, err);
    }
    return 0;
}

/* The stream's summary line, then closed. */
static void stream_close(fp_app_link *l)
{
    if (!l->stream) return;
    char line[512];
    fp_stream_summary(l->stream, line, sizeof line);
    fprintf(stderr, "facepuppet %s: --stream: %s\n", l->o.cmd, line); /* (-q or not) */
    fp_stream_close(&l->stream);
}

int fp_app_link_open(const fp_app_link_options *o, fp_app_link **out)
{
    *out = NULL;
    if (!o->control && !o->stream) return 0;
    fp_app_link *l = calloc(1, sizeof *l);
    if (!l) {
        fprintf(stderr, "facepuppet %s: out of memory\n", o->cmd);
        return FP_EXIT_SOFTWARE;
    }
    l->o = *o;
    char err[1024], warning[512];
    int rc;
    if (o->control) {
        if ((rc = fp_control_open(o->control, &l->ctl, warning, sizeof warning, err, sizeof err))) {
            fprintf(stderr, "facepuppet %s: %s\n", o->cmd, err);
            free(l);
            return fp_app_exit_code(rc, FP_APP_INPUT);
        }
        if (warning[0]) fprintf(stderr, "facepuppet %s: warning: %s\n", o->cmd, warning);
        fp_control_session_init(&l->cs, l->ctl, o->s, o->take, o->plugin_path);
        l->cs.on_take = on_take;
        l->cs.state = state;
        l->cs.user = l;
        fprintf(stderr, "facepuppet %s: --control: listening on port %u%s (%s; docs/osc.md, Control)\n",
                o->cmd, fp_control_port(l->ctl), fp_control_hears_ipv6(l->ctl) ? ", [::1] too" : "",
                fp_control_where(l->ctl));
    }
    if (o->stream && (rc = stream_open(l))) {
        fp_control_close(&l->ctl);
        free(l);
        return rc;
    }
    *out = l;
    return 0;
}

void fp_app_link_origin(fp_app_link *l, int64_t t0_ns)
{
    if (!l) return;
    l->cs.t0_ns = t0_ns;
    if (l->stream) fp_stream_origin(l->stream, t0_ns);
}

void fp_app_link_set_transport(fp_app_link *l, fp_app_link_transport_fn fn, fp_app_link_state_fn st,
                               void *user)
{
    if (!l) return;
    l->transport = fn;
    l->state = st;
    l->user = user;
    l->cs.transport = fn ? transport : NULL;
}

void fp_app_link_before(fp_app_link *l, int64_t now_ns, uint64_t frame)
{
    if (l && l->ctl) fp_control_session_apply(&l->cs, now_ns, frame);
}

void fp_app_link_after_frame(fp_app_link *l, int64_t now_ns, uint64_t frame, const float *pos,
                             const char *timecode)
{
    if (!l) return;
    if (l->ctl) fp_control_session_tick(&l->cs, now_ns, frame);
    if (l->stream) {
        char tc[32] = "";
        fp_session_take *t = l->o.take;
        fp_timecode c;
        if (timecode) snprintf(tc, sizeof tc, "%s", timecode);
        else if (t && fp_session_take_recording(t) && !fp_session_take_timecode(t, now_ns, &c))
            fp_timecode_format(&c, tc, sizeof tc);
        for (size_t k = 0; k < l->nchannels; k++)
            l->values[k] = (float)fp_session_channel(l->o.s, l->channels[k]);
        const uint32_t *ranges = NULL;
        size_t nranges = SIZE_MAX;
        if (!pos && l->o.touched) nranges = fp_session_touched(l->o.s, &ranges);
        fp_stream_frame_ranges(l->stream, pos ? pos : fp_session_positions(l->o.s), ranges, nranges,
                               l->values, now_ns, tc);
    }
}

void fp_app_link_after(fp_app_link *l, int64_t now_ns, uint64_t frame)
{
    fp_app_link_after_frame(l, now_ns, frame, NULL, NULL);
}

void fp_app_link_idle(fp_app_link *l, int64_t now_ns, uint64_t frame)
{
    if (l && l->ctl) fp_control_session_tick(&l->cs, now_ns, frame);
}

void fp_app_link_set_session(fp_app_link *l, fp_session *s)
{
    if (!l) return;
    l->o.s = s;
    l->cs.s = s;
}

int fp_app_link_reopen(fp_app_link *l, fp_session *s, fp_session_take *take, const char *mesh_path,
                       int64_t t0_ns)
{
    if (!l) return 0;
    l->o.s = s;
    l->o.take = take;
    l->o.mesh_path = mesh_path;
    l->cs.s = s;
    l->cs.take = take;
    if (!l->o.stream) return 0;
    stream_close(l);
    int rc = stream_open(l);
    if (!rc) fp_stream_origin(l->stream, t0_ns);
    return rc;
}

bool fp_app_link_quit(const fp_app_link *l) { return l && l->cs.quit; }

void fp_app_link_close(fp_app_link **lp)
{
    fp_app_link *l = lp ? *lp : NULL;
    if (!l) return;
    if (l->ctl) {
        fp_control_stats st;
        fp_control_stats_get(l->ctl, &st);
        if (!l->o.quiet || st.refused)
            fprintf(stderr, "facepuppet %s: --control: %llu packets, %llu commands applied (%llu "
                    "answered with an error), %llu replies, %llu pushes; refused %llu (malformed %llu, "
                    "unknown address %llu, bad types %llu, bad value %llu, queue full %llu)\n",
                    l->o.cmd, (unsigned long long)st.packets, (unsigned long long)l->cs.applied,
                    (unsigned long long)l->cs.failed, (unsigned long long)st.replies,
                    (unsigned long long)st.pushes, (unsigned long long)st.refused,
                    (unsigned long long)st.problems[FP_CTL_MALFORMED],
                    (unsigned long long)st.problems[FP_CTL_UNKNOWN_ADDRESS],
                    (unsigned long long)st.problems[FP_CTL_BAD_TYPES],
                    (unsigned long long)st.problems[FP_CTL_BAD_VALUE],
                    (unsigned long long)st.problems[FP_CTL_QUEUE_FULL]);
        fp_control_close(&l->ctl);
    }
    stream_close(l);
    free(l);
    *lp = NULL;
}

#else /* built without liblo */

int fp_app_link_check(const char *cmd, const char *control, const char *stream)
{
    if (!control && !stream) return 0;
    fprintf(stderr, "facepuppet %s: --control and --stream are left out of this build (liblo-dev "
            "was not found)\n", cmd);
    return FP_EXIT_UNAVAILABLE;
}
int fp_app_link_open(const fp_app_link_options *o, fp_app_link **out)
{
    (void)o;
    *out = NULL;
    return 0;
}
void fp_app_link_origin(fp_app_link *l, int64_t t0_ns) { (void)l; (void)t0_ns; }
void fp_app_link_before(fp_app_link *l, int64_t now_ns, uint64_t frame) { (void)l; (void)now_ns; (void)frame; }
void fp_app_link_after(fp_app_link *l, int64_t now_ns, uint64_t frame) { (void)l; (void)now_ns; (void)frame; }
void fp_app_link_after_frame(fp_app_link *l, int64_t now_ns, uint64_t frame, const float *pos,
                             const char *timecode)
{
    (void)l; (void)now_ns; (void)frame; (void)pos; (void)timecode;
}
void fp_app_link_set_session(fp_app_link *l, fp_session *s) { (void)l; (void)s; }
int fp_app_link_reopen(fp_app_link *l, fp_session *s, fp_session_take *take, const char *mesh_path,
                       int64_t t0_ns)
{
    (void)l; (void)s; (void)take; (void)mesh_path; (void)t0_ns;
    return 0;
}
void fp_app_link_idle(fp_app_link *l, int64_t now_ns, uint64_t frame) { (void)l; (void)now_ns; (void)frame; }
bool fp_app_link_quit(const fp_app_link *l) { (void)l; return false; }
void fp_app_link_set_transport(fp_app_link *l, fp_app_link_transport_fn fn, fp_app_link_state_fn st,
                               void *user)
{
    (void)l; (void)fn; (void)st; (void)user;
}
void fp_app_link_set_take_hook(fp_app_link *l, fp_app_link_take_fn fn, void *user)
{
    (void)l; (void)fn; (void)user;
}
void fp_app_link_close(fp_app_link **l) { (void)l; }

#endif
