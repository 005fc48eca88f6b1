/* The control surface's messages: bundles walked, each message decoded by liblo and checked
 * against its address's type tags and ranges, then queued (fp_control.h). [network thread] */
#define _GNU_SOURCE
#include "control_internal.h"

#include "fp_take.h"
#include "fp_osc_arg.h"

#include <lo/lo.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#define MAX_DEPTH 8
#define TAKE_MAX 999999u

/* An address, its command, and the type tags it takes ('n': a number, f, d, i or h; '?': an
 * optional tail starts, so "?sn" takes "", "s" and "s" + a number). A command that may come
 * without arguments also comes as a button (button_value): one number, which its own tags
 * do not take otherwise. */
static const struct {
    const char *address;
    fp_control_kind kind;
    const char *types;
} table[] = {
    {"/fp/record/start", FP_CTL_RECORD_START, "?sn"}, {"/RecordStart", FP_CTL_RECORD_START, "?sn"},
    {"/fp/record/stop", FP_CTL_RECORD_STOP, ""},      {"/RecordStop", FP_CTL_RECORD_STOP, ""},
    {"/fp/engage", FP_CTL_ENGAGE, ""},                {"/fp/commit", FP_CTL_COMMIT, ""},
    {"/fp/cancel", FP_CTL_CANCEL, ""},                {"/fp/undo", FP_CTL_UNDO, ""},
    {"/fp/reset", FP_CTL_RESET, ""},                  {"/fp/radius", FP_CTL_RADIUS, "n"},
    {"/fp/mapping", FP_CTL_MAPPING, "s"},             {"/fp/channel", FP_CTL_CHANNEL, "sn"},
    {"/fp/play", FP_CTL_PLAY, ""},                    {"/fp/stop", FP_CTL_STOP, ""},
    {"/fp/seek", FP_CTL_SEEK, "n"},                   {"/fp/status", FP_CTL_STATUS, ""},
    {"/fp/subscribe", FP_CTL_SUBSCRIBE, "?n"},        {"/fp/unsubscribe", FP_CTL_UNSUBSCRIBE, "?n"},
    {"/fp/slate", FP_CTL_SLATE, "s"},                 {"/Slate", FP_CTL_SLATE, "s"},
    {"/fp/take", FP_CTL_TAKE, "n"},                   {"/Take", FP_CTL_TAKE, "n"},
    {"/fp/quit", FP_CTL_QUIT, ""},
};

static const char *const kind_names[FP_CTL_KINDS] = {
    "record start", "record stop", "engage", "commit", "cancel", "undo", "reset", "radius",
    "mapping", "channel", "play", "stop", "seek", "status", "subscribe", "unsubscribe", "slate",
    "take", "quit"};

const char *fp_control_kind_name(fp_control_kind k)
{
    return (unsigned)k < FP_CTL_KINDS ? kind_names[k] : "?";
}

/* types matches the pattern (above). */
static bool types_match(const char *pattern, const char *types)
{
    bool optional = false;
    for (;; pattern++) {
        if (*pattern == '?') { optional = true; continue; }
        if (!*types) return !*pattern || optional;
        if (!*pattern) return false;
        char t = *types++;
        if (*pattern == 'n' ? !fp_osc_number_type(t) : t != *pattern) return false;
    }
}

/* A mapping SPEC: NAME[,key=value...] of letters, digits and . _ - , = + (no '/' or ':': a
 * plugin is found by name in the plugin path, never by a path from the network). */
static bool spec_ok(const char *s)
{
    size_t n = strlen(s);
    if (n == 0 || n >= FP_CONTROL_TEXT_MAX || !((s[0] >= 'a' && s[0] <= 'z') || (s[0] >= 'A' && s[0] <= 'Z')))
        return false;
    return strspn(s, "abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789._-,=+") == n;
}

/* A rig channel's name: 1..63 of letters, digits, . _ - */
static bool channel_ok(const char *s)
{
    size_t n = strlen(s);
    return n > 0 && n < 64 &&
           strspn(s, "abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789._-") == n;
}

/* A button's message for a command of these tags: one number, where the tags take no
 * arguments but do not take that one number (as /fp/subscribe's optional port does) */
static bool button_value(const char *pattern, const char *types)
{
    return types_match(pattern, "") && strlen(types) == 1 && fp_osc_number_type(types[0]) &&
           !types_match(pattern, types);
}

/* The arguments of a matched message into cmd; false when a value is refused. */
static bool take_args(fp_control_cmd *cmd, const char *types, lo_arg **argv)
{
    size_t argc = strlen(types);
    switch (cmd->kind) {
    case FP_CTL_RECORD_START:
    case FP_CTL_SLATE:
        if (argc >= 1) {
            if (strlen(&argv[0]->s) >= FP_TAKE_SLATE_MAX || !fp_take_slate_valid(&argv[0]->s)) return false;
            snprintf(cmd->text, sizeof cmd->text, "%s", &argv[0]->s);
            cmd->has_text = true;
        }
        if (argc >= 2) {
            double v = fp_osc_number(types[1], argv[1]);
            if (!(v >= 1 && v <= TAKE_MAX && v == floor(v))) return false;
            cmd->take = (uint32_t)v;
            cmd->has_take = true;
        }
        return true;
    case FP_CTL_TAKE: {
        double v = fp_osc_number(types[0], argv[0]);
        if (!(v >= 1 && v <= TAKE_MAX && v == floor(v))) return false;
        cmd->take = (uint32_t)v;
        cmd->has_take = true;
        return true;
    }
    case FP_CTL_RADIUS: /* (any finite number: the session's range check answers the rest) */
        cmd->value = fp_osc_number(types[0], argv[0]);
        return isfinite(cmd->value);
    case FP_CTL_SEEK:
        cmd->value = fp_osc_number(types[0], argv[0]);
        return isfinite(cmd->value) && cmd->value >= 0 && cmd->value < 1e7;
    case FP_CTL_MAPPING:
        if (!spec_ok(&argv[0]->s)) return false;
        snprintf(cmd->text, sizeof cmd->text, "%s", &argv[0]->s);
        cmd->has_text = true;
        return true;
    case FP_CTL_CHANNEL:
        if (!channel_ok(&argv[0]->s)) return false;
        snprintf(cmd->text, sizeof cmd->text, "%s", &argv[0]->s);
        cmd->has_text = true;
        cmd->value = fp_osc_number(types[1], argv[1]);
        return isfinite(cmd->value) && fabs(cmd->value) < 1e6;
    case FP_CTL_SUBSCRIBE:
    case FP_CTL_UNSUBSCRIBE:
        if (argc >= 1) {
            double v = fp_osc_number(types[0], argv[0]);
            if (!(v >= 1 && v <= 65535 && v == floor(v))) return false;
            cmd->port = (int)v;
        }
        return true;
    default:
        return true;
    }
}

