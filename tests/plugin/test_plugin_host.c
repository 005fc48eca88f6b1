/* The host side of the plugin ABI: SPEC parsing, the loader's errors, the MPSC queue. */
#define _GNU_SOURCE
#include "fp_plugin_host.h"
#include "fp_isolate.h"
#include "log_relay.h"
#include "fp_control_check.h"
#include "fp_event_check.h"
#include "fp_plugin_crash.h"

#include <dirent.h>
#include <math.h>
#include <pthread.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <signal.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>
#include <cmocka.h>

static char fixture_dir[4096], builtin_dir[4096];

static void test_spec_parse(void **state)
{
    (void)state;
    fp_spec s;
    char err[256];
    assert_int_equal(fp_spec_parse("replay:a/b.csv,speed=2,loop=1", &s, err, sizeof err), 0);
    assert_string_equal(s.name, "replay");
    assert_string_equal(s.arg, "a/b.csv");
    assert_int_equal(s.nparams, 2);
    assert_string_equal(s.params[0].key, "speed");
    assert_string_equal(s.params[0].value, "2");
    assert_string_equal(fp_spec_take(&s, "loop"), "1");
    assert_int_equal(s.nparams, 1);
    assert_null(fp_spec_take(&s, "loop"));
    fp_spec_clear(&s);

    assert_int_equal(fp_spec_parse("pedal", &s, err, sizeof err), 0);
    assert_string_equal(s.name, "pedal");
    assert_null(s.arg);
    fp_spec_clear(&s);

    /* An ARG may hold ':' (pedal:VID:PID); keys may have empty values. */
    assert_int_equal(fp_spec_parse("pedal:05f3:00ff,layout=", &s, err, sizeof err), 0);
    assert_string_equal(s.arg, "05f3:00ff");
    assert_string_equal(s.params[0].value, "");
    fp_spec_clear(&s);

    /* A value runs to the next `,key=`: docs/pedal.md's `keys=a,b,c` (before: "'b' is not
     * key=value", exit 64); an item without '=' before any key is still refused. */
    assert_int_equal(fp_spec_parse("pedal,keys=a,b,c,strict=1", &s, err, sizeof err), 0);
    assert_int_equal(s.nparams, 2);
    assert_string_equal(s.params[0].key, "keys");
    assert_string_equal(s.params[0].value, "a,b,c");
    assert_string_equal(s.params[1].key, "strict");
    assert_string_equal(s.params[1].value, "1");
    fp_spec_clear(&s);
    assert_int_not_equal(fp_spec_parse("pedal,a,keys=b", &s, err, sizeof err), 0);
    assert_non_null(strstr(err, "'a' is not key=value"));

    assert_int_not_equal(fp_spec_parse("", &s, err, sizeof err), 0);
    assert_int_not_equal(fp_spec_parse("replay:x,speed", &s, err, sizeof err), 0);
    assert_non_null(strstr(err, "'speed' is not key=value"));
    assert_int_not_equal(fp_spec_parse("replay:x,a=1,a=2", &s, err, sizeof err), 0);
    assert_non_null(strstr(err, "given twice"));
    assert_int_not_equal(fp_spec_parse("re play", &s, err, sizeof err), 0);

    /* A NAME holding a '/' names the plugin's file (docs/plugin-guide.md): its path, up to
     * the ARG's ':' or the first key's ','. Before: refused as a bad name. */
    assert_int_equal(fp_spec_parse("/opt/my plugins/map-x.so,gain=2", &s, err, sizeof err), 0);
    assert_string_equal(s.name, "/opt/my plugins/map-x.so");
    assert_null(s.arg);
    assert_int_equal(s.nparams, 1);
    fp_spec_clear(&s);
    assert_int_equal(fp_spec_parse("./build/input-x.so:dev0,rate=5", &s, err, sizeof err), 0);
    assert_string_equal(s.name, "./build/input-x.so");
    assert_string_equal(s.arg, "dev0");
    fp_spec_clear(&s);
    assert_int_not_equal(fp_spec_parse("./a\nb/map-x.so", &s, err, sizeof err), 0); /* control char */
    assert_int_not_equal(fp_spec_parse("map-x.so", &s, err, sizeof err), 0); /* no '/': a NAME */
    assert_non_null(strstr(err, "bad name"));
}

static int load(const char *name, fp_plugin *p, char *err, size_t len)
{
    const char *dirs[] = {fixture_dir};
    fp_plugin_path path;
    fp_plugin_path_init(&path, dirs, 1, builtin_dir);
    int rc = fp_plugin_load(&path, FP_PLUGIN_INPUT, name, p, err, len);
    fp_plugin_path_clear(&path);
    return rc;
}

static void test_loader_errors(void **state)
{
    (void)state;
    fp_plugin p;
    char err[2048];
    assert_int_equal(load("no-such-thing", &p, err, sizeof err), FP_EPLUGIN_NOT_FOUND);
    assert_non_null(strstr(err, "no input plugin named 'no-such-thing'"));
    assert_non_null(strstr(err, fixture_dir)); /* names the folders searched */
    assert_non_null(strstr(err, "fixture"));   /* and what is available */

    assert_int_equal(load("fixture-abi2", &p, err, sizeof err), FP_EPLUGIN_ABI);
    assert_non_null(strstr(err, "built for plugin ABI 2.0"));
    assert_non_null(strstr(err, "input-fixture-abi2.so"));

    assert_int_equal(load("fixture-noentry", &p, err, sizeof err), FP_EPLUGIN_NO_ENTRY);
    assert_non_null(strstr(err, "no symbol 'facepuppet_plugin_entry'"));

    assert_int_equal(load("fixture-initfails", &p, err, sizeof err), FP_EPLUGIN_INIT);
    assert_non_null(strstr(err, "init failed"));

    /* A mapping asked for under an input plugin's name is not found. */
    const char *dirs[] = {fixture_dir};
    fp_plugin_path path;
    fp_plugin_path_init(&path, dirs, 1, NULL);
    assert_int_equal(fp_plugin_load(&path, FP_PLUGIN_MAPPING, "fixture-initfails", &p, err, sizeof err),
                     FP_EPLUGIN_NOT_FOUND);
    fp_plugin_path_clear(&path);
}

static void test_env_path_and_instance(void **state)
{
    (void)state;
    setenv("FACEPUPPET_PLUGIN_PATH", fixture_dir, 1);
    fp_plugin_path path;
    fp_plugin_path_init(&path, NULL, 0, NULL);
    assert_int_equal(path.count, 1);
    fp_input_instance inst;
    char err[1024];
    assert_int_equal(fp_input_instance_open(&inst, &path, "fixture,bogus=1", 7, err, sizeof err), -22);
    assert_non_null(strstr(err, "unknown key"));
    assert_int_equal(fp_input_instance_open(&inst, &path, "fixture,ok=1", 7, err, sizeof err), 0);
    assert_int_equal(fp_input_instance_start(&inst, err, sizeof err), 0);
    fp_event ev;
    int n = 0, downs = 0;
    while (fp_input_instance_poll(&inst, &ev)) {
        assert_int_equal(ev.header.source, 7); /* stamped by the host */
        if (ev.header.type == FP_EVENT_BUTTON) downs += (int)ev.button.down;
        n++;
    }
    assert_int_equal(n, 4);
    assert_int_equal(downs, 2);
    assert_int_equal(ev.header.type, FP_EVENT_STATUS);
    fp_input_instance_close(&inst);
    fp_plugin_path_clear(&path);
    unsetenv("FACEPUPPET_PLUGIN_PATH");
}

