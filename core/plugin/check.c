/* The plugin validator (fp_plugin_check.h): a plugin exercised through plugin.h as the host
 * would, and harder. */
#define _GNU_SOURCE
#include "fp_plugin_check.h"
#include "fp_control_check.h"
#include "fp_event_check.h"
#include "fp_isolate.h"
#include "fp_plugin_crash.h"

#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

typedef struct checker {
    fp_check_fn fn;
    void *user;
    fp_check_summary *sum;
    const fp_check_options *opt;
    const char *who;          /* the plugin's file, for the crash bracket */
    bool extra;               /* the plugin knows ABI 1.3: frames with further performers */
    fp_check_progress_fn progress; /* told of each call into the plugin, or NULL */
    void *progress_user;
} checker;

/* A call into the plugin begins: bracketed for the crash handler, and told to the progress
 * callback (the guard's: fp_plugin_check) before it is made, outside any timed span. */
static void enter(checker *c, const char *call, uint64_t frame)
{
    if (c->progress) c->progress(c->progress_user, call, frame);
    fp_plugin_call_enter(c->who, call, frame);
}

static void report(checker *c, fp_check_level level, const char *check, const char *fmt, ...)
    __attribute__((format(printf, 4, 5)));
static void report(checker *c, fp_check_level level, const char *check, const char *fmt, ...)
{
    char msg[1024];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    if (level == FP_CHECK_PASS) c->sum->passed++;
    if (level == FP_CHECK_FAIL) c->sum->failed++;
    if (level == FP_CHECK_SKIP) c->sum->skipped++;
    if (c->fn) c->fn(c->user, level, check, msg);
}

static int64_t now_ns(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (int64_t)ts.tv_sec * 1000000000LL + ts.tv_nsec;
}

static bool device_code(int rc)
{
    return rc == -ENOENT || rc == -ENODEV || rc == -EACCES || rc == -EBUSY || rc == -ENXIO ||
           rc == -EPERM;
}

/* ---- creating with keys ------------------------------------------------------------------ */

typedef struct creator {
    checker *c;
    const fp_plugin *plugin;
    fp_host host;
} creator;

/* create() with the options' keys plus `extra` (n of them). *out_inst gets the instance
 * (fp_input* or fp_mapping*) or NULL. Returns create's code; a 0 without an instance is
 * returned as 1. */
static int create_with(creator *cr, const fp_param *extra, size_t n, void **out_inst, char *msg,
                       size_t msglen)
{
    const fp_check_options *o = cr->c->opt;
    fp_param keys[FP_SPEC_MAX_PARAMS + 4];
    size_t k = 0;
    for (size_t i = 0; i < o->nparams && k < FP_SPEC_MAX_PARAMS; i++) keys[k++] = o->params[i];
    for (size_t i = 0; i < n && k < sizeof keys / sizeof keys[0]; i++) keys[k++] = extra[i];
    msg[0] = '\0';
    *out_inst = NULL;
    int rc;
    enter(cr->c, "create", 0);
    if (cr->plugin->kind == FP_PLUGIN_INPUT) {
        const fp_input_factory *f = cr->plugin->factory;
        fp_input *in = NULL;
        rc = f->create(&cr->host, o->arg, keys, k, &in, msg, msglen);
        *out_inst = in;
    } else {
        const fp_mapping_factory *f = cr->plugin->factory;
        fp_mapping *m = NULL;
        rc = f->create(&cr->host, keys, k, &m, msg, msglen);
        *out_inst = m;
    }
    fp_plugin_call_leave();
    msg[msglen - 1] = '\0';
    if (rc == 0 && !*out_inst) return 1;
    if (rc != 0) *out_inst = NULL; /* an instance with an error is not ours to free */
    return rc;
}

static void destroy_inst2(creator *cr, void *inst, bool stopped)
{
    if (!inst) return;
    enter(cr->c, "destroy", 0);
    if (cr->plugin->kind == FP_PLUGIN_INPUT) {
        fp_input *in = inst;
        if (!stopped && in->stop) in->stop(in); /* allowed without a start (plugin.h) */
        if (in->destroy) in->destroy(in);
    } else {
        fp_mapping *m = inst;
        if (m->destroy) m->destroy(m);
    }
    fp_plugin_call_leave();
}

static void destroy_inst(creator *cr, void *inst) { destroy_inst2(cr, inst, false); }

/* The key checks every plugin gets. Returns false when create with the defaults already
 * failed (nothing more can be checked); *device set when it failed for want of a device. */
