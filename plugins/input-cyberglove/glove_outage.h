/*
 * glove_outage.h: how the CyberGlove input says an outage, pure (no fd, no thread, no host):
 * the loss once, a summary 10 s after it and every minute after that, the return once
 * (docs/cyberglove.md, "While performing"). Private to plugins/input-cyberglove;
 * tests/cyberglove/test_glove_outage.c drives it with made-up times.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 *
 * An outage runs from the first attempt to reopen the port (or to probe it again) until the
 * glove answers a probe. The caller says what these functions ask it to say: a DISCONNECTED
 * status for the loss (the session says it, one line), a warning line for the summary, its
 * CONNECTED line with the return's suffix. Each attempt stays a RECONNECTING status (an
 * event for the HUD and `monitor`, not a line).
 *
 * Thread rules: one outage per glove, on its input thread. No allocation, no errors.
 */
#ifndef FP_GLOVE_OUTAGE_H
#define FP_GLOVE_OUTAGE_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

/** The first summary this long after an outage starts (ns, 10 s), then every ..._EVERY_NS. */
#define FPG_OUTAGE_FIRST_SAY_NS 10000000000LL
#define FPG_OUTAGE_SAY_EVERY_NS 60000000000LL

/** Zero-initialised: the glove not up yet, no outage. */
typedef struct fpg_outage {
    int64_t since_ns;  /* the outage's first attempt (host clock, ns); 0: none */
    int64_t say_ns;    /* when the next summary is due */
    unsigned tries;    /* attempts made in this outage */
    bool was_up;       /* the glove answered before this outage */
    bool loss_said;    /* the loss of this outage was said (a DISCONNECTED) */
    char last[160];    /* the last reason an attempt failed, "" none */
} fpg_outage;

/** The connection was lost for `why` (the caller says it, as a DISCONNECTED): the outage's
 *  loss, said; why kept as the last reason. */
void fpg_outage_lost(fpg_outage *o, const char *why);

/** Before an attempt at t_ns (host clock): starts the outage at the first; where a summary is
 *  due, writes it into line (len bytes: "still no answer from PATH after N s, N tries
 *  (last: WHY)") and returns true: the caller logs it as a warning. */
bool fpg_outage_attempt(fpg_outage *o, int64_t t_ns, const char *path, char *line, size_t len);

/** How an attempt that failed for `why` is said: 2, as the loss (a DISCONNECTED: no loss was
 *  said in this outage, e.g. the glove never answered since start); 1, a reason other than
 *  the last (a RECONNECTING status for the HUD, not a line); 0, the same as the last
 *  (nothing). why is kept as the last reason. */
int fpg_outage_failed(fpg_outage *o, const char *why);

/** The glove answered a probe at t_ns: the CONNECTED line's suffix into buf (len bytes;
 *  "; back after 13.1 s, 9 tries", "; answered after ..." where it had never answered
 *  before, "" where there was no outage); the outage ends. */
void fpg_outage_up(fpg_outage *o, int64_t t_ns, char *buf, size_t len);

/** The silence timeout's text where bytes came but formed no record (records of another
 *  length than the probe's answers make: a timestamp or status byte ?D or ?U did not say, a
 *  ?S or ?N that disagrees with the records, or another baud), into why (len bytes): said
 *  as such, not as a glove that stopped answering. bits 8 or 16; timeout_ms the timeout;
 *  noise the bytes skipped; expected the probe's 8-bit record length, seen the length the
 *  records have on the wire (fpg_lenmeter; 0 unknown): where known and not the expected,
 *  "records of SEEN bytes, expected EXPECTED (...)", the same text each time. */
void fpg_noise_text(char *why, size_t len, int bits, int timeout_ms, uint64_t noise, int expected,
                    int seen);

#endif