/* ---- an input's log lines: kept from its own thread, handed over on the owner's ---- */

typedef struct log_seen {
    pthread_t owner;
    int n, on_owner, warnings;
    char lines[40][320];
    char source[64];
} log_seen;

static void seen_log(void *user, int level, const char *source, const char *message)
{
    log_seen *l = user;
    l->on_owner += pthread_equal(pthread_self(), l->owner) != 0;
    l->warnings += level == FP_LOG_WARNING;
    if (l->n < 40) snprintf(l->lines[l->n], sizeof l->lines[0], "%s", message);
    snprintf(l->source, sizeof l->source, "%s", source);
    l->n++;
}

/* The plugin path of the fixtures' folder (fp_plugin_path_init copies the folder's name). */
static void fixture_path(fp_plugin_path *path)
{
    const char *dirs[] = {fixture_dir};
    fp_plugin_path_init(path, dirs, 1, NULL);
}

/* Open the input `spec` from path into *inst, its log lines to *seen, and start it. */
static void start_logged(fp_input_instance *inst, fp_plugin_path *path, const char *spec, log_seen *seen)
{
    char err[1024];
    assert_int_equal(fp_input_instance_open(inst, path, spec, 0, err, sizeof err), 0);
    fp_input_instance_set_log(inst, seen_log, seen);
    assert_int_equal(fp_input_instance_start(inst, err, sizeof err), 0);
}

static void test_log_relayed(void **state)
{
    (void)state;
    const char *dirs[] = {fixture_dir};
    fp_plugin_path path;
    fp_plugin_path_init(&path, dirs, 1, NULL);
    fp_input_instance inst;
    char err[1024];
    log_seen seen = {.owner = pthread_self()};
    /* 40 lines from the plugin's thread before any drain: 32 kept, 8 counted */
    assert_int_equal(fp_input_instance_open(&inst, &path, "fixture,log=40", 0, err, sizeof err), 0);
    assert_int_equal(fp_input_instance_drain_log(&inst), 1); /* "created", no callback: discarded */
    fp_input_instance_set_log(&inst, seen_log, &seen);
    assert_int_equal(fp_input_instance_start(&inst, err, sizeof err), 0);
    assert_int_equal(seen.n, 0); /* nothing is handed over until a drain */
    inst.input->stop(inst.input);  /* joins the plugin's logging thread */
    inst.stopped = true;
    assert_int_equal(fp_input_instance_drain_log(&inst), 33);
    assert_int_equal(seen.n, 33);
    assert_int_equal(seen.on_owner, 33); /* every line on the draining thread */
    assert_string_equal(seen.source, "fixture");
    for (int i = 0; i < 32; i++) {
        char want[32];
        snprintf(want, sizeof want, "line %d", i);
        assert_string_equal(seen.lines[i], want); /* oldest first */
    }
    assert_non_null(strstr(seen.lines[32], "8 log lines dropped"));
    assert_int_equal(seen.warnings, 33);
    assert_int_equal(fp_input_instance_drain_log(&inst), 0); /* emptied */
    fp_input_instance_close(&inst);
    assert_int_equal(seen.n, 33);

    /* create's line waits for the first drain; lines still held at close are handed then */
    seen = (log_seen){.owner = pthread_self()};
    start_logged(&inst, &path, "fixture,log=3", &seen);
    fp_input_instance_close(&inst); /* stop joins the thread; close drains */
    assert_int_equal(seen.n, 4);
    assert_string_equal(seen.lines[0], "created");
    assert_string_equal(seen.lines[3], "line 2");
    assert_int_equal(seen.on_owner, 4);
    assert_int_equal(seen.warnings, 3);
    fp_plugin_path_clear(&path);
}

/* A create that fills err to its very end, without a NUL: the host's message holds what fits
 * and no byte past the plugin's buffer (before: read on past it, garbage from the stack). */
static void test_err_filled(void **state)
{
    (void)state;
    const char *dirs[] = {fixture_dir};
    fp_plugin_path path;
    fp_plugin_path_init(&path, dirs, 1, NULL);
    fp_input_instance inst;
    char err[4096];
    assert_int_equal(fp_input_instance_open(&inst, &path, "fixture,errfill=1", 0, err, sizeof err), -22);
    const char *prefix = "input 'fixture,errfill=1': ";
    assert_int_equal(strncmp(err, prefix, strlen(prefix)), 0);
    size_t n = strlen(err) - strlen(prefix);
    assert_int_equal(strspn(err + strlen(prefix), "E"), n); /* only the plugin's bytes */
    assert_true(n > 100 && n < 1024);
    fp_plugin_path_clear(&path);
}

/* ---- a stop() that never returns is abandoned after FP_INPUT_STOP_DEADLINE_MS ---- */

static void test_stuck_stop_abandoned(void **state)
{
    (void)state;
    fp_plugin_path path;
    fixture_path(&path);
    fp_input_instance inst;
    log_seen seen = {.owner = pthread_self()};
    start_logged(&inst, &path, "fixture,stuck=1", &seen);
    struct timespec t0, t1;
    clock_gettime(CLOCK_MONOTONIC, &t0);
    fp_input_instance_close(&inst); /* before: joined the plugin's thread forever */
    clock_gettime(CLOCK_MONOTONIC, &t1);
    double ms = (double)(t1.tv_sec - t0.tv_sec) * 1e3 + (double)(t1.tv_nsec - t0.tv_nsec) / 1e6;
    assert_true(inst.abandoned);
    assert_true(ms >= FP_INPUT_STOP_DEADLINE_MS - 50 && ms < FP_INPUT_STOP_DEADLINE_MS + 2000);
    assert_true(seen.n >= 1);
    assert_string_equal(seen.source, "fixture");
    bool said = false; /* (then the events it had queued, dropped: test_abandoned_drops_counted) */
    for (int i = 0; i < seen.n && i < 40; i++) said |= strstr(seen.lines[i], "stop has not returned within 5 s") != NULL;
    assert_true(said);
    fp_input_instance_close(&inst); /* again: nothing more */
    assert_true(inst.abandoned);

    /* a stop that returns at once is waited for, not abandoned */
    seen = (log_seen){.owner = pthread_self()};
    start_logged(&inst, &path, "fixture,log=2", &seen);
    fp_input_instance_close(&inst);
    assert_false(inst.abandoned);
    assert_int_equal(seen.n, 3);
    fp_plugin_path_clear(&path);
}

/* An isolated mapping's buffers: a control set of 8 vectors and 2 channels (set_buf_init:
 * the set over b's arrays), and a frame with no hand near the face. */
