/* An isolated mapping (fp_isolate.h): the proxy fp_mapping the session calls, the frame's
 * copy into the shared memory and back, the watchdog's faults, the held control set, the
 * restarts with their back-off and the give-up. The process itself: isolate_proc.c. */
#define _GNU_SOURCE
#include "fp_isolate.h"
#include "fp_control_check.h"
#include "isolate_proc.h"
#include "log_relay.h"

#include "fp_clock.h"
#include "fp_file.h"

#include <errno.h>
#include <fcntl.h>
#include <unistd.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

enum state { UP, STARTING, WAITING, GAVE_UP, STOPPED };

typedef struct proxy {
    fp_mapping m;                        /* what the session holds; plugin_data is this */
    const fp_host *host;                 /* the session's, for log and its extensions */
    const fp_host_surface *surface;
    const fp_host_rig *rig;
    const fp_host_fault_notice *notice;  /* the host's record of faults (the take), or NULL */
    const fp_host_base_version *base_ext; /* when the base changed, or NULL: copied every frame */
    uint64_t base_version;               /* the version of the base in the shared memory */
    const float *base_ptr;               /* and where it came from */
    size_t base_n;
    bool base_valid;                     /* false: copy it at the next frame (a new helper) */
    uint64_t base_off;
    const uint8_t *region_ptr;           /* the rig's regions in the shared memory: from */
    size_t region_n;
    uint64_t region_off;
    bool region_valid;                   /* false: copy them at the next frame (a new helper) */
    char exe[4096], file[4096], name[64];
    int file_fd;                         /* the plugin file, open: a restart loads it from here
                                            (/proc/self/fd/N), even if the file was removed
                                            (live's hot reload loads a copy it removes) */
    fp_spec keys;                        /* the SPEC's keys, for each restart */
    double deadline_ms;
    bool quiet_restarts;
    bool never_wait;    /* fp_isolate_options.never_wait */
    fp_iso_proc proc;
    enum state state;
    int64_t frame_ns;                    /* the time of the frame being processed (its
                                            fp_frame_input.time_ns): the restarts' clock */
    int64_t restart_at;                  /* WAITING: the first frame time the new helper serves */
    int streak;                          /* faults in a row */
    unsigned long calls_ok;              /* calls answered by this helper */
    fp_isolate_stats stats;
    unsigned relayed;                    /* the plugin's log lines relayed this frame */
    unsigned long relay_dropped;         /* and those dropped over FP_ISOLATE_LOG_LINES */
    /* the last good control set, held while the helper is away */
    fp_control_set last;
    float last_start[FP_CONTROL_CAPACITY][3], last_end[FP_CONTROL_CAPACITY][3];
    fp_channel last_channels[FP_CHANNEL_CAPACITY];
    const fp_rig_view *rig_at_create;
    char id[400], version[400];          /* the plugin entry's, as its helper said */
} proxy;

int fp_isolate_mode_parse(const char *text, fp_isolate_mode *out)
{
    if (!text) return -EINVAL;
    if (!strcmp(text, "none")) *out = FP_ISOLATE_NONE;
    else if (!strcmp(text, "third-party")) *out = FP_ISOLATE_THIRD_PARTY;
    else if (!strcmp(text, "all")) *out = FP_ISOLATE_ALL;
    else return -EINVAL;
    return 0;
}

const char *fp_isolate_mode_name(fp_isolate_mode mode)
{
    return mode == FP_ISOLATE_ALL ? "all" : mode == FP_ISOLATE_NONE ? "none" : "third-party";
}

bool fp_isolate_wanted(fp_isolate_mode mode, bool builtin)
{
    return mode == FP_ISOLATE_ALL || (mode == FP_ISOLATE_THIRD_PARTY && !builtin);
}

static void say(proxy *x, fp_log_level level, const char *fmt, ...)
{
    char line[1024];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(line, sizeof line, fmt, ap);
    va_end(ap);
    if (x->host && x->host->log) x->host->log(x->host, level, line);
}

