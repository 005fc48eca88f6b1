/* The contact guard's worker: jobs of tasks that the caller and one worker thread claim one
 * at a time (a step's marking, a check's refit and walk, a carried round's carry, the
 * envelopes' re-centring between steps; fp_contact_set_threads). */
#define _POSIX_C_SOURCE 200809L /* sched_yield */
#include "contact_internal.h"
#include "fp_clock.h"
#include "fp_worker.h"

#include <errno.h>
#include <sched.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>

/* ---- the worker: a step's marking, and a check's refit and walk, on two threads ---- */

/* A job is a list of tasks that both threads claim one at a time (a CAS on next, which
 * carries the job's number, so a late worker claims nothing of a newer job). The caller
 * opens the job and adds its tasks while the worker may already run them (each task is
 * written before the count that publishes it; the worker waits for more while the caller
 * is filling); then the caller works too and waits only for a task the worker holds
 * (busy), never for a worker that has not started: a worker kept off its core costs
 * nothing but its share. Tasks read the shapes and the hierarchy and write their own lane
 * and, in the marking, the stamps (the same value from either thread; own triangles are
 * claimed by an exchange), in the refit their own subtree's triangles and nodes; the
 * caller's writes before a job are published by the job's number (release), the worker's
 * by busy's clearing. */
#define FP_POOL_IDLE_NS 20000000  /* the worker polls (yielding) this long for the next job */

typedef struct wtask {            /* a task: the marking's mark_range(x, y, z), the carry of
                                     mv[x .. y) (fpc_carry_range: its own vertices' carry
                                     written), the refit of
                                     node x (update_subtree), or the walk's node_self(x) (y ==
                                     FP_TRACK_NONE) or node_pairs(x, y) (z == 0) or its
                                     accept_range(x, y) (z == 1) */
    uint32_t x, y, z;
} wtask;

typedef struct pool {
    fp_worker *w;                 /* the thread (fp_worker.h); a job's number is its wake's */
    uint32_t gen;                 /* the newest job's number (written under the worker's lock,
                                     publish_job) */
    uint32_t seen;                /* the worker's: the last job it ran */
    _Atomic uint64_t next;        /* gen << 32 | the next task */
    atomic_uint ntask;            /* the job's tasks so far */
    atomic_bool filling;          /* the caller is still adding tasks to the job */
    atomic_int busy;              /* the worker may hold a task */
    fp_contact *c;                /* the job (written before its number is published) */
    int kind;
    bool record;                  /* the walk's: new pairs' vertices into the lanes' rec */
    const float *s, *ref;
    wtask *task;
    size_t cap_task;
    size_t ntask_max;             /* the open job's list: tasks beyond it run on the caller */
} pool;

/* The acceptance of the step's candidate s, ahead of its check's verdict, on the moved
 * vertices mv[x .. y): P's old positions into pv, P := s there, and those that now differ
 * from ref and are not in D_P into ln->mv (they join it). The walk reads s and ref, never
 * P, so its tasks may run beside these; a candidate that fails gets P back from pv. 0 or
 * -ENOMEM. */
static int accept_range(fp_contact *c, lane *ln, const float *s, const float *ref, uint32_t x, uint32_t y)
{
    struct track *k = c->tk;
    for (uint32_t i = x; i < y; i++) {
        uint32_t v = k->mv[i];
        float *pp = k->p + 3 * (size_t)v;
        memcpy(k->pv + 3 * (size_t)i, pp, 3 * sizeof(float));
        memcpy(pp, s + 3 * (size_t)v, 3 * sizeof(float));
        if (!k->in_dp[v] && vert_differs(s, ref, v) && push_u32(&ln->mv, &ln->nmv, &ln->cap_mv, v))
            return -ENOMEM;
    }
    return 0;
}

