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
} current;

void fp_plugin_call_enter(const char *who, const char *call, uint64_t frame)
{
    current.who = who;
    current.call = call;
    current.frame = frame;
    current.depth++;
}

void fp_plugin_call_leave(void)
{
    if (current.depth > 0 && --current.depth == 0) current.who = current.call = NULL;
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