/* The plugin's lines a frame takes at most: the host's log keeps FP_LOG_RELAY_LINES a frame
 * and drops the newest, so a plugin that floods its log (from process, against the rule)
 * would push out the proxy's own lines said after them (a fault, a restart): the rest of
 * the ring is kept for those. */
#define FP_ISOLATE_LOG_LINES (FP_LOG_RELAY_LINES - 8)

static void relay_log(void *user, int level, const char *message)
{
    proxy *x = user;
    if (level == FP_ISO_LOG_UNSENT) { /* lines the helper had no room to send */
        x->relay_dropped += strtoul(message, NULL, 10);
        return;
    }
    if (x->relayed >= FP_ISOLATE_LOG_LINES) {
        x->relay_dropped++;
        return;
    }
    x->relayed++;
    if (x->host && x->host->log) x->host->log(x->host, (fp_log_level)level, message);
}

/* A frame's end: say how many of the plugin's lines were dropped, and start counting anew. */
static void relay_frame_end(proxy *x)
{
    if (x->relay_dropped)
        say(x, FP_LOG_WARNING, "%lu log line%s of the plugin dropped (more than %d in a frame)",
            x->relay_dropped, x->relay_dropped == 1 ? "" : "s", FP_ISOLATE_LOG_LINES);
    x->relay_dropped = 0;
    x->relayed = 0;
}

/* ---- the frame into the shared memory ------------------------------------------------- */

static size_t align64(size_t n) { return (n + 63) & ~(size_t)63; }

/* Strings of the rig: its name, then each landmark's and channel's. */
static size_t rig_strings(const fp_rig_view *r)
{
    size_t n = strlen(r->name ? r->name : "") + 1;
    for (size_t i = 0; i < r->landmark_count; i++) n += strlen(r->landmarks[i].name ? r->landmarks[i].name : "") + 1;
    for (size_t i = 0; i < r->channel_count; i++) n += strlen(r->channels[i].name ? r->channels[i].name : "") + 1;
    return n;
}

/* The layout of the variable part for `n` vertices and rig r (may be NULL): offsets into
 * shm (when not NULL) and the total size. */
static size_t layout(size_t n, const fp_rig_view *r, fp_iso_shm *shm)
{
    size_t off = align64(sizeof(fp_iso_shm)), base = off;
    off = align64(off + n * 3 * sizeof(float));
    size_t region = off;
    off = align64(off + (r ? r->vertex_count : 0));
    size_t lm = off;
    off = align64(off + (r ? r->landmark_count * sizeof(fp_iso_landmark) : 0));
    size_t ch = off;
    off = align64(off + (r ? r->channel_count * sizeof(fp_iso_channel) : 0));
    size_t str = off;
    off += r ? rig_strings(r) : 0;
    if (shm) {
        shm->off_base = base;
        shm->off_region = region;
        shm->off_landmarks = lm;
        shm->off_channels = ch;
        shm->off_strings = str;
    }
    return off;
}

static uint32_t put_string(char *strings, size_t *used, const char *s)
{
    size_t at = *used, len = strlen(s ? s : "") + 1;
    memcpy(strings + at, s ? s : "", len);
    *used += len;
    return (uint32_t)at;
}

/* The rig into the shared memory (its layout already set); its regions only with
 * `regions` (they change with the rig alone). */
static void put_rig(fp_iso_shm *s, const fp_rig_view *r, bool regions)
{
    s->has_rig = r != NULL;
    if (!r) return;
    s->rig = *r;
    char *base = (char *)s, *strings = base + s->off_strings;
    size_t used = 0;
    s->rig_name = put_string(strings, &used, r->name);
    if (regions && r->vertex_count && r->region) memcpy(base + s->off_region, r->region, r->vertex_count);
    fp_iso_landmark *l = (fp_iso_landmark *)(base + s->off_landmarks);
    for (size_t i = 0; i < r->landmark_count; i++) {
        l[i].name = put_string(strings, &used, r->landmarks[i].name);
        l[i].vertex = r->landmarks[i].vertex;
        memcpy(l[i].position, r->landmarks[i].position, sizeof l[i].position);
    }
    fp_iso_channel *c = (fp_iso_channel *)(base + s->off_channels);
    for (size_t i = 0; i < r->channel_count; i++) {
        const fp_rig_channel_info *ci = &r->channels[i];
        c[i] = (fp_iso_channel){put_string(strings, &used, ci->name), ci->min, ci->max, ci->neutral, ci->value};
    }
}