static void run_task(pool *p, lane *ln, const wtask *t)
{
    long r;
    if (ln->found < 0 || ln->flips < 0) return; /* out of memory: the job fails anyway */
    if (p->kind == FP_JOB_MARK) {
        if (fpc_mark_range(p->c, ln, p->s, t->x, t->y, t->z)) ln->flips = -ENOMEM;
    } else if (p->kind == FP_JOB_RECENTRE) {
        if (fpc_recentre(p->c)) ln->flips = -ENOMEM;
    } else if (p->kind == FP_JOB_CARRY) {
        fpc_carry_range(p->c, t->x, t->y);
    } else if (p->kind == FP_JOB_REFIT) {
        fpc_update_subtree(p->c, ln, p->s, p->ref, t->x, 0);
    } else if (t->z) {
        if (accept_range(p->c, ln, p->s, p->ref, t->x, t->y)) ln->found = -ENOMEM;
    } else {
        r = t->y == FP_TRACK_NONE ? fpc_node_self(p->c, ln, p->s, p->ref, t->x, p->record)
                                  : fpc_node_pairs(p->c, ln, p->s, p->ref, t->x, t->y, p->record);
        ln->found = r < 0 ? r : ln->found + r;
    }
}

/* claim and run job gen's tasks until none is left and none is coming */
static void run_tasks(pool *p, lane *ln, uint32_t gen)
{
    for (unsigned spins = 0;;) {
        uint64_t cur = atomic_load(&p->next);
        if ((uint32_t)(cur >> 32) != gen) return;
        if ((uint32_t)cur >= atomic_load(&p->ntask)) {
            if (!atomic_load(&p->filling)) {
                if ((uint32_t)cur >= atomic_load(&p->ntask)) return; /* (one added before) */
                continue;
            }
            if (++spins > 1024) sched_yield(); /* the caller is making the next task */
            else fp_cpu_pause();
            continue;
        }
        if (atomic_compare_exchange_weak(&p->next, &cur, cur + 1)) run_task(p, ln, &p->task[(uint32_t)cur]);
    }
}

/* The worker (fp_worker.h): parked until a job comes (a step's first is its marking), then
 * it polls for jobs, yielding its core between polls, until none has come for
 * FP_POOL_IDLE_NS: through a deformation at 60 frames a second it does not sleep between
 * frames. Waking it from a sleep took over a millisecond on a 2-core virtual machine, and
 * now and then a whole step: with a 3 ms poll it took no task in about 7% of the 1.7M
 * frames (contact p99 6.6 ms), with 20 ms in none (p99 4.7 ms). One poll: the newest job,
 * when it has not run it yet (its number is the wake's, so the jobs it ran are the wakes it
 * served). */
static bool pool_poll(void *user, fp_worker *w)
{
    pool *p = user;
    uint32_t g = fp_worker_wakes(w);
    if (g == p->seen) return false;
    p->seen = g;
    fp_worker_served(w, g);
    atomic_store(&p->busy, 1);
    run_tasks(p, &p->c->tk->lane[1], g);
    atomic_store(&p->busy, 0);
    return true;
}

void fpc_pool_free(pool *p)
{
    if (!p) return;
    fp_worker_destroy(&p->w);
    free(p->task);
    free(p);
}

/* c's worker, started on first use; NULL: one thread (fp_contact_set_threads 1, or no
 * thread could be made: the check runs on the caller's alone) */
pool *fpc_pool_get(fp_contact *c)
{
    struct track *k = c->tk;
    if (c->threads < 2) return NULL;
    if (k->pool) return k->pool;
    pool *p = calloc(1, sizeof *p);
    if (!p) return NULL;
    atomic_init(&p->next, 0);
    atomic_init(&p->ntask, 0);
    atomic_init(&p->busy, 0);
    p->c = c;
    /* polls with a yield between polls, no pause: a job's tasks come as the caller makes them */
    const fp_worker_spec spec = {.poll = pool_poll, .user = p, .idle_ns = FP_POOL_IDLE_NS,
                                 .yield_ns = 0, .pauses = 0};
    int rc = fp_worker_create(&spec, &p->w);
    if (rc) {
        free(p);
        if (rc != -ENOMEM) c->threads = 1; /* no thread could be made: not again every frame */
        return NULL;
    }
    k->pool = p;
    return p;
}

/* fp_worker_wake's publish: the job's number (the wake's) and its first task, before the
 * number reaches the worker's polls */
static void publish_job(void *arg, uint32_t wake)
{
    pool *p = arg;
    p->gen = wake;
    atomic_store(&p->next, (uint64_t)wake << 32);
}

/* Open a job of this kind on shape s (and ref): the worker may start on its tasks as the
 * caller adds them (add_task), then job_finish. The list holds a quarter of c's share_min
 * tasks, 16 to 1,024 (1,024 by default; 16 for the tests, which share every check, so that
 * their jobs go beyond it): a task beyond it runs on the caller's thread at once. 0 or
 * -ENOMEM. */
