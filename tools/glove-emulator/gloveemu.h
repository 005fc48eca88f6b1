/*
 * gloveemu.h: a byte-exact CyberGlove emulator on a pseudo-terminal (library fp_gloveemu).
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 *
 * The emulator opens a pty master (posix_openpt/grantpt/unlockpt) and answers on it what a
 * CyberGlove box answers on its serial line (shared/docs/devices.md): queries `?G ?S ?N ?R
 * ?V ?D ?U ?B ?T ?K ?M ?P`, `G` (one record), `S` (stream), 0x03 or `^c` (stop), `^I`/`^R`,
 * `t w1 w2\r` (ASCII sample period w1*w2/115200 s), `T` + 4 bytes (w1, w2 as big-endian 16-bit
 * words: an assumption of this emulator), `D`/`U`/`N`/`F`/`L`/`J`/`W`/`Q`/`B` + 1 byte, `M` +
 * 3 bytes, `1eu` (16-bit mode, no reply) and `1S` (16-bit stream); anything else `e?` 0x00.
 * Every reply ends with 0x00.
 *
 * Records are made from a joint-angle recording (the *_cyberglove_like_angles_deg.csv files:
 * degrees -> radians -> raw through the INVERSE of a calibration, clamped to 1..254, or
 * 1..4094 in 16-bit mode at 16 raw units per 8-bit step) or from raw values set directly.
 * Each record sent is kept in a history ring with its sequence number, the angles it was
 * made from and the raw values, so that a test can check the decoder record by record.
 *
 * Faults: glove unplugged from its box (?G = 1; records with status bit0 clear and `eg`;
 * in 16-bit mode no frames), cable pulled (the master is closed: the reader sees EIO/HUP;
 * a pty cannot keep its path, so `link_path`, a symlink, is removed on pull and on replug
 * made to point at a NEW pty: readers must open the link), garbage bytes between records, slow (the
 * period multiplied) and silent (nothing answered, nothing sent).
 *
 * Threads: one service thread per emulator; every function here is [any-thread] except
 * create/destroy. No global state: several emulators run at once.
 */
#ifndef FP_GLOVEEMU_H
#define FP_GLOVEEMU_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

typedef struct fp_gloveemu fp_gloveemu;

typedef struct fp_gloveemu_options {
    int sensors;              /* 18 or 22; 0 = 22 */
    bool left;                /* false: a right glove (?R = 1) */
    const char *link_path;    /* symlink to the current slave, re-pointed on replug; NULL none */
    const char *recording;    /* joint-angle CSV (degrees); NULL: raw 128 on every sensor */
    const char *calibration;  /* calibration file whose inverse makes raw values; NULL default */
    double rate_hz;           /* streaming rate before any t/T command; 0 = 100 */
    bool fast;                /* stream as fast as the reader takes records (ignores t/T) */
    bool timestamps;          /* D on at power-up (5-byte timestamp in 8-bit records) */
    bool loop;                /* loop the recording (default: hold the last frame) */
    const char *version;      /* ?V reply; NULL = "CyberGlove emu 1.0" */
    size_t history;           /* records kept; 0 = 8192 */
    /* A minimal glove box's quirks, as an emulator written from docs/devices.md alone may
     * have them (all off by default): */
    const char *unanswered;   /* letters X whose `?X` query and `X value` command get no reply
                                 at all (still executed), e.g. "RVDU"; NULL none */
    bool caret_stop_only;     /* 0x03 is ignored: only `^c` stops a stream */
    bool streaming_at_start;  /* streaming 8-bit records from power-up, before any S */
    uint32_t sampled;         /* the software mask (?M, bit i sensor i): the sensors sampled,
                                 ?N their count, the 8-bit records' values; 0 = every sensor
                                 the glove has (?K, the hardware mask) */
    int claim_sensors;        /* ?S and ?N answer this (18 or 22) while the records carry
                                 the glove's own: a box whose records disagree with its
                                 answers; 0 = the truth */
    bool error_frames;        /* glove out of its box: `S`|`G` `e` `g` 0x00 in place of each
                                 8-bit record (no values), not a record with its status clear */
} fp_gloveemu_options;

/** A record as sent, in the 22-sensor glove order (for an 18-sensor glove the DIJ entries
 *  are 0 and their bits clear in `present`; so are the sensors not sampled). */
