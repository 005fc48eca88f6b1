/* The helper process of an isolated input (fp_isolate.h): load the input plugin, create the
 * instance, tell the host what its extensions answer, then start and stop it when the host
 * asks; every event the plugin pushes and every line it logs go to the host on the socket, in
 * order. argv: EXE __input-helper MEMFD GO DONE SOCK FILE NAME [KEY=VALUE...]; the SPEC's ARG
 * is in the shared memory (isolate_shm.h). */
#define _GNU_SOURCE
#include "fp_isolate.h"
#include "isolate_proc.h"

#include "fp_clock.h"

#include <errno.h>
#include <poll.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <unistd.h>

static struct {
    int memfd, go, done, sock;
    fp_iso_shm *shm;
    size_t mapped;
    fp_host host;
    fp_iso_joints *joints;
    size_t njoints, joints_cap;
} H;

static bool send_msg(uint32_t type, int rc, const void *data, size_t n)
{
    fp_iso_msg m;
    m.type = type;
    m.rc = rc;
    if (n > sizeof m.text) n = sizeof m.text;
    memcpy(m.text, data, n);
    return send(H.sock, &m, offsetof(fp_iso_msg, text) + n, MSG_DONTWAIT | MSG_NOSIGNAL) >= 0;
}

/* [any-thread] The event's bytes to the host, which checks it as in process (fp_event_check.h):
 * a size out of range is sent as its header, so that the host refuses and names it. False
 * where the socket is full (as a full queue: the plugin may push it again). */
static bool host_push(const fp_host *host, const fp_event_header *ev)
{
    (void)host;
    if (!ev) return false;
    size_t n = ev->size < sizeof *ev || ev->size > sizeof(fp_event) ? sizeof *ev : ev->size;
    if (send_msg(FP_ISO_MSG_EVENT, 0, ev, n)) return true;
    return errno != EAGAIN && errno != EWOULDBLOCK && errno != ENOBUFS; /* (host gone: dropped) */
}

static void host_log(const fp_host *host, fp_log_level level, const char *message)
{
    (void)host;
    const char *t = message ? message : "";
    char text[sizeof ((fp_iso_msg *)0)->text];
    snprintf(text, sizeof text, "%s", t);
    for (int tries = 0; !send_msg(FP_ISO_MSG_LOG, (int)level, text, strlen(text) + 1) && errno == EAGAIN &&
                        tries < 100; tries++)
        usleep(1000); /* a log line waits a little for room; an event does not */
}

static int64_t host_now(const fp_host *host)
{
    (void)host;
    return fp_now_ns();
}

static const void *host_extension(const fp_host *host, const char *id)
{
    (void)host, (void)id;
    return NULL; /* inputs are offered none (input.c) */
}

static void add_joints(void *ctx, int hand, const float (*mm)[3])
{
    (void)ctx;
    if (H.njoints == H.joints_cap) {
        size_t cap = H.joints_cap ? 2 * H.joints_cap : 1024;
        void *p = realloc(H.joints, cap * sizeof *H.joints);
        if (!p) return; /* (fewer samples: the placement works from those) */
        H.joints = p;
        H.joints_cap = cap;
    }
    H.joints[H.njoints].hand = hand;
    memcpy(H.joints[H.njoints].mm, mm, sizeof H.joints[0].mm);
    H.njoints++;
}

/* What the instance's extensions answer, once, into the shared memory (its joints after the
 * header: the memfd grown to hold them). 0 or a negative errno. */
static int put_extensions(fp_input *in)
{
    fp_iso_shm *s = H.shm;
    const void *(*get)(const fp_input *, const char *) =
        FP_HAS_FIELD(in, fp_input, get_extension) ? in->get_extension : NULL;
    const fp_input_workspace *ws = get ? get(in, FP_EXT_WORKSPACE) : NULL;
    const fp_input_clock *ck = get ? get(in, FP_EXT_INPUT_CLOCK) : NULL;
    const fp_input_recording *ri = get ? get(in, FP_EXT_RECORDING_INFO) : NULL;
    const fp_input_recording_joints *rj = get ? get(in, FP_EXT_RECORDING_JOINTS) : NULL;
    uint32_t ext = 0;
    if (ws)
        ext |= FP_ISO_EXT_WORKSPACE | (ws->get && ws->get(in, s->in_ws_min, s->in_ws_max) ? FP_ISO_EXT_WORKSPACE_OK : 0);
    if (ck) ext |= FP_ISO_EXT_CLOCK | (ck->on_recording_clock && ck->on_recording_clock(in) ? FP_ISO_EXT_CLOCK_ON : 0);
    if (ri) ext |= FP_ISO_EXT_INFO | (ri->get && ri->get(in, &s->in_info) ? FP_ISO_EXT_INFO_OK : 0);
    if (rj) ext |= FP_ISO_EXT_JOINTS;
    if (ws && rj && rj->each) rj->each(in, add_joints, NULL); /* (the host asks only then) */
    size_t off = (sizeof *s + 63) & ~(size_t)63, bytes = (off + H.njoints * sizeof *H.joints + 4095) & ~(size_t)4095;
    if (H.njoints && bytes > H.mapped) {
        if (ftruncate(H.memfd, (off_t)bytes)) return -errno;
        void *p = mremap(H.shm, H.mapped, bytes, MREMAP_MAYMOVE);
        if (p == MAP_FAILED) return -errno;
        H.shm = s = p;
        H.mapped = bytes;
        atomic_store(&s->size, bytes);
    }
    if (H.njoints) memcpy((char *)s + off, H.joints, H.njoints * sizeof *H.joints);
    s->off_joints = off;
    s->in_joints = H.njoints;
    s->in_ext = ext;
    free(H.joints);
    H.joints = NULL;
    return 0;
}

