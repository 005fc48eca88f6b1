/* test_take.c: core/take against hand-computed timecodes, bit-identical round trips, a
 * SIGKILLed recording process, every truncation and random byte flips of a small take, take
 * numbering, a full disk (write() interposed below: ENOSPC after a byte budget) and the
 * folder listing. */
#define _GNU_SOURCE
#include "take_testutil.h"

#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <signal.h>
#include <stdatomic.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <sys/syscall.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>
#include <zlib.h>

#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <cmocka.h>

/* ---- write() interposer: the ENOSPC "shim" ------------------------------------------ *
 * The test executable defines write(), so the library's calls reach this one (symbol
 * interposition, as an LD_PRELOAD shim would). While armed, writes to descriptors above 2
 * may use `enospc_budget` bytes more; the write that crosses it writes what fits (a short
 * write, as a filling disk does) and the next fails with ENOSPC. */
static _Atomic long long enospc_budget = -1;   /* -1: disarmed */

ssize_t write(int fd, const void *buf, size_t n)
{
    long long b = atomic_load(&enospc_budget);
    if (fd > 2 && b >= 0) {
        if (b == 0) {
            errno = ENOSPC;
            return -1;
        }
        if ((long long)n > b) n = (size_t)b;
        atomic_fetch_sub(&enospc_budget, (long long)n);
    }
    return syscall(SYS_write, fd, buf, n);
}

/* ---- helpers ------------------------------------------------------------------------ */

static char tmp_root[256];

static void make_dir(char *out, size_t n, const char *name)
{
    snprintf(out, n, "%s/%s", tmp_root, name);
    mkdir(out, 0777);
}

static void rm_rf(const char *dir)
{
    DIR *d = opendir(dir);
    if (!d) return;
    struct dirent *e;
    char p[1024];
    while ((e = readdir(d))) {
        if (!strcmp(e->d_name, ".") || !strcmp(e->d_name, "..")) continue;
        snprintf(p, sizeof p, "%s/%s", dir, e->d_name);
        struct stat st;
        if (!lstat(p, &st) && S_ISDIR(st.st_mode)) rm_rf(p);
        else unlink(p);
    }
    closedir(d);
    rmdir(dir);
}

static uint8_t *slurp(const char *path, size_t *n)
{
    FILE *f = fopen(path, "rb");
    assert_non_null(f);
    fseek(f, 0, SEEK_END);
    long sz = ftell(f);
    fseek(f, 0, SEEK_SET);
    uint8_t *b = malloc((size_t)sz + 1);
    assert_int_equal(fread(b, 1, (size_t)sz, f), (size_t)sz);
    fclose(f);
    *n = (size_t)sz;
    return b;
}

/* Write frames [0, n) (rich content) with the synchronous writer, chunk_frames per chunk. */
static void write_take(const char *dir, const char *slate, uint64_t n, uint32_t chunk_frames,
                       char *path, size_t pathlen)
{
    fp_take_header h;
    tt_header(&h, slate);
    fp_take_writer_options o = {.chunk_frames = chunk_frames, .no_sync = true};
    fp_take_writer *w;
    char err[512];
    int rc = fp_take_writer_create(dir, &h, &o, &w, err, sizeof err);
    if (rc) fail_msg("%s", err);
    snprintf(path, pathlen, "%s", fp_take_writer_path(w));
    for (uint64_t i = 0; i < n; i++) {
        tt_frame t;
        tt_make(&t, i, 1);
        rc = fp_take_writer_add(w, &t.f, err, sizeof err);
        if (rc) fail_msg("%s", err);
    }
    rc = fp_take_writer_close(&w, 0, 0, err, sizeof err);
    if (rc) fail_msg("%s", err);
}

/* Every frame of an open reader equals tt_make(first + i); returns the count. */
static size_t check_frames(fp_take_reader *r)
{
    char err[512];
    size_t n = fp_take_reader_frames(r);
    for (size_t i = 0; i < n; i++) {
        fp_take_frame f;
        tt_frame want;
        if (fp_take_reader_read(r, i, &f, err, sizeof err)) fail_msg("%s", err);
        tt_make(&want, i, 1);
        int d = tt_compare(&f, &want.f);
        if (d) fail_msg("frame %zu differs (part %d)", i, d);
    }
    return n;
}

/* Chunk starts of a valid take, found from its bytes (independent of the reader). */
static size_t chunk_starts(const uint8_t *b, size_t n, uint64_t *starts, uint32_t *frames,
                           char (*types)[5], size_t max)
{
    size_t k = 0, off = 16;
    while (off < n && k < max) {
        uint32_t len = (uint32_t)b[off + 8] | (uint32_t)b[off + 9] << 8 |
                       (uint32_t)b[off + 10] << 16 | (uint32_t)b[off + 11] << 24;
        uint32_t cnt = (uint32_t)b[off + 12] | (uint32_t)b[off + 13] << 8 |
                       (uint32_t)b[off + 14] << 16 | (uint32_t)b[off + 15] << 24;
        starts[k] = off;
        frames[k] = cnt;
        memcpy(types[k], b + off + 4, 4);
        types[k][4] = 0;
        k++;
        off += 20 + len;
    }
    assert_int_equal(off, n);
    return k;
}

/* ---- timecode ----------------------------------------------------------------------- */

static void tc_expect(uint64_t frames, uint32_t num, uint32_t den, bool drop, const char *want)
{
    fp_take_rate r = {num, den};
    fp_timecode tc;
    char buf[32], err[256];
    assert_int_equal(fp_timecode_from_frames(frames, r, drop, &tc), 0);
    assert_int_equal(fp_timecode_format(&tc, buf, sizeof buf), 0);
    if (strcmp(buf, want)) fail_msg("%llu frames at %u/%u%s: %s, expected %s",
                                    (unsigned long long)frames, num, den, drop ? " DF" : "", buf, want);
    fp_timecode back;
    assert_int_equal(fp_timecode_parse(want, r, &back, err, sizeof err), 0);
    uint64_t f;
    assert_int_equal(fp_timecode_to_frames(&back, r, &f), 0);
    /* Back to the same count, modulo 24 hours. */
    uint64_t day = drop ? 24ull * 6 * (num == 30000 ? 17982 : 35964) : 24ull * 3600 * fp_timecode_base(r);
    assert_int_equal(f, frames % day);
}

static void test_timecode_values(void **state)
{
    (void)state;
    tc_expect(0, 60, 1, false, "00:00:00:00");
    tc_expect(59, 60, 1, false, "00:00:00:59");
    tc_expect(60, 60, 1, false, "00:00:01:00");
    tc_expect(216000, 60, 1, false, "01:00:00:00");       /* 3600 s x 60 */
    tc_expect(24ull * 216000 + 61, 60, 1, false, "00:00:01:01");   /* wraps at 24 h */
    tc_expect(91532, 25, 1, false, "01:01:01:07");        /* 3661 s x 25 + 7 */
    tc_expect(86399ull * 24 + 23, 24, 1, false, "23:59:59:23");
    /* 29.97 non-drop: 30 frames a timecode second. 107892 / 30 = 3596 s + 12 frames. */
    tc_expect(107892, 30000, 1001, false, "00:59:56:12");
    /* 29.97 drop-frame (SMPTE 12-1): the classic values. */
    tc_expect(1799, 30000, 1001, true, "00:00:59;29");
    tc_expect(1800, 30000, 1001, true, "00:01:00;02");    /* ;00 and ;01 skipped */
    tc_expect(3597, 30000, 1001, true, "00:01:59;29");
    tc_expect(3598, 30000, 1001, true, "00:02:00;02");
    tc_expect(17981, 30000, 1001, true, "00:09:59;29");
    tc_expect(17982, 30000, 1001, true, "00:10:00;00");   /* tenth minute keeps ;00 */
    tc_expect(107892, 30000, 1001, true, "01:00:00;00");  /* one hour = 6 x 17982 */
    /* 59.94 drop-frame drops four. */
    tc_expect(3599, 60000, 1001, true, "00:00:59;59");
    tc_expect(3600, 60000, 1001, true, "00:01:00;04");
    tc_expect(35964, 60000, 1001, true, "00:10:00;00");
}

