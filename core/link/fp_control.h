/*
 * fp_control.h: the OSC control surface (`--control osc:PORT` of run, live and play;
 * docs/osc.md, "Control"). A UDP socket on loopback (or the address given) and one pthread
 * that reads it: each datagram is walked (bundles, nesting up to 8), each message decoded by
 * liblo (lo_message_deserialise), checked (address, type tags, count, finite, range, text)
 * and queued as an fp_control_cmd in a fixed single-producer single-consumer ring. The
 * frame loop takes the commands between frames (fp_control_next) and applies them itself
 * (fp_control_apply.h for a session): nothing of the session is touched from the network
 * thread. Replies and pushes (fp_control_reply, fp_control_push) are sent by the frame loop
 * from the control socket, so a sender's reply comes from the port it sent to.
 *
 * Refused messages (not OSC, bad bundle, wrong type tags, a value out of range or not
 * finite, a slate or mapping that is not allowed text, an unknown address, the ring full)
 * are counted by kind and get no reply (no amplification); the counts are in the status.
 * A datagram is checked whole first: its commands are queued together or, where any part of
 * it is refused, none is (a bundle's messages take effect together, OSC 1.0).
 * Memory does not grow with traffic: one 64 KiB receive buffer, one liblo message at a time,
 * the ring's fixed slots, at most FP_CONTROL_MAX_SUBSCRIBERS subscribers.
 *
 * Errors: 0 or a negative errno code with a message in err (fp_errorf): -EINVAL a bad SPEC,
 * -EBUSY (the port taken), -ENODEV and the socket's codes when it cannot bind, -ENOMEM. Nothing is printed.
 * Threads: create and destroy on the main thread; next, reply, push, subscribe and stats on
 * one frame thread; the network thread is the control's own.
 */
#ifndef FP_CONTROL_H
#define FP_CONTROL_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <sys/socket.h>

