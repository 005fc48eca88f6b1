/* glove_outage: how the CyberGlove input says an outage (glove_outage.h). */
#include "glove_outage.h"

#include <stdio.h>
#include <string.h>

static void keep(fpg_outage *o, const char *why)
{
    snprintf(o->last, sizeof o->last, "%s", why ? why : "");
}

void fpg_outage_lost(fpg_outage *o, const char *why)
{
    o->loss_said = true;
    keep(o, why);
}

bool fpg_outage_attempt(fpg_outage *o, int64_t t_ns, const char *path, char *line, size_t len)
{
    bool due = false;
    if (!o->since_ns) {
        o->since_ns = t_ns;
        o->say_ns = t_ns + FPG_OUTAGE_FIRST_SAY_NS;
    } else if (t_ns >= o->say_ns) {
        snprintf(line, len, "still no answer from %s after %.0f s, %u %s%s%s%s", path,
                 (double)(t_ns - o->since_ns) / 1e9, o->tries, o->tries == 1 ? "try" : "tries",
                 o->last[0] ? " (last: " : "", o->last, o->last[0] ? ")" : "");
        o->say_ns = t_ns + FPG_OUTAGE_SAY_EVERY_NS;
        due = true;
    }
    o->tries++;
    return due;
}

int fpg_outage_failed(fpg_outage *o, const char *why)
{
    int how = !o->loss_said ? 2 : strcmp(why, o->last) ? 1 : 0;
    o->loss_said = true;
    keep(o, why);
    return how;
}

void fpg_outage_up(fpg_outage *o, int64_t t_ns, char *buf, size_t len)
{
    if (o->since_ns)
        snprintf(buf, len, "; %s after %.1f s, %u %s", o->was_up ? "back" : "answered",
                 (double)(t_ns - o->since_ns) / 1e9, o->tries, o->tries == 1 ? "try" : "tries");
    else if (len)
        buf[0] = '\0';
    *o = (fpg_outage){.was_up = true};
}

void fpg_noise_text(char *why, size_t len, int bits, int timeout_ms, uint64_t noise, int expected,
                    int seen)
{
    if (bits == 16)
        snprintf(why, len, "no well-formed 16-bit frame in %d ms, %llu bytes of line noise",
                 timeout_ms, (unsigned long long)noise);
    else if (seen > 0 && seen != expected) /* (no byte count: said alike each time) */
        snprintf(why, len, "records of %d bytes, expected %d (?S/?N, ?D or ?U disagree with "
                 "the records)", seen, expected); /* (short: a status event's text) */
    else
        snprintf(why, len, "no well-formed record in %d ms, %llu bytes of line noise (expected "
                 "%d-byte records)", timeout_ms, (unsigned long long)noise, expected);
}