static void test_timecode_roundtrip_and_errors(void **state)
{
    (void)state;
    fp_take_rate df = {30000, 1001}, r60 = {60, 1}, r25 = {25, 1};
    fp_timecode tc;
    char err[256];
    for (uint64_t f = 0; f < 24ull * 6 * 17982; f += 7) {
        uint64_t back;
        assert_int_equal(fp_timecode_from_frames(f, df, true, &tc), 0);
        assert_int_equal(fp_timecode_to_frames(&tc, df, &back), 0);
        if (back != f) fail_msg("DF round trip %llu -> %llu", (unsigned long long)f,
                                (unsigned long long)back);
        assert_false(tc.seconds == 0 && tc.frames < 2 && tc.minutes % 10 != 0);
    }
    /* Dropped numbers, fields out of range, drop-frame where undefined. */
    assert_int_equal(fp_timecode_parse("00:01:00;00", df, &tc, err, sizeof err), -EINVAL);
    assert_non_null(strstr(err, "out of range"));
    assert_int_equal(fp_timecode_parse("00:10:00;00", df, &tc, err, sizeof err), 0);
    assert_int_equal(fp_timecode_parse("00:00:00:60", r60, &tc, err, sizeof err), -EINVAL);
    assert_int_equal(fp_timecode_parse("00:00:00:25", r25, &tc, err, sizeof err), -EINVAL);
    assert_int_equal(fp_timecode_parse("24:00:00:00", r25, &tc, err, sizeof err), -EINVAL);
    assert_int_equal(fp_timecode_parse("00:60:00:00", r25, &tc, err, sizeof err), -EINVAL);
    assert_int_equal(fp_timecode_parse("00:00:00;00", r25, &tc, err, sizeof err), -EINVAL);
    assert_int_equal(fp_timecode_parse("1:00:00:00", r25, &tc, err, sizeof err), -EINVAL);
    assert_non_null(strstr(err, "hours"));
    assert_int_equal(fp_timecode_parse("01:00:00:00x", r25, &tc, err, sizeof err), -EINVAL);
    assert_int_equal(fp_timecode_parse("01-00:00:00", r25, &tc, err, sizeof err), -EINVAL);
    assert_int_equal(fp_timecode_from_frames(5, r25, true, &tc), -EINVAL);
    /* Frames in a duration: exact integer arithmetic. */
    assert_int_equal(fp_take_frames_in(1000000000, df), 29);     /* 29.97 */
    assert_int_equal(fp_take_frames_in(1001000000, df), 30);
    assert_int_equal(fp_take_frames_in(16666666, r60), 0);
    assert_int_equal(fp_take_frames_in(16666667, r60), 1);
    assert_int_equal(fp_take_frames_in(3600LL * 1000000000, r60), 216000);
    assert_int_equal(fp_take_frames_in(-5, r60), 0);
    /* A frame's count at its time (whole ns, rounded): frame k at round(k / 60 s) counts k. */
    for (int64_t k = 0; k < 100000; k++)
        assert_int_equal(fp_take_frames_at((k * 1000000000 + 30) / 60, r60), k);
    assert_int_equal(fp_take_frames_at(33333333, r60), 2);       /* fp_take_frames_in: 1 */
    assert_int_equal(fp_take_frames_at(40000000, (fp_take_rate){25, 1}), 1);
    assert_int_equal(fp_take_frames_at(39999998, (fp_take_rate){25, 1}), 0);
    assert_int_equal(fp_take_frames_at(-5, r60), 0);
    assert_int_equal(fp_timecode_base(df), 30);
    assert_true(fp_timecode_drop_allowed((fp_take_rate){60000, 1001}));
    assert_false(fp_timecode_drop_allowed((fp_take_rate){24000, 1001}));
}

/* ---- round trip --------------------------------------------------------------------- */

static void test_roundtrip_writer(void **state)
{
    (void)state;
    char dir[512], path[1024], err[512];
    make_dir(dir, sizeof dir, "roundtrip");
    write_take(dir, "A12", 500, 7, path, sizeof path);
    fp_take_reader *r;
    if (fp_take_reader_open(path, &r, err, sizeof err)) fail_msg("%s", err);
    const fp_take_header *h = fp_take_reader_header(r);
    fp_take_header w;
    tt_header(&w, "A12");
    assert_string_equal(h->slate, "A12");
    assert_int_equal(h->take, 1);
    assert_int_equal(h->rate.num, 60);
    assert_int_equal(h->rate.den, 1);
    char tc[32];
    fp_timecode_format(&h->timecode_in, tc, sizeof tc);
    assert_string_equal(tc, "10:04:31:12");
    assert_false(h->timecode_in.drop);
    assert_int_equal(h->time_origin_ns, w.time_origin_ns);
    assert_int_equal(strlen(h->date), 20);
    assert_string_equal(h->mesh_path, w.mesh_path);
    assert_int_equal(h->mesh_crc32, w.mesh_crc32);
    assert_string_equal(h->mesh_crc_of, "positions");
    assert_int_equal(h->mesh_vertices, 26719);
    assert_null(h->rig_path);
    assert_string_equal(h->mapping, "anchored");
    assert_int_equal(h->mapping_key_count, 2);
    assert_string_equal(h->mapping_keys[1].key, "clamp");
    assert_string_equal(h->mapping_keys[1].value, "0.45");
    assert_int_equal(h->input_count, 2);
    assert_string_equal(h->inputs[0], w.inputs[0]);
    assert_false(h->calibration[0].present);
    assert_true(h->calibration[1].present);
    /* doubles come back bit for bit */
    assert_memory_equal(h->calibration[1].rotation, w.calibration[1].rotation, 4 * sizeof(double));
    assert_memory_equal(h->calibration[1].offset, w.calibration[1].offset, 3 * sizeof(double));
    assert_memory_equal(&h->radius, &w.radius, sizeof(double));
    assert_int_equal(h->performer_count, 2); /* 1.3: every performer's placement, bit for bit */
    for (size_t k = 0; k < 2; k++) {
        const fp_take_performer *a = &h->performers[k], *b = &w.performers[k];
        assert_string_equal(a->name, b->name);
        assert_memory_equal(&a->scale, &b->scale, sizeof(double));
        assert_memory_equal(a->rotation, b->rotation, sizeof a->rotation);
        assert_memory_equal(a->offset, b->offset, sizeof a->offset);
        assert_memory_equal(a->hand_offset, b->hand_offset, sizeof a->hand_offset);
    }
    assert_string_equal(h->description, w.description);
    assert_int_equal(h->rating, 4);

    const fp_take_summary *s = fp_take_reader_summary(r);
    assert_int_equal(s->frames, 500);
    assert_true(s->complete);
    assert_false(s->cut);
    assert_int_equal(s->dropped, 0);
    assert_int_equal(s->first_frame, 0);
    assert_int_equal(s->last_frame, 499);
    assert_string_equal(fp_take_reader_warning(r), "");
    assert_int_equal(check_frames(r), 500);
    /* Random access in reverse, then iteration from a point. */
    for (size_t i = 500; i-- > 0;) {
        fp_take_frame f;
        tt_frame want;
        assert_int_equal(fp_take_reader_read(r, i, &f, err, sizeof err), 0);
        tt_make(&want, i, 1);
        assert_int_equal(tt_compare(&f, &want.f), 0);
    }
    fp_take_frame f;
    assert_int_equal(fp_take_reader_read(r, 497, &f, err, sizeof err), 0);
    assert_int_equal(fp_take_reader_next(r, &f, err, sizeof err), 1);
    assert_int_equal(f.frame, 498);
    assert_int_equal(fp_take_reader_next(r, &f, err, sizeof err), 1);
    assert_int_equal(fp_take_reader_next(r, &f, err, sizeof err), 0);
    assert_int_equal(fp_take_reader_read(r, 500, &f, err, sizeof err), -ERANGE);
    fp_take_reader_close(&r);
    assert_null(r);
    rm_rf(dir);
}

/* The TAIL's reach round trip: the figures, and the vectors a rig held on the skull or the
 * jaw ("held", written only when some were); a take without "held" reads 0. */
static void test_reach_roundtrip(void **state)
{
    (void)state;
    char dir[512], err[512];
    make_dir(dir, sizeof dir, "reach");
    for (int with_held = 0; with_held < 2; with_held++) {
        fp_take_header h;
        tt_header(&h, with_held ? "H" : "N");
        fp_take_writer_options o = {.no_sync = true};
        fp_take_writer *w;
        if (fp_take_writer_create(dir, &h, &o, &w, err, sizeof err)) fail_msg("%s", err);
        char path[1024];
        snprintf(path, sizeof path, "%s", fp_take_writer_path(w));
        tt_frame t;
        tt_make(&t, 0, 1);
        if (fp_take_writer_add(w, &t.f, err, sizeof err)) fail_msg("%s", err);
        fp_take_reach reach = {51, 0.0, 0.0, 159.4, with_held ? 26 : 0};
        fp_take_writer_set_reach(w, &reach);
        if (fp_take_writer_close(&w, 0, 0, err, sizeof err)) fail_msg("%s", err);
        size_t n;
        uint8_t *bytes = slurp(path, &n);
        bool has = memmem(bytes, n, "\"held\"", 6) != NULL;
        free(bytes);
        assert_int_equal(has, with_held);
        fp_take_reader *r;
        if (fp_take_reader_open(path, &r, err, sizeof err)) fail_msg("%s", err);
        const fp_take_reach *got = &fp_take_reader_summary(r)->reach;
        assert_int_equal(got->vectors, 51);
        assert_true(got->longest_drag_mm == 159.4);
        assert_int_equal(got->held, with_held ? 26 : 0);
        fp_take_reader_close(&r);
    }
}

