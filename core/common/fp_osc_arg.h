/*
 * fp_osc_arg.h: an OSC message's numeric arguments as senders type them, for the two places
 * that read OSC (plugins/input-osc, core/link's --control): 'f' (float32), 'd' (float64),
 * 'i' (int32) or 'h' (int64); Node's node-osc, for one, types a whole number as an int.
 *
 * liblo's argv points into the message at 4-byte alignment while lo_arg (a union with 64-bit
 * members) asks for 8, so a value is read through memcpy, never through the union
 * (tests/fuzz/fuzz_osc and fuzz_control found the misaligned access). `arg` is a liblo
 * argv[i]; no errors (a type that is not a number reads as 0); pure, any thread.
 */
#ifndef FP_OSC_ARG_H
#define FP_OSC_ARG_H

#include <stdbool.h>
#include <stdint.h>
#include <string.h>

/** A number's type tag: f, d, i or h. */
static inline bool fp_osc_number_type(char t) { return t == 'f' || t == 'd' || t == 'i' || t == 'h'; }

/** An integer's type tag: i or h. */
static inline bool fp_osc_integer_type(char t) { return t == 'i' || t == 'h'; }

/** The argument of type tag `t` at `arg` as a double (exact for f, d, i; h rounded beyond
 *  2^53); 0 for a type that is not a number. */
static inline double fp_osc_number(char t, const void *arg)
{
    switch (t) {
    case 'f': { float f; memcpy(&f, arg, sizeof f); return f; }
    case 'd': { double d; memcpy(&d, arg, sizeof d); return d; }
    case 'i': { int32_t i; memcpy(&i, arg, sizeof i); return i; }
    case 'h': { int64_t h; memcpy(&h, arg, sizeof h); return (double)h; }
    default: return 0;
    }
}

#endif
