/* The helper process of an isolated mapping (fp_isolate.h): load the plugin, create the
 * instance, then answer the host's requests through the shared memory until told to quit
 * or the host goes away. argv: EXE __plugin-helper MEMFD GO DONE SOCK FILE NAME [KEY=VALUE...] */
#define _GNU_SOURCE
#include "fp_isolate.h"
#include "isolate_proc.h"

#include <errno.h>
#include <fcntl.h>
#include <poll.h>
#include <pthread.h>
#include <sys/prctl.h>
#include <time.h>
#include <signal.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <unistd.h>

typedef struct helper {
    int memfd, go, done, sock;
    fp_iso_shm *shm;
    size_t mapped;
    fp_host host;
    fp_mesh_view mesh;
    fp_rig_view rig;
    fp_rig_landmark *landmarks;
    size_t landmark_cap;
    fp_rig_channel_info *channels;
    size_t channel_cap;
    bool rig_ready;
    uint64_t seen;          /* the last request's sequence number */
    int64_t last, period;   /* when the last request came; the requests' mean interval, ns */
} helper;

#define FP_ISO_SPIN_LEAD_NS 300000      /* spin from 0.3 ms before a request is due */
#define FP_ISO_SPIN_LAG_NS 700000       /* to 0.7 ms after */
#define FP_ISO_SPIN_MAX_PERIOD_NS 50000000

static helper H; /* one per process: the host's callbacks reach it without a pointer */
static unsigned long log_unsent; /* log lines the socket had no room for (FP_ISO_LOG_UNSENT) */

/* A message, never waiting (the frame's deadline runs); a log line with no room counted */
static bool send_msg(uint32_t type, int rc, const char *text)
{
    fp_iso_msg m;
    memset(&m, 0, sizeof m);
    m.type = type;
    m.rc = rc;
    snprintf(m.text, sizeof m.text, "%s", text ? text : "");
    size_t len = offsetof(fp_iso_msg, text) + strlen(m.text) + 1;
    bool sent = send(H.sock, &m, len, MSG_DONTWAIT | MSG_NOSIGNAL) >= 0;
    if (!sent && type == FP_ISO_MSG_LOG && rc != FP_ISO_LOG_UNSENT) log_unsent++;
    return sent;
}

/* The lines not sent, counted to the host before a reply (read by it before the reply's) */
static void send_unsent(void)
{
    char n[32];
    snprintf(n, sizeof n, "%lu", log_unsent);
    if (log_unsent && send_msg(FP_ISO_MSG_LOG, FP_ISO_LOG_UNSENT, n)) log_unsent = 0;
}

static void host_log(const fp_host *host, fp_log_level level, const char *message)
{
    (void)host;
    send_msg(FP_ISO_MSG_LOG, (int)level, message);
}

static int64_t host_now(const fp_host *host)
{
    (void)host;
    return fp_now_ns();
}

static bool host_push(const fp_host *host, const fp_event_header *ev)
{
    (void)host, (void)ev;
    return false; /* a mapping pushes no events */
}

/* Map the memfd again where the host grew it. */
static int remap(void)
{
    size_t want = (size_t)atomic_load(&H.shm->size);
    if (want <= H.mapped) return 0;
    void *p = mremap(H.shm, H.mapped, want, MREMAP_MAYMOVE);
    if (p == MAP_FAILED) return -errno;
    H.shm = p;
    H.mapped = want;
    return 0;
}

static void signal_done(uint32_t reply)
{
    send_unsent();
    H.shm->reply = reply;
    atomic_store(&H.shm->reply_seq, atomic_load(&H.shm->req_seq));
    uint64_t one = 1;
    (void)!write(H.done, &one, sizeof one);
}

/* A new request in the shared memory (its sequence number moved). */
static bool fresh(void) { return atomic_load(&H.shm->req_seq) != H.seen; }