static bool check_keys(creator *cr, const fp_param_info *info, bool *device)
{
    checker *c = cr->c;
    char msg[1024];
    void *inst;
    *device = false;
    int rc = create_with(cr, NULL, 0, &inst, msg, sizeof msg);
    if (rc == 1) {
        report(c, FP_CHECK_FAIL, "create", "create returned 0 without an instance (*out left NULL)");
        return false;
    }
    if (rc) {
        /* a file given with --arg that is not there is the caller's mistake, not a missing
         * device (a recording checked against /nonexist passed as 'skipped') */
        const char *arg = c->opt->arg;
        const bool file_arg = arg && arg[0] && strncmp(arg, "/dev/", 5) != 0 && rc == -ENOENT;
        if (device_code(rc) && msg[0] && !file_arg) {
            *device = true;
            report(c, FP_CHECK_SKIP, "create", "needs a device: create failed with %d (%s): %s", rc,
                   fp_strerror(rc), msg);
        } else {
            report(c, FP_CHECK_FAIL, "create", "create with the default keys failed with %d (%s): %s",
                   rc, fp_strerror(rc), msg[0] ? msg : "(no message)");
        }
        return false;
    }
    report(c, FP_CHECK_PASS, "create", "created with the default keys");
    destroy_inst(cr, inst);

    /* An unknown key must be refused, by name. */
    static const char *bogus = "fpcheck-no-such-key";
    fp_param bad = {bogus, "1"};
    rc = create_with(cr, &bad, 1, &inst, msg, sizeof msg);
    if (rc == 0 || rc == 1) {
        report(c, FP_CHECK_FAIL, "unknown key", "create accepted the unknown key '%s'", bogus);
        destroy_inst(cr, inst);
    } else if (!strstr(msg, bogus)) {
        report(c, FP_CHECK_FAIL, "unknown key",
               "create refused the unknown key '%s' (%d) but its message does not name it: '%s'",
               bogus, rc, msg);
    } else {
        report(c, FP_CHECK_PASS, "unknown key", "refused: %s", msg);
    }
    if (!info) {
        report(c, FP_CHECK_INFO, "keys", "the factory declares no typed keys (fp_param_info)");
        return true;
    }
    /* Every key at its declared default, then each key out of its range. */
    fp_param defaults[FP_SPEC_MAX_PARAMS];
    size_t nd = 0;
    for (const fp_param_info *p = info; p->name && nd < FP_SPEC_MAX_PARAMS; p++) {
        bool given = false;
        for (size_t i = 0; i < c->opt->nparams; i++) given |= !strcmp(c->opt->params[i].key, p->name);
        if (p->default_value && *p->default_value && !given && p->type != FP_PARAM_PATH)
            defaults[nd++] = (fp_param){p->name, p->default_value};
    }
    rc = create_with(cr, defaults, nd, &inst, msg, sizeof msg);
    if (rc) report(c, FP_CHECK_FAIL, "defaults", "create refused its own declared defaults (%d): %s", rc, msg);
    else report(c, FP_CHECK_PASS, "defaults", "%zu key(s) at their declared defaults accepted", nd);
    destroy_inst(cr, inst);
    for (const fp_param_info *p = info; p->name; p++) {
        char value[64];
        switch (p->type) {
        case FP_PARAM_INT:
        case FP_PARAM_FLOAT: {
            double span = p->max - p->min;
            if (!isfinite(p->max) || p->max > 1e300) continue;
            snprintf(value, sizeof value, "%.17g", p->max + (span > 1 ? span : 1));
            break;
        }
        case FP_PARAM_ENUM: snprintf(value, sizeof value, "fpcheck-not-a-choice"); break;
        case FP_PARAM_BOOL: snprintf(value, sizeof value, "2"); break;
        default: continue;
        }
        fp_param one = {p->name, value};
        rc = create_with(cr, &one, 1, &inst, msg, sizeof msg);
        if (rc == 0 || rc == 1) {
            report(c, FP_CHECK_FAIL, "key range", "create accepted %s=%s, outside the key's declared %s",
                   p->name, value, p->type == FP_PARAM_ENUM ? "choices" : "range");
            destroy_inst(cr, inst);
        } else {
            report(c, FP_CHECK_PASS, "key range", "%s=%s refused: %s", p->name, value, msg);
        }
    }
    return true;
}

/* ---- mappings --------------------------------------------------------------------------- */

#define GRID 9
#define NV (GRID * GRID)
#define GUARD 8
#define SEQ 120                     /* frames per half before 1.3; the second half has a rig */
#define XSEQ 40                     /* and after them, from 1.3: frames with further performers */
#define MAX_FRAMES (2 * (SEQ + XSEQ))
#define XROWS ((FP_PERFORMER_CAPACITY - 1) * FP_HANDS) /* extra_hands' rows at most */
#define NFAULT 7
static const unsigned char canary_byte = 0xA5;

typedef struct snapshot {
    bool active;
    uint32_t intents;
    double radius;
    size_t count, channel_count;
    float start[FP_CONTROL_CAPACITY][3], end[FP_CONTROL_CAPACITY][3];
    fp_channel channels[FP_CHANNEL_CAPACITY];
} snapshot;

typedef struct scene {
    float grid[NV][3];
    fp_mesh_view view;
    fp_rig_view rig;
    uint8_t region[NV];
    fp_rig_landmark landmarks[2];
    fp_rig_channel_info channels[1];
    /* the host's arrays, each followed by GUARD canary entries */
    float start[FP_CONTROL_CAPACITY + GUARD][3], end[FP_CONTROL_CAPACITY + GUARD][3];
    fp_channel ch[FP_CHANNEL_CAPACITY + GUARD];
    fp_control_set cs;
    fp_event events[2];
    /* ABI 1.3: the further performers' hands and tip distances, the rows past a frame's
     * FP_HANDS x extra_performers (and GUARD more) holding trap hands (present, NaN joints,
     * touching); copies of both to find a write into them */
    size_t half, frames;      /* frames per half (SEQ, + XSEQ with `extra`), in all */
    fp_hand_pose xhands[XROWS + GUARD], xhands_copy[XROWS + GUARD];
    float xtips[XROWS + GUARD][FP_FINGERS], xtips_copy[XROWS + GUARD][FP_FINGERS];
    char xname[2][4][64];     /* the scenarios' names, "3 further performers, touching" */
} scene;

/* extra: the sequence has the frames with further performers (a plugin of ABI 1.3 on). */
static void scene_init(scene *s, bool extra)
{
    memset(s, 0, sizeof *s);
    s->half = SEQ + (extra ? XSEQ : 0);
    s->frames = 2 * s->half;
    static const char *what[4] = {"hands far", "touching", "edge poses", "their hands gone"};
    for (int b = 0; b < 2; b++)
        for (int k = 0; k < 4; k++)
            snprintf(s->xname[b][k], sizeof s->xname[b][k], "%d further performer%s, %s",
                     b ? FP_PERFORMER_CAPACITY - 1 : 1, b ? "s" : "", what[k]);
    for (int j = 0; j < GRID; j++)
        for (int i = 0; i < GRID; i++) {
            float *v = s->grid[j * GRID + i];
            v[0] = -1 + 2.0f * i / (GRID - 1);
            v[1] = -1 + 2.0f * j / (GRID - 1);
            v[2] = 0.05f * (v[0] * v[0] + v[1] * v[1]); /* a shallow bowl */
        }
    s->view.vertex_count = NV;
    s->view.base = &s->grid[0][0];
    for (int k = 0; k < 3; k++) {
        s->view.bounds_min[k] = k < 2 ? -1 : 0;
        s->view.bounds_max[k] = k < 2 ? 1 : 0.1f;
    }
    for (int v = 0; v < NV; v++) s->region[v] = v < GRID ? FP_REGION_JAW : v >= NV - GRID ? FP_REGION_SKULL : FP_REGION_SOFT;
    s->landmarks[0] = (fp_rig_landmark){"chin", GRID / 2, {0, -1, 0.05f}};
    s->landmarks[1] = (fp_rig_landmark){"nose_tip", NV / 2, {0, 0, 0}};
    s->channels[0] = (fp_rig_channel_info){"jaw.open", 0, 1, 0, 0};
    fp_rig_view *r = &s->rig;
    r->size = sizeof *r;
    r->name = "fpcheck-grid";
    r->mm_per_unit = 100;
    r->up[1] = 1;
    r->forward[2] = 1;
    r->left[0] = 1;
    r->vertex_count = NV;
    r->region = s->region;
    r->landmark_count = 2;
    r->landmarks = s->landmarks;
    r->channel_count = 1;
    r->channels = s->channels;
    r->hinge[0][0] = -1;
    r->hinge[0][1] = -1;
    r->hinge[1][0] = 1;
    r->hinge[1][1] = -1;
    s->cs.size = sizeof s->cs;
    s->cs.capacity = FP_CONTROL_CAPACITY;
    s->cs.start = s->start;
    s->cs.end = s->end;
    s->cs.channel_capacity = FP_CHANNEL_CAPACITY;
    s->cs.channels = s->ch;
    memset(s->start[FP_CONTROL_CAPACITY], canary_byte, sizeof s->start[0] * GUARD);
    memset(s->end[FP_CONTROL_CAPACITY], canary_byte, sizeof s->end[0] * GUARD);
    memset(&s->ch[FP_CHANNEL_CAPACITY], canary_byte, sizeof s->ch[0] * GUARD);
}

