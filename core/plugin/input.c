/* Input instances: a loaded input plugin, the fp_host it pushes through, its queue, and
 * the optional recording of every event it delivered (record=FILE). */
#define _GNU_SOURCE /* pthread_timedjoin_np */
#include "fp_plugin_host.h"

#include "fp_plugin_crash.h"
#include "fp_forward.h"
#include "fp_isolate.h"
#include "fp_record.h"

#include <errno.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#define FP_INPUT_QUEUE_CAPACITY 4096

static bool push_to(fp_input_instance *inst, const fp_event_header *ev)
{
    if (!ev) return false;
    if (ev->size < sizeof *ev || ev->size > sizeof(fp_event)) { /* no room for it: refused, said
        * once with its size (before: false, as for a full queue, which a plugin sends again) */
        uint_least64_t none = 0;
        /* bit 31 marks one as said: an all-zero header (a memset event, size 0, type 0) too */
        atomic_compare_exchange_strong(&inst->oversize, &none,
                                       (uint_least64_t)ev->size << 32 | 1u << 31 | (ev->type & 0xffffu));
        atomic_fetch_add(&inst->refused, 1);
        return true;
    }
    fp_event copy;
    memcpy(&copy, ev, ev->size);
    const char *why;
    fp_event_fault f = fp_event_check(&copy, &why);
    if (!f) f = fp_event_check_time(&copy, inst->own_clock ? 0 : fp_now_ns(), inst->own_clock, &why);
    if (f) { /* dropped here, so a torn or absurd sample never reaches a hand; the owner's
              * next drain says so (no lock on the plugin's thread) */
        const char *none = NULL;
        atomic_compare_exchange_strong(&inst->refused_why[f], &none, why);
        atomic_fetch_add(&inst->refused, 1);
        return true; /* (not a full queue: the plugin must not send it again) */
    }
    copy.header.source = inst->source;
    /* (a recording's times are its own clock's, which speed= stretches: its events' delay is
     * counted from their arrival, fp_session_hand_since) */
    if (!fp_event_queue_push_at(&inst->queue, &copy.header, inst->own_clock ? fp_now_ns() : copy.header.time_ns))
        return false;
    if (inst->forward) fp_event_forwarder_push(inst->forward, &copy); /* (the input's thread) */
    return true;
}

/* The link's instance for one call, busy counted, or NULL once abandoned (then the call does
 * nothing: the instance may be freed). Pair with link_leave. */
static fp_input_instance *link_enter(const fp_host *host)
{
    fp_input_link *l = host ? host->host_data : NULL;
    if (!l) return NULL;
    atomic_fetch_add(&l->busy, 1);
    if (atomic_load(&l->abandoned)) return NULL; /* (seq_cst: the owner sees busy, or we see this) */
    return l->inst;
}
static void link_leave(const fp_host *host)
{
    fp_input_link *l = host ? host->host_data : NULL;
    if (l) atomic_fetch_sub(&l->busy, 1);
}

static bool host_push(const fp_host *host, const fp_event_header *ev)
{
    fp_input_instance *inst = link_enter(host);
    bool taken = inst ? push_to(inst, ev) : true; /* abandoned: dropped, never to be sent again */
    if (!inst && host && host->host_data) /* (counted: the input's closing line says it) */
        atomic_fetch_add(&((fp_input_link *)host->host_data)->dropped, 1);
    link_leave(host);
    return taken;
}

static int64_t host_now(const fp_host *host)
{
    (void)host;
    return fp_now_ns();
}

/* Any thread: the line waits in the instance's relay for its owner (log_relay.h). */
static void host_log(const fp_host *host, fp_log_level level, const char *message)
{
    if (level > FP_LOG_INFO && !getenv("FACEPUPPET_DEBUG")) return;
    fp_input_instance *inst = link_enter(host);
    if (inst) fp_log_relay_push(&inst->log, (int)level, message);
    link_leave(host);
}