/* Spin on the sequence number until `until` (host clock): the frames come at a steady pace,
 * and a helper that is running when one comes answers without a wake-up (tens of
 * microseconds on a virtual machine). */
static bool spin_until(int64_t until)
{
    while (fp_now_ns() < until)
        for (int i = 0; i < 64; i++) {
            if (fresh()) return true;
            __asm__ __volatile__("" ::: "memory");
        }
    return fresh();
}

/* Wait for the host's next request (paced: a frame's; else the answer to a query during one):
 * false when the host is gone. From the pace of the last
 * requests it sleeps until shortly before the next is due (FP_ISO_SPIN_LEAD_NS) and spins
 * until a little after (FP_ISO_SPIN_LAG_NS), then blocks; a request that comes while it
 * spins costs no wake-up. Requests further apart than FP_ISO_SPIN_MAX_PERIOD_NS: no spin. */
static bool wait_go(bool paced)
{
    bool got = false;
    int64_t period = H.period, due = H.last + period;
    if (!paced) { /* the host's answer to a surface query: microseconds away */
        got = spin_until(fp_now_ns() + 100000);
    } else if (period > 0 && period < FP_ISO_SPIN_MAX_PERIOD_NS) {
        int64_t wake = due - FP_ISO_SPIN_LEAD_NS;
        for (int64_t now; !fresh() && (now = fp_now_ns()) < wake;) { /* sleep until then */
            struct timespec ts = {(time_t)((wake - now) / 1000000000), (long)((wake - now) % 1000000000)};
            struct pollfd p[2] = {{H.go, POLLIN, 0}, {H.sock, POLLIN, 0}};
            int k = ppoll(p, 2, &ts, NULL);
            if (k < 0 && errno != EINTR) return false;
            if (k > 0 && (p[1].revents & (POLLHUP | POLLERR))) return false;
            if (k > 0 && (p[1].revents & POLLIN)) {
                char b[16];
                if (recv(H.sock, b, sizeof b, MSG_DONTWAIT) == 0) return false;
            }
            uint64_t n; /* a count left by a request seen spinning wakes it early: drain it */
            if (k > 0 && (p[0].revents & POLLIN)) (void)!read(H.go, &n, sizeof n);
        }
        got = spin_until(due + FP_ISO_SPIN_LAG_NS);
    }
    while (!got && !(got = fresh())) {
        struct pollfd p[2] = {{H.go, POLLIN, 0}, {H.sock, POLLIN, 0}};
        if (poll(p, 2, -1) < 0) {
            if (errno == EINTR) continue;
            return false;
        }
        if (p[1].revents & (POLLHUP | POLLERR)) return false;
        if (p[1].revents & POLLIN) { /* the host sends nothing: drain and go on */
            char b[16];
            if (recv(H.sock, b, sizeof b, MSG_DONTWAIT) == 0) return false;
        }
        if (p[0].revents & POLLIN) {
            uint64_t n;
            (void)!read(H.go, &n, sizeof n);
        }
    }
    uint64_t n;
    (void)!read(H.go, &n, sizeof n); /* (non-blocking: the count of a request seen spinning) */
    H.seen = atomic_load(&H.shm->req_seq);
    if (!paced) return true;
    int64_t now = fp_now_ns();
    if (H.last) { /* the pace: a running mean of the intervals, a long pause starts anew */
        int64_t d = now - H.last;
        H.period = d > FP_ISO_SPIN_MAX_PERIOD_NS || !H.period ? d : (H.period * 7 + d) / 8;
    }
    H.last = now;
    return true;
}