static void fill_create(void *user, fp_iso_shm *s)
{
    proxy *x = user;
    const fp_rig_view *r = x->rig_at_create;
    layout(r ? r->vertex_count : 0, r, s);
    put_rig(s, r, true);
}

/* The further performers' hands and tip distances (ABI 1.3) by value; the helper points
 * its frame's extra_hands and extra_tip_distance at them. */
static void put_extra_hands(fp_iso_shm *s, const fp_frame_input *in)
{
    uint32_t extra = 0;
    if (FP_HAS_FIELD(in, fp_frame_input, extra_tip_distance) && in->extra_hands && in->extra_tip_distance)
        extra = in->extra_performers < FP_PERFORMER_CAPACITY - 1 ? in->extra_performers : FP_PERFORMER_CAPACITY - 1;
    s->in.extra_performers = extra;
    s->in.extra_hands = NULL;
    s->in.extra_tip_distance = NULL;
    if (!extra) return;
    memcpy(s->extra_hands, in->extra_hands, FP_HANDS * extra * sizeof s->extra_hands[0]);
    memcpy(s->extra_tips, in->extra_tip_distance, FP_HANDS * extra * sizeof s->extra_tips[0]);
}

/* This frame's input and the host's control set into the shared memory. */
static int put_frame(proxy *x, const fp_frame_input *in, const fp_control_set *out)
{
    size_t n = in->mesh && in->mesh->base ? in->mesh->vertex_count : 0;
    const fp_rig_view *r = FP_HAS_FIELD(in, fp_frame_input, rig) ? in->rig : NULL;
    int rc = fp_iso_proc_reserve(&x->proc, layout(n, r, NULL));
    if (rc) return rc;
    fp_iso_shm *s = x->proc.shm;
    layout(n, r, s);
    size_t insize = in->size < sizeof s->in ? in->size : sizeof s->in;
    memset(&s->in, 0, sizeof s->in);
    memcpy(&s->in, in, insize);
    s->in.size = in->size < sizeof s->in ? in->size : (uint32_t)sizeof s->in;
    size_t ne = in->events ? in->event_count : 0;
    if (ne > FP_FRAME_EVENT_CAPACITY) ne = FP_FRAME_EVENT_CAPACITY;
    if (ne) memcpy(s->events, in->events, ne * sizeof s->events[0]);
    s->in.event_count = ne;
    put_extra_hands(s, in);
    s->has_mesh = in->mesh != NULL;
    if (in->mesh) {
        s->mesh = *in->mesh;
        /* the base only when it may have changed (the host's version, its address, its
         * size, a new helper): the one copy that grows with the mesh */
        uint64_t v = x->base_ext ? x->base_ext->get(x->host) : 0;
        if (n && (!x->base_ext || !x->base_valid || v != x->base_version || in->mesh->base != x->base_ptr ||
                  n != x->base_n || s->off_base != x->base_off)) {
            memcpy((char *)s + s->off_base, in->mesh->base, n * 3 * sizeof(float));
            x->base_version = v;
            x->base_ptr = in->mesh->base;
            x->base_n = n;
            x->base_off = s->off_base;
            x->base_valid = true;
        }
    }
    bool regions = r && (!x->region_valid || r->region != x->region_ptr || r->vertex_count != x->region_n ||
                         s->off_region != x->region_off);
    put_rig(s, r, regions);
    if (regions) {
        x->region_ptr = r->region;
        x->region_n = r->vertex_count;
        x->region_off = s->off_region;
        x->region_valid = true;
    }
    s->cs = *out;
    if (s->cs.capacity > FP_CONTROL_CAPACITY) s->cs.capacity = FP_CONTROL_CAPACITY;
    if (s->cs.channel_capacity > FP_CHANNEL_CAPACITY) s->cs.channel_capacity = FP_CHANNEL_CAPACITY;
    if (out->start) memcpy(s->start, out->start, s->cs.capacity * sizeof s->start[0]);
    if (out->end) memcpy(s->end, out->end, s->cs.capacity * sizeof s->end[0]);
    if (out->channels) memcpy(s->channels, out->channels, s->cs.channel_capacity * sizeof s->channels[0]);
    return 0;
}