void fp_input_instance_set_log(fp_input_instance *inst, fp_host_log_fn fn, void *user)
{
    inst->log_fn = fn;
    inst->log_user = user;
}

/* On the owner's thread: a warning for each kind of malformed event refused since the last
 * drain and never said before (the first such event's reason). */
static void say_refused(fp_input_instance *inst)
{
    for (int f = 1; f < FP_EVENT_FAULTS; f++) {
        const char *why = atomic_load(&inst->refused_why[f]);
        if (!why || (inst->refused_said & (1u << f))) continue;
        inst->refused_said |= 1u << f;
        char line[200];
        snprintf(line, sizeof line, "refused a malformed event: %s; such events are dropped, and "
                 "counted when the input closes", why);
        fp_log_relay_push(&inst->log, FP_LOG_WARNING, line);
    }
    uint_least64_t big = atomic_load(&inst->oversize);
    if (big && !inst->oversize_said) {
        inst->oversize_said = true;
        char line[300];
        unsigned size = (unsigned)(big >> 32), type = (unsigned)(big & 0xffff);
        bool over = size > sizeof(fp_event);
        snprintf(line, sizeof line, "refused an %s event: %s (header.type %u) of %u bytes, %s %zu "
                 "bytes (%s); such events are dropped, and counted when the input closes",
                 over ? "oversize" : "undersize", fp_event_type_name(type), type, size,
                 over ? "over the host's limit of" : "under the", over ? sizeof(fp_event) : sizeof(fp_event_header),
                 over ? "sizeof(fp_event)" : "the event header's size");
        fp_log_relay_push(&inst->log, FP_LOG_WARNING, line);
    }
}

size_t fp_input_instance_drain_log(fp_input_instance *inst)
{
    say_refused(inst);
    return fp_log_relay_drain(&inst->log, inst->name, inst->log_fn, inst->log_user);
}

/* Inputs are offered no host extension; a mapping's host answers through mapping_extension. */
static const void *host_extension(const fp_host *host, const char *id)
{
    (void)host;
    (void)id;
    return NULL;
}

static void host_fill(fp_host *h, void *data)
{
    memset(h, 0, sizeof *h);
    h->size = sizeof *h;
    h->abi = (fp_version){FP_PLUGIN_ABI_MAJOR, FP_PLUGIN_ABI_MINOR};
    h->host_data = data;
    h->push_event = host_push;
    h->now_ns = host_now;
    h->log = host_log;
    h->get_extension = host_extension;
}

static void named_log(const fp_host *host, fp_log_level level, const char *message)
{
    static const char *names[] = {"error", "warning", "info", "debug"};
    if (level > FP_LOG_INFO && !getenv("FACEPUPPET_DEBUG")) return;
    fprintf(stderr, "facepuppet: %s: %s: %s\n", host->host_data ? (const char *)host->host_data : "plugin",
            names[level <= FP_LOG_DEBUG ? level : FP_LOG_DEBUG], message ? message : "");
}

void fp_host_init_for_mapping(fp_host *host, const char *name)
{
    host_fill(host, (void *)name);
    host->log = named_log;
    host->push_event = NULL; /* mappings do not push events */
}

/* host_data is the fp_mapping_host itself (the fp_host is its first member). */
static void mapping_log(const fp_host *host, fp_log_level level, const char *message)
{
    const fp_mapping_host *mh = (const fp_mapping_host *)host;
    if (level > FP_LOG_INFO && !getenv("FACEPUPPET_DEBUG")) return;
    if (mh->relay) { /* any thread: the owner hands it over on its own */
        fp_log_relay_push(mh->relay, (int)level, message);
        return;
    }
    if (mh->log) {
        mh->log(mh->log_user, (int)level, mh->source, message ? message : "");
        return;
    }
    static const char *names[] = {"error", "warning", "info", "debug"};
    fprintf(stderr, "facepuppet: %s: %s: %s\n", mh->source, names[level <= FP_LOG_DEBUG ? level : FP_LOG_DEBUG],
            message ? message : "");
}

