/*
 * osc_fixture.h: what the input-osc tests share (test_osc.c, test_osc_hands.c): the plugin
 * dlopened from the build tree, a fake host that stores events in a bounded array (a full
 * array refuses, as the host's queue does) and a started input on a free loopback port.
 * Failures are cmocka assertions; for the tests' one thread (the plugin's receive thread
 * only calls the host's push_event, now_ns and log, which lock the host's mutex).
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 */
#ifndef FP_TEST_OSC_FIXTURE_H
#define FP_TEST_OSC_FIXTURE_H

#include "osc.h"

#include <facepuppet/plugin.h>

#include <lo/lo.h>

#include <pthread.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

/** The "osc" input factory, set by osc_fixture_load. */
extern const fp_input_factory *factory;

/* A fake host: events stored in order, up to cap (store), or only counted (flood). */
typedef struct fake_host {
    fp_host host;
    pthread_mutex_t mutex;
    fp_event *events;
    size_t count, cap;
    size_t refused, refused_poses;
    bool store;          /* false: count only (flood) */
    size_t pushed;
    char log[8192];
} fake_host;

/** CLOCK_MONOTONIC in ns (the fake host's now_ns). */
int64_t mono_ns(void);
void sleep_ms(int ms);
/** A fake host storing up to cap events; freed with fake_free. */
fake_host *fake_new(size_t cap);
void fake_free(fake_host *h);
/** Events of `type` stored so far (status `code` where >= 0). */
size_t count_type(fake_host *h, int type, int code);
/** Waits until `n` events of `type` (status `code` where >= 0) are stored; false after 5 s. */
bool wait_type(fake_host *h, int type, int code, size_t n);
/** The i-th joint_positions event in arrival order, NULL if fewer (caller holds no lock: call
 *  once the plugin is quiet). */
const fp_event *nth_positions(fake_host *h, size_t i);

/* A created and started input on a free port, and a liblo address to 127.0.0.1:port. */
typedef struct osc_fixture {
    fake_host *h;
    fp_input *in;
    const fp_osc_ext *ext;
    lo_address to;
    char port[16];
} osc_fixture;

/** factory->create on port 0 with keys "k=v,k=v" (at most 8); returns its code. */
int create(fake_host *h, const char *keys, fp_input **in, char *err, size_t errlen);
/** Creates (keys as create's) and starts an input with a fake host of `cap` events. */
void open_fixture(osc_fixture *f, const char *keys, size_t cap);
void close_fixture(osc_fixture *f);
fp_osc_stats stats(osc_fixture *f);
/** Waits until the plugin has read `packets` datagrams, or read none for 1 s, or 5 s passed. */
void wait_packets(osc_fixture *f, uint64_t packets);

/** dlopens $FP_BUILD_DIR/lib/facepuppet/input-osc.so and sets `factory`; 0 or -1 (said on
 *  stderr). */
int osc_fixture_load(void);
void osc_fixture_unload(void);

#endif