/* The first canary the plugin overwrote in the shared arrays, or NULL. */
static const char *overwritten(const fp_iso_shm *s)
{
    const unsigned char *p[3] = {(const unsigned char *)s->start[FP_CONTROL_CAPACITY],
                                 (const unsigned char *)s->end[FP_CONTROL_CAPACITY],
                                 (const unsigned char *)&s->channels[FP_CHANNEL_CAPACITY]};
    const size_t len[3] = {sizeof s->start[0] * FP_ISO_GUARD, sizeof s->end[0] * FP_ISO_GUARD,
                           sizeof s->channels[0] * FP_ISO_GUARD};
    static const char *names[3] = {"start", "end", "channels"};
    for (int a = 0; a < 3; a++)
        for (size_t i = 0; i < len[a]; i++)
            if (p[a][i] != FP_ISO_CANARY) return names[a];
    return NULL;
}

/* The helper's control set into the host's (counts clamped to the capacities: the host's
 * own check reports a count above them). The capacities are the host's own, never read back
 * from the shared memory: the plugin can write there (before its arrays, into the shared
 * set's scalars), and a capacity it overwrote made this copy run past out's arrays. */
static void get_controls(proxy *x, fp_control_set *out)
{
    const fp_iso_shm *s = x->proc.shm;
    out->active = s->cs.active;
    out->intents = s->cs.intents;
    out->radius = s->cs.radius;
    out->count = s->cs.count;
    out->channel_count = s->cs.channel_count;
    size_t cap = out->capacity < FP_CONTROL_CAPACITY ? out->capacity : FP_CONTROL_CAPACITY;
    size_t ccap = out->channel_capacity < FP_CHANNEL_CAPACITY ? out->channel_capacity : FP_CHANNEL_CAPACITY;
    size_t nc = out->count < cap ? out->count : cap;
    size_t nh = out->channel_count < ccap ? out->channel_count : ccap;
    if (out->start && nc) memcpy(out->start, s->start, nc * sizeof s->start[0]);
    if (out->end && nc) memcpy(out->end, s->end, nc * sizeof s->end[0]);
    if (out->channels && nh) memcpy(out->channels, s->channels, nh * sizeof s->channels[0]);
}

static void keep_last(proxy *x, const fp_control_set *cs)
{
    x->last = *cs;
    size_t nc = cs->count < FP_CONTROL_CAPACITY ? cs->count : FP_CONTROL_CAPACITY;
    size_t nh = cs->channel_count < FP_CHANNEL_CAPACITY ? cs->channel_count : FP_CHANNEL_CAPACITY;
    x->last.count = nc;
    x->last.channel_count = nh;
    if (nc) {
        memcpy(x->last_start, cs->start, nc * sizeof x->last_start[0]);
        memcpy(x->last_end, cs->end, nc * sizeof x->last_end[0]);
    }
    if (nh) memcpy(x->last_channels, cs->channels, nh * sizeof x->last_channels[0]);
}

/* The held set: the last good one without its intents; inactive where it committed (its
 * step is in the base already) or was inactive. */
static void hold(proxy *x, const fp_frame_input *in, fp_control_set *out)
{
    x->stats.held++;
    bool active = x->last.active && !(x->last.intents & (FP_INTENT_COMMIT | FP_INTENT_CANCEL));
    out->active = active;
    out->intents = 0;
    out->radius = x->last.radius > 0 ? x->last.radius : in->radius;
    size_t nc = active && x->last.count <= out->capacity ? x->last.count : 0;
    out->count = nc;
    if (nc) {
        memcpy(out->start, x->last_start, nc * sizeof x->last_start[0]);
        memcpy(out->end, x->last_end, nc * sizeof x->last_end[0]);
    }
    size_t nh = x->last.channel_count <= out->channel_capacity ? x->last.channel_count : 0;
    out->channel_count = nh;
    if (nh) memcpy(out->channels, x->last_channels, nh * sizeof x->last_channels[0]);
}

