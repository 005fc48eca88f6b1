/*
 * fp_clock.h: the project's clock: CLOCK_MONOTONIC in nanoseconds. The host clock of the
 * plugin ABI (fp_host.now_ns gives it to plugins), the session's frame and stage timings,
 * the workers' idle time (fp_worker.h). [any-thread]. Link: fp_common.
 */
#ifndef FP_CLOCK_H
#define FP_CLOCK_H

#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/** CLOCK_MONOTONIC in nanoseconds: the host clock of the ABI. */
int64_t fp_now_ns(void);

#ifdef __cplusplus
}
#endif
#endif
