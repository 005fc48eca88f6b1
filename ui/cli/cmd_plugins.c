/* facepuppet plugins: list every plugin on the search path; plugins check FILE.so: validate one. */
#define _GNU_SOURCE
#include "app_getopt.h"
#include "fp_isolate.h"
#include "app_util.h"
#include "command.h"
#include "fp_plugin_check.h"
#include "fp_plugin_crash.h"
#include "fp_plugin_host.h"

#include <cjson/cJSON.h>
#include <errno.h>
#include <getopt.h>
#include <limits.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

static const char *type_name(fp_param_type t)
{
    switch (t) {
    case FP_PARAM_BOOL: return "bool";
    case FP_PARAM_INT: return "int";
    case FP_PARAM_FLOAT: return "float";
    case FP_PARAM_ENUM: return "enum";
    case FP_PARAM_STRING: return "string";
    case FP_PARAM_PATH: return "path";
    }
    return "?";
}

static const char *code_reason(int code)
{
    switch (code) {
    case 0: return "ok";
    case FP_EPLUGIN_DLOPEN: return "dlopen";
    case FP_EPLUGIN_NO_ENTRY: return "no-entry";
    case FP_EPLUGIN_ABI: return "abi";
    case FP_EPLUGIN_INIT: return "init-failed";
    case FP_EPLUGIN_NO_FACTORY: return "no-factory";
    case -EACCES: return "unsafe";
    default: return "error";
    }
}

/* "[min, max]" for numbers, the choices for an enum, "" otherwise. */
static void range_text(const fp_param_info *p, char *buf, size_t len)
{
    if (p->type == FP_PARAM_INT || p->type == FP_PARAM_FLOAT) snprintf(buf, len, "[%g, %g]", p->min, p->max);
    else if (p->type == FP_PARAM_ENUM) snprintf(buf, len, "%s", p->choices ? p->choices : "");
    else if (p->type == FP_PARAM_BOOL) snprintf(buf, len, "0|1");
    else buf[0] = '\0';
}

/* A plugin file that loaded: the name its factory gives, for the files that give the same one. */
typedef struct listed {
    fp_plugin_kind kind;
    char *name, *file;
} listed;

typedef struct lister {
    bool json;
    cJSON *array;               /* --json: the plugins listed so far */
    size_t broken;
    const fp_plugin_path *path; /* the folders searched */
    pthread_mutex_t lock;       /* array, between on_item and the watchdog */
    listed *loaded;             /* every file that loaded, in listing order */
    size_t nloaded;
} lister;

/* What to give --input/--mapping to load `file` (found as NAME `name`): NAME, or the file's
 * path where an earlier folder's file of that NAME shadows it. */
static const char *load_spec(const fp_plugin_scan_item *it)
{
    return it->shadowed ? it->file : it->name;
}

static void remember(lister *L, const fp_plugin_scan_item *it, const char *name)
{
    listed *grown = realloc(L->loaded, (L->nloaded + 1) * sizeof *grown);
    if (!grown) return;
    L->loaded = grown;
    listed *l = &L->loaded[L->nloaded];
    *l = (listed){it->kind, strdup(name), strdup(it->file)};
    if (l->name && l->file) L->nloaded++;
    else free(l->name), free(l->file);
}

/* A warning for each name that two or more files give (a user's copy of a bundled plugin
 * under another file name, or in another folder): the files, and which one `--input NAME`
 * / `--mapping NAME` loads (the first input-NAME.so / map-NAME.so on the path, maybe none of
 * them). On stderr, or with --json (root not NULL) in the document alone, as "same_name"
 * (its stdout stays one document, even where stderr is merged into it). Before, two such
 * files were listed as the same name with nothing said. */
