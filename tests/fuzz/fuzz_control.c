/* fuzz_control.c: libFuzzer target for the control surface's message checks (core/link:
 * control_parse.c, the bytes any sender on the control port may send: bundles, nesting,
 * liblo's message parser, each address's type tags and ranges). The input is split at each
 * 0xFF 0xFE 0xFD 0xFC into datagrams handed to the packet walker as the network thread would;
 * every queued command must be one the frame loop can apply: a known kind, a valid slate, a
 * take number 1..999999, finite values in range, text NUL-terminated. The queue is drained
 * between datagrams (the frame loop). Seeds: tests/fuzz/corpus/fuzz_control. */
#define _GNU_SOURCE
#include "control_internal.h"
#include "fp_take.h"

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

static void check(const fp_control_cmd *c)
{
    if ((unsigned)c->kind >= FP_CTL_KINDS || !memchr(c->text, 0, sizeof c->text)) abort();
    if ((c->kind == FP_CTL_RECORD_START || c->kind == FP_CTL_SLATE) && c->has_text &&
        !fp_take_slate_valid(c->text))
        abort();
    if (c->has_take && (c->take < 1 || c->take > 999999)) abort();
    if (!isfinite(c->value)) abort(); /* (a radius out of range is answered: the range is the session's) */
    if (c->kind == FP_CTL_SEEK && c->value < 0) abort();
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    static fp_control *c;
    if (!c && !(c = calloc(1, sizeof *c))) return 0;
    static const uint8_t sep[4] = {0xFF, 0xFE, 0xFD, 0xFC};
    fp_control_cmd from = {0};
    for (size_t at = 0; at <= size;) {
        const uint8_t *end = size - at >= 4 ? memmem(data + at, size - at, sep, 4) : NULL;
        size_t n = end ? (size_t)(end - (data + at)) : size - at;
        if (n <= sizeof c->buf) {
            memcpy(c->buf, data + at, n);
            fp__control_packet(c, c->buf, n, &from);
        }
        fp_control_cmd cmd;
        while (fp_control_next(c, &cmd)) check(&cmd);
        at += n + 4;
    }
    return 0;
}