static bool canaries_intact(const scene *s, const char **which)
{
    const unsigned char *p[3] = {(const unsigned char *)s->start[FP_CONTROL_CAPACITY],
                                 (const unsigned char *)s->end[FP_CONTROL_CAPACITY],
                                 (const unsigned char *)&s->ch[FP_CHANNEL_CAPACITY]};
    size_t n[3] = {sizeof s->start[0] * GUARD, sizeof s->end[0] * GUARD, sizeof s->ch[0] * GUARD};
    static const char *names[3] = {"start", "end", "channels"};
    for (int a = 0; a < 3; a++)
        for (size_t i = 0; i < n[a]; i++)
            if (p[a][i] != canary_byte) {
                *which = names[a];
                return false;
            }
    return true;
}

/* A hand whose palm is at (x, y, z + lift) and whose five fingertips lie on a row at height z;
 * collapse: every joint at one point. */
static void make_hand(fp_hand_pose *h, float x, float y, float z, bool collapse)
{
    h->present = true;
    for (int j = 0; j < FP_HAND_JOINTS; j++) {
        h->joints[j][0] = x;
        h->joints[j][1] = y;
        h->joints[j][2] = z;
    }
    if (collapse) return;
    h->joints[FP_JOINT_PALM][2] = z + 0.4f;
    for (int f = 0; f < FP_FINGERS; f++)
        for (int k = 0; k < 4; k++) {
            float t = (k + 1) / 4.0f;
            float *p = h->joints[FP_JOINT(f, k)];
            p[0] = x + t * 0.12f * (f - 2);
            p[1] = y + t * 0.25f;
            p[2] = z + (1 - t) * 0.4f;
        }
}

/* Edge pose k (0..4) of a pair of hands, without NaN: joints all at a vertex, at the bounds'
 * corners, a hand 1e4 units away, both collapsed at one point, an engage and commit at once.
 * Returns the fp_intent bits the pose asks for. */
static uint32_t edge_pose(const scene *s, fp_hand_pose *L, fp_hand_pose *R, int k)
{
    switch (k % 5) {
    case 0: make_hand(R, s->grid[NV / 2][0], s->grid[NV / 2][1], s->grid[NV / 2][2], true); break;
    case 1: make_hand(L, -1, -1, 0, false); make_hand(R, 1, 1, 0.1f, false); break;
    case 2: make_hand(R, 1e4f, -1e4f, 1e4f, false); break;
    case 3: make_hand(L, 0, 0, 0, true); make_hand(R, 0, 0, 0, true); break;
    default: make_hand(R, 0, 0, 0.0f, false); return FP_INTENT_ENGAGE | FP_INTENT_COMMIT;
    }
    return 0;
}

/* The fingertip distances of n hands as the session gives them (plugin.h): to the nearest
 * vertex, exact within FP_TIP_DISTANCE_REACH x radius, +INFINITY beyond it and for an absent
 * hand. */
static void tip_distances(const scene *s, const fp_hand_pose *hands, size_t n, double radius,
                          float (*out)[FP_FINGERS])
{
    for (size_t h = 0; h < n; h++)
        for (int t = 0; t < FP_FINGERS; t++) {
            out[h][t] = INFINITY;
            if (!hands[h].present) continue;
            const float *tip = hands[h].joints[FP_JOINT_TIP(t)];
            double best = INFINITY;
            for (int v = 0; v < NV; v++) {
                double dx = tip[0] - s->grid[v][0], dy = tip[1] - s->grid[v][1], dz = tip[2] - s->grid[v][2];
                double d = dx * dx + dy * dy + dz * dz;
                if (d < best) best = d;
            }
            if (sqrt(best) <= FP_TIP_DISTANCE_REACH * radius) out[h][t] = (float)sqrt(best);
        }
}

/* Frame x (0..XSEQ-1) of a half's frames with further performers (ABI 1.3): 1 then
 * FP_PERFORMER_CAPACITY - 1 of them, their hands far, touching (engage, then commit or
 * cancel; the first performer's right hand with them from the fourth frame on), at the edge
 * poses (each performer another), then gone (extra_performers unchanged, their hands absent,
 * the first performer's touching). The rows past the frame's become trap hands; both arrays
 * are copied for the check that process() left them alone. */
