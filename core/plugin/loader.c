/* Finding and loading plugins: <input|map>-<name>.so on a search path, one entry symbol. */
#define _GNU_SOURCE
#include "fp_plugin_host.h"
#include "fp_plugin_crash.h"

#include <dirent.h>
#include <dlfcn.h>
#include <elf.h>
#include <errno.h>
#include <fcntl.h>
#include <stdio.h>
#include <stdlib.h>
#include <stddef.h>
#include <string.h>
#include <sys/stat.h>
#include <limits.h>
#include <stdint.h>
#include <unistd.h>

static const char *kind_prefix(fp_plugin_kind kind)
{
    return kind == FP_PLUGIN_INPUT ? "input-" : "map-";
}

/* Appends "plugin folder 'DIR' VERDICT: WHY\n" to path->warnings (truncated when full). */
static void add_warning(fp_plugin_path *path, const char *dir, const char *verdict, const char *why)
{
    size_t used = strlen(path->warnings);
    if (used + 1 < sizeof path->warnings)
        snprintf(path->warnings + used, sizeof path->warnings - used,
                 "plugin folder '%.300s' %s: %.200s\n", dir, verdict, why);
}

bool fp_plugin_path_unsafe(const char *p, char *why, size_t whylen)
{
    struct stat st;
    if (stat(p, &st)) return false; /* absent: nothing to load from it */
    uid_t me = getuid();
    if (st.st_mode & (S_IWGRP | S_IWOTH)) {
        snprintf(why, whylen, "writable by %s", st.st_mode & S_IWOTH ? "others" : "its group");
        return true;
    }
    if (st.st_uid != me && st.st_uid != 0) {
        snprintf(why, whylen, "owned by uid %u, neither you (uid %u) nor root",
                 (unsigned)st.st_uid, (unsigned)me);
        return true;
    }
    return false;
}

static void add_dir(fp_plugin_path *path, const char *dir, bool builtin, bool make_absolute)
{
    if (!dir || !*dir || path->count == FP_PLUGIN_MAX_DIRS) return;
    char abs[PATH_MAX];
    if (dir[0] != '/') {
        if (!make_absolute || !realpath(dir, abs)) {
            add_warning(path, dir, "ignored",
                        make_absolute ? "it does not exist" : "a relative path (give an absolute one)");
            return;
        }
        dir = abs;
    }
    char why[128];
    if (!builtin && fp_plugin_path_unsafe(dir, why, sizeof why)) {
        add_warning(path, dir, "skipped", why);
        return;
    }
    for (size_t i = 0; i < path->count; i++)
        if (!strcmp(path->dirs[i], dir)) return; /* already searched */
    char *copy = strdup(dir);
    if (!copy) return;
    if (builtin) path->builtin = path->count;
    path->dirs[path->count++] = copy;
}

void fp_plugin_path_init(fp_plugin_path *path, const char *const *extra_dirs, size_t n_extra,
                         const char *builtin_dir)
{
    memset(path, 0, sizeof *path);
    path->builtin = SIZE_MAX;
    add_dir(path, builtin_dir, true, true);
    for (size_t i = 0; i < n_extra; i++) add_dir(path, extra_dirs[i], false, true);
    const char *env = getenv("FACEPUPPET_PLUGIN_PATH");
    if (env) {
        char *copy = strdup(env);
        char *save = NULL;
        for (char *d = copy ? strtok_r(copy, ":", &save) : NULL; d; d = strtok_r(NULL, ":", &save))
            add_dir(path, d, false, false);
        free(copy);
    }
}

void fp_plugin_path_clear(fp_plugin_path *path)
{
    for (size_t i = 0; i < path->count; i++) free(path->dirs[i]);
    memset(path, 0, sizeof *path);
}

void fp_plugin_list(const fp_plugin_path *path, fp_plugin_kind kind, char *buf, size_t len)
{
    const char *prefix = kind_prefix(kind);
    size_t plen = strlen(prefix), used = 0;
    if (len) buf[0] = '\0';
    for (size_t i = 0; i < path->count; i++) {
        DIR *d = opendir(path->dirs[i]);
        if (!d) continue;
        for (struct dirent *e; (e = readdir(d));) {
            size_t n = strlen(e->d_name);
            if (n <= plen + 3 || strncmp(e->d_name, prefix, plen) || strcmp(e->d_name + n - 3, ".so"))
                continue;
            int w = snprintf(buf + used, used < len ? len - used : 0, "%s%.*s", used ? ", " : "",
                             (int)(n - plen - 3), e->d_name + plen);
            if (w > 0) used += (size_t)w;
        }
        closedir(d);
    }
}

static int fail(fp_plugin *p, int code)
{
    fp_plugin_unload(p);
    return code;
}