static void warn_same_names(const lister *L, cJSON *root)
{
    cJSON *groups = root ? cJSON_AddArrayToObject(root, "same_name") : NULL;
    for (size_t i = 0; i < L->nloaded; i++) {
        const listed *a = &L->loaded[i];
        size_t count = 0;
        bool first = true;
        for (size_t j = 0; j < L->nloaded; j++) {
            const listed *b = &L->loaded[j];
            if (b->kind != a->kind || strcmp(b->name, a->name)) continue;
            if (j < i) first = false;
            count++;
        }
        if (count < 2 || !first) continue;
        const char *kind = a->kind == FP_PLUGIN_INPUT ? "input" : "mapping";
        char files[3000] = "", loads[4096];
        cJSON *g = groups ? cJSON_CreateObject() : NULL, *list = NULL;
        if (g) {
            cJSON_AddStringToObject(g, "kind", kind);
            cJSON_AddStringToObject(g, "name", a->name);
            list = cJSON_AddArrayToObject(g, "files");
        }
        for (size_t j = i; j < L->nloaded; j++) {
            const listed *b = &L->loaded[j];
            if (b->kind != a->kind || strcmp(b->name, a->name)) continue;
            size_t used = strlen(files);
            snprintf(files + used, sizeof files - used, "%s%s", used ? ", " : "", b->file);
            if (list) cJSON_AddItemToArray(list, cJSON_CreateString(b->file));
        }
        bool found = !strchr(a->name, '/') &&
                     fp_plugin_find(L->path, a->kind, a->name, loads, sizeof loads, NULL, NULL, 0);
        char line[8000];
        snprintf(line, sizeof line, "%zu %s plugin files give the name '%s': %s; `--%s %s` loads %s; "
                 "load another by the name or path its listing shows", count, kind, a->name, files,
                 kind, a->name, found ? loads : "none of them (no file of that NAME)");
        if (g) {
            if (found) cJSON_AddStringToObject(g, "loads", loads);
            else cJSON_AddNullToObject(g, "loads");
            cJSON_AddStringToObject(g, "warning", line);
            cJSON_AddItemToArray(groups, g);
        } else {
            fprintf(stderr, "facepuppet plugins: warning: %s\n", line);
        }
    }
}

/* The --json document: folders, skipped, plugins (L's array, given away); with hang set
 * (the watchdog's "plugin 'WHO' has not returned ..."), "complete": false and "error": hang. */
static void print_json(lister *L, const char *hang)
{
    const fp_plugin_path *path = L->path;
    cJSON *root = cJSON_CreateObject();
    cJSON *folders = cJSON_AddArrayToObject(root, "folders");
    for (size_t i = 0; i < path->count; i++) {
        cJSON *f = cJSON_CreateObject();
        cJSON_AddStringToObject(f, "path", path->dirs[i]);
        cJSON_AddBoolToObject(f, "builtin", i == path->builtin);
        cJSON_AddItemToArray(folders, f);
    }
    cJSON *skipped = cJSON_AddArrayToObject(root, "skipped");
    for (const char *w = path->warnings; *w;) {
        const char *nl = strchr(w, '\n');
        int len = nl ? (int)(nl - w) : (int)strlen(w);
        char line[1100];
        snprintf(line, sizeof line, "%.*s", len, w);
        cJSON_AddItemToArray(skipped, cJSON_CreateString(line));
        w += len + (nl ? 1 : 0);
    }
    cJSON_AddItemToObject(root, "plugins", L->array);
    L->array = NULL;
    warn_same_names(L, root);
    cJSON_AddBoolToObject(root, "complete", hang == NULL);
    if (hang) cJSON_AddStringToObject(root, "error", hang);
    char *text = cJSON_Print(root);
    if (text) puts(text);
    free(text);
    cJSON_Delete(root);
}

/* The listing runs each plugin's init in this process: one that never returns would hang it
 * without a word. A watchdog thread (arg: the lister) looks every 100 ms at the plugin call in
 * progress and, past the deadline, names it and ends the listing (exit 78), what was listed
 * kept: printed as it went, or with --json the document of what was listed, "complete":
 * false and the message as "error" (the main thread is inside the plugin: the array stays). */