/* ---- the watchdog ------------------------------------------------------------------------ */

static int surface_answer(void *user, fp_iso_shm *s)
{
    proxy *x = user;
    if (!x->surface) return -ENOTSUP;
    if (s->surf_count > FP_ISO_SURFACE_MAX) return -EINVAL; /* (shared: the plugin may write it) */
    return x->surface->nearest(x->host, (const float(*)[3])s->surf_points, s->surf_count, s->surf_max,
                               s->surf_hits);
}

static uint32_t offers(const proxy *x) { return (x->surface ? 1u : 0u) | (x->rig ? 2u : 0u); }

static int spawn(proxy *x)
{
    x->base_valid = false;
    x->region_valid = false;
    x->rig_at_create = x->rig ? x->rig->get(x->host) : NULL;
    size_t bytes = layout(x->rig_at_create ? x->rig_at_create->vertex_count : 0, x->rig_at_create, NULL);
    char via_fd[64];
    bool restart = x->stats.faults > 0 && x->file_fd >= 0;
    if (restart) snprintf(via_fd, sizeof via_fd, "/proc/self/fd/%d", x->file_fd);
    return fp_iso_proc_spawn(&x->proc, x->exe, FP_ISOLATE_HELPER_ARG, restart ? via_fd : x->file,
                             restart ? x->file_fd : -1, x->name, x->keys.params, x->keys.nparams, bytes, offers(x),
                             fill_create, x);
}

/* A fault: the helper is gone or killed; say why once, and when it comes back. */
static void fault(proxy *x, const char *call, uint64_t frame, const char *cause)
{
    if (x->notice) { /* the take's status event: 116 bytes, so the short form */
        char text[116];
        snprintf(text, sizeof text, "mapping '%.40s' fault: %s during %s (frame %llu)", x->name,
                 strstr(cause, "deadline") ? "deadline missed" : strstr(cause, "SIG") ? strstr(cause, "SIG") : "helper gone",
                 call, (unsigned long long)frame);
        x->notice->notice(x->host, text);
    }
    x->stats.faults++;
    x->streak++;
    x->calls_ok = 0;
    if (x->streak >= FP_ISOLATE_MAX_FAULTS) {
        x->state = GAVE_UP;
        x->stats.gave_up = true;
        say(x, FP_LOG_ERROR,
            "isolated: %s during %s (frame %llu); %d faults in a row: given up, the face stays as it "
            "was and the session goes on without this mapping",
            cause, call, (unsigned long long)frame, x->streak);
        return;
    }
    double wait = FP_ISOLATE_BACKOFF_MS;
    for (int i = 1; i < x->streak && wait < FP_ISOLATE_BACKOFF_MAX_MS; i++) wait *= 2;
    if (wait > FP_ISOLATE_BACKOFF_MAX_MS) wait = FP_ISOLATE_BACKOFF_MAX_MS;
    x->state = WAITING;
    x->restart_at = x->frame_ns + (int64_t)(wait * 1e6); /* on the frames' clock, not the wall's */
    say(x, FP_LOG_ERROR,
        "isolated: %s during %s (frame %llu); the last control set is held and the helper "
        "restarts in %.1f s (fault %d in a row)", cause, call, (unsigned long long)frame, wait / 1e3, x->streak);
}

/* The call a helper that has not said READY was in: "create" from the plugin's create on,
 * "loading" before it (dlopen, the plugin's init). */
static const char *start_call(const proxy *x)
{
    return x->proc.shm && atomic_load(&x->proc.shm->stage) >= FP_ISO_STAGE_CREATE ? "create" : "loading";
}