static void make_extra(scene *s, size_t x, fp_frame_input *in, const char **what)
{
    const int b = x >= XSEQ / 2, k = (int)(x % (XSEQ / 2));
    const uint32_t n = b ? FP_PERFORMER_CAPACITY - 1 : 1;
    const float ph = (float)x / 5.0f;
    memset(s->xhands, 0, sizeof s->xhands);
    for (uint32_t p = 0; p < n; p++) {
        fp_hand_pose *L = &s->xhands[FP_HANDS * p + FP_HAND_LEFT], *R = &s->xhands[FP_HANDS * p + FP_HAND_RIGHT];
        const float px = -0.6f + 0.5f * (float)p, py = 0.3f * sinf(ph + (float)p);
        if (k < 5) {
            make_hand(L, px - 0.2f, py, 2.0f + 0.1f * (float)p, false);
            make_hand(R, px + 0.2f, py, 2.5f, false);
        } else if (k < 12) {
            make_hand(R, px, py, k < 7 ? 0.5f - (k - 5) * 0.24f : 0.02f, false);
            if (p % 2) make_hand(L, px - 0.1f, -py, 0.03f, false);
        } else if (k < 17) {
            in->requested |= edge_pose(s, L, R, k - 12 + (int)p);
        }
    }
    if (k >= 8 && k < 12) make_hand(&in->hands[FP_HAND_RIGHT], 0.2f * cosf(ph), -0.4f, 0.02f, false);
    if (k >= 17) make_hand(&in->hands[FP_HAND_RIGHT], 0.1f, 0.1f, 0.02f, false);
    if (k == 6) in->requested |= FP_INTENT_ENGAGE;
    if (k == 11) in->requested |= b ? FP_INTENT_CANCEL : FP_INTENT_COMMIT;
    *what = s->xname[b][k < 5 ? 0 : k < 12 ? 1 : k < 17 ? 2 : 3];
    tip_distances(s, s->xhands, FP_HANDS * n, in->radius, s->xtips);
    for (size_t r = FP_HANDS * n; r < XROWS + GUARD; r++) {
        s->xhands[r].present = true;
        for (int j = 0; j < FP_HAND_JOINTS; j++)
            for (int c = 0; c < 3; c++) s->xhands[r].joints[j][c] = NAN;
        for (int t = 0; t < FP_FINGERS; t++) s->xtips[r][t] = 0;
    }
    memcpy(s->xhands_copy, s->xhands, sizeof s->xhands);
    memcpy(s->xtips_copy, s->xtips, sizeof s->xtips);
    in->extra_performers = n;
    in->extra_hands = s->xhands;
    in->extra_tip_distance = (const float (*)[FP_FINGERS])s->xtips;
}

/* Frame f (0..s->frames-1) of the sequence: hands, requests, events, the rig in the second
 * half; each half's last XSEQ frames with further performers where the plugin knows them. */
static void make_frame(scene *s, size_t f, fp_frame_input *in, const char **what)
{
    size_t g = f % s->half;
    memset(in, 0, sizeof *in);
    in->size = sizeof *in;
    in->frame = f;
    in->time_ns = (int64_t)f * 16666667;
    in->mesh = &s->view;
    in->radius = 0.3;
    in->touch_radius = in->radius; /* (ABI 1.3: as a session at its default radius fills it) */
    in->mm_per_unit = 100;
    in->face_up[1] = 1;
    in->face_forward[2] = 1;
    in->face_left[0] = 1;
    in->rig = f >= s->half ? &s->rig : NULL;
    float ph = (float)g / 10.0f;
    fp_hand_pose *L = &in->hands[FP_HAND_LEFT], *R = &in->hands[FP_HAND_RIGHT];
    if (g < 10) {
        *what = "no hands";
    } else if (g < 25) {
        *what = "one hand far";
        make_hand(R, 0.2f * sinf(ph), 0, 3, false);
    } else if (g < 55) {
        *what = "one hand touching";
        float z = g < 32 ? 1.0f - (g - 25) * 0.14f : 0.02f;
        make_hand(R, 0.3f * sinf(ph), 0.1f * cosf(ph), z, false);
        if (g == 33) in->requested = FP_INTENT_ENGAGE;
        if (g == 50) in->requested = FP_INTENT_COMMIT;
    } else if (g < 85) {
        *what = "both hands touching";
        make_hand(L, -0.5f + 0.2f * sinf(ph), 0, 0.03f, false);
        make_hand(R, 0.5f - 0.2f * sinf(ph), 0, 0.03f, false);
        if (g == 56) in->requested = FP_INTENT_ENGAGE;
        if (g == 80) in->requested = FP_INTENT_CANCEL;
    } else if (g < 95) {
        *what = "both hands far";
        make_hand(L, -0.5f, 0, 2, false);
        make_hand(R, 0.5f, 0, 2, false);
    } else if (g < 110) {
        *what = "edge poses";
        in->requested = edge_pose(s, L, R, (int)(g % 5));
    } else if (g < SEQ) {
        *what = "no hands, requests";
        in->requested = g % 2 ? FP_INTENT_COMMIT : FP_INTENT_CANCEL;
    } else {
        make_extra(s, g - SEQ, in, what);
    }
    tip_distances(s, in->hands, FP_HANDS, in->radius, in->tip_distance);
    /* Pedal presses now and then: the left button down and up. */
    if (g == 40 || g == 41) {
        fp_event_button *b = &s->events[0].button;
        memset(b, 0, sizeof *b);
        *b = (fp_event_button){{sizeof *b, FP_EVENT_BUTTON, 0, in->time_ns, 0, -1}, FP_BUTTON_LEFT,
                               g == 40, g == 40 ? FP_BUTTON_LEFT : 0};
        in->events = s->events;
        in->event_count = 1;
    }
}

/* Frame f's scenario, "one hand touching, rig", in buf. */
static const char *frame_what(scene *s, size_t f, char *buf, size_t len)
{
    fp_frame_input in;
    const char *what = "";
    make_frame(s, f, &in, &what);
    snprintf(buf, len, "%s%s", what, f >= s->half ? ", rig" : "");
    return buf;
}

typedef struct fault {
    const char *what;
    size_t count;
    size_t first;
    char detail[512];
} fault;

static void fault_add(fault *f, size_t frame, const char *scen, const char *fmt, ...)
    __attribute__((format(printf, 4, 5)));
static void fault_add(fault *f, size_t frame, const char *scen, const char *fmt, ...)
{
    if (!f->count++) {
        f->first = frame;
        char d[400];
        va_list ap;
        va_start(ap, fmt);
        vsnprintf(d, sizeof d, fmt, ap);
        va_end(ap);
        snprintf(f->detail, sizeof f->detail, "%s (first on frame %zu, %s)", d, frame, scen);
    }
}

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return x < y ? -1 : x > y;
}