#define PLUGINS_INIT_DEADLINE_S 10
static void *init_watch(void *arg)
{
    lister *L = arg;
    for (;;) {
        struct timespec ts = {0, 100000000L};
        nanosleep(&ts, NULL);
        fp_plugin_call_info call;
        struct timespec now;
        clock_gettime(CLOCK_MONOTONIC, &now);
        int64_t ns = (int64_t)now.tv_sec * 1000000000LL + now.tv_nsec;
        if (!fp_plugin_call_oldest(&call) || ns - call.since_ns < PLUGINS_INIT_DEADLINE_S * 1000000000LL)
            continue;
        char msg[1400];
        snprintf(msg, sizeof msg, "plugin '%s' has not returned from %s for %d s: it hangs; the listing "
                 "ends here", call.who, call.call ? call.call : "a call", PLUGINS_INIT_DEADLINE_S);
        if (L->json) {
            pthread_mutex_lock(&L->lock);
            print_json(L, msg);
        }
        fflush(stdout);
        fprintf(stderr, "facepuppet plugins: %s\n", msg);
        _exit(FP_EXIT_PLUGIN);
    }
    return NULL;
}

static void print_indented(const char *text, const char *indent)
{
    for (const char *l = text; l && *l;) {
        const char *nl = strchr(l, '\n');
        int n = nl ? (int)(nl - l) : (int)strlen(l);
        printf("%s%.*s\n", indent, n, l);
        l += n + (nl ? 1 : 0);
    }
}

static void on_item(void *user, const fp_plugin_scan_item *it)
{
    lister *L = user;
    const char *kind = it->kind == FP_PLUGIN_INPUT ? "input" : "mapping";
    fp_plugin_about about = {0};
    const fp_plugin_entry *e = it->plugin ? it->plugin->entry : NULL;
    if (it->plugin) fp_plugin_describe(it->plugin, &about);
    if (it->code) L->broken++;
    pthread_mutex_lock(&L->lock); /* (the watchdog's document reads them) */
    if (!it->code) remember(L, it, about.name ? about.name : it->name);
    pthread_mutex_unlock(&L->lock);
    if (L->json) {
        cJSON *o = cJSON_CreateObject();
        cJSON_AddStringToObject(o, "kind", kind);
        cJSON_AddStringToObject(o, "name", about.name ? about.name : it->name);
        cJSON_AddStringToObject(o, "file", it->file);
        cJSON_AddStringToObject(o, "load", load_spec(it)); /* what --input/--mapping takes */
        cJSON_AddStringToObject(o, "status", code_reason(it->code));
        if (it->shadowed) cJSON_AddBoolToObject(o, "shadowed", true);
        if (it->code) cJSON_AddStringToObject(o, "error", it->error ? it->error : fp_strerror(it->code));
        if (e) {
            cJSON_AddStringToObject(o, "id", e->id ? e->id : "");
            cJSON_AddStringToObject(o, "version", e->version ? e->version : "");
            char abi[32];
            snprintf(abi, sizeof abi, "%u.%u", e->abi.major, e->abi.minor);
            cJSON_AddStringToObject(o, "abi", abi);
            cJSON_AddStringToObject(o, "description", about.description ? about.description : "");
            cJSON_AddStringToObject(o, "usage", about.usage ? about.usage : "");
            cJSON *keys = about.params ? cJSON_AddArrayToObject(o, "keys") : NULL;
            for (const fp_param_info *p = about.params; p && p->name; p++) {
                cJSON *k = cJSON_CreateObject();
                cJSON_AddStringToObject(k, "name", p->name);
                cJSON_AddStringToObject(k, "type", type_name(p->type));
                if (p->type == FP_PARAM_INT || p->type == FP_PARAM_FLOAT) {
                    cJSON_AddNumberToObject(k, "min", p->min);
                    cJSON_AddNumberToObject(k, "max", p->max);
                }
                if (p->choices) cJSON_AddStringToObject(k, "choices", p->choices);
                if (p->default_value) cJSON_AddStringToObject(k, "default", p->default_value);
                else cJSON_AddBoolToObject(k, "required", true);
                if (p->unit) cJSON_AddStringToObject(k, "unit", p->unit);
                cJSON_AddStringToObject(k, "description", p->description ? p->description : "");
                cJSON_AddItemToArray(keys, k);
            }
        }
        pthread_mutex_lock(&L->lock);
        cJSON_AddItemToArray(L->array, o);
        pthread_mutex_unlock(&L->lock);
        return;
    }
    if (it->code) {
        printf("%-7s %-14s BROKEN (%s)%s\n        %s\n        %s\n\n", kind, it->name, code_reason(it->code),
               it->shadowed ? " [shadowed]" : "", it->file, it->error ? it->error : fp_strerror(it->code));
        return;
    }
    printf("%-7s %-14s %s %s  ABI %u.%u%s\n", kind, about.name ? about.name : it->name,
           e->id ? e->id : "?", e->version ? e->version : "?", e->abi.major, e->abi.minor,
           it->shadowed ? "  [shadowed by an earlier folder]" : "");
    printf("        %s  (--%s %s)\n", it->file, kind, load_spec(it));
    if (about.description) printf("        %s\n", about.description);
    if (about.usage && *about.usage) {
        printf("        usage:\n");
        print_indented(about.usage, "          ");
    }
    if (about.params) {
        printf("        keys:\n");
        for (const fp_param_info *p = about.params; p->name; p++) {
            char range[128];
            range_text(p, range, sizeof range);
            printf("          %-9s %-6s %-18s %-5s default %-8s %s\n", p->name, type_name(p->type), range,
                   p->unit ? p->unit : "", !p->default_value ? "(required)" : *p->default_value ? p->default_value : "-",
                   p->description ? p->description : "");
        }
    } else {
        printf("        keys: not declared (ABI 1.0 factory or no fp_param_info list)\n");
    }
    printf("\n");
}

