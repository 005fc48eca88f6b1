/*
 * facepuppet/plugin_util.h: small inline helpers for any plugin author (input or mapping),
 * on top of facepuppet/plugin.h. Header-only, no allocation, reentrant, [any-thread].
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#ifndef FACEPUPPET_PLUGIN_UTIL_H
#define FACEPUPPET_PLUGIN_UTIL_H

#include <facepuppet/plugin.h>
/* fp_decimal_span: the one syntax of a number in a key, an option or a data file: a
 * decimal, optional sign, digits with at most one '.', optional exponent; no blanks,
 * hexadecimal ("0x10", "0x1p3"), "inf", "infinity" or "nan" */
#include <facepuppet/decimal.h>
#include <math.h>
#include <stdbool.h>
#include <stdlib.h>
#include <string.h>

/** A set of hands: a bit per fp_hand_side (the `hands=` key of mappings and of replay). */
#define FP_HANDMASK_LEFT (1u << FP_HAND_LEFT)
#define FP_HANDMASK_RIGHT (1u << FP_HAND_RIGHT)
#define FP_HANDMASK_BOTH (FP_HANDMASK_LEFT | FP_HANDMASK_RIGHT)

/** The one parser of a `hands=` value: "left", "right" or "both" -> FP_HANDMASK_*; 0 for
 *  anything else (the caller reports "hands=V: expected left, right or both"). */
static inline unsigned fp_parse_hands(const char *v)
{
    if (!v) return 0;
    if (!strcmp(v, "left")) return FP_HANDMASK_LEFT;
    if (!strcmp(v, "right")) return FP_HANDMASK_RIGHT;
    if (!strcmp(v, "both")) return FP_HANDMASK_BOTH;
    return 0;
}

/** The one parser of an on/off key's value (mapping_util.h's FP_PARAM_BOOL uses it too):
 *  "1", "true", "yes", "on" -> 1; "0", "false", "no", "off" -> 0; anything else (NULL too)
 *  -> -1 (the caller reports "KEY=V: expected 0 or 1"). [any-thread], no allocation. */
static inline int fp_parse_bool(const char *v)
{
    if (!v) return -1;
    if (!strcmp(v, "1") || !strcmp(v, "true") || !strcmp(v, "yes") || !strcmp(v, "on")) return 1;
    if (!strcmp(v, "0") || !strcmp(v, "false") || !strcmp(v, "no") || !strcmp(v, "off")) return 0;
    return -1;
}

/** The number at the start of v as fp_decimal_span reads it, into a finite double (the
 *  nearest, as strtod gives it; '.' is the decimal point: facepuppet never changes the C
 *  locale's LC_NUMERIC). Returns its length, *out set; 0 where v starts with no such number or
 *  its value overflows ("1e999"), *out untouched. The one reading behind fp_parse_decimal and
 *  fp_parse_decimal_list. [any-thread], no allocation. */
static inline size_t fp_decimal_read(const char *v, double *out)
{
    const size_t n = fp_decimal_span(v);
    if (!n) return 0;
    char *end;
    const double x = strtod(v, &end);
    if (end != v + n || !isfinite(x)) return 0; /* ("0x10": strtod reads on past "0") */
    *out = x;
    return n;
}

/** Parse v, the whole of it a number as fp_decimal_span reads it, into a finite double (the
 *  nearest, as strtod gives it; '.' is the decimal point: facepuppet never changes the C
 *  locale's LC_NUMERIC). false where v is no such number or its value overflows ("1e999");
 *  the caller reports "KEY=V: expected a number ..." naming the key or option. [any-thread],
 *  no allocation. */
static inline bool fp_parse_decimal(const char *v, double *out)
{
    double x;
    const size_t n = fp_decimal_read(v, &x);
    if (!n || v[n]) return false; /* *out untouched (a caller's default stays) */
    *out = x;
    return true;
}

/** Parse v as 1 to max numbers as fp_parse_decimal reads one, each followed by `sep` but the
 *  last ("10/20/30" with '/'; with ' ', any run of spaces and tabs separates, and may lead or
 *  trail); returns how many (their values in out[0..]), 0 where v is no such list or has more
 *  than max. [any-thread], no allocation. */
static inline size_t fp_parse_decimal_list(const char *v, char sep, double *out, size_t max)
{
    size_t k = 0;
    const char *p = v;
    while (p && sep == ' ' && (*p == ' ' || *p == '\t')) p++;
    while (p && k < max) {
        const size_t n = fp_decimal_read(p, &out[k]);
        if (!n) return 0;
        k++;
        p += n;
        const char *q = p;
        while (sep == ' ' && (*q == ' ' || *q == '\t')) q++;
        if (!*q) return k;
        if (sep == ' ' ? q == p : *p != sep) return 0;
        p = sep == ' ' ? q : p + 1;
    }
    return 0;
}

/** The `hands=` value naming mask: "left", "right" or "both" (any other mask). */
static inline const char *fp_hands_name(unsigned mask)
{
    return mask == FP_HANDMASK_LEFT ? "left" : mask == FP_HANDMASK_RIGHT ? "right" : "both";
}

#endif