static void test_roundtrip_recorder(void **state)
{
    (void)state;
    char dir[512], err[512];
    make_dir(dir, sizeof dir, "recorder");
    fp_take_header h;
    tt_header(&h, "S1");
    fp_take_recorder_options o = {.writer = {.chunk_frames = 16, .no_sync = true}};
    fp_take_recorder *rec;
    if (fp_take_recorder_start(dir, &h, &o, &rec, err, sizeof err)) fail_msg("%s", err);
    char path[1024];
    snprintf(path, sizeof path, "%s", fp_take_recorder_path(rec));
    assert_non_null(strstr(path, "/S1_T001.fptake"));
    assert_int_equal(fp_take_recorder_take(rec), 1);
    const uint64_t n = 3000;
    uint64_t refused = 0;
    for (uint64_t i = 0; i < n; i++) {
        tt_frame t;
        tt_make(&t, i, 1);
        while (!fp_take_recorder_push(rec, &t.f)) {   /* ring full: let it drain, retry */
            refused++;
            usleep(1000);
        }
    }
    fp_take_recorder_status st;
    if (fp_take_recorder_close(&rec, &st, err, sizeof err)) fail_msg("%s", err);
    assert_null(rec);
    assert_int_equal(st.pushed, n);
    assert_int_equal(st.dropped, refused);
    assert_int_equal(st.written, n);
    assert_int_equal(st.error, 0);
    fp_take_reader *r;
    if (fp_take_reader_open(path, &r, err, sizeof err)) fail_msg("%s", err);
    assert_int_equal(check_frames(r), n);
    assert_true(fp_take_reader_summary(r)->complete);
    assert_int_equal(fp_take_reader_summary(r)->dropped, refused);
    fp_take_reader_close(&r);
    rm_rf(dir);
}

/* A frame larger than a quarter of the ring is refused and counted, never blocks. */
static void test_recorder_drops(void **state)
{
    (void)state;
    char dir[512], err[512];
    make_dir(dir, sizeof dir, "drops");
    fp_take_header h;
    tt_header(&h, "D");
    fp_take_recorder_options o = {.writer = {.no_sync = true}, .ring_bytes = 4096};
    fp_take_recorder *rec;
    if (fp_take_recorder_start(dir, &h, &o, &rec, err, sizeof err)) fail_msg("%s", err);
    static fp_event big[8];
    memset(big, 0, sizeof big);
    for (int i = 0; i < 8; i++) {
        big[i].header.type = FP_EVENT_JOINT_POSITIONS;
        big[i].header.size = sizeof big[i].positions;
    }
    fp_take_frame f = {.frame = 1, .events = big, .event_count = 8};   /* 56 + 8 x 276 > 1024 */
    assert_false(fp_take_recorder_push(rec, &f));
    f.event_count = 2;
    assert_true(fp_take_recorder_push(rec, &f));
    fp_take_recorder_status st;
    assert_int_equal(fp_take_recorder_close(&rec, &st, err, sizeof err), 0);
    assert_int_equal(st.pushed, 1);
    assert_int_equal(st.dropped, 1);
    char path[1024];
    snprintf(path, sizeof path, "%s/D_T001.fptake", dir);
    fp_take_reader *r;
    if (fp_take_reader_open(path, &r, err, sizeof err)) fail_msg("%s", err);
    assert_int_equal(fp_take_reader_frames(r), 1);
    assert_int_equal(fp_take_reader_summary(r)->dropped, 1);
    fp_take_reader_close(&r);
    rm_rf(dir);
}

/* ---- crash: SIGKILL mid-take -------------------------------------------------------- */

typedef struct crash_shared {
    _Atomic uint64_t pushed;
    _Atomic uint64_t written;   /* frames the recorder reported on disk */
    char path[1024];
} crash_shared;

static void test_sigkill_mid_take(void **state)
{
    (void)state;
    char dir[512];
    make_dir(dir, sizeof dir, "crash");
    crash_shared *sh = mmap(NULL, sizeof *sh, PROT_READ | PROT_WRITE, MAP_SHARED | MAP_ANONYMOUS,
                            -1, 0);
    assert_true(sh != MAP_FAILED);
    memset(sh, 0, sizeof *sh);
    const uint32_t chunk = 10;
    pid_t pid = fork();
    assert_true(pid >= 0);
    if (pid == 0) {
        fp_take_header h;
        tt_header(&h, "K");
        fp_take_recorder_options o = {.writer = {.chunk_frames = chunk}};   /* fdatasync on */
        fp_take_recorder *rec;
        char err[512];
        if (fp_take_recorder_start(dir, &h, &o, &rec, err, sizeof err)) _exit(3);
        snprintf(sh->path, sizeof sh->path, "%s", fp_take_recorder_path(rec));
        struct timespec period = {0, 2000000};   /* 500 frames a second */
        for (uint64_t i = 0;; i++) {
            tt_frame t;
            tt_make(&t, i, 1);
            if (!fp_take_recorder_push(rec, &t.f)) _exit(4);
            fp_take_recorder_status st;
            fp_take_recorder_status_get(rec, &st);
            atomic_store(&sh->written, st.written);
            atomic_store(&sh->pushed, i + 1);
            nanosleep(&period, NULL);
        }
    }
    while (atomic_load(&sh->pushed) < 400) usleep(1000);
    kill(pid, SIGKILL);
    int status;
    assert_int_equal(waitpid(pid, &status, 0), pid);
    assert_true(WIFSIGNALED(status) && WTERMSIG(status) == SIGKILL);
    uint64_t pushed = atomic_load(&sh->pushed), written = atomic_load(&sh->written);

    fp_take_reader *r;
    char err[512];
    if (fp_take_reader_open(sh->path, &r, err, sizeof err)) fail_msg("%s", err);
    const fp_take_summary *s = fp_take_reader_summary(r);
    size_t got = check_frames(r);   /* frames 0..got-1, each intact and in order */
    print_message("# SIGKILL after %llu frames pushed, %llu reported written: %zu read back "
                  "(%llu lost)%s%s\n", (unsigned long long)pushed, (unsigned long long)written,
                  got, (unsigned long long)(pushed - got), s->cut ? "; " : "",
                  fp_take_reader_warning(r));
    assert_false(s->complete);             /* no TAIL: the process died */
    assert_true(got >= written);           /* everything reported on disk is there */
    assert_true(got <= pushed + 1);
    /* At most the chunk being gathered plus what reached the ring while the recorder thread
     * waited for a core (0.3 s at 500 frames a second on a loaded machine). */
    assert_true(pushed - got <= chunk + 150);
    fp_take_reader_close(&r);
    munmap(sh, sizeof *sh);
    rm_rf(dir);
}

/* ---- damage: every truncation, random flips ---------------------------------------- */

static void test_truncated_every_offset(void **state)
{
    (void)state;
    char dir[512], path[1024], err[512];
    make_dir(dir, sizeof dir, "trunc");
    write_take(dir, "T", 9, 3, path, sizeof path);   /* HEAD, 3 x FRMS(3), TAIL */
    size_t n;
    uint8_t *b = slurp(path, &n);
    uint64_t starts[16];
    uint32_t frames[16];
    char types[16][5];
    size_t nc = chunk_starts(b, n, starts, frames, types, 16);
    assert_int_equal(nc, 5);
    assert_string_equal(types[0], "HEAD");
    assert_string_equal(types[4], "TAIL");
    for (size_t len = 0; len < n; len++) {
        fp_take_reader *r;
        int rc = fp_take_reader_open_memory(b, len, "t.fptake", &r, err, sizeof err);
        if (len < starts[1]) {   /* signature or header damaged: an error naming the byte */
            assert_int_equal(rc, -EBADMSG);
            if (!strstr(err, "t.fptake: byte ")) fail_msg("len %zu: \"%s\"", len, err);
            assert_null(r);
            continue;
        }
        if (rc) fail_msg("len %zu: %s", len, err);
        /* Expected: frames of the whole chunks in [0, len); a cut unless len is a boundary. */
        size_t want = 0, k = 1;
        for (; k < nc && (k + 1 < nc ? starts[k + 1] : n) <= len; k++) want += frames[k];
        const fp_take_summary *s = fp_take_reader_summary(r);
        assert_int_equal(fp_take_reader_frames(r), want);
        bool boundary = k < nc && starts[k] == len;
        assert_int_equal(s->cut, !boundary);
        if (!boundary) {
            char expect[64];
            snprintf(expect, sizeof expect, "t.fptake: cut at byte %llu: ",
                     (unsigned long long)starts[k]);
            if (strncmp(fp_take_reader_warning(r), expect, strlen(expect)))
                fail_msg("len %zu: \"%s\", expected \"%s...\"", len, fp_take_reader_warning(r), expect);
            assert_int_equal(s->cut_offset, starts[k]);
        }
        assert_false(s->complete);
        assert_int_equal(check_frames(r), want);
        fp_take_reader_close(&r);
    }
    /* The same through a file on disk, for a cut inside the second FRMS chunk. */
    char cut[1100];
    snprintf(cut, sizeof cut, "%s/cut.fptake", dir);
    FILE *f = fopen(cut, "wb");
    fwrite(b, 1, starts[2] + 30, f);
    fclose(f);
    fp_take_reader *r;
    assert_int_equal(fp_take_reader_open(cut, &r, err, sizeof err), 0);
    assert_int_equal(fp_take_reader_frames(r), 3);
    assert_non_null(strstr(fp_take_reader_warning(r), "runs past the end of the file"));
    fp_take_reader_close(&r);
    free(b);
    rm_rf(dir);
}