#ifdef __cplusplus
extern "C" {
#endif

#define FP_CONTROL_TEXT_MAX 256        /* a slate, a mapping SPEC, a channel name (bytes, NUL incl.) */
#define FP_CONTROL_MAX_SUBSCRIBERS 8
#define FP_CONTROL_RING 256            /* commands queued at most (more: refused, queue-full) */

typedef enum fp_control_kind {
    FP_CTL_RECORD_START,   /* /fp/record/start [s slate [i take]]; LLF /RecordStart s i */
    FP_CTL_RECORD_STOP,    /* /fp/record/stop; LLF /RecordStop */
    FP_CTL_ENGAGE,         /* /fp/engage */
    FP_CTL_COMMIT,         /* /fp/commit */
    FP_CTL_CANCEL,         /* /fp/cancel */
    FP_CTL_UNDO,           /* /fp/undo */
    FP_CTL_RESET,          /* /fp/reset */
    FP_CTL_RADIUS,         /* /fp/radius f (mesh units, finite; the session checks its range) */
    FP_CTL_MAPPING,        /* /fp/mapping s (NAME[,key=value...]) */
    FP_CTL_CHANNEL,        /* /fp/channel s f (a rig channel, its value) */
    FP_CTL_PLAY,           /* /fp/play */
    FP_CTL_STOP,           /* /fp/stop */
    FP_CTL_SEEK,           /* /fp/seek f (seconds from the take's start, >= 0) */
    FP_CTL_STATUS,         /* /fp/status */
    FP_CTL_SUBSCRIBE,      /* /fp/subscribe [i port] */
    FP_CTL_UNSUBSCRIBE,    /* /fp/unsubscribe [i port] */
    FP_CTL_SLATE,          /* /fp/slate s; LLF /Slate s: the next take's slate */
    FP_CTL_TAKE,           /* /fp/take i; LLF /Take i: the next take's number */
    FP_CTL_QUIT,           /* /fp/quit: end the command as SIGTERM would */
    FP_CTL_KINDS
} fp_control_kind;

/** One queued command: what the frame loop applies and answers. */
typedef struct fp_control_cmd {
    fp_control_kind kind;
    char address[32];                 /* the address it came to ("/RecordStart"), for the reply */
    char text[FP_CONTROL_TEXT_MAX];   /* slate (RECORD_START, SLATE), SPEC (MAPPING), channel */
    bool has_text;
    double value;                     /* RADIUS, CHANNEL, SEEK */
    uint32_t take;                    /* RECORD_START (has_take), TAKE: 1..999999 */
    bool has_take;
    int port;                         /* SUBSCRIBE, UNSUBSCRIBE: 0 = the sender's own */
    struct sockaddr_storage from;     /* the sender, where the reply goes */
    socklen_t fromlen;
} fp_control_cmd;

/** Why messages were refused (counted, never answered). */
typedef enum fp_control_problem {
    FP_CTL_MALFORMED,       /* not OSC, a bad bundle, nesting beyond 8, over 64 KiB */
    FP_CTL_UNKNOWN_ADDRESS,
    FP_CTL_BAD_TYPES,       /* type tags or count not those of the address */
    FP_CTL_BAD_VALUE,       /* not finite, out of range, text not allowed */
    FP_CTL_QUEUE_FULL,      /* the frame loop did not take them in time */
    FP_CTL_PROBLEMS
} fp_control_problem;

typedef struct fp_control_stats {
    uint64_t packets, messages, queued;
    uint64_t problems[FP_CTL_PROBLEMS];
    uint64_t refused;                /* the sum of problems */
    uint64_t replies, pushes, send_errors;
} fp_control_stats;

/** The status a reply carries (docs/osc.md, "/fp/status"). Strings are the caller's. */
typedef struct fp_control_status {
    const char *state;     /* "idle", "engaged", "committed", "playing", "stopped" */
    const char *timecode;  /* HH:MM:SS:FF of the frame (the take's while recording) */
    const char *slate;     /* the slate of the take recording, else of the next take */
    uint32_t take;         /* the take recording, else the next take's if set, else the last */
    bool recording;
    double time_s;         /* the frame's time since the session's first frame (play: take's) */
    uint64_t frame;
} fp_control_status;

typedef struct fp_control fp_control;

/** Parse SPEC "osc:PORT[,bind=ADDR]" (PORT digits 1..65535, or 0: a free port), bind the
 *  UDP sockets as fp_udp_listen does (fp_net.h; the osc input's bind= alike): 127.0.0.1 unless
 *  bind= says otherwise, and on 127.0.0.1 or localhost also [::1] at the same port, best effort
 *  (fp_control_hears_ipv6); 0.0.0.0 or :: one dual-stack socket on [::] hearing IPv4 and IPv6
 *  senders; another IPv4 or IPv6 literal (bare or in brackets) that address alone; and start
 *  the network thread. Replies go back on the socket a command came in on.
 *  *warning (wlen bytes, may be NULL) gets a line to print when bound beyond loopback (OSC
 *  has no authentication) or where the IPv6 side could not be bound, else "". Returns 0 and
 *  *out, or a negative code with err: -EINVAL (a bad SPEC, bind= not an IP address nor
 *  localhost), -EBUSY (the port taken), -ENODEV (an address this machine lacks), -ENOMEM. */
int fp_control_open(const char *spec, fp_control **out, char *warning, size_t wlen, char *err,
                    size_t errlen);

/** The port bound (useful with osc:0). */
unsigned fp_control_port(const fp_control *c);

/** Where it listens, for the log ("127.0.0.1:9001 and [::1]:9001", "[::]:9001 (IPv4 and
 *  IPv6)"): the control's own text, valid until fp_control_close; "" for NULL. [any thread] */
const char *fp_control_where(const fp_control *c);

/** Whether it also hears [::1] at that port (bound on 127.0.0.1 where the machine has IPv6:
 *  a sender's "localhost" may resolve to ::1 first; replies go back the way a message came).
 *  [any thread] */
bool fp_control_hears_ipv6(const fp_control *c);

/** Take the next queued command into *cmd. Returns true when there was one. [frame thread]
 *  No allocation, no lock. */
bool fp_control_next(fp_control *c, fp_control_cmd *cmd);

/** Answer cmd's sender with /fp/status: the command's address, result ("ok", or "error: "
 *  and why), then st (docs/osc.md). Returns 0 or the send's negative errno (counted). */
int fp_control_reply(fp_control *c, const fp_control_cmd *cmd, const char *result,
                     const fp_control_status *st);

/** Send /fp/status (address "push", result "ok") to every subscriber. Returns how many. */
int fp_control_push(fp_control *c, const fp_control_status *st);

/** SUBSCRIBE / UNSUBSCRIBE cmd's sender (at cmd->port when given). Returns 0, -ENOSPC (full),
 *  -ENOENT (unsubscribe: not subscribed). [frame thread] */
int fp_control_subscribe(fp_control *c, const fp_control_cmd *cmd, bool on);
size_t fp_control_subscribers(const fp_control *c);

/** The counts so far. [any thread] */
void fp_control_stats_get(fp_control *c, fp_control_stats *st);

/** Check SPEC's syntax without binding (a command's options, before any work). Returns 0
 *  or -EINVAL with err naming it. */
int fp_control_spec_check(const char *spec, char *err, size_t errlen);

/** Stop the thread, close the socket, free. *c becomes NULL; NULL is fine. */
void fp_control_close(fp_control **c);

/** The command's name words for logs ("record start"). */
const char *fp_control_kind_name(fp_control_kind k);

#ifdef __cplusplus
}
#endif
#endif