/* FP_HOST_EXT_SURFACE: the host answers during the call, FP_ISO_SURFACE_MAX at a time. */
static int surface_nearest(const fp_host *host, const float (*points)[3], size_t count,
                           float max_distance, fp_surface_hit *out)
{
    (void)host;
    if (count && (!points || !out)) return -EINVAL;
    for (size_t done = 0; done < count || (count == 0 && done == 0);) {
        size_t k = count - done < FP_ISO_SURFACE_MAX ? count - done : FP_ISO_SURFACE_MAX;
        fp_iso_shm *s = H.shm;
        s->surf_count = (uint32_t)k;
        s->surf_max = max_distance;
        if (k) memcpy(s->surf_points, points + done, k * sizeof s->surf_points[0]);
        signal_done(FP_ISO_REPLY_SURFACE);
        if (!wait_go(false)) _exit(0);
        if (remap()) _exit(70);
        s = H.shm;
        if (s->surf_rc) return s->surf_rc;
        if (k) memcpy(out + done, s->surf_hits, k * sizeof s->surf_hits[0]);
        if (!count) break;
        done += k;
    }
    return 0;
}

static const fp_host_surface surface_ext = {surface_nearest};

/* The rig as the last request carried it (the create-time one before the first frame). */
static int rebuild_rig(void)
{
    fp_iso_shm *s = H.shm;
    if (!s->has_rig) return 0;
    const char *strings = (const char *)s + s->off_strings;
    fp_rig_view *r = &H.rig;
    *r = s->rig;
    r->name = strings + s->rig_name;
    r->region = s->rig.vertex_count ? (const uint8_t *)s + s->off_region : NULL;
    if (s->rig.landmark_count > H.landmark_cap) {
        void *p = realloc(H.landmarks, s->rig.landmark_count * sizeof *H.landmarks);
        if (!p) return -ENOMEM;
        H.landmarks = p;
        H.landmark_cap = s->rig.landmark_count;
    }
    if (s->rig.channel_count > H.channel_cap) {
        void *p = realloc(H.channels, s->rig.channel_count * sizeof *H.channels);
        if (!p) return -ENOMEM;
        H.channels = p;
        H.channel_cap = s->rig.channel_count;
    }
    const fp_iso_landmark *l = (const fp_iso_landmark *)((const char *)s + s->off_landmarks);
    for (size_t i = 0; i < s->rig.landmark_count; i++) {
        H.landmarks[i].name = strings + l[i].name;
        H.landmarks[i].vertex = l[i].vertex;
        memcpy(H.landmarks[i].position, l[i].position, sizeof l[i].position);
    }
    const fp_iso_channel *c = (const fp_iso_channel *)((const char *)s + s->off_channels);
    for (size_t i = 0; i < s->rig.channel_count; i++)
        H.channels[i] = (fp_rig_channel_info){strings + c[i].name, c[i].min, c[i].max, c[i].neutral, c[i].value};
    r->landmarks = H.landmarks;
    r->channels = H.channels;
    H.rig_ready = true;
    return 0;
}

static const fp_rig_view *rig_get(const fp_host *host)
{
    (void)host;
    return H.shm->has_rig && H.rig_ready ? &H.rig : NULL;
}

static const fp_host_rig rig_ext = {rig_get};

static const void *host_extension(const fp_host *host, const char *id)
{
    (void)host;
    if (!id) return NULL;
    if (!strcmp(id, FP_HOST_EXT_SURFACE) && (H.shm->offers & 1)) return &surface_ext;
    if (!strcmp(id, FP_HOST_EXT_RIG) && (H.shm->offers & 2)) return &rig_ext;
    return NULL;
}