static void test_random_flips(void **state)
{
    (void)state;
    char dir[512], path[1024], err[512];
    make_dir(dir, sizeof dir, "flips");
    write_take(dir, "F", 12, 4, path, sizeof path);
    size_t n;
    uint8_t *b = slurp(path, &n);
    uint64_t starts[16];
    uint32_t frames[16];
    char types[16][5];
    size_t nc = chunk_starts(b, n, starts, frames, types, 16);
    uint8_t *c = malloc(n);
    uint64_t seed = 12345;
    for (int it = 0; it < 3000; it++) {
        memcpy(c, b, n);
        seed = tt_hash(seed + (uint64_t)it);
        size_t at = (size_t)(seed % n);
        uint8_t x = (uint8_t)(1 + (seed >> 20) % 255);   /* never 0: the byte changes */
        c[at] ^= x;
        fp_take_reader *r;
        int rc = fp_take_reader_open_memory(c, n, "f.fptake", &r, err, sizeof err);
        if (at < starts[1]) {
            /* Signature or HEAD: an error naming a byte, or (a flip the JSON tolerates is
             * impossible: the crc32 covers it) never success. */
            if (rc == 0) fail_msg("flip at %zu accepted", at);
            assert_non_null(strstr(err, "byte "));
            continue;
        }
        if (rc) fail_msg("flip at %zu: %s", at, err);
        size_t k = 1, want = 0;
        while (k + 1 < nc && starts[k + 1] <= at) want += frames[k++];
        const fp_take_summary *s = fp_take_reader_summary(r);
        assert_true(s->cut);
        assert_int_equal(s->cut_offset, starts[k]);
        char expect[64];
        snprintf(expect, sizeof expect, "f.fptake: cut at byte %llu: ", (unsigned long long)starts[k]);
        if (strncmp(fp_take_reader_warning(r), expect, strlen(expect)))
            fail_msg("flip at %zu: \"%s\"", at, fp_take_reader_warning(r));
        assert_int_equal(check_frames(r), want);
        fp_take_reader_close(&r);
    }
    /* Multi-byte garbage anywhere: never a crash, errors and warnings name a byte. */
    for (int it = 0; it < 3000; it++) {
        memcpy(c, b, n);
        for (int j = 0; j < 8; j++) {
            seed = tt_hash(seed + 7);
            c[seed % n] = (uint8_t)(seed >> 40);
        }
        size_t len = (it & 1) ? n : (size_t)(seed >> 8) % (n + 1);
        fp_take_reader *r;
        int rc = fp_take_reader_open_memory(c, len, "g.fptake", &r, err, sizeof err);
        if (rc) {
            assert_non_null(strstr(err, "byte "));
            continue;
        }
        if (fp_take_reader_summary(r)->cut) assert_non_null(strstr(fp_take_reader_warning(r), "cut at byte "));
        fp_take_frame f;
        while (fp_take_reader_next(r, &f, err, sizeof err) == 1) {}
        fp_take_reader_close(&r);
    }
    free(c);
    free(b);
    rm_rf(dir);
}

static void test_bad_files(void **state)
{
    (void)state;
    char dir[512], path[1100], err[512];
    make_dir(dir, sizeof dir, "bad");
    fp_take_reader *r;
    snprintf(path, sizeof path, "%s/missing.fptake", dir);
    assert_int_equal(fp_take_reader_open(path, &r, err, sizeof err), -ENOENT);
    assert_non_null(strstr(err, "missing.fptake"));
    assert_int_equal(fp_take_reader_open(dir, &r, err, sizeof err), -EISDIR); /* (66: an input) */
    assert_int_equal(fp_take_reader_open_memory("# facepuppet-eventlog 1\n", 24, "x.fptake", &r,
                                                err, sizeof err), -EBADMSG);
    assert_string_equal(err, "x.fptake: byte 0: not a facepuppet take (bad signature)");
    /* A later major version is refused; a later minor is read. */
    char tpath[1024];
    write_take(dir, "V", 2, 1, tpath, sizeof tpath);
    size_t n;
    uint8_t *b = slurp(tpath, &n);
    b[8] = 2;
    uint32_t crc = (uint32_t)crc32(0, b, 12);
    memcpy(b + 12, &crc, 4);
    assert_int_equal(fp_take_reader_open_memory(b, n, "v.fptake", &r, err, sizeof err), -ENOTSUP);
    char want[32];
    snprintf(want, sizeof want, "version 2.%d", FP_TAKE_VERSION_MINOR);
    assert_non_null(strstr(err, want));
    b[8] = 1;
    b[10] = 7;
    crc = (uint32_t)crc32(0, b, 12);
    memcpy(b + 12, &crc, 4);
    assert_int_equal(fp_take_reader_open_memory(b, n, "v.fptake", &r, err, sizeof err), 0);
    assert_int_equal(fp_take_reader_frames(r), 2);
    assert_int_equal(fp_take_reader_summary(r)->version_major, 1);
    assert_int_equal(fp_take_reader_summary(r)->version_minor, 7);
    fp_take_reader_close(&r);
    free(b);
    rm_rf(dir);
}

/* The take in b (n bytes) with its HEAD payload (the chunk at byte 16) replaced by the old one
 * with the first `from` (nl bytes) replaced by `to` (tl bytes), the chunk's length and crc32
 * made anew; *out_n its size. A new buffer. */
static uint8_t *rehead(const uint8_t *b, size_t n, const char *from, size_t fl, const char *to,
                       size_t tl, size_t *out_n)
{
    uint32_t len;
    memcpy(&len, b + 16 + 8, 4);
    const uint8_t *pay = b + 32;
    const uint8_t *hit = memmem(pay, len, from, fl);
    assert_non_null(hit);
    const size_t pre = (size_t)(hit - pay), nl = len - fl + tl;
    uint8_t *o = malloc(n - len + nl);
    memcpy(o, b, 32);
    memcpy(o + 32, pay, pre);
    memcpy(o + 32 + pre, to, tl);
    memcpy(o + 32 + pre + tl, hit + fl, len - pre - fl);
    const uint32_t nl32 = (uint32_t)nl;
    memcpy(o + 24, &nl32, 4);
    const uint32_t crc = (uint32_t)crc32(0, o + 16, 16 + (uInt)nl);
    memcpy(o + 32 + nl, &crc, 4);
    memcpy(o + 36 + nl, b + 36 + len, n - 36 - len);
    *out_n = n - len + nl;
    return o;
}

/* A damaged HEAD is refused (-EBADMSG, the field named), though its crc32 is right: a NUL
 * byte anywhere in its JSON or a \u0000 escape in a string (cJSON read them as white space or
 * the string's end: "ta\0ke" was slate "ta"), text after the JSON object. */