typedef struct fp_gloveemu_record {
    uint64_t seq;             /* 0, 1, 2, ... over the emulator's life */
    int64_t sent_ns;          /* CLOCK_MONOTONIC when written to the master */
    int bits;                 /* 8 or 16 */
    uint8_t start;            /* 'S', 'G', or 'S' for 16-bit frames */
    bool plugged;
    uint32_t present;         /* sensors the record carries (the glove has, and are sampled) */
    uint32_t clamped;         /* sensors whose angle lay outside the raw range */
    uint16_t raw[22];
    float radians[22];        /* the angle the raw value was made from */
} fp_gloveemu_record;

typedef struct fp_gloveemu_stats {
    uint64_t records;         /* records sent (seq of the next one) */
    uint64_t session_seq;     /* seq of the first record after the last ?G query */
    uint64_t commands;        /* commands executed */
    uint64_t unknown;         /* commands answered e? */
    uint64_t polls;           /* G commands */
    uint64_t queries;         /* ? commands */
    uint64_t garbage_sent;    /* garbage bytes written */
    int streaming;            /* 0, 8 or 16 */
    bool status_byte, timestamps;
    unsigned period_w1, period_w2;  /* last t/T command (0 if none) */
    double period_s;
    bool cable_in;
} fp_gloveemu_stats;

/** Line settings the reader applied to the slave (tcgetattr on the master). */
typedef struct fp_gloveemu_line {
    int baud;                 /* output speed in bits/s; 0 unknown */
    int ibaud;                /* input speed */
    int data_bits;            /* 5..8 */
    bool parity, two_stop_bits, raw, echo, crtscts, clocal, cread;
    char text[128];           /* e.g. "115200 8N1 raw" */
} fp_gloveemu_line;

/** Make an emulator and start serving. Returns 0 and *out, or a negative errno code after
 *  writing a message to err: -EINVAL a bad option, -EBADMSG a bad recording (naming the
 *  file, line and column; its numbers decimals, facepuppet/decimal.h) or calibration, the
 *  file's own code where one cannot be opened. */
int fp_gloveemu_create(const fp_gloveemu_options *opts, fp_gloveemu **out, char *err,
                       size_t errlen);
/** Stop the thread, close the pty, remove link_path. Sets *emu to NULL. */
void fp_gloveemu_destroy(fp_gloveemu **emu);

/** The current slave path (/dev/pts/N); changes on replug. Copied into buf. */
void fp_gloveemu_slave_path(fp_gloveemu *emu, char *buf, size_t len);
/** The path readers should open: link_path when set, else the slave path. */
const char *fp_gloveemu_path(const fp_gloveemu *emu);

/** Glove plugged into its box (true at creation). */
void fp_gloveemu_set_plugged(fp_gloveemu *emu, bool plugged);
/** Pull the cable: close the master (and the pty) and remove link_path (its pts number may
 *  be handed to another pty at once). Waits until done. Returns 0. */
int fp_gloveemu_pull_cable(fp_gloveemu *emu);
/** Plug the cable back: a new pty, link_path re-pointed. Returns 0 or -errno. */
int fp_gloveemu_replug_cable(fp_gloveemu *emu);
/** Queue bytes to be written before the next record (line noise between records). */
void fp_gloveemu_inject_garbage(fp_gloveemu *emu, const uint8_t *bytes, size_t n);
/** Multiply the record period by factor (>= 1 slows down; 1 = normal). */
void fp_gloveemu_set_slow(fp_gloveemu *emu, double factor);
/** Silent: read and drop every command, send nothing. */
void fp_gloveemu_set_silent(fp_gloveemu *emu, bool silent);
/** Send these raw values (22, glove order, 8-bit scale 1..254) instead of the recording. */
void fp_gloveemu_set_raw(fp_gloveemu *emu, const uint8_t raw[22]);

/** Copy the record of sequence number seq. Returns 0, or -ENOENT (not sent yet, or no longer
 *  in the history ring). */
int fp_gloveemu_get_record(fp_gloveemu *emu, uint64_t seq, fp_gloveemu_record *out);
void fp_gloveemu_get_stats(fp_gloveemu *emu, fp_gloveemu_stats *out);
/** Read the line settings. Returns 0, or -ENODEV while the cable is out. */
int fp_gloveemu_line_settings(fp_gloveemu *emu, fp_gloveemu_line *out);

#endif