typedef struct set_buf {
    float start[8][3], end[8][3];
    fp_channel ch[2];
} set_buf;

static fp_control_set set_buf_init(set_buf *b)
{
    return (fp_control_set){.size = sizeof(fp_control_set), .capacity = 8, .start = b->start, .end = b->end,
                            .channels = b->ch, .channel_capacity = 2};
}

static fp_frame_input no_hands(void)
{
    fp_frame_input in = {.size = sizeof in, .radius = 1.0};
    for (int h = 0; h < FP_HANDS; h++)
        for (int f = 0; f < FP_FINGERS; f++) in.tip_distance[h][f] = INFINITY;
    return in;
}

/* ---- an isolated mapping holds, after a fault, only a set the session would take ---- */

static void test_isolate_holds_only_good_set(void **state)
{
    (void)state;
    char file[4200], helper[4200], err[1024] = "";
    snprintf(file, sizeof file, "%s/map-crash.so", fixture_dir);
    snprintf(helper, sizeof helper, "%s/../../bin/facepuppet", fixture_dir);
    fp_host host;
    fp_host_init_for_mapping(&host, "crash");
    /* frame 1: a set over capacity (refused by the session), frame 2: a crash (SIGSEGV) */
    fp_param keys[] = {{"at", "2"}, {"overcount", "1"}};
    fp_isolate_options opt = {.helper = helper, .deadline_ms = 5000, .quiet_restarts = true};
    fp_mapping *m = NULL;
    int rc = fp_isolate_mapping_create(&opt, file, "crash", &host, keys, 2, &m, err, sizeof err);
    if (rc) fail_msg("isolated map-crash: %s", err);
    set_buf b;
    fp_control_set cs = set_buf_init(&b);
    fp_frame_input in = no_hands();
    in.frame = 0; /* no hands: an empty, inactive set (the last good one) */
    assert_int_equal(m->process(m, &in, &cs), 0);
    assert_int_equal(fp_control_check(&cs, NULL, NULL), FP_CONTROL_OK);
    in.frame = 1;
    assert_int_equal(m->process(m, &in, &cs), 0);
    assert_int_equal(fp_control_check(&cs, NULL, NULL), FP_CONTROL_OVER_CAPACITY); /* refused */
    in.frame = 2; /* the helper crashes: the held set is frame 0's, not frame 1's clamped */
    assert_int_equal(m->process(m, &in, &cs), 0);
    assert_false(cs.active); /* before: active, 8 vectors of the refused set */
    assert_int_equal(cs.count, 0);
    assert_int_equal(fp_control_check(&cs, NULL, NULL), FP_CONTROL_OK);
    m->destroy(m);
}

/* ---- an isolated mapping's fault is said even when the plugin floods its log ---- */

static void test_isolate_fault_said_through_log_flood(void **state)
{
    (void)state;
    char file[4200], helper[4200], err[1024] = "";
    snprintf(file, sizeof file, "%s/map-crash.so", fixture_dir);
    snprintf(helper, sizeof helper, "%s/../../bin/facepuppet", fixture_dir);
    log_seen seen = {.owner = pthread_self()};
    fp_log_relay relay;
    assert_int_equal(fp_log_relay_init(&relay), 0);
    fp_mapping_host mh;
    fp_mapping_host_init(&mh, "crash", seen_log, &seen);
    mh.relay = &relay;
    /* 100 lines logged in each process (from process, against the rule), then a crash on
     * frame 1 after its lines */
    fp_param keys[] = {{"at", "1"}, {"logs", "100"}};
    fp_isolate_options opt = {.helper = helper, .deadline_ms = 5000, .quiet_restarts = true};
    fp_mapping *m = NULL;
    int rc = fp_isolate_mapping_create(&opt, file, "crash", &mh.host, keys, 2, &m, err, sizeof err);
    if (rc) fail_msg("isolated map-crash: %s", err);
    set_buf b;
    fp_control_set cs = set_buf_init(&b);
    fp_frame_input in = no_hands();
    int said = 0, dropped = 0;
    for (uint64_t f = 0; f < 2; f++) {
        in.frame = f;
        assert_int_equal(m->process(m, &in, &cs), 0);
        seen.n = 0;
        fp_mapping_host_drain_log(&mh); /* once a frame, as the session does */
        for (int i = 0; i < seen.n && i < 40; i++) {
            said += strstr(seen.lines[i], "died of SIGSEGV during process (frame 1)") != NULL;
            dropped += strstr(seen.lines[i], "76 log lines of the plugin dropped") != NULL;
        }
    }
    /* before: the plugin's 100 lines filled the host's 32-line ring and the fault's line,
     * said after them, was the one dropped ("69 log lines dropped" and no word of the crash) */
    assert_int_equal(said, 1);
    assert_int_equal(dropped, 2); /* 100 - 24 kept, each frame */
    m->destroy(m);
    fp_log_relay_destroy(&relay);
}

/* ---- an abandoned input's thread that wakes after its instance was freed ---- */

static void test_abandoned_push_after_free(void **state)
{
    (void)state;
    fp_plugin_path path;
    fixture_path(&path);
    fp_input_instance *inst = malloc(sizeof *inst);
    assert_non_null(inst);
    log_seen seen = {.owner = pthread_self()};
    /* stuck=2: a thread stop never ends, which pushes and logs every 50 ms */
    start_logged(inst, &path, "fixture,stuck=2", &seen);
    fp_input_instance_close(inst);
    assert_true(inst->abandoned);
    assert_null(inst->link); /* handed to the plugin's threads, no longer the instance's */
    /* the owner frees what it owns (a session freed with its inputs); the thread goes on
     * pushing and logging through the fp_host it was given (before: &inst->host, inside the
     * freed instance: a call through garbage, SIGSEGV) */
    void *(*volatile wipe)(void *, int, size_t) = memset; /* (not elided before free) */
    wipe(inst, 0xA5, sizeof *inst); /* as the memory would be when used again */
    free(inst);
    struct timespec ts = {0, 300000000L}; /* six pushes and logs */
    nanosleep(&ts, NULL);
    fp_plugin_path_clear(&path);
}

/* ---- what an abandoned input pushed is counted and said ---- */

