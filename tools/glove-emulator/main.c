/*
 * fp-glove-emu: a CyberGlove on a pseudo-terminal, for trying the cyberglove input without
 * hardware.
 *
 * SPDX-License-Identifier: GPL-3.0-or-later
 *
 * Prints the slave path (e.g. /dev/pts/5) on the first line of stdout, then serves until
 * SIGINT/SIGTERM or `quit`. Faults are typed on stdin, one a line:
 *   unplug | plug | pull | replug | garbage N | slow FACTOR | silent | answer | line | stats
 * Exit 0; 64 a bad option; 65 a bad --csv recording or --cal calibration; 66 a file or the
 * pty not opened.
 */
#define _GNU_SOURCE
#include <errno.h>
#include <poll.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "gloveemu.h"
#include <facepuppet/plugin_util.h> /* fp_parse_decimal, fp_parse_whole: numbers as in every option */

static volatile sig_atomic_t quit;
static void on_signal(int s) { (void)s; quit = 1; }

static void usage(FILE *f)
{
    fprintf(f,
            "usage: fp-glove-emu [--sensors 18|22] [--hand left|right] [--csv FILE] [--cal FILE]\n"
            "                    [--rate HZ] [--fast] [--timestamps] [--loop] [--link PATH]\n"
            "                    [--claim-sensors 18|22 (?S and ?N say so; the records stay)]\n"
            "Serves a CyberGlove on a pty; prints its path, then reads fault commands on stdin:\n"
            "  unplug, plug, pull, replug, garbage N, slow FACTOR, silent, answer, line, stats,"
            " quit\n"
            "Use --link so that a reader survives `pull`/`replug` (a new pty, the link "
            "re-pointed).\n");
}

