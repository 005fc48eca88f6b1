/* timecode.c: SMPTE timecode HH:MM:SS:FF at a rational frame rate (SMPTE ST 12-1):
 * non-drop counting at any rate, drop-frame counting at 30000/1001 and 60000/1001. */
#include "fp_take.h"

#include "fp_error.h"

#include <errno.h>
#include <stdio.h>
#include <string.h>
#include <time.h>

uint32_t fp_timecode_base(fp_take_rate r)
{
    if (!r.num || !r.den) return 0;
    return (uint32_t)(((uint64_t)r.num + r.den / 2) / r.den);
}

bool fp_timecode_drop_allowed(fp_take_rate r)
{
    uint64_t n = (uint64_t)r.num * 1001;
    return r.den && (n == (uint64_t)r.den * 30000 || n == (uint64_t)r.den * 60000);
}

/* Frame numbers dropped at the start of each minute but every tenth: 2 at 29.97, 4 at 59.94. */
static uint32_t drop_count(fp_take_rate r) { return fp_timecode_base(r) / 15; }

uint64_t fp_take_frames_in(int64_t ns, fp_take_rate r)
{
    if (ns <= 0 || !r.num || !r.den) return 0;
    unsigned __int128 f = (unsigned __int128)ns * r.num / ((unsigned __int128)r.den * 1000000000u);
    return (uint64_t)f;
}

uint64_t fp_take_frames_at(int64_t ns, fp_take_rate r)
{
    return ns < 0 || ns == INT64_MAX ? fp_take_frames_in(ns, r) : fp_take_frames_in(ns + 1, r);
}

int fp_timecode_from_frames(uint64_t frames, fp_take_rate r, bool drop, fp_timecode *tc)
{
    uint32_t base = fp_timecode_base(r);
    if (!base || !tc || (drop && !fp_timecode_drop_allowed(r))) return -EINVAL;
    uint64_t n = frames;
    if (drop) {
        uint64_t d = drop_count(r);
        uint64_t per10 = 10ull * 60 * base - 9 * d, per1 = 60ull * base - d;
        n %= 24ull * 6 * per10;
        uint64_t tens = n / per10, rem = n % per10;
        n += 9 * d * tens + (rem < d ? 0 : d * ((rem - d) / per1));
    } else {
        n %= 24ull * 3600 * base;
    }
    tc->frames = (uint32_t)(n % base);
    n /= base;
    tc->seconds = (uint32_t)(n % 60);
    tc->minutes = (uint32_t)(n / 60 % 60);
    tc->hours = (uint32_t)(n / 3600 % 24);
    tc->drop = drop;
    return 0;
}

int fp_timecode_to_frames(const fp_timecode *tc, fp_take_rate r, uint64_t *frames)
{
    uint32_t base = fp_timecode_base(r);
    if (!base || !tc || tc->hours >= 24 || tc->minutes >= 60 || tc->seconds >= 60 ||
        tc->frames >= base)
        return -EINVAL;
    uint64_t n = ((uint64_t)tc->hours * 3600 + tc->minutes * 60 + tc->seconds) * base + tc->frames;
    if (tc->drop) {
        if (!fp_timecode_drop_allowed(r)) return -EINVAL;
        uint32_t d = drop_count(r);
        if (tc->seconds == 0 && tc->frames < d && tc->minutes % 10 != 0) return -EINVAL;
        uint64_t minutes = 60ull * tc->hours + tc->minutes;
        n -= d * (minutes - minutes / 10);
    }
    if (frames) *frames = n;
    return 0;
}

int fp_timecode_format(const fp_timecode *tc, char *buf, size_t n)
{
    int k = snprintf(buf, n, "%02u:%02u:%02u%c%02u", tc->hours, tc->minutes, tc->seconds,
                     tc->drop ? ';' : ':', tc->frames);
    return (k < 0 || (size_t)k >= n) ? -EINVAL : 0;
}

static int field(const char **p, uint32_t *v)
{
    const char *s = *p;
    uint32_t x = 0;
    int digits = 0;
    while (*s >= '0' && *s <= '9' && digits < 4) x = 10 * x + (uint32_t)(*s++ - '0'), digits++;
    if (digits < 2 || (*s >= '0' && *s <= '9')) return -1;
    *v = x;
    *p = s;
    return 0;
}

int fp_timecode_parse(const char *text, fp_take_rate r, fp_timecode *tc, char *err, size_t errlen)
{
    static const char *names[4] = {"hours", "minutes", "seconds", "frames"};
    uint32_t v[4];
    const char *p = text;
    bool drop = false;
    if (!text) return fp_errorf(err, errlen, -EINVAL, "timecode: NULL");
    for (int i = 0; i < 4; i++) {
        if (field(&p, &v[i]))
            return fp_errorf(err, errlen, -EINVAL, "timecode \"%s\": %s at column %d are not 2-4 digits",
                             text, names[i], (int)(p - text) + 1);
        if (i < 3) {
            char sep = *p;
            if (sep == ';' || sep == '.') {
                if (i != 2)
                    return fp_errorf(err, errlen, -EINVAL,
                                     "timecode \"%s\": '%c' only before the frames", text, sep);
                drop = true;
            } else if (sep != ':') {
                return fp_errorf(err, errlen, -EINVAL, "timecode \"%s\": expected ':' at column %d",
                                 text, (int)(p - text) + 1);
            }
            p++;
        }
    }
    if (*p) return fp_errorf(err, errlen, -EINVAL, "timecode \"%s\": text after the frames", text);
    fp_timecode t = {v[0], v[1], v[2], v[3], drop};
    if (fp_timecode_to_frames(&t, r, NULL))
        return fp_errorf(err, errlen, -EINVAL,
                         "timecode \"%s\": out of range at %u/%u fps%s (hours < 24, minutes and "
                         "seconds < 60, frames < %u%s)", text, r.num, r.den,
                         drop ? " drop-frame" : "", fp_timecode_base(r),
                         drop ? ", no dropped frame number" : "");
    *tc = t;
    return 0;
}

int fp_timecode_time_of_day(int64_t realtime_s, int64_t realtime_ns, fp_take_rate r, bool drop,
                            fp_timecode *tc)
{
    time_t t = (time_t)realtime_s;
    struct tm tm;
    if (!localtime_r(&t, &tm)) return -EINVAL;
    int64_t ns = ((int64_t)tm.tm_hour * 3600 + tm.tm_min * 60 + (tm.tm_sec > 59 ? 59 : tm.tm_sec)) *
                     1000000000LL + realtime_ns;
    return fp_timecode_from_frames(fp_take_frames_in(ns, r), r, drop, tc);
}