int fpc_job_open(fp_contact *c, pool *p, int kind, const float *s, const float *ref, bool record)
{
    size_t most = c->share_min / 4 < 16 ? 16 : c->share_min / 4 > 1024 ? 1024 : c->share_min / 4;
    if (reserve((void **)&p->task, &p->cap_task, most, sizeof *p->task)) return -ENOMEM;
    p->ntask_max = most;
    p->kind = kind;
    p->record = record;
    p->s = s;
    p->ref = ref;
    atomic_store(&p->ntask, 0);
    atomic_store(&p->filling, true);
    fp_worker_wake(p->w, publish_job, p);
    return 0;
}

/* a task (x, y) into the open job (written, then counted: the count publishes it), or run
 * on the caller's lane now when the list is full */
void fpc_add_task(fp_contact *c, pool *p, uint32_t x, uint32_t y, uint32_t z)
{
    wtask t = {x, y, z};
    uint32_t n = atomic_load_explicit(&p->ntask, memory_order_relaxed);
    if (n >= p->ntask_max) {
        run_task(p, &c->tk->lane[0], &t);
        return;
    }
    p->task[n] = t;
    atomic_store_explicit(&p->ntask, n + 1, memory_order_release);
}

/* the open job closed: a task not claimed yet is never run (a worker that wakes late claims
 * nothing while the next job's list is made); the caller waits for the one the worker
 * holds, if any */
static void job_close(fp_contact *c, pool *p)
{
    struct track *k = c->tk;
    atomic_store(&p->filling, false);
    atomic_store(&p->next, (uint64_t)p->gen << 32 | UINT32_MAX);
    if (!atomic_load(&p->busy)) return;
    int64_t w0 = fp_now_ns(); /* timed only when there is a wait */
    for (unsigned spins = 0; atomic_load(&p->busy); spins++)
        if (spins > 256) sched_yield(); /* the worker finishes its task */
    k->waited_ns += fp_now_ns() - w0;
}

/* the open job's tasks run on both threads to the last; the lanes' counts hold its results */
void fpc_job_finish(fp_contact *c, pool *p)
{
    atomic_store(&p->filling, false);
    run_tasks(p, &c->tk->lane[0], p->gen);
    job_close(c, p);
}

/* the lanes' sum of a job's results (found or flips), or -ENOMEM */
long fpc_lanes_sum(const struct track *k, bool flips)
{
    long sum = 0;
    for (int i = 0; i < FP_CONTACT_MAX_THREADS; i++) {
        long r = flips ? k->lane[i].flips : k->lane[i].found;
        if (r < 0) return r;
        sum += r;
    }
    return sum;
}

/* After an envelope step with moved triangles, with a worker (fp_contact_set_threads 2):
 * recentre posted as its job, not waited for; every later call on c that reads or writes
 * the track joins it first (bg_join). No worker (one thread, or none could be made): no
 * re-centring, the step's renewals as before. */
void fpc_bg_post(fp_contact *c)
{
    struct track *k = c->tk;
    if (k->tree || !k->nmt || c->threads < 2) return;
    pool *p = fpc_pool_get(c);
    if (!p) return;
    for (int i = 0; i < FP_CONTACT_MAX_THREADS; i++) k->lane[i].flips = k->lane[i].found = 0;
    if (fpc_job_open(c, p, FP_JOB_RECENTRE, k->p, NULL, false)) return;
    fpc_add_task(c, p, 0, 0, 0);
    atomic_store(&p->filling, false); /* the one task: the worker need not wait for more */
    k->bg = true;
}

/* The posted recentre finished, or dropped when the worker has not started it (a worker
 * woken from its sleep may take over a millisecond: the step then renews what its motion
 * needs, as without a worker, instead of waiting or re-centring here); out of memory in it:
 * the track is broken (the next call returns -ENOMEM) */
void fpc_bg_join(fp_contact *c)
{
    struct track *k = c ? c->tk : NULL;
    if (!k || !k->bg) return;
    k->bg = false;
    job_close(c, k->pool); /* not started: dropped; started: waited for */
    if (fpc_lanes_sum(k, true) < 0) k->broken = true;
}

