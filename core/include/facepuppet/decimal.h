/*
 * facepuppet/decimal.h: the one syntax of a number, wherever facepuppet reads one from text:
 * command-line options, plugin keys (plugin_util.h's fp_parse_decimal builds on it), and the
 * data files (Leap CSVs, event logs, CyberGlove calibrations, OBJ/PLY/OFF/STL meshes); and
 * the whole numbers of integer options (fp_parse_whole).
 * Header-only (C and C++), no allocation, reentrant, [any-thread]; it needs no other facepuppet
 * header, so a library that reads files includes it without the plugin ABI.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#ifndef FACEPUPPET_DECIMAL_H
#define FACEPUPPET_DECIMAL_H

#include <stdbool.h>
#include <stddef.h>

/** A decimal: an optional sign, digits with at most one '.' (at least one digit: "5",
 *  "-0.5", ".5", "5."), then an optional exponent, 'e' or 'E', an optional sign and digits
 *  ("1e-3", "2E+2", "1e-05"). Returns the length of the longest such number at the start of v
 *  (0: none), so that a list ("1/2/3") or a field ("1.5,2") can be read number by number; a
 *  reader that took a token with strtod/strtof compares this length with what they read. Not
 *  what strtod also takes: leading blanks, hexadecimal ("0x10", "0x1p3"), "inf", "infinity",
 *  "nan". [any-thread], no allocation. */
static inline size_t fp_decimal_span(const char *v)
{
    if (!v) return 0;
    size_t i = (v[0] == '+' || v[0] == '-') ? 1 : 0, digits = 0;
    for (; v[i] >= '0' && v[i] <= '9'; i++) digits++;
    if (v[i] == '.')
        for (i++; v[i] >= '0' && v[i] <= '9'; i++) digits++;
    if (!digits) return 0;
    if (v[i] == 'e' || v[i] == 'E') {
        size_t j = i + 1 + (v[i + 1] == '+' || v[i + 1] == '-');
        if (v[j] >= '0' && v[j] <= '9') {
            while (v[j] >= '0' && v[j] <= '9') j++;
            i = j;
        }
    }
    return i;
}

/** A whole number, as an integer option reads one (a count, a size, a frame index): an
 *  optional '+' (as fp_decimal_span takes one) then decimal digits, the whole of v: no blanks
 *  (strtol skipped them), no '-' (strtoull wrapped it round), no '.', exponent or hexadecimal.
 *  true with *out where its value is at most max; false otherwise, the caller naming the
 *  option ("--frames must be a whole number > 0, got ' 5'"). [any-thread], no allocation. */
static inline bool fp_parse_whole(const char *v, unsigned long long max, unsigned long long *out)
{
    if (!v) return false;
    size_t i = v[0] == '+';
    if (!(v[i] >= '0' && v[i] <= '9')) return false;
    unsigned long long x = 0;
    for (; v[i] >= '0' && v[i] <= '9'; i++) {
        const unsigned d = (unsigned)(v[i] - '0');
        if (d > max || x > (max - d) / 10) return false; /* beyond max, never wrapped */
        x = x * 10 + d;
    }
    if (v[i]) return false;
    *out = x;
    return true;
}

#endif
