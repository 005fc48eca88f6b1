/* A CyberGlove session recorded by the host (record=FILE on the input's SPEC, the
 * event-log format of docs/eventlog.md) and performed again through input-replay gives
 * the same joint angles, bit for bit, in the same order. */
#define _GNU_SOURCE
#include "fp_plugin_host.h"
#include "fp_test_support.h"
#include "gloveemu.h"

#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>
#include <cmocka.h>

#define WANT 200

static void test_record_and_replay(void **state)
{
    (void)state;
    char tmp[] = "/tmp/fp-glove-rec-XXXXXX", rec[128], csv[4200], err[2048], spec[4400];
    assert_non_null(mkdtemp(tmp));
    snprintf(rec, sizeof rec, "%s/glove.log", tmp);
    snprintf(csv, sizeof csv, "%s/hands/leap-motion/grab_cyberglove_like_angles_deg.csv", fp_test_data_dir());
    fp_gloveemu_options o = {0};
    o.recording = csv;
    o.rate_hz = 400;
    o.loop = true;
    fp_gloveemu *e = NULL;
    int rc = fp_gloveemu_create(&o, &e, err, sizeof err);
    if (rc) fprintf(stderr, "%s\n", err);
    assert_int_equal(rc, 0);
    char pts[256];
    fp_gloveemu_slave_path(e, pts, sizeof pts);

    const fp_plugin_path *path = fp_test_plugin_path();
    fp_input_instance in;
    snprintf(spec, sizeof spec, "cyberglove:%s,record=%s", pts, rec);
    rc = fp_input_instance_open(&in, path, spec, 0, err, sizeof err);
    if (rc) fprintf(stderr, "%s\n", err);
    assert_int_equal(rc, 0);
    assert_int_equal(fp_input_instance_start(&in, err, sizeof err), 0);
    static fp_event_joint_angles live[WANT];
    int n = 0;
    int64_t deadline = fp_now_ns() + 30LL * 1000000000LL;
    while (n < WANT && fp_now_ns() < deadline) {
        fp_event ev;
        if (!fp_input_instance_poll(&in, &ev)) { fp_test_nap_ms(2); continue; }
        if (ev.header.type == FP_EVENT_JOINT_ANGLES) live[n++] = ev.angles;
    }
    assert_int_equal(n, WANT);
    fp_input_instance_close(&in); /* stops the glove and closes the log */
    fp_gloveemu_destroy(&e);

    /* Perform it again from the log. */
    snprintf(spec, sizeof spec, "replay:%s,fast=1", rec);
    rc = fp_input_instance_open(&in, path, spec, 0, err, sizeof err);
    if (rc) fprintf(stderr, "%s\n", err);
    assert_int_equal(rc, 0);
    assert_int_equal(fp_input_instance_start(&in, err, sizeof err), 0);
    int m = 0;
    bool ended = false;
    deadline = fp_now_ns() + 30LL * 1000000000LL;
    while (!ended && fp_now_ns() < deadline) {
        fp_event ev;
        if (!fp_input_instance_poll(&in, &ev)) { fp_test_nap_ms(2); continue; }
        if (ev.header.type == FP_EVENT_STATUS && ev.status.code == FP_STATUS_END_OF_STREAM) ended = true;
        if (ev.header.type != FP_EVENT_JOINT_ANGLES || m >= WANT) continue;
        assert_int_equal(ev.angles.valid, live[m].valid);
        assert_int_equal(ev.header.hand, live[m].header.hand);
        assert_memory_equal(ev.angles.radians, live[m].radians, sizeof live[m].radians);
        m++;
    }
    assert_true(ended);
    assert_true(m >= WANT); /* everything delivered live is in the log */
    fp_input_instance_close(&in);
    unlink(rec);
    rmdir(tmp);
}

int main(void)
{
    const struct CMUnitTest tests[] = {cmocka_unit_test(test_record_and_replay)};
    return cmocka_run_group_tests(tests, NULL, NULL);
}
