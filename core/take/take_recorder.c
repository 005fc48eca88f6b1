/* take_recorder.c: the take writer on its own thread, fed by the session thread through a
 * bounded lock-free single-producer single-consumer byte ring.
 *
 * Ring: `cap` bytes (a power of two), a producer position `head` and a consumer position
 * `tail` (byte counts since the start, never wrapped; head - tail <= cap). A slot is an
 * 8-byte slot header {u32 length, u32 kind} followed by the encoded frame record (the exact
 * bytes of docs/take-format.md), padded to 8 bytes. A record never wraps: when it does not
 * fit before the end of the buffer, a PAD slot fills the rest and the record starts at 0.
 * The producer writes the slot, then publishes head with a release store; the consumer reads
 * head with acquire, copies the record into its chunk, then publishes tail with release.
 */
#include "take_internal.h"

#include "fp_error.h"

#include <errno.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <time.h>

#define SLOT_HEAD 8u
#define SLOT_FRAME 1u
#define SLOT_PAD 2u

struct fp_take_recorder {
    /* producer side (session thread) */
    _Alignas(64) _Atomic uint64_t head;
    uint64_t tail_cache;
    _Atomic uint64_t pushed;
    _Atomic uint64_t dropped;
    /* consumer side (recorder thread) */
    _Alignas(64) _Atomic uint64_t tail;
    _Atomic uint64_t written;
    _Atomic uint64_t bytes;
    _Atomic int error;
    _Atomic bool stopped;
    _Atomic bool stop;
    /* shared, read-only after start */
    _Alignas(64) uint8_t *ring;
    size_t cap;
    double flush_s;
    fp_take_writer *w;
    char *path;
    uint32_t take;
    pthread_t thread;
    bool joined;
    char errmsg[512];
    fp_take_reach reach;   /* main thread: for the end chunk (fp_take_recorder_set_reach) */
};

void fp_take_recorder_set_reach(fp_take_recorder *rec, const fp_take_reach *reach)
{
    if (rec && reach) rec->reach = *reach;
}

static size_t pad8(size_t n) { return (n + 7) & ~(size_t)7; }

static double mono_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + (double)ts.tv_nsec * 1e-9;
}

bool fp_take_recorder_push(fp_take_recorder *rec, const fp_take_frame *frame)
{
    if (atomic_load_explicit(&rec->stopped, memory_order_relaxed)) goto drop;
    size_t n = fp_take_frame_size(frame);
    if (!n || n > rec->cap / 4) goto drop;
    size_t need = SLOT_HEAD + pad8(n);
    uint64_t head = atomic_load_explicit(&rec->head, memory_order_relaxed);
    size_t pos = (size_t)(head & (rec->cap - 1)), room = rec->cap - pos;
    size_t total = need <= room ? need : room + need;
    if (head + total - rec->tail_cache > rec->cap) {
        rec->tail_cache = atomic_load_explicit(&rec->tail, memory_order_acquire);
        if (head + total - rec->tail_cache > rec->cap) goto drop;
    }
    if (need > room) {   /* PAD to the end, the record at 0 */
        le_put32(rec->ring + pos, (uint32_t)(room - SLOT_HEAD));
        le_put32(rec->ring + pos + 4, SLOT_PAD);
        pos = 0;
    }
    le_put32(rec->ring + pos, (uint32_t)n);
    le_put32(rec->ring + pos + 4, SLOT_FRAME);
    fp_take_frame_encode(frame, rec->ring + pos + SLOT_HEAD, n);
    atomic_store_explicit(&rec->head, head + total, memory_order_release);
    atomic_fetch_add_explicit(&rec->pushed, 1, memory_order_relaxed);
    return true;
drop:
    atomic_fetch_add_explicit(&rec->dropped, 1, memory_order_relaxed);
    return false;
}

static void fail(fp_take_recorder *rec, int code, const char *msg)
{
    snprintf(rec->errmsg, sizeof rec->errmsg, "%s", msg);
    atomic_store_explicit(&rec->error, code, memory_order_release);
    atomic_store_explicit(&rec->stopped, true, memory_order_release);
}

/* Move every published record into the writer, and what it took into the file (one chunk,
 * a write(2): a process killed now keeps them; synced to disk later, recorder_main). Returns
 * 0 or the writer's error. */
static int drain(fp_take_recorder *rec)
{
    uint64_t head = atomic_load_explicit(&rec->head, memory_order_acquire);
    uint64_t tail = atomic_load_explicit(&rec->tail, memory_order_relaxed);
    char msg[512];
    while (tail != head) {
        size_t pos = (size_t)(tail & (rec->cap - 1));
        uint32_t len = le_get32(rec->ring + pos), kind = le_get32(rec->ring + pos + 4);
        if (kind == SLOT_FRAME) {
            int rc = fp_take_writer_add_encoded(rec->w, rec->ring + pos + SLOT_HEAD, len, msg,
                                                sizeof msg);
            if (rc) {
                fail(rec, rc, msg);
                return rc;
            }
        }
        tail += SLOT_HEAD + pad8(len);
        atomic_store_explicit(&rec->tail, tail, memory_order_release);
    }
    int rc = fp_take_writer_flush(rec->w, msg, sizeof msg);
    if (rc) fail(rec, rc, msg);
    return rc;
}