/* One process() call on the request in the shared memory. */
static int do_process(fp_mapping *m)
{
    fp_iso_shm *s = H.shm;
    fp_frame_input in = s->in;
    in.events = s->events;
    bool extra = FP_HAS_FIELD(&s->in, fp_frame_input, extra_tip_distance) && s->in.extra_performers > 0 &&
                 s->in.extra_performers < FP_PERFORMER_CAPACITY;
    in.extra_performers = extra ? s->in.extra_performers : 0;
    in.extra_hands = extra ? s->extra_hands : NULL; /* (the host's copies, ABI 1.3) */
    in.extra_tip_distance = extra ? (const float (*)[FP_FINGERS])s->extra_tips : NULL;
    in.mesh = NULL;
    if (s->has_mesh) {
        H.mesh = s->mesh;
        H.mesh.base = s->mesh.vertex_count ? (const float *)((const char *)s + s->off_base) : NULL;
        in.mesh = &H.mesh;
    }
    int rc = rebuild_rig();
    if (rc) return rc;
    in.rig = s->has_rig ? &H.rig : NULL;
    fp_control_set cs = s->cs;
    cs.start = s->start;
    cs.end = s->end;
    cs.channels = s->channels;
    rc = m->process(m, &in, &cs);
    s = H.shm; /* (a surface query may have remapped it) */
    s->cs.active = cs.active;
    s->cs.intents = cs.intents;
    s->cs.radius = cs.radius;
    s->cs.count = cs.count;
    s->cs.channel_count = cs.channel_count;
    return rc;
}

/* The helper outlives no host: this thread waits for the socket's hang-up (the host exited,
 * even by SIGKILL) and ends the process, also while the plugin spins in a call. */
static void *host_watch(void *arg)
{
    (void)arg;
    for (;;) {
        struct pollfd p = {H.sock, 0, 0}; /* POLLHUP and POLLERR are always reported */
        if (poll(&p, 1, -1) < 0 && errno != EINTR) _exit(0);
        if (p.revents & (POLLHUP | POLLERR | POLLNVAL)) _exit(0);
    }
    return NULL;
}

int fp_iso_helper_arg_fd(const char *s)
{
    char *end;
    long v = strtol(s, &end, 10);
    return *end || v < 0 || v > 1 << 20 ? -1 : (int)v;
}

/* A plugin that eats memory without end (a leak in every process(), a runaway create) must
 * not take the host with it: where the kernel runs out, its OOM killer takes this helper
 * first (the most a process may ask for itself; the host restarts a helper that died). */
void fp_iso_helper_oom_first(void)
{
    int fd = open("/proc/self/oom_score_adj", O_WRONLY | O_CLOEXEC);
    if (fd < 0) return;
    ssize_t w = write(fd, "1000", 4);
    (void)w;
    close(fd);
}

size_t fp_iso_helper_params(int argc, char **argv, fp_param *params)
{
    size_t np = 0;
    for (int i = 8; i < argc && np < FP_SPEC_MAX_PARAMS; i++) {
        char *eq = strchr(argv[i], '=');
        if (!eq) continue;
        *eq = '\0';
        params[np++] = (fp_param){argv[i], eq + 1};
    }
    return np;
}

int fp_iso_helper_load(fp_plugin_kind kind, const char *file, fp_plugin *plugin, char *err, size_t errlen)
{
    fp_plugin_path none;
    memset(&none, 0, sizeof none);
    none.builtin = SIZE_MAX;
    return fp_plugin_load(&none, kind, file, plugin, err, errlen);
}

int fp_iso_helper_begin(char **argv, int *memfd, int *go, int *done, int *sock, fp_iso_shm **shm,
                        size_t *mapped)
{
    *memfd = fp_iso_helper_arg_fd(argv[2]);
    *go = fp_iso_helper_arg_fd(argv[3]);
    *done = fp_iso_helper_arg_fd(argv[4]);
    *sock = fp_iso_helper_arg_fd(argv[5]);
    if (*memfd < 0 || *go < 0 || *done < 0 || *sock < 0) return 64;
    /* the plugin's printf goes to the host's stderr: the host's stdout is its own (run's
     * summary, which scripts parse), shared with this process since the spawn */
    fflush(stdout);
    if (dup2(STDERR_FILENO, STDOUT_FILENO) < 0) return 70;
    signal(SIGPIPE, SIG_IGN);
    fp_iso_helper_oom_first();
    /* room for a burst of log lines or events (the kernel caps it at wmem_max) */
    int big = 1 << 20;
    (void)setsockopt(*sock, SOL_SOCKET, SO_SNDBUF, &big, sizeof big);
    struct stat st;
    if (fstat(*memfd, &st) || (size_t)st.st_size < sizeof(fp_iso_shm)) return 66;
    *mapped = (size_t)st.st_size;
    *shm = mmap(NULL, *mapped, PROT_READ | PROT_WRITE, MAP_SHARED, *memfd, 0);
    if (*shm == MAP_FAILED || (*shm)->magic != FP_ISO_MAGIC || (*shm)->version != FP_ISO_VERSION) {
        *shm = NULL;
        return 66;
    }
    return 0;
}