static void fault_died(proxy *x, const char *call, uint64_t frame)
{
    char why[96] = "went away";
    fp_iso_proc_drain_log(&x->proc, relay_log, x);
    fp_iso_proc_kill(&x->proc, why, sizeof why);
    char cause[160];
    snprintf(cause, sizeof cause, "the helper process %s", why);
    fault(x, call, frame, cause);
}

static void fault_hung(proxy *x, const char *call, uint64_t frame)
{
    fp_iso_proc_kill(&x->proc, NULL, 0);
    char cause[160];
    snprintf(cause, sizeof cause, "no answer within the deadline of %g ms (the helper was killed)", x->deadline_ms);
    fault(x, call, frame, cause);
}

/* Bring the helper up where it is away: false while it is not (yet) there. The restart is
 * decided on the frames' clock (x->frame_ns), so that a run gives the same frames whatever
 * its speed: the new helper is started at the first frame after the fault, in the background,
 * and the frame that is due (restart_at) waits for it to be ready, at most the create's
 * deadline (FP_ISOLATE_CREATE_MS from its start); the frames before hold the set. Live
 * (never_wait) the due frame and those after it only look, holding the set, until then. */
static bool ensure_up(proxy *x, uint64_t frame)
{
    if (x->state == UP) return true;
    if (x->state == GAVE_UP || x->state == STOPPED) return false;
    if (x->state == WAITING) {
        if (x->proc.pid <= 0) {
            int rc = spawn(x);
            if (rc) {
                char cause[160];
                snprintf(cause, sizeof cause, "no helper could be started (%s)", strerror(-rc));
                fault(x, "restart", frame, cause);
                return false;
            }
        }
        if (x->frame_ns < x->restart_at) return false;
        x->state = STARTING;
    }
    double left_ms = FP_ISOLATE_CREATE_MS - (double)(fp_now_ns() - x->proc.started_ns) / 1e6;
    /* live: a look, not a wait, while the create's deadline lasts (the set held meanwhile) */
    int rc = x->never_wait && left_ms > 0 ? fp_iso_proc_poll_ready(&x->proc, relay_log, x)
                                          : fp_iso_proc_wait_ready(&x->proc, left_ms > 0 ? left_ms : 0, relay_log, x);
    if ((rc == FP_ISO_PENDING || rc == FP_ISO_HUNG) && x->never_wait && left_ms > 0) return false;
    if (rc == FP_ISO_PENDING || rc == FP_ISO_HUNG) {
        const char *call = start_call(x);
        fp_iso_proc_kill(&x->proc, NULL, 0);
        char cause[160];
        snprintf(cause, sizeof cause, "the new helper was not ready within %g s (it was killed)",
                 FP_ISOLATE_CREATE_MS / 1e3);
        fault(x, call, frame, cause);
        return false;
    }
    if (rc == FP_ISO_DIED) {
        fault_died(x, start_call(x), frame);
        return false;
    }
    if (x->proc.ready_rc) {
        char cause[1100];
        snprintf(cause, sizeof cause, "the restarted plugin's create failed: %s", x->proc.ready_text);
        fp_iso_proc_kill(&x->proc, NULL, 0);
        fault(x, "create", frame, cause);
        return false;
    }
    x->state = UP;
    x->stats.restarts++;
    if (!x->quiet_restarts)
        say(x, FP_LOG_INFO, "isolated: the helper is back (restart %lu, pid %d) from frame %llu",
            x->stats.restarts, (int)x->proc.pid, (unsigned long long)frame);
    return true;
}