static void *recorder_main(void *arg)
{
    fp_take_recorder *rec = arg;
    double synced = mono_s();
    struct timespec nap = {0, 2000000};   /* 2 ms between looks at the ring */
    long nap_ns = (long)(rec->flush_s * 1e9 / 8);
    if (nap_ns < 1000000) nap_ns = 1000000;
    if (nap_ns < nap.tv_nsec) nap.tv_nsec = nap_ns;
    char msg[512];
    for (;;) {
        bool stopping = atomic_load_explicit(&rec->stop, memory_order_acquire);
        if (drain(rec)) break;
        if (mono_s() - synced >= rec->flush_s) { /* (to disk: a power cut loses less) */
            int rc = fp_take_writer_sync(rec->w, msg, sizeof msg);
            if (rc) {
                fail(rec, rc, msg);
                break;
            }
            synced = mono_s();
        }
        atomic_store_explicit(&rec->written, take_writer_frames(rec->w), memory_order_relaxed);
        atomic_store_explicit(&rec->bytes, take_writer_bytes(rec->w), memory_order_relaxed);
        if (stopping) break;   /* everything pushed before stop was drained above */
        nanosleep(&nap, NULL);
    }
    return NULL;
}

int fp_take_recorder_start(const char *dir, const fp_take_header *header,
                           const fp_take_recorder_options *opt, fp_take_recorder **out,
                           char *err, size_t errlen)
{
    *out = NULL;
    fp_take_recorder_options o = {0};
    if (opt) o = *opt;
    size_t want = o.ring_bytes ? o.ring_bytes : (size_t)8 << 20;
    if (want < 4096) want = 4096;
    size_t cap = 4096;
    while (cap < want) cap <<= 1;
    fp_take_recorder *rec = aligned_alloc(64, (sizeof *rec + 63) & ~(size_t)63);
    if (!rec) return fp_errorf(err, errlen, -ENOMEM, "take recorder: out of memory");
    memset(rec, 0, sizeof *rec);
    rec->cap = cap;
    rec->flush_s = o.flush_seconds > 0 ? o.flush_seconds : 0.25;
    rec->ring = malloc(cap);
    if (!rec->ring) {
        free(rec);
        return fp_errorf(err, errlen, -ENOMEM, "take recorder: out of memory for a %zu-byte ring", cap);
    }
    memset(rec->ring, 0, cap);   /* touch every page now, not on the session thread */
    o.writer.sync_later = true; /* (recorder_main syncs every flush_s) */
    int rc = fp_take_writer_create(dir, header, &o.writer, &rec->w, err, errlen);
    if (rc) {
        free(rec->ring);
        free(rec);
        return rc;
    }
    rec->path = strdup(fp_take_writer_path(rec->w));
    rec->take = fp_take_writer_take(rec->w);
    rc = rec->path ? pthread_create(&rec->thread, NULL, recorder_main, rec) : ENOMEM;
    if (rc) {
        char path[4096];
        snprintf(path, sizeof path, "%s", fp_take_writer_path(rec->w));
        fp_take_writer_close(&rec->w, 0, -rc, NULL, 0);
        remove(path);
        free(rec->path);
        free(rec->ring);
        free(rec);
        return fp_errorf(err, errlen, -rc, "take recorder: cannot start its thread: %s", strerror(rc));
    }
    *out = rec;
    return 0;
}

void fp_take_recorder_status_get(const fp_take_recorder *r, fp_take_recorder_status *st)
{
    fp_take_recorder *rec = (fp_take_recorder *)r;
    memset(st, 0, sizeof *st);
    st->pushed = atomic_load_explicit(&rec->pushed, memory_order_relaxed);
    st->dropped = atomic_load_explicit(&rec->dropped, memory_order_relaxed);
    st->written = atomic_load_explicit(&rec->written, memory_order_relaxed);
    st->bytes = atomic_load_explicit(&rec->bytes, memory_order_relaxed);
    st->error = atomic_load_explicit(&rec->error, memory_order_acquire);
    st->stopped = atomic_load_explicit(&rec->stopped, memory_order_acquire);
}

const char *fp_take_recorder_error(const fp_take_recorder *r)
{
    fp_take_recorder *rec = (fp_take_recorder *)r;
    return atomic_load_explicit(&rec->error, memory_order_acquire) ? rec->errmsg : "";
}

const char *fp_take_recorder_path(const fp_take_recorder *rec) { return rec->path; }
uint32_t fp_take_recorder_take(const fp_take_recorder *rec) { return rec->take; }

int fp_take_recorder_close(fp_take_recorder **rp, fp_take_recorder_status *st, char *err,
                           size_t errlen)
{
    fp_take_recorder *rec = rp ? *rp : NULL;
    if (!rec) return 0;
    *rp = NULL;
    atomic_store_explicit(&rec->stop, true, memory_order_release);
    pthread_join(rec->thread, NULL);
    int error = atomic_load_explicit(&rec->error, memory_order_acquire);
    /* Every frame offered is either on disk or dropped: refused by push, or lost after a
     * write error (still in the ring or in the chunk that failed). */
    uint64_t pushed = atomic_load(&rec->pushed), refused = atomic_load(&rec->dropped);
    uint64_t on_disk = take_writer_frames(rec->w);
    uint64_t will_be = on_disk + (error ? 0 : fp_take_writer_pending(rec->w));
    char msg[512] = "";
    fp_take_writer_set_reach(rec->w, &rec->reach); /* (the thread is joined: the writer is ours) */
    int rc = fp_take_writer_close(&rec->w, refused + pushed - will_be, error, msg, sizeof msg);
    if (!error && rc) {
        error = rc;
        fail(rec, rc, msg);
        will_be = on_disk;
    }
    atomic_store(&rec->written, will_be);
    atomic_store(&rec->dropped, refused + pushed - will_be);
    if (st) {
        fp_take_recorder_status_get(rec, st);
        st->stopped = true;
    }
    if (error) fp_errorf(err, errlen, error, "%s", rec->errmsg);
    free(rec->path);
    free(rec->ring);
    free(rec);
    return error;
}