/* FP_HOST_EXT_RIG: the session's rig view (host_data is the fp_mapping_host). */
static const fp_rig_view *mapping_rig(const fp_host *host)
{
    const fp_mapping_host *mh = host ? host->host_data : NULL;
    return mh ? mh->rig : NULL;
}

static const fp_host_rig mapping_rig_ext = {mapping_rig};

static void mapping_fault(const fp_host *host, const char *text)
{
    const fp_mapping_host *mh = host ? host->host_data : NULL;
    if (mh && mh->fault) mh->fault(mh->fault_user, text);
}

static const fp_host_fault_notice mapping_fault_ext = {mapping_fault};

static uint64_t mapping_base_version(const fp_host *host)
{
    const fp_mapping_host *mh = host ? host->host_data : NULL;
    return mh && mh->services && mh->services->base_version ? mh->services->base_version(mh->services->user) : 0;
}

static const fp_host_base_version mapping_base_version_ext = {mapping_base_version};

static const void *mapping_extension(const fp_host *host, const char *id)
{
    const fp_mapping_host *mh = host ? host->host_data : NULL;
    if (!id) return NULL;
    if (!strcmp(id, FP_HOST_EXT_RIG)) return &mapping_rig_ext;
    if (!strcmp(id, FP_HOST_EXT_FAULT_NOTICE) && mh && mh->fault) return &mapping_fault_ext;
    if (!strcmp(id, FP_HOST_EXT_BASE_VERSION) && mh && mh->services && mh->services->base_version)
        return &mapping_base_version_ext;
    if (!strcmp(id, FP_HOST_EXT_SURFACE) && mh && mh->services && mh->services->surface.nearest)
        return &mh->services->surface;
    return NULL;
}

void fp_mapping_host_init(fp_mapping_host *mh, const char *name, fp_host_log_fn log, void *log_user)
{
    memset(mh, 0, sizeof *mh);
    host_fill(&mh->host, mh);
    mh->host.log = mapping_log;
    mh->host.push_event = NULL; /* mappings do not push events */
    mh->host.get_extension = mapping_extension;
    snprintf(mh->source, sizeof mh->source, "mapping '%s'", name ? name : "?");
    mh->log = log;
    mh->log_user = log_user;
}

size_t fp_mapping_host_drain_log(fp_mapping_host *mh)
{
    return mh->relay ? fp_log_relay_drain(mh->relay, mh->source, mh->log, mh->log_user) : 0;
}

/* performer=NAME, the host's key (whose hands the input's are): into inst->performer. */
static int take_performer(fp_input_instance *inst, fp_spec *spec, const char *spec_text, char *err,
                          size_t errlen)
{
    const char *name = fp_spec_take(spec, "performer");
    if (!name) return 0;
    size_t n = strlen(name);
    bool ok = n >= 1 && n <= FP_PERFORMER_NAME_MAX;
    for (size_t i = 0; ok && i < n; i++) {
        char c = name[i];
        ok = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '-' || c == '_';
    }
    if (!ok)
        return fp_errorf(err, errlen, -EINVAL, "input '%s': performer=%s: expected a name of 1 to %d "
                         "letters, digits, '-' or '_'", spec_text, name, FP_PERFORMER_NAME_MAX);
    memcpy(inst->performer, name, n + 1);
    return 0;
}

/* calibration=FILE, the host's key (its performer's placement): the path, kept for the
 * session, which reads it. */
static int take_calibration(fp_input_instance *inst, fp_spec *spec, const char *spec_text, char *err,
                            size_t errlen)
{
    const char *path = fp_spec_take(spec, "calibration");
    if (!path) return 0;
    if (!path[0] || strlen(path) >= sizeof inst->calibration)
        return fp_errorf(err, errlen, -EINVAL, "input '%s': calibration=: expected a file (docs/calibration.md) "
                         "of under %zu bytes", spec_text, sizeof inst->calibration);
    snprintf(inst->calibration, sizeof inst->calibration, "%s", path);
    return 0;
}