int fp_isolate_helper_main(int argc, char **argv)
{
    if (argc < 8) return 64;
    const char *file = argv[6];
    int rc0 = fp_iso_helper_begin(argv, &H.memfd, &H.go, &H.done, &H.sock, &H.shm, &H.mapped);
    if (rc0) return rc0;
    prctl(PR_SET_TIMERSLACK, 1UL, 0, 0, 0); /* wake for the spin when asked, not 50 us late */
    int fl = fcntl(H.go, F_GETFL);
    if (fl < 0 || fcntl(H.go, F_SETFL, fl | O_NONBLOCK)) return 70;
    if (remap()) return 70;
    if (rebuild_rig()) return 70;
    pthread_t watch;
    if (pthread_create(&watch, NULL, host_watch, NULL)) return 70;
    pthread_detach(watch);

    memset(&H.host, 0, sizeof H.host);
    H.host.size = sizeof H.host;
    H.host.abi = (fp_version){FP_PLUGIN_ABI_MAJOR, FP_PLUGIN_ABI_MINOR};
    H.host.push_event = host_push;
    H.host.now_ns = host_now;
    H.host.log = host_log;
    H.host.get_extension = host_extension;

    fp_param params[FP_SPEC_MAX_PARAMS];
    size_t np = fp_iso_helper_params(argc, argv, params);
    fp_plugin plugin;
    char err[900] = "";
    atomic_store(&H.shm->stage, FP_ISO_STAGE_LOAD);
    int rc = fp_iso_helper_load(FP_PLUGIN_MAPPING, file, &plugin, err, sizeof err);
    fp_mapping *m = NULL;
    if (!rc) {
        const fp_mapping_factory *f = plugin.factory;
        atomic_store(&H.shm->stage, FP_ISO_STAGE_CREATE);
        rc = f->create(&H.host, params, np, &m, err, sizeof err);
        err[sizeof err - 1] = '\0'; /* (a plugin that filled it to the end) */
        if (!rc && !m) {
            snprintf(err, sizeof err, "create returned 0 without an instance");
            rc = FP_EPLUGIN_FAULT;
        } else if (!rc && (!FP_HAS_FIELD(m, fp_mapping, destroy) || !m->process)) {
            snprintf(err, sizeof err, "the fp_mapping has size %u or no process()", m->size);
            rc = FP_EPLUGIN_FAULT;
            m = NULL;
        }
    }
    if (!rc) /* what the host shows of it: the entry's id and version */
        snprintf(err, sizeof err, "%.400s\n%.400s", plugin.entry->id ? plugin.entry->id : "?",
                 plugin.entry->version ? plugin.entry->version : "?");
    atomic_store(&H.shm->stage, FP_ISO_STAGE_READY);
    send_msg(FP_ISO_MSG_READY, rc, rc && !err[0] ? "create failed" : err);
    if (rc) return 0;
    for (;;) {
        if (!wait_go(true)) break;
        if (remap()) return 70;
        uint32_t op = H.shm->op;
        if (op == FP_ISO_OP_QUIT) break;
        if (op == FP_ISO_OP_PROCESS) H.shm->rc = do_process(m);
        else if (op == FP_ISO_OP_RESET && m->reset) m->reset(m);
        signal_done(FP_ISO_REPLY_DONE);
    }
    if (m->destroy) m->destroy(m);
    fp_plugin_unload(&plugin);
    return 0;
}
