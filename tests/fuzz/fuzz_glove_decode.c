/* fuzz_glove_decode.c: libFuzzer target for the CyberGlove record decoder
 * (plugins/input-cyberglove/glove_decode.c), the bytes a glove (or anything on its serial
 * port) sends. Input: byte 0 picks the wire format (8 or 16 bits, 18 or 22 sensors, timestamp
 * and status bytes), byte 1 seeds the chunk sizes, the rest is the stream. Checks: the same
 * units come out whether the stream is fed whole or in chunks; every record has the format's
 * sensor count and raw values in the wire's range (8-bit 1..255, 16-bit 1..4094 / 16); the
 * angles of every record, under the default calibration and under one whose gains and offsets
 * come from the input (huge, tiny, infinite), are finite where valid and 0 elsewhere.
 * Byte 0 also picks a record of fewer sensors sampled (fpg_decoder_set_order), byte 1 a settle
 * (fpg_decoder_settle) after the last bytes.
 * Seeds: tests/fuzz/corpus/fuzz_glove_decode (records of each format). */
#include "glove_decode.h"

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

#define MAX_UNITS 4096

typedef struct sink {
    fpg_unit units[MAX_UNITS];
    size_t n;
    size_t noise;
} sink;

static sink whole, chunked;

static void on_unit(void *user, const fpg_unit *u)
{
    sink *s = user;
    if (u->kind == FPG_UNIT_NOISE) {
        if (u->noise == 0) abort();
        s->noise += u->noise;
        return;
    }
    if (u->kind != FPG_UNIT_RECORD && u->kind != FPG_UNIT_ERROR) abort();
    if (s->n < MAX_UNITS) s->units[s->n++] = *u;
}

static void check_angles(const fpg_cal *cal, const fpg_unit *u)
{
    float rad[FPG_SENSORS];
    uint32_t valid = 0;
    int dropped = fpg_angles_from_raw(cal, u, rad, &valid);
    if (dropped < 0 || dropped > u->nraw || valid >> FPG_SENSORS) abort();
    for (int i = 0; i < FPG_SENSORS; i++) {
        if (!isfinite(rad[i])) abort();
        if (!(valid & (1u << i)) && rad[i] != 0) abort();
        if ((valid & (1u << i)) && !(cal->used & (1u << i))) abort();
    }
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    if (size < 2) return 0;
    const int bits = data[0] & 1 ? 16 : 8, sensors = data[0] & 2 ? 22 : 18;
    const bool ts_on = data[0] & 4, status_on = data[0] & 8, status_seen = data[0] & 16;
    /* bit 5: fewer sensors sampled (fpg_decoder_set_order), every k-th glove sensor left
     * out for k from bits 6-7 */
    uint8_t order[FPG_SENSORS];
    int sampled = 0;
    for (int i = 0; i < FPG_SENSORS && (data[0] & 32); i++)
        if (i % (2 + (data[0] >> 6)) != 1) order[sampled++] = (uint8_t)i;
    const bool settle = data[1] & 1; /* a settle after the last bytes, on both */
    unsigned seed = data[1];
    data += 2;
    size -= 2;
    static fpg_decoder d;
    whole.n = whole.noise = chunked.n = chunked.noise = 0;
    fpg_decoder_init(&d, bits, sensors, ts_on, status_on);
    if (sampled && fpg_decoder_set_order(&d, sampled, order)) abort();
    d.status_seen = status_seen;
    fpg_decoder_feed(&d, data, size, on_unit, &whole);
    if (settle) fpg_decoder_settle(&d, on_unit, &whole);
    size_t pending_whole = d.len;
    fpg_decoder_init(&d, bits, sensors, ts_on, status_on);
    if (sampled && fpg_decoder_set_order(&d, sampled, order)) abort();
    d.status_seen = status_seen;
    for (size_t at = 0; at < size;) {
        seed = seed * 1103515245u + 12345u;
        size_t k = 1 + (seed >> 16) % 64;
        if (k > size - at) k = size - at;
        fpg_decoder_feed(&d, data + at, k, on_unit, &chunked);
        at += k;
    }
    if (settle) fpg_decoder_settle(&d, on_unit, &chunked);
    if (whole.n != chunked.n || whole.noise != chunked.noise || d.len != pending_whole) abort();
    if (d.len >= FPG_DECODE_CAP) abort();

    /* A calibration from the input's first bytes: any float, infinities and NaN included. */
    fpg_cal def, wild;
    fpg_cal_default(&def);
    memset(&wild, 0, sizeof wild);
    wild.used = (1u << FPG_SENSORS) - 1;
    for (int i = 0; i < FPG_SENSORS; i++) {
        uint32_t g = 0, o = 0;
        for (int b = 0; b < 4; b++) {
            size_t at = (size_t)(8 * i + b);
            g = g << 8 | (at < size ? data[at] : 0x7f);
            o = o << 8 | (at + 4 < size ? data[at + 4] : 0x7f);
        }
        memcpy(&wild.gain[i], &g, sizeof g);
        memcpy(&wild.offset[i], &o, sizeof o);
    }
    for (size_t i = 0; i < whole.n; i++) {
        const fpg_unit *u = &whole.units[i], *v = &chunked.units[i];
        if (u->kind != v->kind || u->errc != v->errc) abort();
        if (u->kind != FPG_UNIT_RECORD) continue;
        if (u->nraw != (bits == 16 ? FPG_SENSORS : sampled ? sampled : sensors) || u->nraw != v->nraw ||
            u->plugged != v->plugged)
            abort();
        for (int k = 0; k < u->nraw; k++) {
            double lo = bits == 16 ? 1 / 16.0 : 1, hi = bits == 16 ? 4094 / 16.0 : 255;
            if (!(u->raw[k] >= lo && u->raw[k] <= hi) || u->raw[k] != v->raw[k]) abort();
        }
        check_angles(&def, u);
        check_angles(&wild, u);
    }
    return 0;
}