static void test_bad_header(void **state)
{
    (void)state;
    char dir[512], tpath[1024], err[512];
    make_dir(dir, sizeof dir, "badhead");
    write_take(dir, "H", 3, 1, tpath, sizeof tpath);
    size_t n, m;
    uint8_t *b = slurp(tpath, &n);
    fp_take_reader *r;
    assert_int_equal(fp_take_reader_open_memory(b, n, "h.fptake", &r, err, sizeof err), 0);
    fp_take_reader_close(&r);
    static const struct { const char *from, *to; size_t tl; const char *says; } cases[] = { /* tl 0: strlen */
        {"\"slate\":\"H\"", "\"slate\":\"H\0x\"", 13, "header: a NUL in \"slate\""},
        {"\"path\":\"", "\"path\":\"\0", 9, "header: a NUL in \"mesh.path\""},
        {"\"pedal\"", "\"ped\0al\"", 8, "header: a NUL in \"inputs[1]\""},
        {"\"release\"", "\"rel\0ease\"", 10, "header: a NUL in a key of \"mapping.keys\""},
        {",\"take\"", ",\0\"take\"", 8, "header: a NUL between the fields of the header"},
        {"\"rating\":4}", "\"rating\":4}\0", 12, "header: a NUL outside the JSON object"},
        {"\"description\":\"", "\"description\":\"a\\u0000", 22, "header: a NUL in \"description\""},
        {"\"rating\":4}", "\"rating\":4} x", 0, "header: text after the JSON object"},
        /* inputs and mapping of the wrong JSON type: cJSON_ArrayForEach read an object's
         * members as inputs and an array's entries as keys without a name */
        {"\"inputs\":[", "\"inputs\":{\"a\":\"x\"},\"y\":[", 0, "header: \"inputs\" is not an array"},
        {"\"inputs\":[", "\"inputs\":[\"x\",7,", 0, "header: \"inputs[1]\" is not a string"},
        {"\"keys\":{", "\"keys\":[\"a\"],\"k\":{", 0, "header: \"mapping.keys\" is not an object"},
        {"\"keys\":{", "\"keys\":{\"a\":1,", 0, "header: \"mapping.keys\" key 0 is not a string"},
        {"\"mapping\":{", "\"mapping\":7,\"m\":{", 0, "header: \"mapping\" is not an object"},
        /* 1.3: each performer's placement */
        {"\"performers\":[", "\"performers\":{\"a\":1},\"p\":[", 0, "header: \"performers\" is not an array of at most 4"},
        {"\"performers\":[", "\"performers\":[1,2,3,4,", 0, "header: \"performers\" is not an array of at most 4"},
        {"\"name\":\"B\"", "\"name\":7", 0, "header: invalid \"performers\"[1]"},
        {"\"scale\":0.1,\"rotation\":[1,", "\"scale\":0,\"rotation\":[1,", 0, "header: invalid \"performers\"[0]"},
        {"\"hand_offset\":[[", "\"hand_offset\":[[\"x\",", 0, "header: invalid \"performers\"[0] hand_offset"},
        /* take numbers start at 1; the face's axes (1.4) are two non-zero vectors */
        {"\"take\":1,", "\"take\":0,", 0, "header: missing or invalid \"take\""},
        {"\"radius\":", "\"face\":{\"up\":[0,0,0],\"facing\":[0,0,1]},\"radius\":", 0,
         "header: invalid \"face\" (up or facing is a zero vector)"},
        /* a key twice: the first was read and the other ignored (a patched take's "take":7
         * after "take":1 played as take 1), as rig, calibration and stack files refuse it */
        {"\"take\":1,", "\"take\":1,\"take\":7,", 0, "header: \"take\" given twice"},
        {"\"release\"", "\"engage\":\"0.3\",\"engage\":\"0.4\",\"release\"", 0,
         "header: \"mapping.keys.engage\" given twice"},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        const size_t tl = cases[i].tl ? cases[i].tl : strlen(cases[i].to); /* (tl: with a NUL) */
        uint8_t *c = rehead(b, n, cases[i].from, strlen(cases[i].from), cases[i].to, tl, &m);
        err[0] = '\0';
        assert_int_equal(fp_take_reader_open_memory(c, m, "h.fptake", &r, err, sizeof err), -EBADMSG);
        print_message("%s\n", err);
        assert_non_null(strstr(err, "h.fptake: byte "));
        assert_non_null(strstr(err, cases[i].says));
        assert_null(r);
        free(c);
    }
    /* white space after the object, and an escaped backslash before "u0000", are no damage */
    static const char *const fine[][2] = {{"\"rating\":4}", "\"rating\":4} \n"},
                                          {"\"description\":\"", "\"description\":\"\\\\u0000"}};
    for (size_t i = 0; i < 2; i++) {
        uint8_t *c = rehead(b, n, fine[i][0], strlen(fine[i][0]), fine[i][1], strlen(fine[i][1]), &m);
        assert_int_equal(fp_take_reader_open_memory(c, m, "h.fptake", &r, err, sizeof err), 0);
        assert_int_equal(fp_take_reader_frames(r), 3);
        fp_take_reader_close(&r);
        free(c);
    }
    /* more inputs than a take holds (FP_TAKE_MAX_INPUTS) */
    char many[16 * (FP_TAKE_MAX_INPUTS + 1) + 16];
    size_t w = (size_t)snprintf(many, sizeof many, "\"inputs\":[");
    for (int i = 0; i < FP_TAKE_MAX_INPUTS + 1; i++) w += (size_t)snprintf(many + w, sizeof many - w, "\"i%d\",", i);
    uint8_t *c = rehead(b, n, "\"inputs\":[", 10, many, w, &m);
    assert_int_equal(fp_take_reader_open_memory(c, m, "h.fptake", &r, err, sizeof err), -EBADMSG);
    assert_non_null(strstr(err, "header: \"inputs\" has more than 16 entries"));
    free(c);
    free(b);
    rm_rf(dir);
}

/* A chunk's crc32 again after a patch (chunk at off: 16-byte head, payload, crc32). */
static void rechunk(uint8_t *b, size_t off)
{
    uint32_t len;
    memcpy(&len, b + off + 8, 4);
    uint32_t crc = (uint32_t)crc32(0, b + off, 16 + len);
    memcpy(b + off + 16 + len, &crc, 4);
}

/* The file at path (*n bytes; free it) of five chunks, HEAD, 3 x FRMS, TAIL: their file
 * offsets into starts (16). */
static uint8_t *slurp_five(const char *path, size_t *n, uint64_t *starts)
{
    uint8_t *b = slurp(path, n);
    uint32_t frames[16];
    char types[16][5];
    assert_int_equal(chunk_starts(b, *n, starts, frames, types, 16), 5);
    return b;
}

/* Frames out of order (a patched or clock-jumped record, crc32 intact): the take is cut at the
 * chunk that holds it, with the reason; the summary counts only the frames kept. */
static void test_frames_out_of_order(void **state)
{
    (void)state;
    char dir[512], path[1024], err[512];
    make_dir(dir, sizeof dir, "order");
    write_take(dir, "O", 9, 3, path, sizeof path); /* HEAD, 3 x FRMS(3), TAIL */
    size_t n;
    uint64_t starts[16];
    uint8_t *b = slurp_five(path, &n, starts);
    fp_take_reader *r;
    assert_int_equal(fp_take_reader_open_memory(b, n, "o.fptake", &r, err, sizeof err), 0);
    assert_int_equal(fp_take_reader_frames(r), 9);
    fp_take_frame f;
    assert_int_equal(fp_take_reader_read(r, 5, &f, err, sizeof err), 0);
    const uint64_t fn6 = f.frame;
    const int64_t t6 = f.time_ns;
    fp_take_reader_close(&r);
    static const struct { size_t field; const char *why; } cases[] = {
        {16, "goes back"},  /* the 7th frame's time: INT64_MIN */
        {8, "after frame"}, /* the 7th frame's number: the 6th's less one */
    };
    for (size_t c = 0; c < 2; c++) {
        uint8_t *p = malloc(n);
        memcpy(p, b, n);
        uint8_t *rec = p + starts[3] + 16; /* the third FRMS chunk's first frame record */
        if (cases[c].field == 16) {
            int64_t t = INT64_MIN;
            memcpy(rec + 16, &t, 8);
        } else {
            const uint64_t back = fn6 - 1;
            memcpy(rec + 8, &back, 8);
        }
        rechunk(p, starts[3]);
        assert_int_equal(fp_take_reader_open_memory(p, n, "o.fptake", &r, err, sizeof err), 0);
        assert_int_equal(fp_take_reader_frames(r), 6);
        if (!strstr(fp_take_reader_warning(r), cases[c].why))
            fail_msg("case %zu: \"%s\"", c, fp_take_reader_warning(r));
        const fp_take_summary *sm = fp_take_reader_summary(r);
        assert_int_equal(sm->frames, 6);
        assert_int_equal(sm->last_frame, fn6);
        assert_int_equal(sm->last_time_ns, t6);
        fp_take_reader_close(&r);
        free(p);
    }
    free(b);
    rm_rf(dir);
}

/* A new folder `name` (its path into dir, 512 bytes) with a take of `slate`: nine frames of
 * tt_make(i, 0) in chunks of three, each passed to tweak (may be NULL) before it is written;
 * its path into path (1024 bytes). Returns the take opened (fp_take_reader_open). */
static fp_take_reader *nine_frames(const char *name, const char *slate, void (*tweak)(tt_frame *, uint64_t),
                                   char *dir, char *path)
{
    char err[512];
    make_dir(dir, 512, name);
    fp_take_header h;
    tt_header(&h, slate); /* two inputs */
    fp_take_writer_options o = {.chunk_frames = 3, .no_sync = true};
    fp_take_writer *w;
    assert_int_equal(fp_take_writer_create(dir, &h, &o, &w, err, sizeof err), 0);
    snprintf(path, 1024, "%s", fp_take_writer_path(w));
    for (uint64_t i = 0; i < 9; i++) {
        tt_frame t;
        tt_make(&t, i, 0); /* 10 vectors; 4 events, 2 positions and 2 wrists, sources 0 and 1 */
        if (tweak) tweak(&t, i);
        assert_int_equal(fp_take_writer_add(w, &t.f, err, sizeof err), 0);
    }
    assert_int_equal(fp_take_writer_close(&w, 0, 0, err, sizeof err), 0);
    fp_take_reader *r;
    if (fp_take_reader_open(path, &r, err, sizeof err)) fail_msg("%s", err);
    return r;
}

static void source_beyond(tt_frame *t, uint64_t i)
{
    if (i == 7) t->ev[3].header.source = 2;
}

/* A chunk of frames missing from the middle, the chunks around it whole (a copy that lost a
 * block): the TAIL says how many frames were written; the take read as closed normally with
 * fewer, and play skipped the gap's commits with no word. Now it is cut at the TAIL, naming
 * both counts. */