static int frame_process(proxy *x, const fp_frame_input *in, fp_control_set *out)
{
    if (x->state == STOPPED) return FP_EPLUGIN_FAULT;
    x->frame_ns = in->time_ns;
    if (!ensure_up(x, in->frame)) {
        hold(x, in, out);
        return 0;
    }
    int rc = put_frame(x, in, out);
    if (rc) return rc;
    rc = fp_iso_proc_call(&x->proc, FP_ISO_OP_PROCESS, x->deadline_ms, surface_answer, relay_log, x);
    if (rc == FP_ISO_HUNG) fault_hung(x, "process", in->frame);
    else if (rc) fault_died(x, "process", in->frame);
    if (rc) {
        hold(x, in, out);
        return 0;
    }
    const char *which = overwritten(x->proc.shm);
    if (which) {
        say(x, FP_LOG_ERROR, "wrote past the capacity of the host's %s array on frame %llu; the "
            "mapping is stopped, the base stays shown", which, (unsigned long long)in->frame);
        fp_iso_proc_end(&x->proc, 200, relay_log, x);
        x->state = STOPPED;
        return FP_EPLUGIN_FAULT;
    }
    get_controls(x, out);
    rc = x->proc.shm->rc;
    /* the last good set is one the session takes: its rule (fp_control_check.h), else a set
     * it refused (e.g. over capacity, kept clamped) was shown after a later fault */
    if (rc >= 0 && fp_control_check(out, NULL, NULL) == FP_CONTROL_OK) keep_last(x, out);
    if (++x->calls_ok >= FP_ISOLATE_HEALTHY_CALLS) x->streak = 0;
    return rc;
}

static int proxy_process(fp_mapping *self, const fp_frame_input *in, fp_control_set *out)
{
    proxy *x = self->plugin_data;
    int rc = frame_process(x, in, out);
    relay_frame_end(x);
    return rc;
}

static void proxy_reset(fp_mapping *self)
{
    proxy *x = self->plugin_data;
    x->last.active = false;
    x->last.count = 0;
    if (x->state != UP) return;
    int rc = fp_iso_proc_call(&x->proc, FP_ISO_OP_RESET, x->deadline_ms, surface_answer, relay_log, x);
    if (rc == FP_ISO_HUNG) fault_hung(x, "reset", 0);
    else if (rc) fault_died(x, "reset", 0);
}

static void proxy_destroy(fp_mapping *self)
{
    proxy *x = self->plugin_data;
    if (x->proc.pid > 0) fp_iso_proc_end(&x->proc, 1000, relay_log, x);
    if (x->file_fd >= 0) close(x->file_fd);
    fp_spec_clear(&x->keys);
    free(x);
}

bool fp_isolate_mapping_stats(const fp_mapping *m, fp_isolate_stats *out)
{
    if (!m || m->process != proxy_process) return false;
    const proxy *x = m->plugin_data;
    *out = x->stats;
    out->pid = x->state == UP || x->state == STARTING ? (int)x->proc.pid : 0;
    return true;
}

bool fp_isolate_mapping_about(const fp_mapping *m, const char **id, const char **version)
{
    if (!m || m->process != proxy_process) return false;
    const proxy *x = m->plugin_data;
    *id = x->id;
    *version = x->version;
    return true;
}

int fp_iso_open_plugin_file(const char *file, int *rc, char *err, size_t errlen)
{
    int fd = fp_file_open_regular(file);
    if (fd < 0)
        *rc = fp_errorf(err, errlen, FP_EPLUGIN_DLOPEN, "%s: cannot load: %s", file,
                        fd == -ENXIO ? "not a regular file (a FIFO, device or socket)"
                                     : fp_file_error_text(fd));
    return fd < 0 ? -1 : fd;
}

int fp_iso_copy_keys(fp_spec *spec, const fp_param *params, size_t nparams)
{
    memset(spec, 0, sizeof *spec);
    size_t len = 1;
    for (size_t i = 0; i < nparams; i++)
        len += strlen(params[i].key) + strlen(params[i].value ? params[i].value : "") + 2;
    if (!(spec->buffer = malloc(len))) return -ENOMEM;
    char *p = spec->buffer;
    for (size_t i = 0; i < nparams && i < FP_SPEC_MAX_PARAMS; i++) {
        size_t k = strlen(params[i].key) + 1, v = strlen(params[i].value ? params[i].value : "") + 1;
        memcpy(p, params[i].key, k);
        spec->params[i].key = p;
        p += k;
        memcpy(p, params[i].value ? params[i].value : "", v);
        spec->params[i].value = p;
        p += v;
        spec->nparams++;
    }
    return 0;
}