static void test_abandoned_drops_counted(void **state)
{
    (void)state;
    fp_plugin_path path;
    fixture_path(&path);
    fp_input_instance inst;
    log_seen seen = {.owner = pthread_self()};
    /* stuck=2: a thread stop never ends, which pushes a status and logs every 50 ms */
    start_logged(&inst, &path, "fixture,stuck=2", &seen);
    struct timespec ts = {0, 200000000L};
    nanosleep(&ts, NULL);
    fp_event ev;
    while (fp_input_instance_poll(&inst, &ev)) {
    }
    fp_input_instance_drain_log(&inst);
    seen = (log_seen){.owner = pthread_self()};
    fp_input_instance_close(&inst); /* 5 s of pushes into its queue, then abandoned */
    assert_true(inst.abandoned);
    /* its closing line: what it queued while stop was waited for, what it pushed after
     * (before: no line, the events lost uncounted) */
    const char *line = NULL;
    for (int i = 0; i < seen.n && i < 40; i++)
        if (strstr(seen.lines[i], "abandoned: dropped")) line = seen.lines[i];
    if (!line) fail_msg("no line counts the abandoned input's events (%d lines, last: %s)", seen.n,
                        seen.n ? seen.lines[seen.n - 1] : "");
    /* ... nor the abandonment's own line lost behind the 32 lines the plugin logged meanwhile
     * (before: "69 log lines dropped" and no "stop has not returned") */
    bool said = false;
    for (int i = 0; i < seen.n && i < 40; i++) said |= strstr(seen.lines[i], "stop has not returned within 5 s") != NULL;
    assert_true(said);
    unsigned long long total, queued, after;
    assert_int_equal(sscanf(line, "abandoned: dropped %llu events it pushed while its stop() did not return "
                            "(%llu queued and never read, %llu pushed after", &total, &queued, &after), 3);
    assert_int_equal(total, queued + after);
    assert_int_equal(queued, inst.unread);
    assert_true(queued >= 20); /* one every 50 ms for the 5 s waited */
    /* it goes on pushing: counted, for the figure a summary reads (fp_session_dropped) */
    uint64_t then = fp_input_instance_dropped(&inst);
    assert_true(then >= total);
    ts.tv_nsec = 300000000L;
    nanosleep(&ts, NULL);
    assert_true(fp_input_instance_dropped(&inst) >= then + 2);
    fp_plugin_path_clear(&path);
}

/* ---- malformed events are refused at push_event, said once per kind and counted ---- */

static void test_malformed_events_refused(void **state)
{
    (void)state;
    fp_plugin_path path;
    fixture_path(&path);
    fp_input_instance inst;
    log_seen seen = {.owner = pthread_self()};
    /* 600 pushes of a still hand, every 100 six of them malformed (fixture_plugin.c
     * FIXTURE_BAD_EVENTS), then 3 buttons and the end of the stream */
    start_logged(&inst, &path, "fixture-badevents", &seen);
    fp_event ev;
    int joints = 0, other = 0;
    while (fp_input_instance_poll(&inst, &ev)) {
        const char *why = NULL;
        assert_int_equal(fp_event_check(&ev, &why), FP_EVENT_OK); /* none reaches the queue */
        if (ev.header.type == FP_EVENT_JOINT_POSITIONS) {
            joints++;
            for (int j = 0; j < FP_HAND_JOINTS; j++)
                for (int k = 0; k < 3; k++) assert_true(fabsf(ev.positions.mm[j][k]) <= 200);
        } else {
            other++;
        }
    }
    assert_int_equal(joints, 600 - 36); /* 6 wrist poses pushed in 6 joints' place, 30 bad joints */
    assert_int_equal(other, 4);         /* 3 buttons and the status */
    assert_int_equal((int)atomic_load(&inst.refused), 36);
    assert_int_equal(seen.n, 0); /* said on the owner's thread, at its drain */
    assert_int_equal(fp_input_instance_drain_log(&inst), 6); /* one warning per kind */
    const char *kinds[] = {"unknown type", "size is not that of its type", "a pose event without a hand",
                           "a joint position is not finite", "a joint position is beyond 10 m",
                           "the wrist rotation is not a unit quaternion"}; /* (fp_event_fault order) */
    for (int i = 0; i < 6; i++) {
        assert_non_null(strstr(seen.lines[i], "refused a malformed event"));
        assert_non_null(strstr(seen.lines[i], kinds[i]));
    }
    fp_input_instance_close(&inst);
    assert_int_equal(seen.n, 7);
    assert_non_null(strstr(seen.lines[6], "refused 36 malformed events in all"));
    assert_int_equal(seen.warnings, 7);

    /* the good fixture: nothing refused, nothing said */
    seen = (log_seen){.owner = pthread_self()};
    start_logged(&inst, &path, "fixture", &seen);
    while (fp_input_instance_poll(&inst, &ev)) {
    }
    fp_input_instance_close(&inst);
    assert_int_equal(seen.n, 0);
    fp_plugin_path_clear(&path);
}

/* ---- an event larger than the host takes: refused, said once with its size, counted ---- */

static void test_oversize_events_refused(void **state)
{
    (void)state;
    fp_plugin_path path;
    fixture_path(&path);
    fp_input_instance inst;
    log_seen seen = {.owner = pthread_self()};
    /* 3 joint angles events of sizeof(fp_event) + 64 bytes, then 3 buttons and the end */
    start_logged(&inst, &path, "fixture,oversize=3", &seen);
    fp_event ev;
    int taken = 0;
    while (fp_input_instance_poll(&inst, &ev)) {
        assert_int_equal(fp_event_check(&ev, NULL), FP_EVENT_OK);
        assert_int_not_equal(ev.header.type, FP_EVENT_JOINT_ANGLES);
        taken++;
    }
    assert_int_equal(taken, 4);
    assert_int_equal((int)atomic_load(&inst.refused), 3); /* before: 0, nothing counted */
    /* one warning for the three, naming the kind, the size and the limit (before: none, and
     * push_event answered false, a full queue, which a plugin sends again) */
    assert_int_equal(fp_input_instance_drain_log(&inst), 1);
    char want[160];
    snprintf(want, sizeof want, "refused an oversize event: joint angles (header.type 1) of %zu bytes, "
             "over the host's limit of %zu bytes", sizeof(fp_event) + 64, sizeof(fp_event));
    if (!strstr(seen.lines[0], want)) fail_msg("said: %s\nwanted: %s", seen.lines[0], want);
    assert_string_equal(seen.source, "fixture");
    fp_input_instance_close(&inst);
    assert_int_equal(seen.n, 2); /* not said again; the closing count */
    assert_non_null(strstr(seen.lines[1], "refused 3 malformed events in all"));
    fp_plugin_path_clear(&path);
}

/* Events whose header is all zeros (a plugin that memsets an event and never sets its header):
 * refused and counted, and said (before: counted, never said, as the first one's record, 0,
 * read as "none yet") */
static void test_zeroed_events_said(void **state)
{
    (void)state;
    fp_plugin_path path;
    fixture_path(&path);
    fp_input_instance inst;
    log_seen seen = {.owner = pthread_self()};
    start_logged(&inst, &path, "fixture,zeroed=2", &seen);
    fp_event ev;
    while (fp_input_instance_poll(&inst, &ev)) {
    }
    assert_int_equal((int)atomic_load(&inst.refused), 2);
    assert_int_equal(fp_input_instance_drain_log(&inst), 1);
    if (!strstr(seen.lines[0], "refused an undersize event:") || !strstr(seen.lines[0], "of 0 bytes"))
        fail_msg("said: %s", seen.lines[0]);
    fp_input_instance_close(&inst);
    fp_plugin_path_clear(&path);
}

/* ---- an event's time: the host refuses what `plugins check` fails (fp_event_check_time) ---- */