static void faults_init(fault *f)
{
    static const char *what[NFAULT] = {"process", "capacity", "overrun", "finite points", "radius",
                                       "channels", "performers"};
    for (int k = 0; k < NFAULT; k++) f[k] = (fault){.what = what[k]};
}

/* After a frame with further performers: whether process() left the host's extra_hands and
 * extra_tip_distance as they were (its rows and the trap rows after them); where not, a
 * fault naming the first row written, and both arrays restored. */
static void check_extra_untouched(scene *s, const fp_frame_input *in, fault *fx, size_t f, const char *where)
{
    const size_t rows = FP_HANDS * (size_t)in->extra_performers;
    for (size_t r = 0; r < XROWS + GUARD; r++) {
        bool hand = memcmp(&s->xhands[r], &s->xhands_copy[r], sizeof s->xhands[r]) != 0;
        if (!hand && !memcmp(s->xtips[r], s->xtips_copy[r], sizeof s->xtips[r])) continue;
        fault_add(fx, f, where, "wrote into the host's %s[%zu]%s (const: the further performers' "
                  "hands are the host's, plugin.h)", hand ? "extra_hands" : "extra_tip_distance", r,
                  r < rows ? "" : ", past its FP_HANDS x extra_performers rows");
        memcpy(s->xhands, s->xhands_copy, sizeof s->xhands);
        memcpy(s->xtips, s->xtips_copy, sizeof s->xtips);
        return;
    }
}

/* One pass over the sequence: checks each frame, records times and control sets. */
static void run_sequence(checker *c, fp_mapping *m, scene *s, snapshot *snaps, double *times_us,
                         fault *faults, bool *dead)
{
    enum { F_RC, F_COUNT, F_CANARY, F_NONFINITE, F_RADIUS, F_CHANNEL, F_EXTRA };
    for (size_t f = 0; f < s->frames && !*dead; f++) {
        fp_frame_input in;
        const char *what = "";
        char scen[96];
        make_frame(s, f, &in, &what);
        snprintf(scen, sizeof scen, "%s%s", what, f >= s->half ? ", rig" : "");
        enter(c, in.extra_performers ? "process with further performers" : "process", f);
        int64_t t0 = now_ns();
        int rc = m->process(m, &in, &s->cs);
        int64_t t1 = now_ns();
        fp_plugin_call_leave();
        times_us[f] = (t1 - t0) / 1e3;
        if (in.extra_performers) check_extra_untouched(s, &in, &faults[F_EXTRA], f, scen);
        const char *which = NULL;
        fp_control_set *cs = &s->cs;
        if (!canaries_intact(s, &which)) {
            fault_add(&faults[F_CANARY], f, scen,
                      "wrote past the capacity of the host's %s array (%zu entries; the canary after "
                      "it was overwritten); count %zu",
                      which, !strcmp(which, "channels") ? cs->channel_capacity : cs->capacity, cs->count);
            *dead = true; /* the host's memory is no longer trustworthy: stop here */
            memset(s->start[FP_CONTROL_CAPACITY], canary_byte, sizeof s->start[0] * GUARD);
            memset(s->end[FP_CONTROL_CAPACITY], canary_byte, sizeof s->end[0] * GUARD);
            memset(&s->ch[FP_CHANNEL_CAPACITY], canary_byte, sizeof s->ch[0] * GUARD);
        }
        if (rc < 0) {
            fault_add(&faults[F_RC], f, scen, "process returned %d (%s)", rc, fp_strerror(rc));
            continue;
        }
        size_t v = 0;
        int at_start = 0;
        const fp_control_fault cf = fp_control_check(cs, &v, &at_start); /* the host's rule */
        if (cf == FP_CONTROL_OVER_CAPACITY) {
            fault_add(&faults[F_COUNT], f, scen, "count %zu > capacity %zu or channel_count %zu > %zu",
                      cs->count, cs->capacity, cs->channel_count, cs->channel_capacity);
            continue;
        }
        if (cf == FP_CONTROL_NO_ARRAY) {
            fault_add(&faults[F_COUNT], f, scen, "count %zu with the start or end array set to NULL (the host's)",
                      cs->count);
            continue;
        }
        if (cf == FP_CONTROL_BAD_RADIUS)
            fault_add(&faults[F_RADIUS], f, scen, "active with radius %g (the host takes %g to %g)", cs->radius,
                      FP_CONTROL_RADIUS_MIN, FP_CONTROL_RADIUS_MAX);
        if (cf == FP_CONTROL_BAD_POINT) {
            const float *p = at_start ? cs->start[v] : cs->end[v];
            const bool finite = isfinite(p[0]) && isfinite(p[1]) && isfinite(p[2]);
            fault_add(&faults[F_NONFINITE], f, scen, "control vector %zu: %s point (%g, %g, %g) %s%s", v,
                      at_start ? "start" : "end", p[0], p[1], p[2],
                      finite ? "lies beyond 1e15 (FP_CONTROL_COORD_MAX)" : "is not finite",
                      in.extra_performers ? " (the frame's hands are finite; only extra_hands' rows "
                      "past FP_HANDS x extra_performers hold NaN: read past them?)" : "");
        }
        for (size_t i = 0; i < cs->channel_count; i++)
            if (!isfinite(cs->channels[i].value) || !memchr(cs->channels[i].name, 0, sizeof cs->channels[i].name)) {
                fault_add(&faults[F_CHANNEL], f, scen, "channel %zu: name not NUL-terminated or value not finite", i);
                break;
            }
        snapshot *sn = &snaps[f];
        memset(sn, 0, sizeof *sn);
        sn->active = cs->active;
        sn->intents = cs->intents;
        sn->radius = cs->active ? cs->radius : 0;
        sn->count = cs->active ? cs->count : 0;
        sn->channel_count = cs->channel_count;
        memcpy(sn->start, cs->start, sn->count * sizeof sn->start[0]);
        memcpy(sn->end, cs->end, sn->count * sizeof sn->end[0]);
        for (size_t i = 0; i < cs->channel_count; i++) {
            memcpy(sn->channels[i].name, cs->channels[i].name, sizeof sn->channels[i].name);
            sn->channels[i].value = cs->channels[i].value;
        }
    }
}