static void usage(FILE *f)
{
    fprintf(f,
        "usage: facepuppet plugins [--json] [--plugin-dir DIR]...\n"
        "       facepuppet plugins check FILE.so [--json] [--arg ARG] [--key K=V]...\n"
        "                                [--budget MS] [--cycles N] [--deadline S]\n\n"
        "plugins: every input-*.so and map-*.so on the plugin search path (the built-in\n"
        "folder, --plugin-dir folders, FACEPUPPET_PLUGIN_PATH), loaded and described: kind,\n"
        "name, id, version, ABI, file and what --input/--mapping takes to load it,\n"
        "description, usage and typed keys; a broken one with the reason (dlopen error, no\n"
        "entry, ABI, init failed, no factory, unsafe file). Also the folders searched and\n"
        "those skipped for safety, and a warning where two files give the same name (which\n"
        "one --input NAME / --mapping NAME loads; with --json in the document, \"same_name\").\n"
        "  -P, --plugin-dir DIR  look for plugins in DIR too, after the built-in folder\n"
        "                        (repeatable)\n"
        "      --json            one JSON document\n\n"
        "plugins check: validate one plugin file (docs/plugin-guide.md, \"Checking a\n"
        "plugin\"): create with defaults and with bad keys; a mapping gets synthetic frames\n"
        "(capacity canaries, NaN, radius, time per call, determinism, destroy; from ABI 1.3\n"
        "also frames with 1 and 3 further performers' hands, which it must not write); an\n"
        "input is created, started, stopped and destroyed --cycles times and its events checked.\n"
        "The checks run in a child process: a plugin that crashes, calls exit() or hangs (no\n"
        "progress for --deadline) fails the check with a FAIL line naming the signal, the exit\n"
        "or the hang and the call and frame it was in; the plugin's stdout goes to stderr.\n"
        "  --arg ARG       an input's ARG (e.g. the recording of input-replay)\n"
        "  --key K=V       a key added to every create (repeatable), e.g. --key fast=1\n"
        "  --budget MS     a mapping's process() budget (default 2 ms)\n"
        "  --cycles N      an input's start/stop cycles (default 5)\n"
        "  --deadline S    the longest one call into the plugin may take before it counts\n"
        "                  as hung (default 10 s)\n"
        "  --isolate WHICH third-party (default): a mapping not in facepuppet's own plugin\n"
        "                  folder whose frames pass runs them again in a helper process\n"
        "                  (as run and live would run it), control sets compared frame by\n"
        "                  frame (\"isolated\"); all: any mapping; none: no such pass\n"
        "  --json          machine-readable output\n\n"
        "Exit status: 0 passed (skips allowed, e.g. \"needs a device\"), 1 a check failed (a\n"
        "crash, exit() or hang in the plugin included),\n"
        "64 usage, 78 the plugin cannot be loaded (missing, ABI, no entry, init, factory).\n");
}

