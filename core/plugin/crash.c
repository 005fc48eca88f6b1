/* Fatal signals inside plugins: say which plugin, then end as the signal would. */
#define _GNU_SOURCE
#include "fp_plugin_crash.h"

#include <dlfcn.h>
#include <errno.h>
#include <link.h>
#include <signal.h>
#include <stdatomic.h>
#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <ucontext.h>
#include <unistd.h>

#define MAX_PLUGINS 64

typedef struct loaded_range {
    atomic_uintptr_t lo;      /* 0: free slot */
    uintptr_t hi;
    void *handle;
    char path[256];
} loaded_range;

static loaded_range ranges[MAX_PLUGINS];

static _Thread_local struct {
    const char *who, *call;
    uint64_t frame;
    int depth;
    int slot;      /* its slot in `calls` + 1 while a call is in progress (0: none) */
} current;

/* The calls in progress, for other threads (fp_plugin_call_oldest): a slot is owned by one
 * thread from its outermost enter to its leave; its fields are written under a sequence
 * count (odd while being written), which a reader checks before and after. */
#define MAX_CALLS 64
typedef struct call_slot {
    atomic_bool owned;
    atomic_uint seq;
    _Atomic(const char *) who, call;
    _Atomic uint64_t frame;
    _Atomic int64_t since_ns;
} call_slot;

static call_slot calls[MAX_CALLS];

static int64_t mono_ns(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (int64_t)ts.tv_sec * 1000000000LL + ts.tv_nsec;
}

static void slot_write(call_slot *c, const char *who, const char *call, uint64_t frame,
                       int64_t since_ns)
{
    unsigned q = atomic_load_explicit(&c->seq, memory_order_relaxed);
    atomic_store_explicit(&c->seq, q + 1, memory_order_relaxed);
    atomic_thread_fence(memory_order_release);
    atomic_store_explicit(&c->who, who, memory_order_relaxed);
    atomic_store_explicit(&c->call, call, memory_order_relaxed);
    atomic_store_explicit(&c->frame, frame, memory_order_relaxed);
    atomic_store_explicit(&c->since_ns, since_ns, memory_order_relaxed);
    atomic_store_explicit(&c->seq, q + 2, memory_order_release);
}

void fp_plugin_call_enter(const char *who, const char *call, uint64_t frame)
{
    current.who = who;
    current.call = call;
    current.frame = frame;
    if (current.depth++ == 0) { /* the outermost call: a slot, if one is free */
        for (int i = 0; i < MAX_CALLS && !current.slot; i++)
            if (!atomic_load_explicit(&calls[i].owned, memory_order_relaxed) &&
                !atomic_exchange_explicit(&calls[i].owned, true, memory_order_acquire))
                current.slot = i + 1;
        if (current.slot) slot_write(&calls[current.slot - 1], who, call, frame, mono_ns());
    } else if (current.slot) { /* nested: the innermost is named, since the outermost began */
        call_slot *c = &calls[current.slot - 1];
        slot_write(c, who, call, frame, atomic_load_explicit(&c->since_ns, memory_order_relaxed));
    }
}

void fp_plugin_call_leave(void)
{
    if (current.depth > 0 && --current.depth == 0) {
        current.who = current.call = NULL;
        if (current.slot) {
            call_slot *c = &calls[current.slot - 1];
            slot_write(c, NULL, NULL, 0, 0);
            atomic_store_explicit(&c->owned, false, memory_order_release);
            current.slot = 0;
        }
    }
}

bool fp_plugin_call_oldest(fp_plugin_call_info *out)
{
    bool found = false;
    for (int i = 0; i < MAX_CALLS; i++) {
        call_slot *c = &calls[i];
        if (!atomic_load_explicit(&c->owned, memory_order_acquire)) continue;
        unsigned q = atomic_load_explicit(&c->seq, memory_order_acquire);
        if (q & 1) continue;
        fp_plugin_call_info got = {atomic_load_explicit(&c->who, memory_order_relaxed),
                                   atomic_load_explicit(&c->call, memory_order_relaxed),
                                   atomic_load_explicit(&c->frame, memory_order_relaxed),
                                   atomic_load_explicit(&c->since_ns, memory_order_relaxed)};
        atomic_thread_fence(memory_order_acquire);
        if (atomic_load_explicit(&c->seq, memory_order_relaxed) != q || !got.who) continue;
        if (!found || got.since_ns < out->since_ns) *out = got;
        found = true;
    }
    return found;
}

/* ---- address ranges of loaded plugins ---- */

typedef struct range_query {
    uintptr_t base;
    uintptr_t lo, hi;
} range_query;