int fp_input_instance_open(fp_input_instance *inst, const fp_plugin_path *path,
                           const char *spec_text, uint32_t source, char *err, size_t errlen)
{
    return fp_input_instance_open_isolated(inst, path, spec_text, source, FP_ISOLATE_NONE, NULL, err, errlen);
}

/* The plugin loaded here, or only found where it runs in a helper (fp_isolate.h): then
 * inst->plugin holds its path alone and *found the file. */
static int load_plugin(fp_input_instance *inst, const fp_plugin_path *path, const char *name, int isolate,
                       char *found, size_t foundlen, char *err, size_t errlen)
{
    bool builtin = false;
    inst->isolated = isolate != FP_ISOLATE_NONE &&
                     fp_plugin_find(path, FP_PLUGIN_INPUT, name, found, foundlen, &builtin, NULL, 0) &&
                     fp_isolate_wanted((fp_isolate_mode)isolate, builtin);
    if (!inst->isolated) return fp_plugin_load(path, FP_PLUGIN_INPUT, name, &inst->plugin, err, errlen);
    memset(&inst->plugin, 0, sizeof inst->plugin);
    inst->plugin.kind = FP_PLUGIN_INPUT;
    if (!(inst->plugin.path = strdup(found))) return fp_errorf(err, errlen, -ENOMEM, "out of memory");
    return 0;
}