static void test_frames_chunk_missing(void **state)
{
    (void)state;
    char dir[512], path[1024], err[512];
    make_dir(dir, sizeof dir, "gap");
    write_take(dir, "G", 9, 3, path, sizeof path); /* HEAD, 3 x FRMS(3), TAIL */
    size_t n;
    uint8_t *b = slurp(path, &n);
    uint64_t starts[16];
    uint32_t frames[16];
    char types[16][5];
    assert_int_equal(chunk_starts(b, n, starts, frames, types, 16), 5);
    assert_string_equal(types[4], "TAIL");
    const size_t gap = starts[3] - starts[2]; /* the second FRMS chunk out */
    memmove(b + starts[2], b + starts[3], n - starts[3]);
    fp_take_reader *r;
    assert_int_equal(fp_take_reader_open_memory(b, n - gap, "g.fptake", &r, err, sizeof err), 0);
    assert_int_equal(fp_take_reader_frames(r), 6);
    const fp_take_summary *sm = fp_take_reader_summary(r);
    assert_true(sm->cut);
    assert_false(sm->complete);
    if (!strstr(fp_take_reader_warning(r), "TAIL chunk says 9 frames, the file holds 6"))
        fail_msg("\"%s\"", fp_take_reader_warning(r));
    fp_take_reader_close(&r);
    free(b);
    rm_rf(dir);
}

/* An event of an input the header does not list (source >= its inputs' count; crc32 right):
 * its chunk is damage, the take cut there naming the field; the frames before it play. */
static void test_event_source(void **state)
{
    (void)state;
    char dir[512], err[512], path[1024];
    fp_take_reader *r = nine_frames("source", "S", source_beyond, dir, path);
    print_message("%s\n", fp_take_reader_warning(r));
    assert_int_equal(fp_take_reader_frames(r), 6);
    assert_true(fp_take_reader_summary(r)->cut);
    assert_non_null(strstr(fp_take_reader_warning(r), "event source beyond the header's \"inputs\""));
    fp_take_frame f;
    assert_int_equal(fp_take_reader_read(r, 5, &f, err, sizeof err), 0);
    assert_int_equal(f.frame, 5);
    fp_take_reader_close(&r);
    rm_rf(dir);
}

/* Two channels, "jaw.open" 0.25 and "mapping.x": NaN in frame 4, infinite in frame 5, else 1. */
static void two_channels(tt_frame *t, uint64_t i)
{
    t->cs.channel_count = 2;
    snprintf(t->chan[0].name, sizeof t->chan[0].name, "jaw.open");
    t->chan[0].value = 0.25f;
    snprintf(t->chan[1].name, sizeof t->chan[1].name, "mapping.x");
    t->chan[1].value = i == 4 ? NAN : i == 5 ? INFINITY : 1.0f;
}

/* Floats a take may not hold: a channel value or an event's field that is NaN or infinite
 * (patched in, crc32 right) is damage, named by its frame and channel or event, the take cut
 * there; the writer leaves out a channel whose value is not finite (a mapping's without a
 * rig), so the take it writes reads whole. */
static void test_not_finite(void **state)
{
    (void)state;
    char dir[512], path[1024], err[512];
    fp_take_reader *r = nine_frames("finite", "F", two_channels, dir, path);
    assert_false(fp_take_reader_summary(r)->cut);
    assert_int_equal(fp_take_reader_frames(r), 9);
    for (size_t i = 3; i < 7; i++) {
        fp_take_frame f;
        assert_int_equal(fp_take_reader_read(r, i, &f, err, sizeof err), 0);
        assert_int_equal(f.control->channel_count, i == 4 || i == 5 ? 1 : 2);
        assert_string_equal(f.control->channels[0].name, "jaw.open");
    }
    fp_take_reader_close(&r);
    size_t n;
    uint64_t starts[16];
    uint8_t *b = slurp_five(path, &n, starts);
    /* frame 6, the third FRMS chunk's first record: 56 + 10 x 24 bytes, then its channels */
    const size_t rec = starts[3] + 16, chan0 = 56 + 10 * 24, ev0 = chan0 + 2 * 36;
    static const struct { size_t at; float v; const char *why; } cases[] = {
        {chan0 + 32, NAN, "frame 6 (its record at byte %zu): channel \"jaw.open\" value not finite"},
        {chan0 + 36 + 32, -INFINITY, "frame 6 (its record at byte %zu): channel \"mapping.x\" value not finite"},
        {ev0 + 24 + 4 * 7, INFINITY, "frame 6 (its record at byte %zu): event 0 (type 2): a value not finite"},
    };
    for (size_t c = 0; c < sizeof cases / sizeof *cases; c++) {
        uint8_t *p = malloc(n);
        memcpy(p, b, n);
        memcpy(p + rec + cases[c].at, &cases[c].v, 4);
        rechunk(p, starts[3]);
        assert_int_equal(fp_take_reader_open_memory(p, n, "f.fptake", &r, err, sizeof err), 0);
        char want[200];
        snprintf(want, sizeof want, cases[c].why, rec);
        if (!strstr(fp_take_reader_warning(r), want) || !strstr(fp_take_reader_warning(r), "f.fptake"))
            fail_msg("case %zu: \"%s\", not \"%s\"", c, fp_take_reader_warning(r), want);
        assert_int_equal(fp_take_reader_frames(r), 6);
        assert_true(fp_take_reader_summary(r)->cut);
        fp_take_reader_close(&r);
        free(p);
    }
    { /* a damaged name with an escape byte: the reason carries no control byte */
        uint8_t *p = malloc(n);
        memcpy(p, b, n);
        const float nan = NAN;
        p[rec + chan0] = 0x1b;
        memcpy(p + rec + chan0 + 32, &nan, 4);
        rechunk(p, starts[3]);
        assert_int_equal(fp_take_reader_open_memory(p, n, "f.fptake", &r, err, sizeof err), 0);
        assert_non_null(strstr(fp_take_reader_warning(r), "aw.open\" value not finite"));
        assert_null(strchr(fp_take_reader_warning(r), 0x1b));
        fp_take_reader_close(&r);
        free(p);
    }
    free(b);
    rm_rf(dir);
}

/* ---- numbering ---------------------------------------------------------------------- */

static uint32_t record_one(const char *dir, const char *slate)
{
    fp_take_header h;
    tt_header(&h, slate);
    fp_take_writer *w;
    char err[512];
    fp_take_writer_options o = {.no_sync = true};
    if (fp_take_writer_create(dir, &h, &o, &w, err, sizeof err)) fail_msg("%s", err);
    uint32_t t = fp_take_writer_take(w);
    tt_frame f;
    tt_make(&f, t, 1);
    assert_int_equal(fp_take_writer_add(w, &f.f, err, sizeof err), 0);
    assert_int_equal(fp_take_writer_close(&w, 0, 0, err, sizeof err), 0);
    return t;
}

static void test_numbering(void **state)
{
    (void)state;
    char dir[512], err[512], p[1100];
    make_dir(dir, sizeof dir, "numbers");
    rm_rf(dir);   /* a missing folder is created */
    uint32_t t;
    assert_int_equal(fp_take_next_number(dir, "A", &t, err, sizeof err), 0);
    assert_int_equal(t, 1);
    assert_int_equal(record_one(dir, "A"), 1);
    assert_int_equal(record_one(dir, "A"), 2);
    assert_int_equal(record_one(dir, "B"), 1);   /* a new slate starts at 1 */
    assert_int_equal(record_one(dir, "A"), 3);   /* back to A: on from its last */
    assert_int_equal(record_one(dir, "A_T1"), 1);   /* a slate that looks like a take name */
    assert_int_equal(record_one(dir, "A"), 4);
    /* A foreign file in the way is never overwritten: the number goes past it. */
    snprintf(p, sizeof p, "%s/A_T007.fptake", dir);
    FILE *f = fopen(p, "wb");
    fputs("not mine", f);
    fclose(f);
    assert_int_equal(record_one(dir, "A"), 8);
    size_t n;
    uint8_t *b = slurp(p, &n);
    assert_int_equal(n, 8);
    assert_memory_equal(b, "not mine", 8);
    free(b);
    /* Four-digit numbers sort after three-digit ones. */
    snprintf(p, sizeof p, "%s/C_T999.fptake", dir);
    fclose(fopen(p, "wb"));
    assert_int_equal(record_one(dir, "C"), 1000);
    assert_int_equal(fp_take_next_number(dir, "C", &t, err, sizeof err), 0);
    assert_int_equal(t, 1001);
    char name[64];
    assert_int_equal(fp_take_filename("C", 1000, name, sizeof name), 0);
    assert_string_equal(name, "C_T1000.fptake");
    assert_int_equal(fp_take_filename("A", 3, name, sizeof name), 0);
    assert_string_equal(name, "A_T003.fptake");
    /* Takes 1..4 of A are intact and say so. */
    for (uint32_t k = 1; k <= 4; k++) {
        snprintf(p, sizeof p, "%s/A_T%03u.fptake", dir, k);
        fp_take_reader *r;
        if (fp_take_reader_open(p, &r, err, sizeof err)) fail_msg("%s", err);
        assert_int_equal(fp_take_reader_header(r)->take, k);
        assert_int_equal(fp_take_reader_frames(r), 1);
        fp_take_reader_close(&r);
    }
    /* Bad slates. */
    const char *bad[] = {"", ".hidden", "a/b", "a b", "\xc3\xa9",
                         "0123456789012345678901234567890123456789012345678901234567890123"};
    for (size_t i = 0; i < sizeof bad / sizeof *bad; i++) {
        assert_false(fp_take_slate_valid(bad[i]));
        assert_int_equal(fp_take_next_number(dir, bad[i], &t, err, sizeof err), -EINVAL);
        if (strlen(bad[i]) >= sizeof ((fp_take_header *)0)->slate) continue;   /* cannot be held */
        fp_take_header h;
        tt_header(&h, "X");
        snprintf(h.slate, sizeof h.slate, "%s", bad[i]);
        fp_take_writer *w;
        assert_int_equal(fp_take_writer_create(dir, &h, NULL, &w, err, sizeof err), -EINVAL);
        assert_non_null(strstr(err, "slate"));
    }
    rm_rf(dir);
}

