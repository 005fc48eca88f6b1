/* The project's clock (fp_clock.h). */
#define _POSIX_C_SOURCE 200809L /* clock_gettime */
#include "fp_clock.h"

#include <time.h>

int64_t fp_now_ns(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (int64_t)ts.tv_sec * 1000000000LL + ts.tv_nsec;
}