static void test_event_times_refused(void **state)
{
    (void)state;
    fp_plugin_path path;
    fixture_path(&path);
    fp_input_instance inst;
    log_seen seen = {.owner = pthread_self()};
    start_logged(&inst, &path, "fixture", &seen);
    assert_false(inst.own_clock); /* a device's input: its times are the host's */
    fp_event ev;
    while (fp_input_instance_poll(&inst, &ev)) {
    }
    uint64_t before = atomic_load(&inst.refused);
    fp_event_status st = {{sizeof st, FP_EVENT_STATUS, 0, 0, 0, -1}, FP_STATUS_CONNECTED, "t"};
    int64_t ahead[] = {-1, fp_now_ns() + 10 * FP_EVENT_MAX_AHEAD_NS, INT64_MAX, fp_now_ns()};
    for (int i = 0; i < 4; i++) {
        st.header.time_ns = ahead[i];
        assert_true(inst.link->host.push_event(&inst.link->host, &st.header));
    }
    /* the negative and the future ones refused (before: taken), the one of now kept */
    assert_int_equal((int)(atomic_load(&inst.refused) - before), 3);
    bool now_kept = false;
    while (fp_input_instance_poll(&inst, &ev))
        if (ev.header.type == FP_EVENT_STATUS && ev.header.time_ns == ahead[3]) now_kept = true;
    assert_true(now_kept);
    fp_input_instance_drain_log(&inst);
    bool said = false;
    for (int i = 0; i < seen.n; i++) said = said || strstr(seen.lines[i], "time_ns");
    assert_true(said);
    fp_input_instance_close(&inst);
    fp_plugin_path_clear(&path);

    /* the rule itself: an input with its own clock may run ahead, never below 0 */
    const char *why = NULL;
    fp_event e;
    memset(&e, 0, sizeof e);
    e.status = st;
    e.header.time_ns = fp_now_ns() + 10 * FP_EVENT_MAX_AHEAD_NS;
    assert_int_equal(fp_event_check_time(&e, fp_now_ns(), true, &why), FP_EVENT_OK);
    assert_int_equal(fp_event_check_time(&e, fp_now_ns(), false, &why), FP_EVENT_BAD_TIME);
    assert_non_null(strstr(why, "ahead"));
    e.header.time_ns = -5;
    assert_int_equal(fp_event_check_time(&e, fp_now_ns(), true, &why), FP_EVENT_BAD_TIME);
}

/* ---- plugin folders that could be hijacked are skipped, with the reason ---- */

/* A fresh folder holding a copy of the good fixture plugin as input-NAME.so. */
static void make_plugin_dir(char *dir, size_t len, const char *name, mode_t mode)
{
    snprintf(dir, len, "/tmp/fp-plugdir-XXXXXX");
    assert_non_null(mkdtemp(dir));
    char src[4200], dst[4200], cmd[9000];
    snprintf(src, sizeof src, "%s/input-fixture.so", fixture_dir);
    snprintf(dst, sizeof dst, "%s/input-%s.so", dir, name);
    snprintf(cmd, sizeof cmd, "cp '%s' '%s'", src, dst);
    assert_int_equal(system(cmd), 0);
    assert_int_equal(chmod(dst, 0755), 0);
    assert_int_equal(chmod(dir, mode), 0);
}

static void remove_dir(const char *dir)
{
    char cmd[4200];
    snprintf(cmd, sizeof cmd, "rm -rf '%s'", dir);
    assert_int_equal(system(cmd), 0);
}

static void test_unsafe_folders_skipped(void **state)
{
    (void)state;
    char dir[64], err[2048];
    fp_plugin p;
    fp_plugin_path path;

    /* World-writable folder: skipped, its plugin never loads. */
    make_plugin_dir(dir, sizeof dir, "hijack", 0777);
    setenv("FACEPUPPET_PLUGIN_PATH", dir, 1);
    fp_plugin_path_init(&path, NULL, 0, builtin_dir);
    assert_non_null(strstr(path.warnings, dir));
    assert_non_null(strstr(path.warnings, "skipped: writable by others"));
    assert_int_equal(fp_plugin_load(&path, FP_PLUGIN_INPUT, "hijack", &p, err, sizeof err),
                     FP_EPLUGIN_NOT_FOUND);
    fp_plugin_path_clear(&path);

    /* The same folder made safe: the plugin loads (the rule, not the name, decided). */
    assert_int_equal(chmod(dir, 0755), 0);
    fp_plugin_path_init(&path, NULL, 0, builtin_dir);
    assert_string_equal(path.warnings, "");
    assert_int_equal(fp_plugin_load(&path, FP_PLUGIN_INPUT, "hijack", &p, err, sizeof err), 0);
    fp_plugin_unload(&p);
    fp_plugin_path_clear(&path);

    /* A group-writable plugin file inside a safe folder: skipped, and the error says why. */
    char file[128];
    snprintf(file, sizeof file, "%s/input-hijack.so", dir);
    assert_int_equal(chmod(file, 0775), 0);
    fp_plugin_path_init(&path, NULL, 0, builtin_dir);
    assert_int_equal(fp_plugin_load(&path, FP_PLUGIN_INPUT, "hijack", &p, err, sizeof err),
                     FP_EPLUGIN_NOT_FOUND);
    assert_non_null(strstr(err, "skipped: writable by its group"));
    fp_plugin_path_clear(&path);
    assert_int_equal(chmod(file, 0755), 0);

    /* Owned by another user (only root can arrange it): skipped. */
    if (getuid() == 0) {
        assert_int_equal(chown(dir, 65534, 65534), 0);
        fp_plugin_path_init(&path, NULL, 0, builtin_dir);
        assert_non_null(strstr(path.warnings, "owned by uid 65534"));
        assert_int_equal(path.count, 1); /* the built-in folder alone */
        fp_plugin_path_clear(&path);
        assert_int_equal(chown(dir, 0, 0), 0);
    }

    /* A relative entry is ignored; an empty one too. */
    setenv("FACEPUPPET_PLUGIN_PATH", "build/tests/plugins::", 1);
    fp_plugin_path_init(&path, NULL, 0, builtin_dir);
    assert_non_null(strstr(path.warnings, "'build/tests/plugins' ignored: a relative path"));
    assert_int_equal(path.count, 1);
    fp_plugin_path_clear(&path);
    unsetenv("FACEPUPPET_PLUGIN_PATH");
    remove_dir(dir);
}

/* A built-in plugin's name resolves to the built-in folder even when an extra folder that
 * comes first on the command line holds a file of the same name. */
static void test_builtin_first(void **state)
{
    (void)state;
    char dir[64], err[2048];
    make_plugin_dir(dir, sizeof dir, "replay", 0755);
    const char *dirs[] = {dir};
    fp_plugin_path path;
    fp_plugin_path_init(&path, dirs, 1, builtin_dir);
    assert_int_equal(path.builtin, 0);
    fp_plugin p;
    assert_int_equal(fp_plugin_load(&path, FP_PLUGIN_INPUT, "replay", &p, err, sizeof err), 0);
    assert_non_null(strstr(p.path, builtin_dir));
    assert_string_equal(p.entry->id, "org.facepuppet.input-replay");
    fp_plugin_unload(&p);
    fp_plugin_path_clear(&path);
    remove_dir(dir);
}

