/*
 * facepuppet/decimal.h: the one syntax of a number, wherever facepuppet reads one from text:
 * command-line options, plugin keys (plugin_util.h's fp_parse_decimal builds on it), and the
 * data files (Leap CSVs, event logs, CyberGlove calibrations, OBJ/PLY/OFF/STL meshes).
 * Header-only (C and C++), no allocation, reentrant, [any-thread]; it needs no other facepuppet
 * header, so a library that reads files includes it without the plugin ABI.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#ifndef FACEPUPPET_DECIMAL_H
#define FACEPUPPET_DECIMAL_H

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

#endif