/* ---- full disk ---------------------------------------------------------------------- */

static void test_enospc(void **state)
{
    (void)state;
    char dir[512], err[512], path[1024];
    make_dir(dir, sizeof dir, "enospc");
    fp_take_header h;
    tt_header(&h, "E");

    /* No room for the header: start fails, no file is left behind. */
    atomic_store(&enospc_budget, 100);
    fp_take_recorder *rec;
    assert_int_equal(fp_take_recorder_start(dir, &h, NULL, &rec, err, sizeof err), -ENOSPC);
    atomic_store(&enospc_budget, -1);
    assert_non_null(strstr(err, "E_T001.fptake"));
    assert_non_null(strstr(err, "No space left on device"));
    snprintf(path, sizeof path, "%s/E_T001.fptake", dir);
    assert_int_equal(access(path, F_OK), -1);

    /* Room for the header and some chunks: the take stops cleanly at the full disk. */
    atomic_store(&enospc_budget, 60000);
    fp_take_recorder_options o = {.writer = {.chunk_frames = 5}};
    if (fp_take_recorder_start(dir, &h, &o, &rec, err, sizeof err)) fail_msg("%s", err);
    snprintf(path, sizeof path, "%s", fp_take_recorder_path(rec));
    uint64_t i = 0;
    fp_take_recorder_status st;
    for (; i < 100000; i++) {
        tt_frame t;
        tt_make(&t, i, 1);
        fp_take_recorder_push(rec, &t.f);
        fp_take_recorder_status_get(rec, &st);
        if (st.stopped) break;
        usleep(200);
    }
    assert_true(st.stopped);
    assert_int_equal(st.error, -ENOSPC);
    assert_non_null(strstr(fp_take_recorder_error(rec), "No space left on device"));
    tt_frame t;
    tt_make(&t, i + 1, 1);
    assert_false(fp_take_recorder_push(rec, &t.f));   /* refused after the error, no block */
    int rc = fp_take_recorder_close(&rec, &st, err, sizeof err);
    atomic_store(&enospc_budget, -1);
    assert_int_equal(rc, -ENOSPC);
    assert_non_null(strstr(err, "chunk at byte "));
    print_message("# ENOSPC: %s (%llu frames on disk, %llu refused)\n", err,
                  (unsigned long long)st.written, (unsigned long long)st.dropped);
    /* What is on disk is whole: no cut, no TAIL, every written frame readable. */
    fp_take_reader *r;
    if (fp_take_reader_open(path, &r, err, sizeof err)) fail_msg("%s", err);
    const fp_take_summary *s = fp_take_reader_summary(r);
    assert_false(s->cut);
    assert_false(s->complete);
    assert_true(s->frames > 0);
    assert_int_equal(s->frames, st.written);   /* (in chunks of what the recorder took at
                                                  a time, 5 frames at most: no multiple) */
    assert_int_equal(st.written + st.dropped, i + 2);   /* every frame counted once */
    assert_int_equal(check_frames(r), s->frames);
    fp_take_reader_close(&r);
    rm_rf(dir);
}

/* A cut says what it leaves unplayed: a byte flipped in the first FRMS chunk of a take of 12
 * frames in chunks of 4 plays none, and the warning counts the 8 frames in the whole chunks
 * past the damage and the end chunk's 12 (before: only "cut at byte N", the rest unsaid). A
 * file cut short (a kill -9) has nothing whole past it. */
static void test_cut_says_what_is_lost(void **state)
{
    (void)state;
    char dir[512], path[1024], err[512];
    make_dir(dir, sizeof dir, "lost");
    write_take(dir, "L", 12, 4, path, sizeof path);
    size_t n;
    uint8_t *b = slurp(path, &n);
    uint64_t starts[16];
    uint32_t frames[16];
    char types[16][5];
    size_t nc = chunk_starts(b, n, starts, frames, types, 16);
    assert_int_equal(nc, 5); /* HEAD, 3 x FRMS, TAIL */
    b[starts[1] + 40] ^= 0x20;
    fp_take_reader *r;
    if (fp_take_reader_open_memory(b, n, "l.fptake", &r, err, sizeof err)) fail_msg("%s", err);
    const fp_take_summary *s = fp_take_reader_summary(r);
    assert_true(s->cut);
    assert_int_equal(s->frames, 0);
    assert_int_equal(s->after_bytes, n - starts[1]);
    assert_int_equal(s->after_frames, 8);
    assert_int_equal(s->after_total, 12);
    char expect[160];
    snprintf(expect, sizeof expect, "; the %zu bytes from there are not read: 8 frames in whole "
             "chunks past the damage, of the 12 the end chunk counts", n - (size_t)starts[1]);
    if (!strstr(fp_take_reader_warning(r), expect)) fail_msg("%s", fp_take_reader_warning(r));
    fp_take_reader_close(&r);
    b[starts[1] + 40] ^= 0x20; /* whole again, then cut short inside the third FRMS chunk */
    if (fp_take_reader_open_memory(b, (size_t)starts[3] + 7, "l.fptake", &r, err, sizeof err))
        fail_msg("%s", err);
    s = fp_take_reader_summary(r);
    assert_int_equal(s->frames, 8);
    assert_int_equal(s->after_bytes, 7);
    assert_int_equal(s->after_frames, 0);
    assert_int_equal(s->after_total, 0);
    assert_non_null(strstr(fp_take_reader_warning(r), "; the 7 bytes from there are not read: 0 frames"));
    fp_take_reader_close(&r);
    free(b);
    rm_rf(dir);
}

/* The take's folder removed while it records (a clean-up script, a stage hand's rm -rf):
 * writes to the unlinked file all succeed, so the take used to close "ok" with every frame
 * counted, and vanish. The recorder stops at the next chunk with -ENOENT naming the file. */
static void test_folder_removed(void **state)
{
    (void)state;
    char dir[512], err[512];
    make_dir(dir, sizeof dir, "removed");
    fp_take_header h;
    tt_header(&h, "R");
    fp_take_recorder_options o = {.writer = {.chunk_frames = 5}};
    fp_take_recorder *rec;
    if (fp_take_recorder_start(dir, &h, &o, &rec, err, sizeof err)) fail_msg("%s", err);
    uint64_t i = 0;
    for (; i < 12; i++) {
        tt_frame t;
        tt_make(&t, i, 1);
        assert_true(fp_take_recorder_push(rec, &t.f));
    }
    rm_rf(dir);
    rmdir(dir);
    fp_take_recorder_status st;
    for (; i < 100000; i++) {
        tt_frame t;
        tt_make(&t, i, 1);
        fp_take_recorder_push(rec, &t.f);
        fp_take_recorder_status_get(rec, &st);
        if (st.stopped) break;
        usleep(200);
    }
    assert_true(st.stopped);   /* (before: never, the frames went to a file with no name) */
    assert_int_equal(st.error, -ENOENT);
    assert_non_null(strstr(fp_take_recorder_error(rec), "R_T001.fptake"));
    assert_non_null(strstr(fp_take_recorder_error(rec), "deleted while recording"));
    assert_int_equal(fp_take_recorder_close(&rec, &st, err, sizeof err), -ENOENT);
    assert_non_null(strstr(err, "deleted while recording"));
}

/* The writer alone: the file unlinked between chunks fails the next flush, and the close. */
static void test_file_unlinked(void **state)
{
    (void)state;
    char dir[512], err[512];
    make_dir(dir, sizeof dir, "unlinked");
    fp_take_header h;
    tt_header(&h, "U");
    fp_take_writer_options o = {.chunk_frames = 4, .no_sync = true};
    fp_take_writer *w;
    if (fp_take_writer_create(dir, &h, &o, &w, err, sizeof err)) fail_msg("%s", err);
    tt_frame t;
    for (uint64_t i = 0; i < 4; i++) {
        tt_make(&t, i, 1);
        if (fp_take_writer_add(w, &t.f, err, sizeof err)) fail_msg("%s", err);
    }
    assert_int_equal(unlink(fp_take_writer_path(w)), 0);
    tt_make(&t, 4, 1);
    assert_int_equal(fp_take_writer_add(w, &t.f, err, sizeof err), 0);   /* (buffered) */
    assert_int_equal(fp_take_writer_flush(w, err, sizeof err), -ENOENT);
    assert_non_null(strstr(err, "U_T001.fptake: the file was deleted while recording"));
    assert_int_equal(fp_take_writer_close(&w, 0, 0, err, sizeof err), -ENOENT);
    rm_rf(dir);
    rmdir(dir);
}