/* Which plugins are facepuppet's own (fp_plugin_shipped), and so run in process by default:
 * the list holds every plugin in the built-in folder, and a third party's plugin copied into
 * that folder (as the SDK's install step does) is not one of them (before: any file there was
 * "built-in", so a user's crashing mapping installed there ended the run). */
static void test_shipped_only_builtin(void **state)
{
    (void)state;
    DIR *d = opendir(builtin_dir);
    assert_non_null(d);
    int seen = 0;
    for (struct dirent *e; (e = readdir(d));) {
        size_t l = strlen(e->d_name);
        if (l < 4 || strcmp(e->d_name + l - 3, ".so")) continue;
        char name[256];
        snprintf(name, sizeof name, "%.*s", (int)(l - 3), e->d_name);
        bool input = !strncmp(name, "input-", 6), map = !strncmp(name, "map-", 4);
        assert_true(input || map);
        if (!fp_plugin_shipped(input ? FP_PLUGIN_INPUT : FP_PLUGIN_MAPPING, name + (input ? 6 : 4)))
            fail_msg("%s/%s is built but not in fp_plugin_shipped's list", builtin_dir, e->d_name);
        seen++;
    }
    closedir(d);
    assert_true(seen >= 9);
    /* a third party's mapping in the built-in folder: found there, not built-in */
    char dir[64] = "/tmp/fp-builtin-XXXXXX", src[4200], dst[4200], cmd[16384], file[4200];
    assert_non_null(mkdtemp(dir));
    snprintf(src, sizeof src, "%s/map-anchored.so", builtin_dir);
    snprintf(dst, sizeof dst, "%s/map-mine.so", dir);
    snprintf(cmd, sizeof cmd, "cp '%s' '%s' && cp '%s' '%s/map-anchored.so'", src, dst, src, dir);
    assert_int_equal(system(cmd), 0);
    fp_plugin_path path;
    fp_plugin_path_init(&path, NULL, 0, dir);
    bool builtin = true;
    assert_true(fp_plugin_find(&path, FP_PLUGIN_MAPPING, "mine", file, sizeof file, &builtin, NULL, 0));
    assert_false(builtin);
    assert_true(fp_isolate_wanted(FP_ISOLATE_THIRD_PARTY, builtin));
    assert_true(fp_plugin_find(&path, FP_PLUGIN_MAPPING, "anchored", file, sizeof file, &builtin, NULL, 0));
    assert_true(builtin);
    fp_plugin_path_clear(&path);
    remove_dir(dir);
}

/* ---- a fatal signal inside a plugin names the plugin, then ends the process ---- */

/* Runs fn in a child with the crash handler installed; returns what the child wrote to
 * stderr and its terminating signal (0 if it exited). */
static int crash_child(void (*fn)(void), char *out, size_t len)
{
    int pipefd[2];
    assert_int_equal(pipe(pipefd), 0);
    pid_t pid = fork();
    assert_true(pid >= 0);
    if (pid == 0) {
        dup2(pipefd[1], STDERR_FILENO);
        close(pipefd[0]);
        if (fp_plugin_crash_install()) _exit(90);
        fn();
        _exit(0);
    }
    close(pipefd[1]);
    size_t n = 0;
    ssize_t r;
    while (n + 1 < len && (r = read(pipefd[0], out + n, len - 1 - n)) > 0) n += (size_t)r;
    out[n] = '\0';
    close(pipefd[0]);
    int status = 0;
    assert_int_equal(waitpid(pid, &status, 0), pid);
    return WIFSIGNALED(status) ? WTERMSIG(status) : 0;
}

static void load_crashinit(void)
{
    fp_plugin p;
    char err[1024];
    load("fixture-crashinit", &p, err, sizeof err);
}

static void start_crashthread(void)
{
    const char *dirs[] = {fixture_dir};
    fp_plugin_path path;
    fp_plugin_path_init(&path, dirs, 1, NULL);
    fp_input_instance inst;
    char err[1024];
    if (fp_input_instance_open(&inst, &path, "fixture-crashthread", 0, err, sizeof err)) _exit(91);
    fp_input_instance_start(&inst, err, sizeof err);
}

static void test_crash_names_plugin(void **state)
{
    (void)state;
    char out[2048];
    assert_int_equal(crash_child(load_crashinit, out, sizeof out), SIGSEGV);
    assert_non_null(strstr(out, "facepuppet: fatal signal SIGSEGV in plugin '"));
    assert_non_null(strstr(out, "input-fixture-crashinit.so' during init (frame 0)"));

    assert_int_equal(crash_child(start_crashthread, out, sizeof out), SIGSEGV);
    assert_non_null(strstr(out, "facepuppet: fatal signal SIGSEGV in plugin "));
    assert_non_null(strstr(out, "input-fixture-crashthread.so (its own thread)"));
}

/* ---- queue: several producers, one consumer; nothing lost or duplicated ---- */
#define PRODUCERS 4
#define PER_PRODUCER 20000
static fp_event_queue q;

static void *producer(void *arg)
{
    int id = (int)(intptr_t)arg;
    for (int i = 0; i < PER_PRODUCER; i++) {
        fp_event_button b = {{sizeof b, FP_EVENT_BUTTON, 0, i, (uint32_t)id, -1}, 1, 1, (uint32_t)i};
        while (!fp_event_queue_push(&q, &b.header)) sched_yield();
    }
    return NULL;
}

/* A thread inside a plugin call, until released: what fp_plugin_call_oldest shows of it. */
typedef struct stuck_call {
    pthread_mutex_t mu;
    pthread_cond_t cv;
    int phase;   /* 1 entered, 2 released */
} stuck_call;

static void *call_and_wait(void *u)
{
    stuck_call *c = u;
    fp_plugin_call_enter("spinner", "process", 29);
    fp_plugin_call_enter("spinner", "reset", 29); /* nested: the innermost is named */
    pthread_mutex_lock(&c->mu);
    c->phase = 1;
    pthread_cond_broadcast(&c->cv);
    while (c->phase != 2) pthread_cond_wait(&c->cv, &c->mu);
    pthread_mutex_unlock(&c->mu);
    fp_plugin_call_leave();
    fp_plugin_call_leave();
    return NULL;
}

/* Another thread sees a call in progress (the watchdog of `run`: app_stop.h): its plugin,
 * call, frame and start; none once it left; a call on this thread is seen too. */