int fp_input_instance_open_isolated(fp_input_instance *inst, const fp_plugin_path *path, const char *spec_text,
                                    uint32_t source, int isolate, const struct fp_isolate_options *opt,
                                    char *err, size_t errlen)
{
    memset(inst, 0, sizeof *inst);
    fp_spec spec;
    int rc = fp_spec_parse(spec_text, &spec, err, errlen);
    if (rc) return rc;
    if (fp_log_relay_init(&inst->log)) {
        fp_spec_clear(&spec);
        return fp_errorf(err, errlen, -ENOMEM, "input '%s': out of memory", spec_text);
    }
    snprintf(inst->name, sizeof inst->name, "%s", spec.name);
    inst->source = source;
    const char *record = fp_spec_take(&spec, "record");
    const char *forward = fp_spec_take(&spec, "forward");
    /* force=1 (only beside record=): overwrite the recording's file instead of taking the
     * next free name. */
    const char *force = record ? fp_spec_take(&spec, "force") : NULL;
    if (force && strcmp(force, "0") && strcmp(force, "1")) {
        snprintf(err, errlen, "input '%s': force=%s: expected 0 or 1", spec_text, force);
        rc = -EINVAL;
        goto out;
    }
    /* The filter of its hand events (fp_filter.h), the session's: the plugin never sees
     * these keys, so every input takes them, a third party's too. */
    const char *filter = fp_spec_take(&spec, "filter"), *mincutoff = fp_spec_take(&spec, "mincutoff");
    const char *beta = fp_spec_take(&spec, "beta"), *dcutoff = fp_spec_take(&spec, "dcutoff");
    const char *trend = fp_spec_take(&spec, "trend");
    char ferr[256];
    if ((rc = fp_filter_parse(spec.name, filter, mincutoff, beta, dcutoff, trend, &inst->filter, ferr,
                              sizeof ferr))) {
        snprintf(err, errlen, "input '%s': %s", spec_text, ferr);
        goto out;
    }
    if ((rc = take_performer(inst, &spec, spec_text, err, errlen)) ||
        (rc = take_calibration(inst, &spec, spec_text, err, errlen)))
        goto out;
    char found[4096];
    rc = load_plugin(inst, path, spec.name, isolate, found, sizeof found, err, errlen);
    if (rc) goto out;
    rc = fp_event_queue_init(&inst->queue, FP_INPUT_QUEUE_CAPACITY);
    if (rc) {
        snprintf(err, errlen, "%s: out of memory", spec_text);
        goto out;
    }
    if (!(inst->link = calloc(1, sizeof *inst->link))) {
        rc = fp_errorf(err, errlen, -ENOMEM, "%s: out of memory", spec_text);
        goto out;
    }
    inst->link->inst = inst;
    host_fill(&inst->link->host, inst->link);
    const fp_input_factory *f = inst->plugin.factory;
    char perr[512] = "";
    fp_plugin_call_enter(inst->name, "create", 0);
    if (inst->isolated)
        rc = fp_isolate_input_create(opt, found, inst->name, &inst->link->host, spec.arg, spec.params,
                                     spec.nparams, &inst->input, perr, sizeof perr);
    else
        rc = f->create(&inst->link->host, spec.arg, spec.params, spec.nparams, &inst->input, perr, sizeof perr);
    fp_plugin_call_leave();
    perr[sizeof perr - 1] = '\0'; /* (a plugin that filled it to the end: read no further) */
    if (rc || !inst->input) {
        snprintf(err, errlen, "input '%s': %s", spec_text,
                 perr[0] ? perr : rc ? "create failed" : "create returned 0 without an instance");
        inst->input = NULL;
        if (!rc) rc = FP_EPLUGIN_FAULT;
        goto out;
    }
    if (!FP_HAS_FIELD(inst->input, fp_input, destroy) || !inst->input->start) {
        /* as `plugins check` refuses it (before: start was called through NULL) */
        snprintf(err, errlen, "input '%s': the fp_input has size %u, or no start()", spec_text,
                 inst->input->size);
        if (FP_HAS_FIELD(inst->input, fp_input, destroy) && inst->input->destroy) {
            fp_plugin_call_enter(inst->name, "destroy", 0);
            inst->input->destroy(inst->input); /* (an instance too short for one: left) */
            fp_plugin_call_leave();
        }
        inst->input = NULL;
        rc = FP_EPLUGIN_FAULT;
        goto out;
    }
    if (record) {
        char used[4096];
        rc = fp_event_recorder_create(record, force && !strcmp(force, "1") ? FP_RECORD_OVERWRITE : 0,
                                      used, sizeof used, &inst->record, perr, sizeof perr);
        if (rc) {
            snprintf(err, errlen, "input '%s': record=%s: %s", spec_text, record, perr);
            goto out;
        }
        if (strcmp(used, record)) {
            char msg[8400];
            snprintf(msg, sizeof msg, "record=%s exists: recording to %s instead (force=1 "
                     "overwrites)", record, used);
            inst->link->host.log(&inst->link->host, FP_LOG_WARNING, msg);
        }
    }
    if (forward) {
        if ((rc = fp_event_forwarder_create(forward, &inst->forward, perr, sizeof perr))) {
            snprintf(err, errlen, "input '%s': %s", spec_text, perr);
            goto out;
        }
        char line[400];
        snprintf(line, sizeof line, "forwarding its events to %s over OSC (docs/osc.md, Forward)",
                 fp_event_forwarder_target(inst->forward));
        inst->link->host.log(&inst->link->host, FP_LOG_INFO, line);
    }
    if (inst->filter.kind != FP_FILTER_OFF) {
        char line[512];
        fp_filter_describe(&inst->filter, line, sizeof line);
        inst->link->host.log(&inst->link->host, FP_LOG_INFO, line);
    }
out:
    fp_spec_clear(&spec);
    if (rc) {
        fp_input_instance_close(inst);
        return rc;
    }
    return 0;
}

int fp_input_instance_start(fp_input_instance *inst, char *err, size_t errlen)
{
    char perr[512] = "";
    inst->own_clock = fp_input_own_clock(inst->input); /* (fp_event_check_time) */
    fp_plugin_call_enter(inst->name, "start", 0);
    int rc = inst->input->start(inst->input, perr, sizeof perr);
    fp_plugin_call_leave();
    perr[sizeof perr - 1] = '\0';
    if (rc) {
        snprintf(err, errlen, "input '%s': %s", inst->name, perr[0] ? perr : "start failed");
        return rc;
    }
    inst->started = true;
    return 0;
}