typedef struct check_printer {
    bool json;
    cJSON *array;
} check_printer;

static void on_check(void *user, fp_check_level level, const char *check, const char *message)
{
    check_printer *cp = user;
    static const char *names[] = {"PASS", "FAIL", "SKIP", "INFO"};
    if (cp->json) {
        cJSON *o = cJSON_CreateObject();
        char lower[8];
        for (int i = 0; i < 5; i++) lower[i] = (char)(names[level][i] | (names[level][i] ? 0x20 : 0));
        cJSON_AddStringToObject(o, "result", lower);
        cJSON_AddStringToObject(o, "check", check);
        cJSON_AddStringToObject(o, "message", message);
        cJSON_AddItemToArray(cp->array, o);
    } else {
        printf("%s  %-14s %s\n", names[level], check, message);
    }
}

/* Whether `file` is in facepuppet's own plugin folder (its real directory is that one). */
static bool in_builtin_dir(const char *file)
{
    char dir[4200], real_dir[PATH_MAX], real_file[PATH_MAX];
    fp_app_builtin_plugin_dir(dir, sizeof dir);
    if (!realpath(dir, real_dir) || !realpath(file, real_file)) return false;
    char *slash = strrchr(real_file, '/');
    if (!slash) return false;
    *slash = '\0';
    return !strcmp(real_dir, real_file);
}