/* ---- listing ------------------------------------------------------------------------ */

static void test_list(void **state)
{
    (void)state;
    char dir[512], err[512], p[1100], path[1024];
    make_dir(dir, sizeof dir, "list");
    write_take(dir, "B", 120, 30, path, sizeof path);
    write_take(dir, "A", 61, 30, path, sizeof path);
    write_take(dir, "A", 10, 30, path, sizeof path);
    snprintf(p, sizeof p, "%s/Z_T001.fptake", dir);
    FILE *f = fopen(p, "wb");
    fputs("garbage", f);
    fclose(f);
    snprintf(p, sizeof p, "%s/notes.txt", dir);
    fclose(fopen(p, "wb"));
    fp_take_info *v;
    size_t n;
    assert_int_equal(fp_take_list(dir, &v, &n, err, sizeof err), 0);
    assert_int_equal(n, 4);
    assert_string_equal(v[0].slate, "A");
    assert_int_equal(v[0].take, 1);
    assert_int_equal(v[0].frames, 61);
    /* Frames 0..60 at 16666667 ns: 1.000000020 s from the origin = 60 frames at 60 fps. */
    assert_true(fabs(v[0].duration_s - 60 * 0.016666667) < 1e-9);
    char tc[32];
    fp_timecode_format(&v[0].timecode_in, tc, sizeof tc);
    assert_string_equal(tc, "10:04:31:12");
    fp_timecode_format(&v[0].timecode_out, tc, sizeof tc);
    assert_string_equal(tc, "10:04:32:12");
    assert_string_equal(v[0].mapping, "anchored");
    assert_string_equal(v[0].mesh, "../shared/data/faces/ict/neutral.obj");
    assert_int_equal(v[0].rating, 4);
    assert_true(v[0].complete);
    assert_int_equal(v[1].take, 2);
    assert_int_equal(v[1].frames, 10);
    assert_string_equal(v[2].slate, "B");
    assert_int_equal(v[2].frames, 120);
    assert_string_equal(v[3].slate, "Z");
    assert_int_equal(v[3].take, 1);
    assert_int_equal(v[3].error, -EBADMSG);
    assert_non_null(strstr(v[3].message, "byte 0"));
    free(v);
    snprintf(p, sizeof p, "%s/nope", dir);
    assert_int_equal(fp_take_list(p, &v, &n, err, sizeof err), -ENOENT);
    rm_rf(dir);
}

/* A header's frame rate outside 1..10000 fps is refused by the writer (-EINVAL) and by the
 * reader (-EBADMSG: 2^31 fps made timecodes like 15:37:04:1109533224). */
static void test_rate_range(void **state)
{
    (void)state;
    char dir[512], err[512];
    make_dir(dir, sizeof dir, "rate");
    fp_take_header h;
    tt_header(&h, "R");
    fp_take_writer *w;
    fp_take_writer_options o = {.no_sync = true};
    h.rate = (fp_take_rate){10001, 1};
    assert_int_equal(fp_take_writer_create(dir, &h, &o, &w, err, sizeof err), -EINVAL);
    assert_non_null(strstr(err, "frame rate"));
    h.rate = (fp_take_rate){10000, 1}; /* the fastest allowed, then patched past it */
    assert_int_equal(fp_take_writer_create(dir, &h, &o, &w, err, sizeof err), 0);
    char path[1024];
    snprintf(path, sizeof path, "%s", fp_take_writer_path(w));
    assert_int_equal(fp_take_writer_close(&w, 0, 0, err, sizeof err), 0);
    size_t n;
    uint8_t *b = slurp(path, &n);
    uint64_t starts[16];
    uint32_t frames[16];
    char types[16][5];
    chunk_starts(b, n, starts, frames, types, 16);
    assert_string_equal(types[0], "HEAD");
    uint8_t *at = memmem(b, n, "\"num\":10000", 11);
    assert_non_null(at);
    memcpy(at + 6, "99999", 5);
    rechunk(b, starts[0]);
    fp_take_reader *r;
    assert_int_equal(fp_take_reader_open_memory(b, n, "r.fptake", &r, err, sizeof err), -EBADMSG);
    assert_non_null(strstr(err, "frame_rate"));
    memcpy(at + 6, "10000", 5); /* and back: it reads */
    rechunk(b, starts[0]);
    assert_int_equal(fp_take_reader_open_memory(b, n, "r.fptake", &r, err, sizeof err), 0);
    fp_take_reader_close(&r);
    free(b);
    rm_rf(dir);
}

/* Timecode out follows frame times from the origin. */
static void test_timecode_out(void **state)
{
    (void)state;
    char dir[512], err[512];
    make_dir(dir, sizeof dir, "tcout");
    fp_take_header h;
    tt_header(&h, "O");
    h.time_origin_ns = 0;
    h.rate = (fp_take_rate){30000, 1001};
    char tcerr[128];
    assert_int_equal(fp_timecode_parse("00:00:59;28", h.rate, &h.timecode_in, tcerr, sizeof tcerr), 0);
    fp_take_writer *w;
    fp_take_writer_options o = {.no_sync = true};
    assert_int_equal(fp_take_writer_create(dir, &h, &o, &w, err, sizeof err), 0);
    char path[1024];
    snprintf(path, sizeof path, "%s", fp_take_writer_path(w));
    tt_frame t;
    tt_make(&t, 0, 0);
    t.f.time_ns = 0;
    assert_int_equal(fp_take_writer_add(w, &t.f, err, sizeof err), 0);
    t.f.time_ns = 100100000;   /* 0.1001 s = 3 frames at 29.97: 00:00:59;28 + 3 = 00:01:00;03 */
    assert_int_equal(fp_take_writer_add(w, &t.f, err, sizeof err), 0);
    assert_int_equal(fp_take_writer_close(&w, 0, 0, err, sizeof err), 0);
    fp_take_reader *r;
    assert_int_equal(fp_take_reader_open(path, &r, err, sizeof err), 0);
    char tc[32];
    fp_timecode_format(&fp_take_reader_summary(r)->timecode_out, tc, sizeof tc);
    assert_string_equal(tc, "00:01:00;03");
    assert_true(fp_take_reader_header(r)->timecode_in.drop);
    fp_take_reader_close(&r);
    rm_rf(dir);
}

/* FP_TAKE_WRITE_CORPUS=DIR: write the fuzz seeds (small valid takes) there. */
static void write_corpus(const char *out)
{
    char dir[512], path[1024];
    make_dir(dir, sizeof dir, "corpus");
    write_take(dir, "seed", 3, 2, path, sizeof path);
    write_take(dir, "seed", 1, 1, path, sizeof path);
    write_take(dir, "seed", 6, 4, path, sizeof path);
    char cmd[2048];
    snprintf(cmd, sizeof cmd, "mkdir -p '%s' && cp '%s'/*.fptake '%s'/", out, dir, out);
    if (system(cmd)) fail_msg("%s failed", cmd);
    rm_rf(dir);
}

static int setup(void **state)
{
    (void)state;
    snprintf(tmp_root, sizeof tmp_root, "/tmp/fp-take-test-XXXXXX");
    if (!mkdtemp(tmp_root)) return -1;
    return 0;
}

static int teardown(void **state)
{
    (void)state;
    rm_rf(tmp_root);
    return 0;
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_timecode_values),
        cmocka_unit_test(test_timecode_roundtrip_and_errors),
        cmocka_unit_test(test_roundtrip_writer),
        cmocka_unit_test(test_reach_roundtrip),
        cmocka_unit_test(test_roundtrip_recorder),
        cmocka_unit_test(test_recorder_drops),
        cmocka_unit_test(test_sigkill_mid_take),
        cmocka_unit_test(test_truncated_every_offset),
        cmocka_unit_test(test_frames_out_of_order),
        cmocka_unit_test(test_frames_chunk_missing),
        cmocka_unit_test(test_random_flips),
        cmocka_unit_test(test_bad_files),
        cmocka_unit_test(test_bad_header),
        cmocka_unit_test(test_event_source),
        cmocka_unit_test(test_not_finite),
        cmocka_unit_test(test_numbering),
        cmocka_unit_test(test_enospc),
        cmocka_unit_test(test_folder_removed),
        cmocka_unit_test(test_cut_says_what_is_lost),
        cmocka_unit_test(test_file_unlinked),
        cmocka_unit_test(test_list),
        cmocka_unit_test(test_timecode_out),
        cmocka_unit_test(test_rate_range),
    };
    const char *corpus = getenv("FP_TAKE_WRITE_CORPUS");
    if (corpus) {
        setup(NULL);
        write_corpus(corpus);
        teardown(NULL);
        return 0;
    }
    return cmocka_run_group_tests(tests, setup, teardown);
}