/* One datagram's walk: its commands staged (c->stage) until the whole datagram is checked. */
typedef struct walk {
    fp_control *c;
    const fp_control_cmd *from;
    size_t staged;
    int problem;                      /* the first refusal (malformed before any), or -1 */
} walk;

static void refuse(walk *w, fp_control_problem p)
{
    if (w->problem < 0 || p == FP_CTL_MALFORMED) w->problem = (int)p;
}

static void stage(walk *w, const fp_control_cmd *cmd)
{
    if (w->staged == FP_CONTROL_RING) refuse(w, FP_CTL_QUEUE_FULL); /* (more than the ring holds) */
    else w->c->stage[w->staged++] = *cmd;
}

static void message(walk *w, unsigned char *data, size_t size)
{
    int result = 0;
    size_t alen = strnlen((const char *)data, size);
    size_t tags = (alen + 4) & ~(size_t)3; /* the type tags must follow: no tag-less message */
    if (tags >= size || data[tags] != ',') {
        refuse(w, FP_CTL_MALFORMED);
        return;
    }
    lo_message m = lo_message_deserialise(data, size, &result);
    if (!m) {
        refuse(w, FP_CTL_MALFORMED);
        return;
    }
    atomic_fetch_add_explicit(&w->c->messages, 1, memory_order_relaxed);
    const char *path = (const char *)data; /* validated by lo_message_deserialise */
    const char *types = lo_message_get_types(m);
    if (!types) types = "";
    size_t k = 0, n = sizeof table / sizeof table[0];
    while (k < n && strcmp(path, table[k].address)) k++;
    if (k == n) {
        refuse(w, FP_CTL_UNKNOWN_ADDRESS);
        lo_message_free(m);
        return;
    }
    fp_control_cmd cmd;
    memset(&cmd, 0, sizeof cmd);
    cmd.from = w->from->from;
    cmd.fromlen = w->from->fromlen;
    cmd.kind = table[k].kind;
    snprintf(cmd.address, sizeof cmd.address, "%s", table[k].address);
    lo_arg **argv = lo_message_get_argv(m);
    if (button_value(table[k].types, types)) {
        /* a control surface's button (TouchOSC, Open Stage Control: 1 pressed, 0 let go) on a
         * command that may come without arguments: any value but 0 runs it so, 0 does nothing */
        double v = fp_osc_number(types[0], argv[0]);
        if (!isfinite(v)) refuse(w, FP_CTL_BAD_VALUE);
        else if (v != 0) stage(w, &cmd);
    } else if (!types_match(table[k].types, types)) {
        refuse(w, FP_CTL_BAD_TYPES);
    } else if (take_args(&cmd, types, argv)) {
        stage(w, &cmd);
    } else {
        refuse(w, FP_CTL_BAD_VALUE);
    }
    lo_message_free(m);
}

static uint32_t be32(const unsigned char *p)
{
    return (uint32_t)p[0] << 24 | (uint32_t)p[1] << 16 | (uint32_t)p[2] << 8 | p[3];
}

/* A message or a bundle (depth: bundles nested so far). A bundle's elements are walked to its
 * end, each message checked (the first refusal kept); a bad size stops the walk. */
static void element(walk *w, unsigned char *data, size_t size, int depth)
{
    if (size >= 8 && memcmp(data, "#bundle", 8) == 0) {
        if (size < 16 || depth >= MAX_DEPTH) {
            refuse(w, FP_CTL_MALFORMED);
            return;
        }
        for (size_t at = 16; at < size;) { /* (timetags: commands apply on arrival) */
            uint32_t len = size - at >= 4 ? be32(data + at) : 0;
            at += 4;
            if (len == 0 || len % 4 || at > size || len > size - at) {
                refuse(w, FP_CTL_MALFORMED);
                return;
            }
            element(w, data + at, len, depth + 1);
            at += len;
        }
        return;
    }
    if (size < 4 || size % 4 || data[0] != '/') {
        refuse(w, FP_CTL_MALFORMED);
        return;
    }
    message(w, data, size);
}

void fp__control_packet(fp_control *c, unsigned char *data, size_t size, const fp_control_cmd *from)
{
    walk w = {c, from, 0, -1};
    element(&w, data, size, 0);
    if (w.problem < 0 && w.staged && !fp__control_queue_all(c, c->stage, w.staged))
        w.problem = FP_CTL_QUEUE_FULL;
    if (w.problem >= 0) fp__control_problem(c, (fp_control_problem)w.problem);
}