static int find_object(struct dl_phdr_info *info, size_t size, void *data)
{
    (void)size;
    range_query *q = data;
    if (info->dlpi_addr != q->base) return 0;
    for (int i = 0; i < info->dlpi_phnum; i++) {
        const ElfW(Phdr) *ph = &info->dlpi_phdr[i];
        if (ph->p_type != PT_LOAD) continue;
        uintptr_t lo = q->base + ph->p_vaddr, hi = lo + ph->p_memsz;
        if (!q->lo || lo < q->lo) q->lo = lo;
        if (hi > q->hi) q->hi = hi;
    }
    return 1;
}

void fp_plugin_crash_register(void *handle, const char *path)
{
    struct link_map *lm = NULL;
    if (!handle || dlinfo(handle, RTLD_DI_LINKMAP, &lm) || !lm) return;
    range_query q = {(uintptr_t)lm->l_addr, 0, 0};
    dl_iterate_phdr(find_object, &q);
    if (!q.lo) return;
    for (int i = 0; i < MAX_PLUGINS; i++) {
        if (atomic_load(&ranges[i].lo)) continue;
        ranges[i].hi = q.hi;
        ranges[i].handle = handle;
        snprintf(ranges[i].path, sizeof ranges[i].path, "%s", path ? path : "?");
        atomic_store(&ranges[i].lo, q.lo); /* published last */
        return;
    }
}

void fp_plugin_crash_unregister(void *handle)
{
    for (int i = 0; i < MAX_PLUGINS; i++)
        if (atomic_load(&ranges[i].lo) && ranges[i].handle == handle) atomic_store(&ranges[i].lo, 0);
}

/* ---- the handler: async-signal-safe formatting only ---- */

typedef struct line {
    char buf[768];
    size_t n;
} line;

static void put(line *l, const char *s)
{
    while (s && *s && l->n + 1 < sizeof l->buf) l->buf[l->n++] = *s++;
}

static void put_u64(line *l, uint64_t v)
{
    char tmp[24];
    int k = 0;
    do tmp[k++] = (char)('0' + v % 10); while ((v /= 10) && k < 23);
    while (k && l->n + 1 < sizeof l->buf) l->buf[l->n++] = tmp[--k];
}

static const char *signal_name(int sig)
{
    switch (sig) {
    case SIGSEGV: return "SIGSEGV";
    case SIGBUS: return "SIGBUS";
    case SIGFPE: return "SIGFPE";
    case SIGILL: return "SIGILL";
    case SIGABRT: return "SIGABRT";
    default: return "signal";
    }
}

static uintptr_t fault_pc(void *uctx)
{
    ucontext_t *uc = uctx;
    if (!uc) return 0;
#if defined(__x86_64__)
    return (uintptr_t)uc->uc_mcontext.gregs[REG_RIP];
#elif defined(__aarch64__)
    return (uintptr_t)uc->uc_mcontext.pc;
#else
    return 0;
#endif
}

static const int fatal_signals[] = {SIGSEGV, SIGBUS, SIGFPE, SIGILL, SIGABRT};

static void on_fatal(int sig, siginfo_t *si, void *uctx)
{
    (void)si;
    line l = {.n = 0};
    put(&l, "facepuppet: fatal signal ");
    put(&l, signal_name(sig));
    if (current.who) {
        put(&l, " in plugin '");
        put(&l, current.who);
        put(&l, "' during ");
        put(&l, current.call ? current.call : "a call");
        put(&l, " (frame ");
        put_u64(&l, current.frame);
        put(&l, ")");
    } else {
        uintptr_t pc = fault_pc(uctx);
        const char *path = NULL;
        for (int i = 0; i < MAX_PLUGINS && pc; i++) {
            uintptr_t lo = atomic_load(&ranges[i].lo);
            if (lo && pc >= lo && pc < ranges[i].hi) path = ranges[i].path;
        }
        if (path) {
            put(&l, " in plugin ");
            put(&l, path);
            put(&l, " (its own thread)");
        } else {
            put(&l, " (not inside a plugin)");
        }
    }
    put(&l, "\n");
    ssize_t w = write(STDERR_FILENO, l.buf, l.n);
    (void)w;
    signal(sig, SIG_DFL);
    raise(sig);
}

int fp_plugin_crash_install(void)
{
    static atomic_bool installed;
    if (atomic_exchange(&installed, true)) return 0;
    static char alt[64 * 1024];
    stack_t ss = {.ss_sp = alt, .ss_size = sizeof alt, .ss_flags = 0};
    if (sigaltstack(&ss, NULL)) return -errno;
    struct sigaction sa;
    memset(&sa, 0, sizeof sa);
    sa.sa_sigaction = on_fatal;
    sa.sa_flags = SA_SIGINFO | SA_ONSTACK | SA_RESETHAND | SA_NODEFER;
    sigemptyset(&sa.sa_mask);
    for (size_t i = 0; i < sizeof fatal_signals / sizeof fatal_signals[0]; i++)
        if (sigaction(fatal_signals[i], &sa, NULL)) return -errno;
    return 0;
}