/* The host's next request (START or QUIT); QUIT where the host went away. */
static uint32_t next_op(uint64_t *seen)
{
    for (;;) {
        if (atomic_load(&H.shm->req_seq) != *seen) {
            *seen = atomic_load(&H.shm->req_seq);
            return H.shm->op;
        }
        struct pollfd p[2] = {{H.go, POLLIN, 0}, {H.sock, POLLIN, 0}};
        if (poll(p, 2, -1) < 0 && errno != EINTR) return FP_ISO_OP_QUIT;
        if (p[1].revents & (POLLHUP | POLLERR)) _exit(0); /* the host is gone: so are we */
        if (p[1].revents & POLLIN) {
            char b[16];
            if (recv(H.sock, b, sizeof b, MSG_DONTWAIT) == 0) _exit(0);
        }
        uint64_t n;
        if (p[0].revents & POLLIN) (void)!read(H.go, &n, sizeof n);
    }
}

static void reply(int rc)
{
    H.shm->rc = rc;
    H.shm->reply = FP_ISO_REPLY_DONE;
    atomic_store(&H.shm->reply_seq, atomic_load(&H.shm->req_seq));
    uint64_t one = 1;
    (void)!write(H.done, &one, sizeof one);
}

static int create(fp_plugin *plugin, const char *file, int argc, char **argv, fp_input **in, char *err,
                  size_t errlen)
{
    fp_param params[FP_SPEC_MAX_PARAMS];
    size_t np = fp_iso_helper_params(argc, argv, params);
    atomic_store(&H.shm->stage, FP_ISO_STAGE_LOAD);
    int rc = fp_iso_helper_load(FP_PLUGIN_INPUT, file, plugin, err, errlen);
    if (rc) return rc;
    const fp_input_factory *f = plugin->factory;
    atomic_store(&H.shm->stage, FP_ISO_STAGE_CREATE);
    H.shm->in_arg[sizeof H.shm->in_arg - 1] = '\0';
    rc = f->create(&H.host, H.shm->in_has_arg ? H.shm->in_arg : NULL, params, np, in, err, errlen);
    err[errlen - 1] = '\0'; /* (a plugin that filled it to the end) */
    if (!rc && !*in) {
        snprintf(err, errlen, "create returned 0 without an instance");
        return FP_EPLUGIN_FAULT;
    }
    if (!rc && (!FP_HAS_FIELD(*in, fp_input, destroy) || !(*in)->start)) {
        snprintf(err, errlen, "the fp_input has size %u, or no start()", (*in)->size);
        *in = NULL;
        return FP_EPLUGIN_FAULT;
    }
    return rc ? rc : put_extensions(*in);
}

int fp_isolate_input_helper_main(int argc, char **argv)
{
    if (argc < 8) return 64;
    int rc0 = fp_iso_helper_begin(argv, &H.memfd, &H.go, &H.done, &H.sock, &H.shm, &H.mapped);
    if (rc0) return rc0;

    memset(&H.host, 0, sizeof H.host);
    H.host.size = sizeof H.host;
    H.host.abi = (fp_version){FP_PLUGIN_ABI_MAJOR, FP_PLUGIN_ABI_MINOR};
    H.host.push_event = host_push;
    H.host.now_ns = host_now;
    H.host.log = host_log;
    H.host.get_extension = host_extension;
    fp_plugin plugin;
    memset(&plugin, 0, sizeof plugin);
    fp_input *in = NULL;
    char err[900] = "";
    int rc = create(&plugin, argv[6], argc, argv, &in, err, sizeof err);
    atomic_store(&H.shm->stage, FP_ISO_STAGE_READY);
    uint64_t seen = atomic_load(&H.shm->req_seq); /* (before READY: the host asks only after it) */
    const char *said = rc && !err[0] ? "create failed" : err;
    send_msg(FP_ISO_MSG_READY, rc, said, strlen(said) + 1);
    if (rc) return 0;
    for (uint32_t op; (op = next_op(&seen)) != FP_ISO_OP_QUIT;) {
        if (op != FP_ISO_OP_START) continue;
        char perr[512] = "";
        rc = in->start(in, perr, sizeof perr);
        perr[sizeof perr - 1] = '\0';
        snprintf(H.shm->in_err, sizeof H.shm->in_err, "%s", perr[0] ? perr : rc ? "start failed" : "");
        reply(rc);
    }
    if (in->stop) in->stop(in);
    if (in->destroy) in->destroy(in);
    fp_plugin_unload(&plugin);
    return 0;
}