bool fp_input_instance_poll(fp_input_instance *inst, fp_event *out)
{
    if (!inst->queue.cells || !fp_event_queue_pop(&inst->queue, out)) return false;
    if (inst->record) fp_event_recorder_push(inst->record, out); /* written on its own thread */
    return true;
}

/* The plugin's stop() on a thread of the host's (freed by whichever side is last: the caller
 * when the call returned in time, else nobody: a stop that never returns keeps it). */
typedef struct stop_call {
    fp_input *input;
    char who[64]; /* a copy of the instance's name: an abandoned call outlives the instance,
                     and fp_plugin_call_oldest reads its name */
} stop_call;

static void *stop_thread(void *arg)
{
    stop_call *c = arg;
    fp_plugin_call_enter(c->who, "stop", 0);
    c->input->stop(c->input);
    fp_plugin_call_leave();
    return NULL;
}

/* stop(), waited for FP_INPUT_STOP_DEADLINE_MS: true when it returned. A stop that does not
 * (a thread of the plugin's blocked in a read that nothing ends) is abandoned, so that it
 * cannot keep the command from ending; said in the input's log. Where no thread can be
 * started, stop is called here and waited for. */
static bool stop_within_deadline(fp_input_instance *inst)
{
    stop_call *c = malloc(sizeof *c);
    pthread_t t;
    if (c) {
        c->input = inst->input;
        snprintf(c->who, sizeof c->who, "%s", inst->name);
    }
    if (!c || pthread_create(&t, NULL, stop_thread, c)) {
        free(c);
        fp_plugin_call_enter(inst->name, "stop", 0);
        inst->input->stop(inst->input);
        fp_plugin_call_leave();
        return true;
    }
    struct timespec until;
    clock_gettime(CLOCK_REALTIME, &until); /* (pthread_timedjoin_np's clock) */
    until.tv_sec += FP_INPUT_STOP_DEADLINE_MS / 1000;
    until.tv_nsec += (FP_INPUT_STOP_DEADLINE_MS % 1000) * 1000000L;
    if (until.tv_nsec >= 1000000000L) until.tv_sec++, until.tv_nsec -= 1000000000L;
    int rc;
    while ((rc = pthread_timedjoin_np(t, NULL, &until)) == EINTR) {}
    if (!rc) {
        free(c);
        return true;
    }
    pthread_detach(t);
    fp_input_instance_drain_log(inst); /* room for the host's lines: a plugin that logged 32 lines
                                        * while stop was waited for had them dropped */
    char line[300];
    snprintf(line, sizeof line, "stop has not returned within %g s (a thread of the plugin's does "
             "not end): abandoned, the plugin left loaded and running; nothing more of it is "
             "called", FP_INPUT_STOP_DEADLINE_MS / 1000.0);
    fp_log_relay_push(&inst->log, FP_LOG_ERROR, line);
    return false;
}

/* An abandoned input's threads may run on: from here its link sends nothing to inst (the
 * calls already in progress are waited for: push and log are wait-free), and the link is
 * never freed, so that a push after the owner freed inst touches only the link. */
static void detach_link(fp_input_instance *inst)
{
    fp_input_link *l = inst->link;
    if (!l) return;
    atomic_store(&l->abandoned, true);
    while (atomic_load(&l->busy)) {
        struct timespec ts = {0, 100000L};
        nanosleep(&ts, NULL);
    }
    inst->link = NULL; /* leaked on purpose: the plugin holds &l->host */
    inst->orphan = l;
}

uint64_t fp_input_instance_dropped(const fp_input_instance *inst)
{
    uint64_t n = inst->queue.cells ? fp_event_queue_dropped(&inst->queue) : 0;
    return n + inst->unread + (inst->orphan ? atomic_load(&inst->orphan->dropped) : 0);
}

