/* facepuppet monitor: print every event of one input as a JSON line (as evtest, oscdump). */
#define _GNU_SOURCE
#include "app_getopt.h"
#include "app_util.h"
#include "command.h"
#include "fp_text.h"

#include <errno.h>
#include <getopt.h>
#include <inttypes.h>
#include <limits.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

static volatile sig_atomic_t interrupted;
static void on_signal(int sig) { (void)sig; interrupted = 1; }

static const char *hand_name(int h)
{
    return h == FP_HAND_LEFT ? "left" : h == FP_HAND_RIGHT ? "right" : NULL;
}

static void print_floats(const float *v, size_t n)
{
    putchar('[');
    for (size_t i = 0; i < n; i++) printf("%s%.6g", i ? "," : "", v[i]);
    putchar(']');
}

/* s as a JSON string: a plugin's text made well-formed UTF-8 without control characters
 * first (fp_text_clean: U+FFFD for each), so that every line parses as JSON */
static void print_json_string(const char *s)
{
    char clean[1024];
    fp_text_clean(s, clean, sizeof clean);
    putchar('"');
    for (const char *p = clean; *p; p++) {
        if (*p == '"' || *p == '\\') putchar('\\');
        putchar(*p);
    }
    putchar('"');
}

/** One event as one JSON object on one line; `performer` (the SPEC's performer=, or "")
 *  named after the hand where given. */
static void print_event(const fp_event *ev, const char *performer)
{
    static const char *types[] = {"",       "joint_angles", "joint_positions", "wrist_pose",
                                  "button", "status",       "channel"};
    static const char *codes[] = {"", "connected", "disconnected", "reconnecting", "warning", "error",
                                  "end_of_stream"};
    int t = ev->header.type;
    printf("{\"time_ns\":%" PRId64 ",\"type\":\"%s\"", ev->header.time_ns,
           t >= 1 && t <= FP_EVENT_CHANNEL ? types[t] : "unknown");
    const char *hand = hand_name(ev->header.hand);
    if (hand) printf(",\"hand\":\"%s\"", hand);
    if (performer[0]) printf(",\"performer\":\"%s\"", performer); /* ([A-Za-z0-9_-]) */
    switch (t) {
    case FP_EVENT_JOINT_ANGLES:
        printf(",\"valid\":%" PRIu32 ",\"radians\":", ev->angles.valid);
        print_floats(ev->angles.radians, FP_GLOVE_SENSORS);
        break;
    case FP_EVENT_JOINT_POSITIONS:
        printf(",\"mm\":");
        print_floats(&ev->positions.mm[0][0], FP_HAND_JOINTS * 3);
        break;
    case FP_EVENT_WRIST_POSE:
        printf(",\"position_mm\":");
        print_floats(ev->wrist.position_mm, 3);
        printf(",\"rotation_wxyz\":");
        print_floats(ev->wrist.rotation, 4);
        break;
    case FP_EVENT_BUTTON: {
        const char *b = ev->button.button == FP_BUTTON_LEFT ? "left"
                        : ev->button.button == FP_BUTTON_MIDDLE ? "middle"
                        : ev->button.button == FP_BUTTON_RIGHT ? "right" : "other";
        printf(",\"button\":\"%s\",\"down\":%s,\"mask\":%" PRIu32, b, ev->button.down ? "true" : "false",
               ev->button.mask);
        break;
    }
    case FP_EVENT_STATUS:
        printf(",\"code\":\"%s\",\"text\":", ev->status.code >= 1 && ev->status.code <= 6
                                                 ? codes[ev->status.code] : "unknown");
        print_json_string(ev->status.text);
        break;
    case FP_EVENT_CHANNEL: { /* a rig channel an input drives (ABI 1.2: the audio input's jaw.open) */
        char name[sizeof ev->channel.name + 1];
        snprintf(name, sizeof name, "%.*s", (int)sizeof ev->channel.name, ev->channel.name);
        printf(",\"name\":");
        print_json_string(name);
        printf(",\"value\":%.6g", ev->channel.value);
        break;
    }
    default:
        break;
    }
    puts("}");
}

