/*
 * test_glove_outage.c: how the CyberGlove input says an outage (plugins/input-cyberglove/
 * glove_outage.h), driven with made-up times: the loss once whatever the failures that
 * follow, a summary 10 s after the outage starts and every minute after that (with the last
 * reason), the return once with how long it took and how many tries.
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include <stdio.h>
#include <string.h>

#include "glove_outage.h"

#define S 1000000000LL

/* A glove that stops answering: the session's loss, then retries every 2 s for `secs` s
 * whose probes fail (the first for another reason than the loss); the lines said. */
static void test_silence_said_briefly(void **state)
{
    (void)state;
    fpg_outage o = {0};
    char line[400], back[64];
    fpg_outage_up(&o, 0, back, sizeof back); /* the first connection: no outage before */
    assert_string_equal(back, "");
    fpg_outage_lost(&o, "glove stopped answering (no record for 250 ms)");
    int losses = 0, events = 0, summaries = 0;
    int64_t t = 100 * S;
    for (int k = 0; t < 100 * S + 75 * S; k++, t += 2 * S) {
        if (fpg_outage_attempt(&o, t, "/dev/ttyUSB0", line, sizeof line)) {
            summaries++;
            if (summaries == 1) {
                /* due 10 s after the first attempt: said at the first attempt from then on */
                assert_string_equal(line, "still no answer from /dev/ttyUSB0 after 10 s, 5 tries "
                                          "(last: no answer to ?G)");
            }
        }
        int how = fpg_outage_failed(&o, "no answer to ?G");
        losses += how == 2;
        events += how == 1;
    }
    assert_int_equal(losses, 0);  /* the loss was said by the session (before: a second line) */
    assert_int_equal(events, 1);  /* the new reason once, as an event */
    assert_int_equal(summaries, 2); /* at 10 s and 70 s */
    fpg_outage_up(&o, t, back, sizeof back);
    assert_string_equal(back, "; back after 76.0 s, 38 tries");
    /* over: the next outage starts afresh */
    fpg_outage_lost(&o, "cable pulled (hang-up)");
    assert_false(fpg_outage_attempt(&o, t + S, "/dev/ttyUSB0", line, sizeof line));
    fpg_outage_up(&o, t + 3 * S, back, sizeof back);
    assert_string_equal(back, "; back after 2.0 s, 1 try");
}

/* A glove that never answered since start: the first failure is the loss, said once; the
 * first answer says "answered after". */
static void test_never_answered(void **state)
{
    (void)state;
    fpg_outage o = {0};
    char line[400], back[64];
    assert_int_equal(fpg_outage_failed(&o, "glove not plugged into its box (eg)"), 2);
    assert_false(fpg_outage_attempt(&o, 5 * S, "/dev/ttyUSB0", line, sizeof line));
    assert_int_equal(fpg_outage_failed(&o, "glove not plugged into its box (eg)"), 0);
    assert_false(fpg_outage_attempt(&o, 7 * S, "/dev/ttyUSB0", line, sizeof line));
    fpg_outage_up(&o, 8 * S, back, sizeof back);
    assert_string_equal(back, "; answered after 3.0 s, 2 tries");
}

/* A box whose records are another length than the probe's: both lengths named, the same text
 * whatever noise came (said once as the loss, the same reason after); unknown length or
 * 16-bit frames: the noise count. */
static void test_noise_text(void **state)
{
    (void)state;
    char a[200], b[200];
    fpg_noise_text(a, sizeof a, 8, 250, 546, 25, 21);
    assert_string_equal(a, "records of 21 bytes, expected 25 (?S/?N, ?D or ?U disagree with the records)");
    fpg_noise_text(b, sizeof b, 8, 250, 525, 25, 21);
    assert_string_equal(a, b);
    fpg_noise_text(a, sizeof a, 8, 3000, 4221, 25, 0);
    assert_string_equal(a, "no well-formed record in 3000 ms, 4221 bytes of line noise (expected 25-byte records)");
    fpg_noise_text(a, sizeof a, 16, 500, 77, 56, 30);
    assert_string_equal(a, "no well-formed 16-bit frame in 500 ms, 77 bytes of line noise");
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_silence_said_briefly),
        cmocka_unit_test(test_never_answered),
        cmocka_unit_test(test_noise_text),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