static void stop_input(fp_input_instance *inst)
{
    if (inst->input && !inst->stopped && inst->input->stop && !stop_within_deadline(inst)) {
        inst->abandoned = true;
        detach_link(inst);
    }
    inst->stopped = true;
    inst->started = false;
}

int fp_input_instance_record_error(fp_input_instance *inst, char *err, size_t errlen)
{
    return inst->record ? fp_event_recorder_error(inst->record, err, errlen) : 0;
}

int fp_input_instance_close_record(fp_input_instance *inst, char *err, size_t errlen)
{
    if (!inst->record) return 0;
    stop_input(inst);
    fp_event ev;
    while (fp_input_instance_poll(inst, &ev)) {} /* keep what was read */
    return fp_event_recorder_close(&inst->record, err, errlen);
}

/* The closing line of an abandoned input: what of its events was dropped (before: nothing
 * said, the events it had queued and those it pushed after lost uncounted). */
static void say_abandoned_drops(fp_input_instance *inst)
{
    fp_event ev; /* (a recording has kept what was queued: fp_input_instance_close_record) */
    while (fp_event_queue_pop(&inst->queue, &ev)) inst->unread++;
    uint64_t after = atomic_load(&inst->orphan->dropped);
    char line[300];
    snprintf(line, sizeof line, "abandoned: dropped %llu event%s it pushed while its stop() did not "
             "return (%llu queued and never read, %llu pushed after it was abandoned; what it pushes "
             "from here is dropped too)", (unsigned long long)(inst->unread + after),
             inst->unread + after == 1 ? "" : "s", (unsigned long long)inst->unread, (unsigned long long)after);
    fp_log_relay_push(&inst->log, FP_LOG_WARNING, line);
}

void fp_input_instance_close(fp_input_instance *inst)
{
    fp_input_instance_close_record(inst, NULL, 0);
    stop_input(inst);
    if (inst->abandoned) { /* its threads may still run its code and push: nothing is freed
                            * that they use (the queue, the log relay, the plugin's code) */
        if (inst->input) say_abandoned_drops(inst);
        inst->input = NULL;
        fp_input_instance_drain_log(inst);
        return;
    }
    if (inst->input) {
        if (inst->input->destroy) {
            fp_plugin_call_enter(inst->name, "destroy", 0);
            inst->input->destroy(inst->input);
            fp_plugin_call_leave();
        }
        inst->input = NULL;
    }
    if (inst->forward) { /* (the input's threads are gone) */
        fp_forward_stats fs;
        fp_event_forwarder_stats(inst->forward, &fs);
        char line[400];
        snprintf(line, sizeof line, "forwarded %llu events to %s (%llu not forwarded: statuses, "
                 "channels, key requests; %llu failed sends)", (unsigned long long)fs.sent,
                 fp_event_forwarder_target(inst->forward), (unsigned long long)fs.skipped,
                 (unsigned long long)fs.errors);
        fp_log_relay_push(&inst->log, FP_LOG_INFO, line);
        fp_event_forwarder_destroy(&inst->forward);
    }
    say_refused(inst);
    uint64_t refused = atomic_load(&inst->refused);
    if (refused) {
        char line[200];
        snprintf(line, sizeof line, "refused %llu malformed event%s in all (fp_event_check.h: the "
                 "plugin sent them; every other event was taken)", (unsigned long long)refused,
                 refused == 1 ? "" : "s");
        fp_log_relay_push(&inst->log, FP_LOG_WARNING, line);
    }
    fp_event_queue_destroy(&inst->queue);
    fp_plugin_unload(&inst->plugin);
    inst->started = false;
    fp_input_instance_drain_log(inst); /* (the plugin's threads are gone) */
    fp_log_relay_destroy(&inst->log);
    free(inst->link);
    inst->link = NULL;
}
