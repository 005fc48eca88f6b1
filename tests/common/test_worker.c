/* test_worker.c: fp_worker (core/common/fp_worker.h), the thread that spins, then parks:
 *  - it parks until woken; each wake's published work is seen by a poll, run once;
 *  - after its last work it polls for idle_ns, then parks (awake / asleep in pairs), and a
 *    wake that came while it polled makes it poll once more unless a poll served it;
 *  - its hooks: enter and leave once, on the thread; destroy joins a parked or polling one.
 * Waits are generous (a loaded 2-core machine may hold the thread off its core). */
#define _POSIX_C_SOURCE 200809L /* nanosleep */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include <stdatomic.h>
#include <time.h>

#include "fp_clock.h"
#include "fp_worker.h"

typedef struct probe {
    atomic_uint posted, ran;      /* publish's calls; the last wake whose work a poll ran
                                     (work is numbered by its wake, as the contact guard's jobs) */
    atomic_uint enters, leaves, awakes, asleeps, polls;
    atomic_uint unpublished;      /* polls that saw a wake's number before its publish */
    bool serve;                   /* polls say fp_worker_served for the wake they ran */
    atomic_uint last_wake;
} probe;

static bool poll_fn(void *u, fp_worker *w)
{
    probe *p = u;
    atomic_fetch_add(&p->polls, 1);
    uint32_t g = fp_worker_wakes(w);
    if (atomic_load(&p->ran) == g) return false;
    if (atomic_load(&p->posted) < g) /* (counted: no assert off the test's thread) */
        atomic_fetch_add(&p->unpublished, 1);
    if (p->serve) fp_worker_served(w, g);
    atomic_store(&p->ran, g);
    return true;
}
static void enter(void *u) { atomic_fetch_add(&((probe *)u)->enters, 1); }
static void leave(void *u) { atomic_fetch_add(&((probe *)u)->leaves, 1); }
static void awake(void *u) { atomic_fetch_add(&((probe *)u)->awakes, 1); }
static void asleep(void *u) { atomic_fetch_add(&((probe *)u)->asleeps, 1); }
static void publish(void *arg, uint32_t wake)
{
    probe *p = arg;
    atomic_store(&p->last_wake, wake);
    atomic_fetch_add(&p->posted, 1);
}

static void nap_ms(int ms)
{
    struct timespec t = {ms / 1000, (long)(ms % 1000) * 1000000L};
    nanosleep(&t, NULL);
}

/* waits up to 10 s for *v to reach want */
static bool wait_for(atomic_uint *v, unsigned want)
{
    for (int64_t t0 = fp_now_ns(); fp_now_ns() - t0 < 10000000000LL; nap_ms(1))
        if (atomic_load(v) >= want) return true;
    return atomic_load(v) >= want;
}

static fp_worker *make(probe *p, bool serve, int64_t idle_ns)
{
    *p = (probe){0};
    p->serve = serve;
    fp_worker_spec sp = {.poll = poll_fn, .user = p, .idle_ns = idle_ns, .yield_ns = 0, .pauses = 4,
                         .enter = enter, .leave = leave, .awake = awake, .asleep = asleep};
    fp_worker *w = NULL;
    assert_int_equal(fp_worker_create(&sp, &w), 0);
    assert_non_null(w);
    return w;
}

/* parked until the first wake; the work is run; it parks again after its idle time */
static void test_wake_run_park(void **state)
{
    (void)state;
    probe p;
    fp_worker *w = make(&p, true, 20000000);
    assert_true(wait_for(&p.enters, 1));
    nap_ms(30);
    assert_int_equal(atomic_load(&p.polls), 0); /* parked: no poll before a wake */
    assert_int_equal(fp_worker_wake(w, publish, &p), 1);
    assert_int_equal(atomic_load(&p.last_wake), 1);
    assert_true(wait_for(&p.ran, 1));
    assert_true(wait_for(&p.asleeps, 1)); /* parked after idle_ns */
    assert_int_equal(atomic_load(&p.awakes), 1);
    unsigned polls = atomic_load(&p.polls);
    nap_ms(50);
    assert_int_equal(atomic_load(&p.polls), polls); /* parked: no polls */
    assert_int_equal(fp_worker_wake(w, publish, &p), 2);
    assert_true(wait_for(&p.ran, 2));
    fp_worker_destroy(&w); /* (polling or parked) */
    assert_null(w);
    assert_int_equal(atomic_load(&p.leaves), 1);
    assert_int_equal(atomic_load(&p.enters), 1);
    assert_int_equal(atomic_load(&p.awakes), atomic_load(&p.asleeps));
    assert_int_equal(atomic_load(&p.unpublished), 0);
    fp_worker_destroy(&w); /* NULL: nothing */
    fp_worker_destroy(NULL);
}

/* wakes while it polls: served, it parks after one idle time; not served, it polls once more
 * (a wake is never lost) */
static void test_wakes_while_polling(void **state)
{
    (void)state;
    for (int serve = 0; serve < 2; serve++) {
        probe p;
        fp_worker *w = make(&p, serve, 300000000); /* 0.3 s: the wakes below come within it */
        fp_worker_wake(w, publish, &p);
        assert_true(wait_for(&p.ran, 1));
        for (unsigned i = 2; i <= 5; i++) { /* while it polls (each run restarts its idle time) */
            fp_worker_wake(w, publish, &p);
            assert_true(wait_for(&p.ran, i));
        }
        assert_true(wait_for(&p.asleeps, 1));
        nap_ms(700); /* (a second round would be over by now: 0.3 s) */
        assert_int_equal(atomic_load(&p.awakes), serve ? 1 : 2);
        assert_true(wait_for(&p.asleeps, atomic_load(&p.awakes)));
        fp_worker_destroy(&w);
        assert_int_equal(atomic_load(&p.ran), 5);
        assert_int_equal(atomic_load(&p.unpublished), 0);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_wake_run_park),
        cmocka_unit_test(test_wakes_while_polling),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