/* The first of n frames whose control sets differ between two passes, or n. */
static size_t first_difference(const snapshot *a, const snapshot *b, size_t n)
{
    size_t f = 0;
    for (; f < n; f++) {
        const snapshot *x = &a[f], *y = &b[f];
        if (x->active != y->active || x->intents != y->intents || x->radius != y->radius ||
            x->count != y->count || x->channel_count != y->channel_count ||
            memcmp(x->start, y->start, x->count * sizeof x->start[0]) ||
            memcmp(x->end, y->end, x->count * sizeof x->end[0]))
            break;
        bool same = true;
        for (size_t i = 0; i < x->channel_count; i++)
            same &= !strncmp(x->channels[i].name, y->channels[i].name, sizeof x->channels[i].name) &&
                    x->channels[i].value == y->channels[i].value;
        if (!same) break;
    }
    return f;
}

/* The same sequence with the mapping in a helper process (fp_isolate.h): the control sets
 * must be those of the first pass in process (`a`), frame for frame. */
static void check_isolated(checker *c, creator *cr, const snapshot *a)
{
    const fp_check_options *o = c->opt;
    fp_isolate_options io = {.helper = o->helper, .deadline_ms = 10000, .quiet_restarts = true};
    fp_mapping *m = NULL;
    char msg[1024] = "";
    if (c->progress) c->progress(c->progress_user, "create in a helper process", 0);
    int rc = fp_isolate_mapping_create(&io, c->who, c->sum->name, &cr->host, o->params, o->nparams, &m, msg,
                                       sizeof msg);
    if (rc) {
        report(c, FP_CHECK_FAIL, "isolated", "in a helper process: %s", msg);
        return;
    }
    scene *s = calloc(1, sizeof *s);
    snapshot *b = calloc(MAX_FRAMES, sizeof *b);
    double *t = calloc(MAX_FRAMES, sizeof *t);
    fault faults[NFAULT];
    faults_init(faults);
    bool dead = false;
    if (s && b && t) {
        scene_init(s, c->extra); /* (the helper carries the further performers' hands: isolate_shm.h) */
        const size_t n = s->frames;
        char what[96];
        run_sequence(c, m, s, b, t, faults, &dead);
        fp_isolate_stats st;
        fp_isolate_mapping_stats(m, &st);
        size_t f = first_difference(a, b, n);
        qsort(t, n, sizeof *t, cmp_double);
        if (st.faults || dead)
            report(c, FP_CHECK_FAIL, "isolated", "in a helper process: %lu fault(s) (a crash or a hang "
                   "there that in process did not happen)", st.faults);
        else if (f < n)
            report(c, FP_CHECK_FAIL, "isolated", "in a helper process frame %zu (%s) gave another control "
                   "set (active %d/%d, count %zu/%zu): it depends on something the copy does not carry "
                   "(shared globals? a pointer kept from an earlier frame?)", f,
                   frame_what(s, f, what, sizeof what), a[f].active, b[f].active, a[f].count, b[f].count);
        else
            report(c, FP_CHECK_PASS, "isolated", "in a helper process the same %zu frames gave identical "
                   "control sets (a call's median %.1f us there, copies and wake-ups included)", n,
                   t[n / 2]);
    } else {
        report(c, FP_CHECK_FAIL, "memory", "out of memory");
    }
    m->destroy(m);
    free(s);
    free(b);
    free(t);
}

static void check_mapping(checker *c, creator *cr)
{
    void *inst;
    char msg[1024];
    int rc = create_with(cr, NULL, 0, &inst, msg, sizeof msg);
    if (rc) return; /* reported by check_keys */
    fp_mapping *m = inst;
    if (!FP_HAS_FIELD(m, fp_mapping, destroy) || !m->process) {
        report(c, FP_CHECK_FAIL, "instance", "the fp_mapping has size %u or no process()", m->size);
        destroy_inst(cr, m);
        return;
    }
    /* Frames with further performers only for a plugin that knows them: a host must not
     * rely on fields past those of the plugin's ABI (plugin.h) */
    const fp_version abi = cr->plugin->entry->abi;
    c->extra = abi.minor >= 3;
    if (!c->extra)
        report(c, FP_CHECK_INFO, "performers", "the plugin declares ABI %u.%u, before 1.3: no frames with "
               "further performers' hands (fp_frame_input.extra_hands)", abi.major, abi.minor);
    scene *s = calloc(1, sizeof *s);
    snapshot *a = calloc(MAX_FRAMES, sizeof *a), *b = calloc(MAX_FRAMES, sizeof *b);
    double *ta = calloc(MAX_FRAMES, sizeof *ta), *tb = calloc(MAX_FRAMES, sizeof *tb);
    fault faults[NFAULT];
    faults_init(faults);
    bool dead = false; /* read after `out` too */
    if (!s || !a || !b || !ta || !tb) {
        report(c, FP_CHECK_FAIL, "memory", "out of memory");
        goto out;
    }
    scene_init(s, c->extra);
    const size_t n = s->frames;
    run_sequence(c, m, s, a, ta, faults, &dead);
    bool ran_twice = false;
    if (!dead) {
        if (m->reset) {
            enter(c, "reset", n);
            m->reset(m);
            fp_plugin_call_leave();
        }
        fault again[NFAULT];
        faults_init(again);
        run_sequence(c, m, s, b, tb, again, &dead);
        for (int k = 0; k < NFAULT; k++)
            if (!faults[k].count && again[k].count) faults[k] = again[k];
        ran_twice = true;
    }
    bool any = false;
    for (int k = 0; k < NFAULT; k++)
        if (faults[k].count) {
            any = true;
            report(c, FP_CHECK_FAIL, faults[k].what, "%s; %zu frame(s)", faults[k].detail, faults[k].count);
        }
    if (!any)
        report(c, FP_CHECK_PASS, "control sets",
               "%zu frames (no hands, one hand, both, touching and far, edge poses%s; without and "
               "with a rig): count <= capacity, canaries intact, points finite within 1e15, radius in [1e-15, 1e15]", n,
               c->extra ? ", with further performers" : "");
    if (!any && c->extra)
        report(c, FP_CHECK_PASS, "performers", "%d frames with 1 and %d further performers (hands far, "
               "touching, edge poses, gone): extra_hands and extra_tip_distance left as given", 2 * XSEQ,
               FP_PERFORMER_CAPACITY - 1);
    /* Timing: per frame the lower of the two runs. */
    size_t nt = dead ? 0 : n;
    double *t = calloc(MAX_FRAMES, sizeof *t);
    char what[96];
    if (t && nt) {
        size_t worst = 0;
        for (size_t f = 0; f < nt; f++) {
            t[f] = ran_twice && tb[f] < ta[f] ? tb[f] : ta[f];
            if (t[f] > t[worst]) worst = f;
        }
        double max = t[worst];
        qsort(t, nt, sizeof *t, cmp_double);
        c->sum->frames = nt;
        c->sum->median_us = t[nt / 2];
        c->sum->max_us = max;
        double budget_us = c->opt->budget_ms * 1e3;
        if (max > budget_us)
            report(c, FP_CHECK_FAIL, "time",
                   "process took %.3f ms on frame %zu (in both runs), over the budget of %g ms "
                   "(median %.3f ms; %s)", max / 1e3, worst, c->opt->budget_ms, c->sum->median_us / 1e3,
                   frame_what(s, worst, what, sizeof what));
        else
            report(c, FP_CHECK_PASS, "time", "process median %.1f us, max %.1f us (budget %g ms)",
                   c->sum->median_us, max, c->opt->budget_ms);
    }
    free(t);
    if (ran_twice && !any) {
        size_t f = first_difference(a, b, n);
        if (f < n)
            report(c, FP_CHECK_FAIL, "determinism",
                   "after reset the same frames gave a different control set on frame %zu, %s "
                   "(active %d/%d, count %zu/%zu, intents %u/%u)", f, frame_what(s, f, what, sizeof what),
                   a[f].active, b[f].active, a[f].count, b[f].count, a[f].intents, b[f].intents);
        else
            report(c, FP_CHECK_PASS, "determinism", "after reset the same %zu frames gave identical control sets",
                   n);
        if (f == n && c->opt->isolate) check_isolated(c, cr, a);
    } else if (!m->reset && !dead) {
        report(c, FP_CHECK_INFO, "determinism", "the mapping has no reset()");
    }
out:
    if (!dead) {
        destroy_inst(cr, m);
        report(c, FP_CHECK_PASS, "destroy", "destroyed");
    } else {
        report(c, FP_CHECK_INFO, "destroy", "not destroyed: the host's memory was overwritten");
    }
    free(s);
    free(a);
    free(b);
    free(ta);
    free(tb);
}