static void usage(FILE *f)
{
    fprintf(f, "usage: facepuppet monitor [--count N] [--duration S] [--plugin-dir DIR] SPEC\n\n"
               "Print every event of one input as a JSON line, to check a device or a recording.\n"
               "Stops at the end of a recording, after N events or S seconds, or on Ctrl-C.\n"
               "  -n, --count N          stop after N events\n"
               "  -d, --duration S       stop after S seconds\n"
               "  -P, --plugin-dir DIR   look for plugins in DIR too, after the built-in folder\n"
               "                         (repeatable)\n"
               "  e.g. facepuppet monitor replay:../shared/data/hands/leap-motion/grab_joints_mm.csv,fast=1\n"
               "       facepuppet monitor pedal\n"
               "       facepuppet monitor cyberglove:/dev/ttyUSB0\n\n"
               "Exit status: 0 done (the end of a recording, N events, S seconds or Ctrl-C),\n"
               "64 usage (a bad option or SPEC key), 65 a malformed recording, 66 an input that\n"
               "cannot be opened (file, device, port), 78 a plugin missing or failing.\n");
}

static int monitor_main(int argc, char **argv)
{
    static const struct option opts[] = {{"count", required_argument, 0, 'n'},
                                         {"duration", required_argument, 0, 'd'},
                                         {"plugin-dir", required_argument, 0, 'P'},
                                         {"help", no_argument, 0, 'h'}, {0, 0, 0, 0}};
    long long count = -1;
    double duration = 0;
    const char *dirs[8];
    size_t ndirs = 0;
    optind = 1;
    for (int c; (c = fp_app_getopt(argc, argv, "n:d:P:h", opts)) != -1;) {
        switch (c) {
        case 'n': {
            unsigned long long n;
            if (!fp_parse_whole(optarg, LLONG_MAX, &n) || n < 1) {
                fprintf(stderr, "facepuppet monitor: --count must be a whole number > 0, got '%s'\n",
                        optarg);
                return FP_EXIT_USAGE;
            }
            count = (long long)n;
            break;
        }
        case 'd': {
            if (!fp_parse_decimal(optarg, &duration) || !(duration > 0 && duration < FP_APP_MAX_DURATION_S)) {
                fprintf(stderr, "facepuppet monitor: --duration must be > 0 seconds and under "
                                "1e7, got '%s'\n", optarg);
                return FP_EXIT_USAGE;
            }
            break;
        }
        case 'P': if (ndirs < 8) dirs[ndirs++] = optarg; break;
        case 'h': usage(stdout); return FP_EXIT_OK;
        default: usage(stderr); return FP_EXIT_USAGE;
        }
    }
    if (optind != argc - 1) {
        fprintf(stderr, "facepuppet monitor: %s\n\n", optind >= argc ? "give one input SPEC" : "one SPEC only");
        usage(stderr);
        return FP_EXIT_USAGE;
    }
    fp_plugin_path path;
    fp_app_plugin_path(&path, dirs, ndirs);
    fp_input_instance inst;
    char err[2048];
    int rc = fp_input_instance_open(&inst, &path, argv[optind], 0, err, sizeof err);
    if (!rc) fp_input_instance_set_log(&inst, fp_app_log_line, NULL); /* its log lines */
    if (!rc) rc = fp_input_instance_start(&inst, err, sizeof err);
    if (rc) {
        fprintf(stderr, "facepuppet monitor: %s\n", err);
        fp_input_instance_close(&inst);
        fp_plugin_path_clear(&path);
        return fp_app_exit_code(rc, FP_APP_INPUT);
    }
    signal(SIGINT, on_signal);
    signal(SIGTERM, on_signal);
    int64_t t0 = fp_now_ns();
    long long printed = 0;
    bool ended = false;
    while (!interrupted && !ended && (count < 0 || printed < count)) {
        fp_event ev;
        bool any = false;
        while ((count < 0 || printed < count) && fp_input_instance_poll(&inst, &ev)) {
            print_event(&ev, inst.performer);
            printed++;
            any = true;
            if (ev.header.type == FP_EVENT_STATUS && ev.status.code == FP_STATUS_END_OF_STREAM) ended = true;
        }
        fp_input_instance_drain_log(&inst);
        if (duration > 0 && fp_now_ns() - t0 > (int64_t)(duration * 1e9)) break;
        if (!any) {
            fflush(stdout);
            struct timespec ts = {0, 2000000};
            nanosleep(&ts, NULL);
        }
    }
    fflush(stdout);
    fp_input_instance_close(&inst);
    fp_plugin_path_clear(&path);
    return FP_EXIT_OK;
}

const fp_command fp_command_monitor = {"monitor", "print every event of one input as JSON lines",
                                       monitor_main};
