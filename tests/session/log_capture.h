/* A log callback that keeps the lines it got, for the session step tests. */
#ifndef FP_TEST_LOG_CAPTURE_H
#define FP_TEST_LOG_CAPTURE_H

#include "session_log.h"

#include <stdio.h>
#include <string.h>

typedef struct log_capture {
    int count;
    int level;
    char source[64];
    char lines[16][512];
} log_capture;

static void capture_log(void *user, int level, const char *source, const char *message)
{
    log_capture *c = user;
    if (c->count < 16) snprintf(c->lines[c->count], sizeof c->lines[0], "%s", message);
    c->count++;
    c->level = level;
    snprintf(c->source, sizeof c->source, "%s", source);
}

#endif