static void test_call_oldest(void **state)
{
    (void)state;
    fp_plugin_call_info info;
    assert_false(fp_plugin_call_oldest(&info));
    stuck_call c = {PTHREAD_MUTEX_INITIALIZER, PTHREAD_COND_INITIALIZER, 0};
    pthread_t th;
    assert_int_equal(pthread_create(&th, NULL, call_and_wait, &c), 0);
    pthread_mutex_lock(&c.mu);
    while (c.phase != 1) pthread_cond_wait(&c.cv, &c.mu);
    pthread_mutex_unlock(&c.mu);
    assert_true(fp_plugin_call_oldest(&info));
    assert_string_equal(info.who, "spinner");
    assert_string_equal(info.call, "reset");
    assert_int_equal(info.frame, 29);
    assert_true(info.since_ns > 0);
    int64_t first = info.since_ns;
    fp_plugin_call_enter("later", "create", 0); /* this thread's, begun after: not the oldest */
    assert_true(fp_plugin_call_oldest(&info));
    assert_string_equal(info.who, "spinner");
    assert_int_equal(info.since_ns, first);
    pthread_mutex_lock(&c.mu);
    c.phase = 2;
    pthread_cond_broadcast(&c.cv);
    pthread_mutex_unlock(&c.mu);
    pthread_join(th, NULL);
    assert_true(fp_plugin_call_oldest(&info));
    assert_string_equal(info.who, "later");
    fp_plugin_call_leave();
    assert_false(fp_plugin_call_oldest(&info));
    for (int i = 0; i < 200; i++) { /* slots are given back: more calls than slots */
        fp_plugin_call_enter("again", "process", (uint64_t)i);
        fp_plugin_call_leave();
    }
    fp_plugin_call_enter("again", "process", 7);
    assert_true(fp_plugin_call_oldest(&info));
    assert_int_equal(info.frame, 7);
    fp_plugin_call_leave();
}

static void test_queue_mpsc(void **state)
{
    (void)state;
    assert_int_equal(fp_event_queue_init(&q, 100), 0);
    assert_int_equal(q.mask + 1, 128);
    pthread_t t[PRODUCERS];
    for (int i = 0; i < PRODUCERS; i++) pthread_create(&t[i], NULL, producer, (void *)(intptr_t)i);
    int next[PRODUCERS] = {0};
    long got = 0;
    while (got < PRODUCERS * PER_PRODUCER) {
        fp_event ev;
        if (!fp_event_queue_pop(&q, &ev)) { sched_yield(); continue; }
        int id = (int)ev.header.source;
        assert_true(id >= 0 && id < PRODUCERS);
        assert_int_equal(ev.button.mask, (uint32_t)next[id]); /* per-producer order kept */
        next[id]++;
        got++;
    }
    for (int i = 0; i < PRODUCERS; i++) pthread_join(t[i], NULL);
    fp_event ev;
    assert_false(fp_event_queue_pop(&q, &ev));
    fp_event_queue_destroy(&q);
}

static void test_queue_full(void **state)
{
    (void)state;
    assert_int_equal(fp_event_queue_init(&q, 4), 0);
    fp_event_button b = {{sizeof b, FP_EVENT_BUTTON, 0, 0, 0, -1}, 1, 1, 0};
    for (int i = 0; i < 4; i++) assert_true(fp_event_queue_push(&q, &b.header));
    assert_false(fp_event_queue_push(&q, &b.header));
    assert_int_equal(atomic_load(&q.dropped), 1);
    fp_event_header bad = {sizeof(fp_event) + 1, FP_EVENT_BUTTON, 0, 0, 0, -1};
    fp_event ev;
    assert_true(fp_event_queue_pop(&q, &ev));
    assert_false(fp_event_queue_push(&q, &bad)); /* oversize refused */
    fp_event_queue_destroy(&q);
}

/* An input that floods poses cannot push out its end of stream or a button: poses find the
 * queue full with 1/8 of it free, which the other events take (before: the status was
 * dropped like any event, and `run` waited for that end of stream forever). */
static void test_queue_reserve(void **state)
{
    (void)state;
    assert_int_equal(fp_event_queue_init(&q, 64), 0);
    fp_event_joint_positions jp = {{sizeof jp, FP_EVENT_JOINT_POSITIONS, 0, 0, 0, 1}, {{0}}};
    int poses = 0;
    while (poses < 100 && fp_event_queue_push(&q, &jp.header)) jp.header.time_ns = ++poses;
    assert_int_equal(poses, 64 - 64 / FP_EVENT_QUEUE_RESERVE);
    fp_event_status st = {{sizeof st, FP_EVENT_STATUS, 0, 0, 0, -1}, FP_STATUS_END_OF_STREAM, "done"};
    fp_event_button b = {{sizeof b, FP_EVENT_BUTTON, 0, 0, 0, -1}, 1, 1, 1};
    assert_true(fp_event_queue_push(&q, &b.header));
    assert_true(fp_event_queue_push(&q, &st.header));
    int others = 2;
    while (fp_event_queue_push(&q, &b.header)) others++; /* the rest of the capacity */
    assert_int_equal(poses + others, 64);
    fp_event ev;
    int n = 0, last_type = 0;
    while (fp_event_queue_pop(&q, &ev)) n++, last_type = ev.header.type;
    assert_int_equal(n, 64);
    assert_int_equal(last_type, FP_EVENT_BUTTON);
    fp_event_queue_destroy(&q);
}

/* A producer that waits for room (the replay's fast=1, fp_pacer_push) pushes the refused event
 * again: once it is taken, its refusals are not drops; an event refused and never pushed
 * again (another came instead) stays one */
static void test_queue_retry(void **state)
{
    (void)state;
    assert_int_equal(fp_event_queue_init(&q, 4), 0);
    fp_event ev;
    for (uint32_t i = 0; i < 4; i++) {
        fp_event_button b = {{sizeof b, FP_EVENT_BUTTON, 0, (int64_t)i, 0, -1}, 1, 1, i};
        assert_true(fp_event_queue_push(&q, &b.header));
    }
    fp_event_button e5 = {{sizeof e5, FP_EVENT_BUTTON, 0, 5, 0, -1}, 1, 1, 5};
    for (int i = 0; i < 3; i++) assert_false(fp_event_queue_push(&q, &e5.header));
    assert_int_equal(atomic_load(&q.dropped), 1); /* one event, refused three times */
    assert_true(fp_event_queue_pop(&q, &ev));
    assert_true(fp_event_queue_push(&q, &e5.header)); /* the same event, taken */
    assert_int_equal(atomic_load(&q.dropped), 0);
    fp_event_button e6 = {{sizeof e6, FP_EVENT_BUTTON, 0, 6, 0, -1}, 1, 1, 6};
    fp_event_button e7 = e6;
    e7.header.time_ns = 7; /* the same but for its time: another event */
    assert_false(fp_event_queue_push(&q, &e6.header));
    assert_false(fp_event_queue_push(&q, &e6.header));
    assert_false(fp_event_queue_push(&q, &e7.header));
    assert_false(fp_event_queue_push(&q, &e7.header));
    assert_int_equal(atomic_load(&q.dropped), 2);
    assert_int_equal(fp_event_queue_dropped(&q), 1); /* e6; e7 may yet be pushed again */
    assert_true(fp_event_queue_pop(&q, &ev));
    assert_true(fp_event_queue_push(&q, &e7.header));
    assert_int_equal(atomic_load(&q.dropped), 1); /* e6, never pushed again */
    assert_int_equal(fp_event_queue_dropped(&q), 1);
    assert_true(fp_event_queue_pop(&q, &ev));
    assert_true(fp_event_queue_push(&q, &e6.header)); /* too late: counted */
    assert_int_equal(fp_event_queue_dropped(&q), 1);
    /* refused and not pushed again yet (a replay stopped while it waited for room): not
     * counted until another event is refused, then once */
    fp_event_button e8 = e6, e9 = e6;
    e8.header.time_ns = 8;
    e9.header.time_ns = 9;
    for (int i = 0; i < 5; i++) assert_false(fp_event_queue_push(&q, &e8.header));
    assert_int_equal(fp_event_queue_dropped(&q), 1);
    assert_false(fp_event_queue_push(&q, &e9.header));
    assert_int_equal(fp_event_queue_dropped(&q), 2);
    /* another event taken after a refusal: the refused one was given up, counted at once */
    fp_event_button e10 = e6;
    e10.header.time_ns = 10;
    assert_true(fp_event_queue_pop(&q, &ev));
    assert_true(fp_event_queue_push(&q, &e10.header));
    assert_int_equal(fp_event_queue_dropped(&q), 3);
    assert_int_equal(atomic_load(&q.refused), 0);
    fp_event_queue_destroy(&q);
}