/* ---- inputs ------------------------------------------------------------------------------ */

typedef struct input_host {
    fp_event_queue queue;
    atomic_bool stopped;          /* stop() returned */
    atomic_ulong after_stop;      /* pushes after that */
    atomic_ulong bad_size;        /* pushes with a size no event has */
    atomic_uint_least64_t first_bad; /* the first of them: its size << 32 | its type */
} input_host;

static bool ih_push(const fp_host *host, const fp_event_header *ev)
{
    input_host *ih = host->host_data;
    if (atomic_load(&ih->stopped)) {
        atomic_fetch_add(&ih->after_stop, 1);
        return false;
    }
    if (!ev) return false;
    if (ev->size < sizeof *ev || ev->size > sizeof(fp_event)) { /* true, as the host answers (do
        * not send it again; before: false, a full queue, which a pacer retries for good) */
        uint_least64_t none = 0;
        atomic_compare_exchange_strong(&ih->first_bad, &none, (uint_least64_t)ev->size << 32 | ev->type);
        atomic_fetch_add(&ih->bad_size, 1);
        return true;
    }
    return fp_event_queue_push(&ih->queue, ev);
}
static int64_t ih_now(const fp_host *host) { (void)host; return now_ns(); }
static void ih_log(const fp_host *host, fp_log_level level, const char *message)
{
    (void)host; (void)level; (void)message;
}
static const void *ih_ext(const fp_host *host, const char *id) { (void)host; (void)id; return NULL; }

/* Why ev is malformed, or NULL: its content and its time, the host's rule (fp_event_check.h).
 * now: the host's clock when the queue is read; own_clock: the input keeps its own. */
static const char *event_problem(const fp_event *ev, int64_t now, bool own_clock)
{
    const char *why;
    if (fp_event_check(ev, &why) || fp_event_check_time(ev, now, own_clock, &why)) return why;
    return NULL;
}