int fp_isolate_mapping_create(const fp_isolate_options *opt, const char *file, const char *name,
                              const fp_host *host, const fp_param *params, size_t nparams,
                              fp_mapping **out, char *err, size_t errlen)
{
    *out = NULL;
    int rc;
    int fd = fp_iso_open_plugin_file(file, &rc, err, errlen);
    if (fd < 0) return rc;
    proxy *x = calloc(1, sizeof *x);
    if (!x || fp_iso_copy_keys(&x->keys, params, nparams)) {
        if (x) fp_spec_clear(&x->keys);
        free(x);
        close(fd);
        return fp_errorf(err, errlen, -ENOMEM, "out of memory");
    }
    fp_iso_proc_init(&x->proc);
    x->m.plugin_data = x;
    x->file_fd = fd;
    x->host = host;
    x->deadline_ms = opt && opt->deadline_ms > 0 ? opt->deadline_ms : FP_ISOLATE_DEADLINE_MS;
    x->quiet_restarts = opt && opt->quiet_restarts;
    x->never_wait = opt && opt->never_wait;
    snprintf(x->exe, sizeof x->exe, "%s", opt && opt->helper ? opt->helper : "/proc/self/exe");
    snprintf(x->file, sizeof x->file, "%s", file);
    snprintf(x->name, sizeof x->name, "%s", name);
    if (host && host->get_extension) {
        x->surface = host->get_extension(host, FP_HOST_EXT_SURFACE);
        x->rig = host->get_extension(host, FP_HOST_EXT_RIG);
        x->notice = host->get_extension(host, FP_HOST_EXT_FAULT_NOTICE);
        x->base_ext = host->get_extension(host, FP_HOST_EXT_BASE_VERSION);
    }
    rc = spawn(x);
    if (rc) {
        proxy_destroy(&x->m);
        return fp_errorf(err, errlen, -EIO, "cannot start its helper process %s: %s",
                         opt && opt->helper ? opt->helper : "/proc/self/exe", strerror(-rc));
    }
    rc = fp_iso_proc_wait_ready(&x->proc, FP_ISOLATE_CREATE_MS, relay_log, x);
    if (rc || x->proc.ready_rc) {
        /* (the caller names the mapping: the message does not) */
        char why[96] = "did not answer";
        const bool in_create = !strcmp(start_call(x), "create");
        if (rc == FP_ISO_DIED) {
            fp_iso_proc_kill(&x->proc, why, sizeof why);
            if (in_create) snprintf(err, errlen, "its helper process %s in the plugin's create", why);
            else snprintf(err, errlen, "its helper process %s while loading %s", why, file);
            rc = FP_EPLUGIN_FAULT;
        } else if (rc) {
            fp_iso_proc_kill(&x->proc, NULL, 0);
            if (in_create)
                snprintf(err, errlen, "the plugin's create did not return within %g s (in its helper process)",
                         FP_ISOLATE_CREATE_MS / 1e3);
            else
                snprintf(err, errlen, "its helper process did not load %s within %g s", file,
                         FP_ISOLATE_CREATE_MS / 1e3);
            rc = FP_EPLUGIN_FAULT;
        } else {
            snprintf(err, errlen, "%s", x->proc.ready_text);
            rc = x->proc.ready_rc;
            fp_iso_proc_kill(&x->proc, NULL, 0);
        }
        proxy_destroy(&x->m);
        return rc;
    }
    char *nl = strchr(x->proc.ready_text, '\n');
    if (nl) *nl = '\0';
    snprintf(x->id, sizeof x->id, "%.399s", x->proc.ready_text);
    snprintf(x->version, sizeof x->version, "%.399s", nl ? nl + 1 : "?");
    x->state = UP;
    x->m.size = sizeof x->m;
    x->m.plugin_data = x;
    x->m.process = proxy_process;
    x->m.reset = proxy_reset;
    x->m.destroy = proxy_destroy;
    x->last.size = sizeof x->last;
    *out = &x->m;
    return 0;
}