int main(int argc, char **argv)
{
    fp_gloveemu_options o = {0};
    o.loop = false;
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i];
        const char *v = i + 1 < argc ? argv[i + 1] : NULL;
        if (!strcmp(a, "--sensors") && v) {
            unsigned long long n;
            if (!fp_parse_whole(v, 22, &n) || (n != 18 && n != 22)) {
                fprintf(stderr, "fp-glove-emu: --sensors '%s': expected 18 or 22\n", v);
                return 64;
            }
            o.sensors = (int)n;
            i++;
        }
        else if (!strcmp(a, "--claim-sensors") && v) {
            unsigned long long n;
            if (!fp_parse_whole(v, 22, &n) || (n != 18 && n != 22)) {
                fprintf(stderr, "fp-glove-emu: --claim-sensors '%s': expected 18 or 22\n", v);
                return 64;
            }
            o.claim_sensors = (int)n;
            i++;
        }
        else if (!strcmp(a, "--hand") && v) {
            if (strcmp(v, "left") && strcmp(v, "right")) {
                fprintf(stderr, "fp-glove-emu: --hand %s: expected left or right\n", v);
                return 64;
            }
            o.left = !strcmp(v, "left");
            i++;
        }
        else if (!strcmp(a, "--csv") && v) { o.recording = v; i++; }
        else if (!strcmp(a, "--cal") && v) { o.calibration = v; i++; }
        else if (!strcmp(a, "--rate") && v) {
            if (!fp_parse_decimal(v, &o.rate_hz) || !(o.rate_hz > 0 && o.rate_hz <= 100000)) {
                fprintf(stderr, "fp-glove-emu: --rate '%s': expected a number of Hz, > 0 and at most "
                        "100000\n", v);
                return 64;
            }
            i++;
        }
        else if (!strcmp(a, "--link") && v) { o.link_path = v; i++; }
        else if (!strcmp(a, "--fast")) o.fast = true;
        else if (!strcmp(a, "--timestamps")) o.timestamps = true;
        else if (!strcmp(a, "--loop")) o.loop = true;
        else if (!strcmp(a, "--help") || !strcmp(a, "-h")) { usage(stdout); return 0; }
        else {
            fprintf(stderr, "fp-glove-emu: unknown or incomplete option %s\n", a);
            usage(stderr);
            return 64;
        }
    }
    char err[512];
    fp_gloveemu *e = NULL;
    int rc = fp_gloveemu_create(&o, &e, err, sizeof err);
    if (rc < 0) { /* 64 a bad option, 65 a bad --csv or --cal, 66 a file or pty not opened */
        fprintf(stderr, "fp-glove-emu: %s\n", err);
        return rc == -EINVAL ? 64 : rc == -EBADMSG || rc == -ERANGE ? 65 : 66;
    }
    char slave[64];
    fp_gloveemu_slave_path(e, slave, sizeof slave);
    printf("%s\n", slave);
    if (o.link_path)
        fprintf(stderr, "fp-glove-emu: %s -> %s\n", o.link_path, slave);
    fflush(stdout);
    struct sigaction sa = {0};
    sa.sa_handler = on_signal;
    sigaction(SIGINT, &sa, NULL);
    sigaction(SIGTERM, &sa, NULL);
    bool stdin_open = true;
    char last_line[128] = "";
    char line[256];
    size_t len = 0;
    while (!quit) {
        struct pollfd p = {.fd = 0, .events = POLLIN};
        int r = poll(&p, stdin_open ? 1 : 0, 200);
        fp_gloveemu_line l;   /* report the reader's line settings whenever they change */
        if (fp_gloveemu_line_settings(e, &l) == 0 && strcmp(l.text, last_line) != 0) {
            snprintf(last_line, sizeof last_line, "%s", l.text);
            fprintf(stderr, "fp-glove-emu: line settings now %s%s\n", l.text,
                    l.baud == 115200 && l.data_bits == 8 && !l.parity && !l.two_stop_bits && l.raw
                        ? "" : " (a CyberGlove expects 115200 8N1 raw, or 19200 on old boxes)");
        }
        if (r <= 0 || !(p.revents & (POLLIN | POLLHUP)))
            continue;
        ssize_t n = read(0, line + len, sizeof line - 1 - len);
        if (n <= 0) {
            stdin_open = false;
            continue;
        }
        len += (size_t)n;
        line[len] = '\0';
        char *nl;
        while ((nl = strchr(line, '\n'))) {
            *nl = '\0';
            char cmd[32] = "", text[200] = "";
            double arg = 0;
            int k = sscanf(line, "%31s %199s", cmd, text); /* an argument: a decimal */
            if (k == 2 && (!strcmp(cmd, "garbage") || !strcmp(cmd, "slow")) &&
                !fp_parse_decimal(text, &arg)) {
                fprintf(stderr, "fp-glove-emu: %s '%s': expected a number\n", cmd, text);
                k = 0;
            }
            if (k >= 1) {
                if (!strcmp(cmd, "unplug")) fp_gloveemu_set_plugged(e, false);
                else if (!strcmp(cmd, "plug")) fp_gloveemu_set_plugged(e, true);
                else if (!strcmp(cmd, "pull")) fp_gloveemu_pull_cable(e);
                else if (!strcmp(cmd, "replug")) {
                    if (fp_gloveemu_replug_cable(e) == 0) {
                        fp_gloveemu_slave_path(e, slave, sizeof slave);
                        printf("%s\n", slave);
                    }
                }
                else if (!strcmp(cmd, "garbage")) {
                    uint8_t g[4096];
                    size_t count = k == 2 && arg > 0 ? (arg < sizeof g ? (size_t)arg : sizeof g) : 16;
                    for (size_t j = 0; j < count; j++)
                        g[j] = (uint8_t)(rand() & 0xff);
                    fp_gloveemu_inject_garbage(e, g, count);
                }
                else if (!strcmp(cmd, "slow")) fp_gloveemu_set_slow(e, k == 2 ? arg : 4.0);
                else if (!strcmp(cmd, "silent")) fp_gloveemu_set_silent(e, true);
                else if (!strcmp(cmd, "answer")) fp_gloveemu_set_silent(e, false);
                else if (!strcmp(cmd, "line")) {
                    fp_gloveemu_line l;
                    if (fp_gloveemu_line_settings(e, &l) == 0)
                        printf("line %s\n", l.text);
                    else
                        printf("line (cable out)\n");
                }
                else if (!strcmp(cmd, "stats")) {
                    fp_gloveemu_stats s;
                    fp_gloveemu_get_stats(e, &s);
                    printf("records %llu commands %llu unknown %llu polls %llu streaming %d "
                           "period %.4f s\n", (unsigned long long)s.records,
                           (unsigned long long)s.commands, (unsigned long long)s.unknown,
                           (unsigned long long)s.polls, s.streaming, s.period_s);
                }
                else if (!strcmp(cmd, "quit")) quit = 1;
                else fprintf(stderr, "fp-glove-emu: unknown command %s\n", cmd);
                fflush(stdout);
            }
            len -= (size_t)(nl + 1 - line);
            memmove(line, nl + 1, len + 1);
        }
        if (len >= sizeof line - 1)
            len = 0;
    }
    fp_gloveemu_destroy(&e);
    return 0;
}