void fp_plugin_not_found(const fp_plugin_path *path, fp_plugin_kind kind, const char *name,
                         const char *warning, char *err, size_t errlen)
{
    const char *what = kind == FP_PLUGIN_INPUT ? "input" : "mapping";
    char dirs[1024] = "", avail[1024];
    size_t used = 0;
    for (size_t i = 0; i < path->count; i++) {
        int w = snprintf(dirs + used, used < sizeof dirs ? sizeof dirs - used : 0, "%s%s",
                         i ? ", " : "", path->dirs[i]);
        if (w > 0) used += (size_t)w;
    }
    fp_plugin_list(path, kind, avail, sizeof avail);
    if (strchr(name, '/'))
        snprintf(err, errlen, "%s plugin file '%s' not found", what, name);
    else
        snprintf(err, errlen, "no %s plugin named '%s' (looked for %s%s.so in: %s; available: %s)%s%s",
                 what, name, kind_prefix(kind), name, path->count ? dirs : "no folders",
                 avail[0] ? avail : "none", warning && warning[0] ? "; " : "", warning ? warning : "");
}

bool fp_plugin_shipped(fp_plugin_kind kind, const char *name)
{
    /* plugins/: every fp_add_plugin of a mapping and an input (tests/plugin checks the list
     * against the built plugin folder) */
    static const char *const mappings[] = {"anchored", "unanchored", "onehand"};
    static const char *const inputs[] = {"replay", "take", "osc", "cyberglove", "pedal", "audio"};
    const char *const *list = kind == FP_PLUGIN_INPUT ? inputs : mappings;
    size_t n = kind == FP_PLUGIN_INPUT ? sizeof inputs / sizeof *inputs : sizeof mappings / sizeof *mappings;
    for (size_t i = 0; name && i < n; i++)
        if (!strcmp(name, list[i])) return true;
    return false;
}

bool fp_plugin_find(const fp_plugin_path *path, fp_plugin_kind kind, const char *name, char *file,
                    size_t filelen, bool *builtin, char *warning, size_t warnlen)
{
    struct stat st;
    bool found = false;
    if (builtin) *builtin = false;
    if (strchr(name, '/')) {
        snprintf(file, filelen, "%s", name);
        return stat(file, &st) == 0;
    }
    for (size_t i = 0; i < path->count && !found; i++) {
        snprintf(file, filelen, "%s/%s%s.so", path->dirs[i], kind_prefix(kind), name);
        found = stat(file, &st) == 0;
        char why[128];
        if (found && i != path->builtin && fp_plugin_path_unsafe(file, why, sizeof why)) {
            size_t used = warning ? strlen(warning) : 0;
            if (warning && used < warnlen)
                snprintf(warning + used, warnlen - used, "%s%.300s skipped: %.120s", used ? "; " : "", file, why);
            found = false;
        }
        if (found && builtin) *builtin = i == path->builtin && fp_plugin_shipped(kind, name);
    }
    return found;
}

/* What makes an offered factory unusable, for the message (NULL: usable). An ABI 1.0 factory
 * ends before `params`; fields past its size are never read. */
static const char *factory_broken(fp_plugin_kind kind, const void *factory)
{
    bool sized, named, creates;
    if (kind == FP_PLUGIN_INPUT) {
        const fp_input_factory *f = factory;
        sized = FP_HAS_FIELD(f, fp_input_factory, create);
        named = sized && f->name, creates = sized && f->create;
    } else {
        const fp_mapping_factory *f = factory;
        sized = FP_HAS_FIELD(f, fp_mapping_factory, create);
        named = sized && f->name, creates = sized && f->create;
    }
    return !sized ? "is too small: its size ends before create"
           : !named ? "has no name (NULL)" : !creates ? "has no create (NULL)" : NULL;
}

/* Whether the regular file `file` is a shared object of this machine's ELF class whose
 * program headers or loaded segments end past the file's end (a copy cut short): into why.
 * dlopen maps such segments, and the first touch past the end raises SIGBUS in the host,
 * before any plugin code runs. Anything else (not ELF, another class, unreadable) is left
 * for dlopen to judge. */
static bool elf_cut_short(const char *file, char *why, size_t n)
{
#if UINTPTR_MAX > 0xffffffffu
    typedef Elf64_Ehdr ehdr;
    typedef Elf64_Phdr phdr;
    const unsigned char cls = ELFCLASS64;
#else
    typedef Elf32_Ehdr ehdr;
    typedef Elf32_Phdr phdr;
    const unsigned char cls = ELFCLASS32;
#endif
    int fd = open(file, O_RDONLY | O_CLOEXEC | O_NONBLOCK);
    struct stat st;
    ehdr eh;
    bool cut = false;
    if (fd < 0) return false;
    if (fstat(fd, &st) || pread(fd, &eh, sizeof eh, 0) != (ssize_t)sizeof eh ||
        memcmp(eh.e_ident, ELFMAG, SELFMAG) || eh.e_ident[EI_CLASS] != cls || eh.e_phentsize != sizeof(phdr)) {
        close(fd);
        return false;
    }
    const uint64_t size = (uint64_t)st.st_size;
    const uint64_t ph_end = (uint64_t)eh.e_phoff + (uint64_t)eh.e_phnum * sizeof(phdr);
    if (ph_end > size) {
        snprintf(why, n, "cut short: its program headers end at byte %llu of a file of %llu bytes",
                 (unsigned long long)ph_end, (unsigned long long)size);
        cut = true;
    }
    for (unsigned i = 0; !cut && i < eh.e_phnum; i++) {
        phdr ph;
        if (pread(fd, &ph, sizeof ph, (off_t)(eh.e_phoff + (uint64_t)i * sizeof ph)) != (ssize_t)sizeof ph) break;
        const uint64_t end = (uint64_t)ph.p_offset + (uint64_t)ph.p_filesz;
        if (ph.p_type == PT_LOAD && end > size) {
            snprintf(why, n, "cut short: its loaded segment %u ends at byte %llu of a file of %llu bytes "
                     "(a copy interrupted?)", i, (unsigned long long)end, (unsigned long long)size);
            cut = true;
        }
    }
    close(fd);
    return cut;
}