static int check_main(int argc, char **argv)
{
    static const struct option opts[] = {{"json", no_argument, 0, 'j'},      {"arg", required_argument, 0, 'a'},
                                         {"key", required_argument, 0, 'k'}, {"budget", required_argument, 0, 'b'},
                                         {"cycles", required_argument, 0, 'c'}, {"help", no_argument, 0, 'h'},
                                         {"isolate", required_argument, 0, 'I'},
                                         {"deadline", required_argument, 0, 'D'}, {0, 0, 0, 0}};
    fp_check_options o = {0};
    fp_isolate_mode isolate = FP_ISOLATE_THIRD_PARTY;
    fp_param keys[FP_SPEC_MAX_PARAMS];
    char *keybuf[FP_SPEC_MAX_PARAMS];
    size_t nkeys = 0;
    bool json = false;
    unsigned long long whole; /* an integer option (fp_parse_whole) */
    optind = 1;
    int status = FP_EXIT_OK;
    for (int c; (c = fp_app_getopt(argc, argv, "h", opts)) != -1;) {
        switch (c) {
        case 'j': json = true; break;
        case 'a': o.arg = optarg; break;
        case 'k': {
            char *eq = strchr(optarg, '=');
            if (!eq || eq == optarg || nkeys == FP_SPEC_MAX_PARAMS) {
                fprintf(stderr, "facepuppet plugins check: --key wants KEY=VALUE (at most %d), got '%s'\n",
                        FP_SPEC_MAX_PARAMS, optarg);
                status = FP_EXIT_USAGE;
                goto out;
            }
            keybuf[nkeys] = strdup(optarg);
            keybuf[nkeys][eq - optarg] = '\0';
            keys[nkeys] = (fp_param){keybuf[nkeys], keybuf[nkeys] + (eq - optarg) + 1};
            nkeys++;
            break;
        }
        case 'b':
            if (!fp_parse_decimal(optarg, &o.budget_ms) || !(o.budget_ms > 0 && o.budget_ms < 1e4)) {
                fprintf(stderr, "facepuppet plugins check: --budget must be a time in ms > 0, got '%s'\n", optarg);
                status = FP_EXIT_USAGE;
                goto out;
            }
            break;
        case 'c':
            if (!fp_parse_whole(optarg, 1000, &whole) || whole < 1) {
                fprintf(stderr, "facepuppet plugins check: --cycles must be in 1..1000, got '%s'\n", optarg);
                status = FP_EXIT_USAGE;
                goto out;
            }
            o.cycles = (int)whole;
            break;
        case 'D':
            if (!fp_parse_decimal(optarg, &o.deadline_s) || !(o.deadline_s >= 0.1 && o.deadline_s <= 3600)) {
                fprintf(stderr, "facepuppet plugins check: --deadline must be 0.1 to 3600 s, got '%s'\n", optarg);
                status = FP_EXIT_USAGE;
                goto out;
            }
            break;
        case 'I':
            if (fp_isolate_mode_parse(optarg, &isolate)) {
                fprintf(stderr, "facepuppet plugins check: --isolate must be all, none or third-party, got '%s'\n",
                        optarg);
                status = FP_EXIT_USAGE;
                goto out;
            }
            break;
        case 'h': usage(stdout); goto out;
        default: usage(stderr); status = FP_EXIT_USAGE; goto out;
        }
    }
    if (optind + 1 != argc) {
        fprintf(stderr, "facepuppet plugins check: give one FILE.so (see --help)\n");
        status = FP_EXIT_USAGE;
        goto out;
    }
    o.params = keys;
    o.nparams = nkeys;
    char file[4200];
    snprintf(file, sizeof file, "%s%s", strchr(argv[optind], '/') ? "" : "./", argv[optind]);
    o.isolate = fp_isolate_wanted(isolate, in_builtin_dir(file));
    fp_plugin_crash_install();
    check_printer cp = {json, json ? cJSON_CreateArray() : NULL};
    fp_check_summary sum;
    char err[2048] = "";
    if (!json) printf("checking %s\n", file);
    int rc = fp_plugin_check(file, &o, on_check, &cp, &sum, err, sizeof err);
    status = rc == 0 ? FP_EXIT_OK : rc == FP_EPLUGIN_FAULT ? FP_EXIT_FAILURE : fp_app_exit_code(rc, FP_APP_INPUT);
    if (json) {
        cJSON *root = cJSON_CreateObject();
        cJSON_AddStringToObject(root, "file", file);
        cJSON_AddStringToObject(root, "kind", sum.kind == FP_PLUGIN_INPUT ? "input" : "mapping");
        cJSON_AddStringToObject(root, "name", sum.name);
        cJSON_AddStringToObject(root, "id", sum.id);
        cJSON_AddStringToObject(root, "version", sum.version);
        cJSON_AddBoolToObject(root, "passed", rc == 0);
        cJSON_AddNumberToObject(root, "passes", sum.passed);
        cJSON_AddNumberToObject(root, "failures", sum.failed);
        cJSON_AddNumberToObject(root, "skips", sum.skipped);
        if (sum.frames) {
            cJSON_AddNumberToObject(root, "frames", (double)sum.frames);
            cJSON_AddNumberToObject(root, "process_median_us", sum.median_us);
            cJSON_AddNumberToObject(root, "process_max_us", sum.max_us);
        }
        if (sum.kind == FP_PLUGIN_INPUT) cJSON_AddNumberToObject(root, "events", (double)sum.events);
        cJSON_AddItemToObject(root, "checks", cp.array);
        char *text = cJSON_Print(root);
        if (text) puts(text);
        free(text);
        cJSON_Delete(root);
    } else if (rc == 0) {
        printf("passed: %u checks, %u skipped\n", sum.passed, sum.skipped);
    } else {
        printf("FAILED: %s (%u failed, %u passed, %u skipped)\n", err, sum.failed, sum.passed, sum.skipped);
    }
out:
    for (size_t i = 0; i < nkeys; i++) free(keybuf[i]);
    return status;
}