/* The next event of an isolated input, waited for up to 10 s (its helper's events come
 * through the host's reader thread). */
static bool poll_wait(fp_input_instance *inst, fp_event *ev)
{
    for (int i = 0; i < 10000; i++) {
        if (fp_input_instance_poll(inst, ev)) return true;
        struct timespec ts = {0, 1000000};
        nanosleep(&ts, NULL);
    }
    return false;
}

/* An isolated input (fp_isolate.h): the bad-events fixture in a helper gives the queue the same
 * events, the malformed refused alike and said alike, as in process (test_malformed_events_refused);
 * input-crashy's SIGSEGV on its own thread comes after its 20 samples, in their order, as one
 * status of the input naming the signal, then each hand released; the helper is restarted. */
static void test_isolated_input(void **state)
{
    (void)state;
    fp_plugin_path path;
    fixture_path(&path);
    char helper[4200], err[1024] = "";
    snprintf(helper, sizeof helper, "%s/../../bin/facepuppet", fixture_dir);
    fp_isolate_options opt = {.helper = helper};
    fp_input_instance inst;
    log_seen seen = {.owner = pthread_self()};
    assert_int_equal(fp_input_instance_open_isolated(&inst, &path, "fixture-badevents", 0, FP_ISOLATE_THIRD_PARTY,
                                                     &opt, err, sizeof err), 0);
    assert_true(inst.isolated);
    fp_input_instance_set_log(&inst, seen_log, &seen);
    assert_int_equal(fp_input_instance_start(&inst, err, sizeof err), 0);
    fp_event ev;
    int joints = 0, other = 0;
    for (bool ended = false; !ended && poll_wait(&inst, &ev);) {
        const char *why = NULL;
        assert_int_equal(fp_event_check(&ev, &why), FP_EVENT_OK);
        joints += ev.header.type == FP_EVENT_JOINT_POSITIONS;
        other += ev.header.type != FP_EVENT_JOINT_POSITIONS;
        ended = ev.header.type == FP_EVENT_STATUS && ev.status.code == FP_STATUS_END_OF_STREAM;
    }
    assert_int_equal(joints, 600 - 36);
    assert_int_equal(other, 4);
    assert_int_equal((int)atomic_load(&inst.refused), 36);
    assert_int_equal(fp_input_instance_drain_log(&inst), 6); /* one warning per kind */
    fp_input_instance_close(&inst);
    assert_non_null(strstr(seen.lines[6], "refused 36 malformed events in all"));

    seen = (log_seen){.owner = pthread_self()};
    assert_int_equal(fp_input_instance_open_isolated(&inst, &path, "crashy", 0, FP_ISOLATE_THIRD_PARTY, &opt, err,
                                                     sizeof err), 0);
    fp_input_instance_set_log(&inst, seen_log, &seen);
    assert_int_equal(fp_input_instance_start(&inst, err, sizeof err), 0);
    int64_t last = 0;
    for (joints = 0; poll_wait(&inst, &ev) && ev.header.type == FP_EVENT_JOINT_POSITIONS; joints++) {
        assert_true(ev.header.time_ns >= last); /* as pushed, in order */
        assert_true(ev.positions.mm[0][0] == 0.5f * (float)joints);
        last = ev.header.time_ns;
    }
    assert_int_equal(joints, 20);
    assert_int_equal(ev.header.type, FP_EVENT_STATUS);
    assert_int_equal(ev.status.code, FP_STATUS_WARNING);
    assert_true(strstr(ev.status.text, "isolated: the helper process died of SIGSEGV; hands released, restarts in "
                                       "0.1 s (fault 1 in a row)") ||
                strstr(ev.status.text, "exited with status 1")); /* (ASan's report of the SEGV) */
    for (int h = FP_HAND_LEFT; h <= FP_HAND_RIGHT; h++) {
        assert_true(poll_wait(&inst, &ev));
        assert_int_equal(ev.status.code, FP_STATUS_DISCONNECTED);
        assert_int_equal(ev.header.hand, h);
    }
    assert_true(poll_wait(&inst, &ev)); /* the new helper's first sample */
    assert_int_equal(ev.header.type, FP_EVENT_JOINT_POSITIONS);
    fp_isolate_stats st;
    assert_true(fp_isolate_input_stats(inst.input, &st));
    assert_true(st.faults >= 1 && st.restarts >= 1);
    fp_input_instance_close(&inst);
    fp_plugin_path_clear(&path);
}

int main(void)
{
    const char *build = getenv("FP_BUILD_DIR");
    snprintf(fixture_dir, sizeof fixture_dir, "%s/tests/plugins", build ? build : "build");
    snprintf(builtin_dir, sizeof builtin_dir, "%s/lib/facepuppet", build ? build : "build");
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_spec_parse),        cmocka_unit_test(test_loader_errors),
        cmocka_unit_test(test_env_path_and_instance),
        cmocka_unit_test(test_log_relayed), cmocka_unit_test(test_malformed_events_refused),
        cmocka_unit_test(test_event_times_refused), cmocka_unit_test(test_oversize_events_refused),
        cmocka_unit_test(test_zeroed_events_said),
        cmocka_unit_test(test_isolate_holds_only_good_set),
        cmocka_unit_test(test_isolate_fault_said_through_log_flood),
        cmocka_unit_test(test_isolated_input),
        cmocka_unit_test(test_err_filled),
        cmocka_unit_test(test_queue_mpsc),
        cmocka_unit_test(test_queue_full),        cmocka_unit_test(test_queue_retry),
        cmocka_unit_test(test_queue_reserve),
        cmocka_unit_test(test_unsafe_folders_skipped),
        cmocka_unit_test(test_builtin_first),
        cmocka_unit_test(test_shipped_only_builtin),     cmocka_unit_test(test_crash_names_plugin),
        cmocka_unit_test(test_call_oldest),
        /* last: its abandoned stop() stays a call in progress (test_call_oldest wants none) */
        cmocka_unit_test(test_stuck_stop_abandoned),
        cmocka_unit_test(test_abandoned_push_after_free), /* (the same) */
        cmocka_unit_test(test_abandoned_drops_counted),   /* (the same) */
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