int fp_plugin_load(const fp_plugin_path *path, fp_plugin_kind kind, const char *name,
                   fp_plugin *out, char *err, size_t errlen)
{
    const char *what = kind == FP_PLUGIN_INPUT ? "input" : "mapping";
    memset(out, 0, sizeof *out);
    out->kind = kind;
    char file[4096];
    bool found = fp_plugin_find(path, kind, name, file, sizeof file, NULL, out->warning, sizeof out->warning);
    if (!found) {
        fp_plugin_not_found(path, kind, name, out->warning, err, errlen);
        return FP_EPLUGIN_NOT_FOUND;
    }
    out->path = strdup(file);
    /* a regular file only: dlopen would wait on a FIFO for a writer (`plugins check FIFO`, or a
     * FIFO named like a plugin in a plugin folder, hung the command) */
    struct stat st;
    bool there = stat(file, &st) == 0;
    if (!there || !S_ISREG(st.st_mode)) {
        snprintf(err, errlen, "%s: cannot load: %s", file,
                 !there ? strerror(errno) : "not a regular file (a FIFO, device or socket)");
        return fail(out, FP_EPLUGIN_DLOPEN);
    }
    char why[200];
    if (elf_cut_short(file, why, sizeof why)) {
        snprintf(err, errlen, "%s: cannot load: %s", file, why);
        return fail(out, FP_EPLUGIN_DLOPEN);
    }
    out->handle = dlopen(file, RTLD_NOW | RTLD_LOCAL);
    if (!out->handle) {
        snprintf(err, errlen, "%s: cannot load: %s", file, dlerror());
        return fail(out, FP_EPLUGIN_DLOPEN);
    }
    out->entry = (const fp_plugin_entry *)dlsym(out->handle, FP_PLUGIN_ENTRY_SYMBOL);
    if (!out->entry) {
        snprintf(err, errlen, "%s: not a facepuppet plugin (no symbol '%s')", file,
                 FP_PLUGIN_ENTRY_SYMBOL);
        return fail(out, FP_EPLUGIN_NO_ENTRY);
    }
    fp_version host = {FP_PLUGIN_ABI_MAJOR, FP_PLUGIN_ABI_MINOR};
    if (!fp_version_is_compatible(host, out->entry->abi)) {
        snprintf(err, errlen,
                 "%s: built for plugin ABI %u.%u, this facepuppet has ABI %u.%u (%s); rebuild "
                 "the plugin against this facepuppet's facepuppet/plugin.h",
                 file, out->entry->abi.major, out->entry->abi.minor, host.major, host.minor,
                 out->entry->abi.major != host.major ? "another major" : "a newer minor");
        out->entry = NULL; /* do not call its deinit */
        return fail(out, FP_EPLUGIN_ABI);
    }
    fp_plugin_crash_register(out->handle, file);
    fp_plugin_call_enter(out->path, "init", 0);
    bool init_ok = !out->entry->init || out->entry->init(file);
    fp_plugin_call_leave();
    if (!init_ok) {
        snprintf(err, errlen, "%s: the plugin's init failed", file);
        out->entry = NULL;
        return fail(out, FP_EPLUGIN_INIT);
    }
    const char *fid = kind == FP_PLUGIN_INPUT ? FP_INPUT_FACTORY_ID : FP_MAPPING_FACTORY_ID;
    out->factory = out->entry->get_factory ? out->entry->get_factory(fid) : NULL;
    if (!out->entry->get_factory || !out->factory) {
        snprintf(err, errlen, "%s: offers no %s factory ('%s'%s)", file, what, fid,
                 out->entry->get_factory ? "" : ": its entry's get_factory is NULL");
        return fail(out, FP_EPLUGIN_NO_FACTORY);
    }
    const char *broken = factory_broken(kind, out->factory);
    if (broken) {
        snprintf(err, errlen, "%s: its %s factory ('%s') %s", file, what, fid, broken);
        return fail(out, FP_EPLUGIN_NO_FACTORY);
    }
    return 0;
}

void fp_plugin_unload(fp_plugin *p)
{
    if (p->entry && p->entry->deinit) {
        fp_plugin_call_enter(p->path, "deinit", 0);
        p->entry->deinit();
        fp_plugin_call_leave();
    }
    if (p->handle) {
        fp_plugin_crash_unregister(p->handle);
        dlclose(p->handle);
    }
    free(p->path);
    fp_plugin_kind kind = p->kind;
    memset(p, 0, sizeof *p);
    p->kind = kind;
}