static int plugins_main(int argc, char **argv)
{
    if (argc >= 2 && !strcmp(argv[1], "check")) {
        static char prog[] = "facepuppet plugins check"; /* getopt's messages start with it */
        argv[1] = prog;
        return check_main(argc - 1, argv + 1);
    }
    static const struct option opts[] = {{"json", no_argument, 0, 'j'},
                                         {"plugin-dir", required_argument, 0, 'P'},
                                         {"help", no_argument, 0, 'h'},
                                         {0, 0, 0, 0}};
    const char *dirs[FP_PLUGIN_MAX_DIRS];
    size_t ndirs = 0;
    bool json = false;
    optind = 1;
    for (int c; (c = fp_app_getopt(argc, argv, "P:h", opts)) != -1;) {
        switch (c) {
        case 'j': json = true; break;
        case 'P':
            if (ndirs < FP_PLUGIN_MAX_DIRS) dirs[ndirs++] = optarg;
            break;
        case 'h': usage(stdout); return FP_EXIT_OK;
        default: usage(stderr); return FP_EXIT_USAGE;
        }
    }
    if (optind < argc) {
        fprintf(stderr, "facepuppet plugins: unexpected argument '%s' (see --help)\n", argv[optind]);
        return FP_EXIT_USAGE;
    }
    fp_plugin_crash_install();
    fp_plugin_path path;
    char builtin[4200];
    fp_app_builtin_plugin_dir(builtin, sizeof builtin);
    fp_plugin_path_init(&path, dirs, ndirs, builtin); /* warnings are listed below, not on stderr */
    lister L = {json, json ? cJSON_CreateArray() : NULL, 0, &path, PTHREAD_MUTEX_INITIALIZER, NULL, 0};
    if (!json) {
        printf("plugin folders searched, in order:\n");
        for (size_t i = 0; i < path.count; i++)
            printf("  %s%s\n", path.dirs[i], i == path.builtin ? "  (built-in)" : "");
        if (path.warnings[0]) {
            printf("skipped:\n");
            print_indented(path.warnings, "  ");
        }
        printf("\n");
    }
    pthread_t watch;
    if (!pthread_create(&watch, NULL, init_watch, &L)) pthread_detach(watch);
    size_t n = fp_plugin_scan(&path, on_item, &L);
    if (json) {
        pthread_mutex_lock(&L.lock); /* the watchdog prints no second document */
        print_json(&L, NULL);
    } else {
        printf("%zu plugin file(s), %zu broken\n", n, L.broken);
        fflush(stdout); /* (the warnings after the listing, where both go to one terminal) */
        warn_same_names(&L, NULL);
    }
    for (size_t i = 0; i < L.nloaded; i++) free(L.loaded[i].name), free(L.loaded[i].file);
    free(L.loaded);
    fp_plugin_path_clear(&path);
    return FP_EXIT_OK;
}

const fp_command fp_command_plugins = {"plugins", "list the plugins found (or check one: plugins check FILE.so)",
                                       plugins_main};