static void check_input(checker *c, creator *cr)
{
    input_host *ih = calloc(1, sizeof *ih);
    if (!ih || fp_event_queue_init(&ih->queue, 8192)) {
        report(c, FP_CHECK_FAIL, "memory", "out of memory");
        free(ih);
        return;
    }
    cr->host.host_data = ih;
    cr->host.push_event = ih_push;
    int cycles = c->opt->cycles;
    size_t events = 0, bad = 0;
    char first_bad[256] = "";
    bool skipped = false, failed = false;
    for (int k = 0; k < cycles && !skipped && !failed; k++) {
        atomic_store(&ih->stopped, false);
        void *inst;
        char msg[1024];
        int rc = create_with(cr, NULL, 0, &inst, msg, sizeof msg);
        if (rc) {
            report(c, FP_CHECK_FAIL, "cycle", "cycle %d: create failed with %d: %s", k + 1, rc, msg);
            failed = true;
            break;
        }
        fp_input *in = inst;
        if (!FP_HAS_FIELD(in, fp_input, destroy) || !in->start || !in->destroy) {
            report(c, FP_CHECK_FAIL, "instance", "the fp_input has size %u, or no start or destroy", in->size);
            destroy_inst(cr, in);
            failed = true;
            break;
        }
        enter(c, "start", 0);
        rc = in->start(in, msg, sizeof msg);
        fp_plugin_call_leave();
        msg[sizeof msg - 1] = '\0';
        if (rc) {
            if (device_code(rc) && msg[0]) {
                report(c, FP_CHECK_SKIP, "start", "needs a device: start failed with %d (%s): %s", rc,
                       fp_strerror(rc), msg);
                skipped = true;
            } else {
                report(c, FP_CHECK_FAIL, "start", "cycle %d: start failed with %d (%s): %s", k + 1, rc,
                       fp_strerror(rc), msg[0] ? msg : "(no message)");
                failed = true;
            }
        } else {
            struct timespec ts = {0, 100 * 1000000L};
            nanosleep(&ts, NULL);
        }
        if (in->stop) {
            enter(c, "stop", 0);
            in->stop(in);
            fp_plugin_call_leave();
        }
        atomic_store(&ih->stopped, true);
        /* a device's events are measured by now; a recording's are on its own clock
         * (fp_event_check_time, as the host applies it at push_event) */
        const bool own_clock = fp_input_own_clock(in);
        const int64_t now = now_ns();
        fp_event ev;
        while (fp_event_queue_pop(&ih->queue, &ev)) {
            events++;
            const char *why = event_problem(&ev, now, own_clock);
            if (why && !bad++)
                snprintf(first_bad, sizeof first_bad, "cycle %d, event %zu (type %u, size %u, hand %d): %s",
                         k + 1, events, ev.header.type, ev.header.size, ev.header.hand, why);
        }
        /* Give a thread that outlived stop() a moment to show itself. */
        struct timespec ts = {0, 20 * 1000000L};
        nanosleep(&ts, NULL);
        destroy_inst2(cr, in, true);
    }
    if (!skipped && !failed)
        report(c, FP_CHECK_PASS, "cycle", "%d x create, start, stop, destroy", cycles);
    c->sum->events = events;
    if (bad)
        report(c, FP_CHECK_FAIL, "events", "%zu of %zu events malformed; first: %s", bad, events, first_bad);
    else if (!skipped)
        report(c, FP_CHECK_PASS, "events", "%zu events well-formed", events);
    uint_least64_t first = atomic_load(&ih->first_bad);
    if (atomic_load(&ih->bad_size))
        report(c, FP_CHECK_FAIL, "events", "%lu push_event calls with a size no event has (the first: "
               "%s, header.type %u, of %u bytes; the host takes %zu to %zu, sizeof(fp_event))",
               atomic_load(&ih->bad_size), fp_event_type_name((uint32_t)(first & 0xffff)),
               (unsigned)(first & 0xffff), (unsigned)(first >> 32), sizeof(fp_event_header), sizeof(fp_event));
    if (atomic_load(&ih->after_stop))
        report(c, FP_CHECK_FAIL, "stop", "%lu push_event calls after stop() returned",
               atomic_load(&ih->after_stop));
    fp_event_queue_destroy(&ih->queue);
    free(ih);
}

/* ---- the entry ------------------------------------------------------------------------- */

int fp_plugin_check_direct(const char *file, const fp_check_options *opt_in, fp_check_fn fn, void *user,
                           fp_check_progress_fn progress, void *progress_user, fp_check_summary *sum,
                           char *err, size_t errlen)
{
    fp_check_options opt = opt_in ? *opt_in : (fp_check_options){0};
    if (!(opt.budget_ms > 0)) opt.budget_ms = 2;
    if (opt.cycles <= 0) opt.cycles = 5;
    fp_check_summary local;
    if (!sum) sum = &local;
    memset(sum, 0, sizeof *sum);
    checker c = {fn, user, sum, &opt, file, false, progress, progress_user};
    const char *base = strrchr(file, '/');
    base = base ? base + 1 : file;
    fp_plugin_path none;
    memset(&none, 0, sizeof none);
    none.builtin = SIZE_MAX;
    fp_plugin p;
    int rc;
    if (progress) progress(progress_user, "load", 0); /* (dlopen runs its constructors) */
    if (!strncmp(base, "input-", 6)) {
        rc = fp_plugin_load(&none, FP_PLUGIN_INPUT, file, &p, err, errlen);
    } else {
        rc = fp_plugin_load(&none, FP_PLUGIN_MAPPING, file, &p, err, errlen);
        if (rc == FP_EPLUGIN_NO_FACTORY || !strncmp(base, "map-", 4)) {
            if (rc == FP_EPLUGIN_NO_FACTORY && strncmp(base, "map-", 4))
                rc = fp_plugin_load(&none, FP_PLUGIN_INPUT, file, &p, err, errlen);
        }
    }
    if (rc) {
        report(&c, FP_CHECK_FAIL, "load", "%s", err);
        return rc;
    }
    sum->kind = p.kind;
    snprintf(sum->id, sizeof sum->id, "%s", p.entry->id ? p.entry->id : "");
    snprintf(sum->version, sizeof sum->version, "%s", p.entry->version ? p.entry->version : "");
    fp_plugin_about about;
    fp_plugin_describe(&p, &about);
    snprintf(sum->name, sizeof sum->name, "%s", about.name);
    report(&c, FP_CHECK_PASS, "load", "%s plugin '%s' (%s %s), ABI %u.%u",
           p.kind == FP_PLUGIN_INPUT ? "input" : "mapping", about.name, sum->id, sum->version,
           p.entry->abi.major, p.entry->abi.minor);
    if (!about.description || !*about.description)
        report(&c, FP_CHECK_INFO, "factory", "the factory has no description");
    creator cr = {&c, &p, {0}};
    cr.host.size = sizeof cr.host;
    cr.host.abi = (fp_version){FP_PLUGIN_ABI_MAJOR, FP_PLUGIN_ABI_MINOR};
    cr.host.now_ns = ih_now;
    cr.host.log = ih_log;
    cr.host.get_extension = ih_ext;
    /* A scratch queue for inputs whose create already pushes (before check_input's host). */
    input_host scratch;
    memset(&scratch, 0, sizeof scratch);
    atomic_store(&scratch.stopped, true);
    cr.host.host_data = &scratch;
    cr.host.push_event = p.kind == FP_PLUGIN_INPUT ? ih_push : NULL;
    bool device = false;
    if (check_keys(&cr, about.params, &device)) {
        if (p.kind == FP_PLUGIN_MAPPING) check_mapping(&c, &cr);
        else check_input(&c, &cr);
    }
    fp_plugin_unload(&p);
    if (sum->failed) {
        snprintf(err, errlen, "%s: %u check(s) failed", file, sum->failed);
        return FP_EPLUGIN_FAULT;
    }
    return 0;
}
