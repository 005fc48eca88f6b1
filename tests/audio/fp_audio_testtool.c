/* fp_audio_testtool: the measurements behind tests/audio/test_audio.sh (issue 54, items 4-6).
 *
 *   ltc OUT.wav NUM DEN HH:MM:SS[:;]FF SECONDS [glitch]
 *       LTC made with libltc's encoder at NUM/DEN fps (30000/1001 with ';': drop-frame),
 *       48 kHz mono, starting at the timecode given at sample 0; OUT.wav.txt lists the
 *       timecode of every frame encoded, as libltc counted them (ltc_encoder_get_timecode).
 *       glitch: two frames misread as a worn tape or a lossy codec gives them (the list
 *       keeps their true timecodes): the first with its seconds 7 on, the 13th with the
 *       frame field one past the last of a second (24 at 24 fps).
 *   sync REF.wav OUT.wav OFFSET_S
 *       Where OUT's samples sit in REF: the lag (samples) of the best match of OUT against
 *       REF from OFFSET_S on, searched over +-0.25 s, and the relative error there. Exit 1
 *       when |lag| exceeds one 60 fps frame (REF's rate / 60) or the error exceeds 1e-4.
 *   timecodes TAKE NUM DEN LIST.txt
 *       Every frame's timecode of TAKE (timecode_in + frames of the take's rate since its
 *       origin) against the LTC encoded: line k of LIST (ltc's list), k the LTC frames of
 *       NUM/DEN since the first frame's time. Exit 1 at the first difference (printed) or a
 *       wrong rate.
 *   jaw TAKE ONSETS ENDS [RELEASE_S]
 *       ONSETS, ENDS: comma-separated syllable onsets and ends (seconds from the take's first
 *       frame). Checks jaw.open > 0.3 within two frames (at the take's rate) of each onset,
 *       and < 0.1 in the silences (before the first onset, and from each end + RELEASE_S,
 *       default 0.25, to the next onset or the take's end). Prints the figures; exit 1 on
 *       a miss.
 *   span TAKE WAV
 *       WAV's length against the take's span: its last frame's time - time_origin_ns + one
 *       period of 60 fps (a frame's end). Exit 1 when they differ by more than 1/60 s.
 *   ramp OUT.wav SECONDS
 *       A 48 kHz mono 32-bit float WAV whose sample k is ((k mod 32768) + 1) / 65536: every
 *       sample says where it is (an emulated microphone for --audio-in file:).
 *   ramp-check WAV
 *       WAV's samples are one run of a ramp's without a gap or a repeat; prints where it
 *       starts. Exit 1 at a break.
 *   range REF.wav OUT.wav START_S FRAMES
 *       OUT is FRAMES sample frames, each channel equal bit for bit to REF's from round(START_S
 *       x rate) on (0 outside REF). Exit 1 at the first difference (printed).
 *   take-range TAKE SOUNDTRACK FIRST LAST|last
 *       Prints "START_S FRAMES": where frames FIRST..LAST (indices) of TAKE lie in its
 *       soundtrack (offset_s + the first's time since the origin) and how many of the
 *       soundtrack's samples they span (the last's time - the first's + one period of the
 *       take's rate), for `range`.
 * timecodes also takes a 6th argument `any`: the take's timecode_in may be any of the LTC's
 *       (a live take starts later than the LTC's first sample); from there frames follow.
 * SPDX-License-Identifier: GPL-3.0-or-later */
#include "fp_take.h"

#include <ltc.h>
#include <math.h>
#include <sndfile.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static int parse_tc(const char *s, fp_timecode *tc)
{
    char sep = ':';
    unsigned h, m, sec, f;
    if (sscanf(s, "%u:%u:%u%c%u", &h, &m, &sec, &sep, &f) != 5) return -1;
    *tc = (fp_timecode){h, m, sec, f, sep == ';'};
    return 0;
}

static float *read_wav(const char *path, SF_INFO *si)
{
    memset(si, 0, sizeof *si);
    SNDFILE *sf = sf_open(path, SFM_READ, si);
    if (!sf) {
        fprintf(stderr, "%s: %s\n", path, sf_strerror(NULL));
        return NULL;
    }
    float *buf = malloc((size_t)si->frames * (size_t)si->channels * sizeof *buf + 1);
    if (buf) si->frames = sf_readf_float(sf, buf, si->frames);
    sf_close(sf);
    for (sf_count_t i = 0; buf && i < si->frames; i++) buf[i] = buf[i * si->channels]; /* first channel */
    return buf;
}

static int cmd_ltc(char **argv)
{
    double fps = atof(argv[3]) / atof(argv[4]), seconds = atof(argv[6]);
    const bool glitch = argv[7] && !strcmp(argv[7], "glitch");
    fp_timecode tc;
    if (parse_tc(argv[5], &tc)) return 2;
    const double rate = 48000;
    LTCEncoder *e = ltc_encoder_create(rate, fps, fabs(fps - 25) < 0.01 ? LTC_TV_625_50 : LTC_TV_525_60,
                                       LTC_USE_DATE);
    SMPTETimecode st = {.timezone = "+0000", .years = 26, .months = 1, .days = 1, .hours = (unsigned char)tc.hours,
                        .mins = (unsigned char)tc.minutes, .secs = (unsigned char)tc.seconds,
                        .frame = (unsigned char)tc.frames};
    ltc_encoder_set_timecode(e, &st);
    SF_INFO si = {.samplerate = (int)rate, .channels = 1, .format = SF_FORMAT_WAV | SF_FORMAT_PCM_16};
    SNDFILE *sf = sf_open(argv[2], SFM_WRITE, &si);
    if (!sf) return fprintf(stderr, "%s: %s\n", argv[2], sf_strerror(NULL)), 1;
    char listname[4200];
    snprintf(listname, sizeof listname, "%s.txt", argv[2]);
    FILE *list = fopen(listname, "w");
    if (!list) return perror(listname), 1;
    long frames = lround(seconds * fps);
    for (long k = 0; k < frames; k++) {
        SMPTETimecode now;
        ltc_encoder_get_timecode(e, &now);
        fprintf(list, "%02d:%02d:%02d%c%02d\n", now.hours, now.mins, now.secs, tc.drop ? ';' : ':', now.frame);
        const bool bad = glitch && (k == 0 || k == 12);
        if (bad) {
            SMPTETimecode g = now;
            if (k == 0) g.secs = (unsigned char)((now.secs + 7) % 60);
            else g.frame = (unsigned char)lround(fps);
            ltc_encoder_set_timecode(e, &g);
        }
        ltc_encoder_encode_frame(e);
        if (bad) ltc_encoder_set_timecode(e, &now);
        ltcsnd_sample_t *buf;
        int n = ltc_encoder_get_bufferptr(e, &buf, 1);
        float out[4096];
        for (int i = 0; i < n && i < 4096; i++) out[i] = ((float)buf[i] - 128.f) / 160.f;
        sf_writef_float(sf, out, n);
        ltc_encoder_inc_timecode(e);
    }
    sf_close(sf);
    fclose(list);
    ltc_encoder_free(e);
    printf("ltc: %s: %ld frames at %.5f fps from %s\n", argv[2], frames, fps, argv[5]);
    return 0;
}

static int cmd_sync(char **argv)
{
    SF_INFO a, b;
    float *ref = read_wav(argv[2], &a), *out = read_wav(argv[3], &b);
    if (!ref || !out) return 1;
    if (a.samplerate != b.samplerate) return fprintf(stderr, "sync: rates differ\n"), 1;
    long start = lround(atof(argv[4]) * a.samplerate), search = a.samplerate / 4, n = (long)b.frames;
    long best = 0;
    double best_err = INFINITY, energy = 0;
    for (long k = 0; k < n; k++) energy += (double)out[k] * out[k];
    for (long lag = -search; lag <= search; lag++) {
        double err = 0;
        for (long k = 0; k < n && err < best_err * energy; k++) {
            long i = start + lag + k;
            double r = i >= 0 && i < a.frames ? ref[i] : 0.0, d = out[k] - r;
            err += d * d;
        }
        err /= energy > 0 ? energy : 1;
        if (err < best_err) best_err = err, best = lag;
    }
    long tol = a.samplerate / 60;
    printf("sync: %s: %ld samples (%.3f s) matched at lag %ld samples (%.2f ms; tolerance %ld), "
           "relative error %.3g\n", argv[3], n, (double)n / a.samplerate, best,
           1e3 * (double)best / a.samplerate, tol, best_err);
    free(ref);
    free(out);
    return labs(best) <= tol && best_err <= 1e-4 && n > 0 ? 0 : 1;
}

static int cmd_timecodes(char **argv)
{
    fp_take_reader *r = NULL;
    char err[1024];
    if (fp_take_reader_open(argv[2], &r, err, sizeof err)) return fprintf(stderr, "%s\n", err), 1;
    const fp_take_header *h = fp_take_reader_header(r);
    fp_take_rate want = {(uint32_t)atoi(argv[3]), (uint32_t)atoi(argv[4])};
    char (*lines)[32] = calloc(100000, sizeof *lines), in[32], ws[32] = "";
    size_t nl = 0;
    FILE *lf = fopen(argv[5], "r");
    if (!lf || !lines) return perror(argv[5]), 1;
    while (nl < 100000 && fgets(lines[nl], sizeof lines[nl], lf)) lines[nl][strcspn(lines[nl], "\n")] = 0, nl++;
    fclose(lf);
    fp_timecode_format(&h->timecode_in, in, sizeof in);
    int bad = h->rate.num != want.num || h->rate.den != want.den;
    if (bad) printf("timecodes: the take's rate is %u/%u, the LTC's %u/%u\n", h->rate.num, h->rate.den, want.num, want.den);
    uint64_t in_n = 0;
    fp_timecode_to_frames(&h->timecode_in, h->rate, &in_n);
    fp_take_frame f;
    size_t n = fp_take_reader_frames(r), checked = 0, base = 0;
    int64_t t_first = 0;
    const bool any = argv[6] && !strcmp(argv[6], "any");
    if (any) { /* timecode_in is one of the LTC's */
        for (base = 0; base < nl && strcmp(lines[base], in); base++) {
        }
        if (base == nl) printf("timecodes: timecode_in %s is none of the LTC's\n", in), bad = 1;
        else printf("timecodes: timecode_in %s is the LTC's frame %zu\n", in, base);
    }
    for (size_t i = 0; i < n && !bad; i++) {
        if (fp_take_reader_read(r, i, &f, err, sizeof err)) return fprintf(stderr, "%s\n", err), 1;
        if (!i) t_first = f.time_ns;
        fp_timecode got;
        fp_timecode_from_frames(in_n + fp_take_frames_at(f.time_ns - h->time_origin_ns, h->rate), h->rate,
                                h->timecode_in.drop, &got);
        uint64_t k = base + fp_take_frames_at(f.time_ns - (any ? h->time_origin_ns : t_first), want);
        if (k >= nl) break; /* (past the LTC encoded) */
        snprintf(ws, sizeof ws, "%s", lines[k]);
        char gs[32];
        fp_timecode_format(&got, gs, sizeof gs);
        if (strcmp(gs, ws)) {
            printf("timecodes: frame %zu: %s, the LTC's %s\n", i, gs, ws);
            bad = 1;
        }
        checked++;
    }
    printf("timecodes: %s: timecode_in %s (source %s), rate %u/%u; %zu of %zu frames equal the LTC's "
           "(last %s)\n", argv[2], in, h->timecode_source ? h->timecode_source : "system", h->rate.num,
           h->rate.den, bad ? checked - 1 : checked, n, ws);
    fp_take_reader_close(&r);
    free(lines);
    return bad || !checked;
}

static size_t parse_list(const char *s, double *out, size_t max)
{
    size_t n = 0;
    for (char *end; *s && n < max; s = *end ? end + 1 : end) out[n++] = strtod(s, &end);
    return n;
}

static int cmd_jaw(int argc, char **argv)
{
    double on[64], end[64], release = argc > 5 ? atof(argv[5]) : 0.25;
    size_t n = parse_list(argv[3], on, 64);
    if (parse_list(argv[4], end, 64) != n || !n) return fprintf(stderr, "jaw: onsets and ends differ\n"), 2;
    fp_take_reader *r = NULL;
    char err[1024];
    if (fp_take_reader_open(argv[2], &r, err, sizeof err)) return fprintf(stderr, "%s\n", err), 1;
    const fp_take_header *h = fp_take_reader_header(r);
    size_t nf = fp_take_reader_frames(r);
    double *t = malloc(nf * sizeof *t), *jaw = malloc(nf * sizeof *jaw);
    fp_take_frame f;
    for (size_t i = 0; i < nf; i++) {
        fp_take_reader_read(r, i, &f, err, sizeof err);
        t[i] = (double)(f.time_ns - h->time_origin_ns) * 1e-9;
        jaw[i] = NAN;
        for (size_t c = 0; f.control && c < f.control->channel_count; c++)
            if (!strcmp(f.control->channels[c].name, "jaw.open")) jaw[i] = f.control->channels[c].value;
    }
    double period = (double)h->rate.den / h->rate.num;
    int bad = 0;
    for (size_t s = 0; s < n; s++) { /* the first frame at or after the onset, then two more */
        double when = NAN, peak = 0;
        for (size_t i = 0; i < nf; i++) {
            if (t[i] >= on[s] - 1e-9 && t[i] <= end[s] && jaw[i] > peak) peak = jaw[i];
            if (t[i] >= on[s] - 1e-9 && jaw[i] > 0.3 && isnan(when)) when = t[i];
        }
        double late = (when - on[s]) / period;
        printf("jaw: syllable %zu at %.3f s: jaw.open > 0.3 at %.3f s (%.2f frames after the onset), peak %.3f\n",
               s + 1, on[s], when, late, peak);
        if (isnan(when) || late > 2.0 + 1e-6) bad = 1;
    }
    for (size_t s = 0; s <= n; s++) { /* silence s: before syllable s (after s-1's release) */
        double from = s ? end[s - 1] + release : 0.0, to = s < n ? on[s] : t[nf - 1] + 1e-9;
        double most = 0;
        size_t frames = 0;
        for (size_t i = 0; i < nf; i++)
            if (t[i] >= from && t[i] < to) {
                frames++;
                if (!(jaw[i] < most)) most = jaw[i];
            }
        printf("jaw: silence %.3f - %.3f s: %zu frames, jaw.open at most %.3f\n", from, to, frames, most);
        if (!(most < 0.1)) bad = 1;
    }
    free(t);
    free(jaw);
    fp_take_reader_close(&r);
    return bad;
}

static int cmd_span(char **argv)
{
    fp_take_reader *r = NULL;
    char err[1024];
    if (fp_take_reader_open(argv[2], &r, err, sizeof err)) return fprintf(stderr, "%s\n", err), 1;
    const fp_take_header *h = fp_take_reader_header(r);
    size_t n = fp_take_reader_frames(r);
    fp_take_frame f;
    if (!n || fp_take_reader_read(r, n - 1, &f, err, sizeof err)) return fprintf(stderr, "%s: no frames\n", argv[2]), 1;
    double span = (double)(f.time_ns - h->time_origin_ns) * 1e-9 + 1.0 / 60;
    fp_take_reader_close(&r);
    SF_INFO si;
    float *w = read_wav(argv[3], &si);
    if (!w) return 1;
    free(w);
    double len = (double)si.frames / si.samplerate;
    printf("span: %s: %.4f s; %s: %.4f s (%ld frames at %d Hz); difference %.2f ms (tolerance %.2f)\n", argv[2],
           span, argv[3], len, (long)si.frames, si.samplerate, 1e3 * (len - span), 1e3 / 60);
    return fabs(len - span) <= 1.0 / 60 ? 0 : 1;
}

static float ramp_value(long k) { return (float)((k % 32768) + 1) / 65536.0f; }

static int cmd_ramp(char **argv)
{
    long n = lround(atof(argv[3]) * 48000);
    SF_INFO si = {.samplerate = 48000, .channels = 1, .format = SF_FORMAT_WAV | SF_FORMAT_FLOAT};
    SNDFILE *sf = sf_open(argv[2], SFM_WRITE, &si);
    float *buf = malloc((size_t)n * sizeof *buf);
    if (!sf || !buf) return fprintf(stderr, "%s: %s\n", argv[2], sf_strerror(NULL)), 1;
    for (long k = 0; k < n; k++) buf[k] = ramp_value(k);
    sf_writef_float(sf, buf, n);
    sf_close(sf);
    free(buf);
    return 0;
}

static int cmd_ramp_check(char **argv)
{
    SF_INFO si;
    float *w = read_wav(argv[2], &si);
    if (!w || si.frames < 2) return fprintf(stderr, "ramp-check: %s: no samples\n", argv[2]), 1;
    long start = lround(w[0] * 65536.0) - 1;
    for (long k = 1; k < (long)si.frames; k++)
        if (w[k] != ramp_value(start + k)) {
            printf("ramp-check: %s: sample %ld is %.8g, the ramp's %.8g (a gap or a repeat)\n", argv[2], k,
                   w[k], ramp_value(start + k));
            return 1;
        }
    if (w[0] <= 0) return printf("ramp-check: %s: starts with silence\n", argv[2]), 1;
    printf("ramp-check: %s: %ld samples, one run of the ramp from its sample %ld (mod 32768)\n", argv[2],
           (long)si.frames, start);
    free(w);
    return 0;
}

static int cmd_range(char **argv)
{
    SF_INFO a, b;
    memset(&a, 0, sizeof a);
    memset(&b, 0, sizeof b);
    SNDFILE *fa = sf_open(argv[2], SFM_READ, &a), *fb = sf_open(argv[3], SFM_READ, &b);
    if (!fa || !fb) return fprintf(stderr, "range: %s\n", sf_strerror(NULL)), 1;
    if (a.samplerate != b.samplerate || a.channels != b.channels)
        return printf("range: rate or channels differ (%d/%d, %d/%d)\n", a.samplerate, a.channels,
                      b.samplerate, b.channels), 1;
    size_t ch = (size_t)a.channels;
    float *ra = malloc((size_t)a.frames * ch * sizeof(float) + 4), *rb = malloc((size_t)b.frames * ch * sizeof(float) + 4);
    sf_readf_float(fa, ra, a.frames);
    sf_readf_float(fb, rb, b.frames);
    sf_close(fa);
    sf_close(fb);
    long start = lround(atof(argv[4]) * a.samplerate), want = atol(argv[5]);
    if (b.frames != want) return printf("range: %s has %ld frames, want %ld\n", argv[3], (long)b.frames, want), 1;
    long nonzero = 0;
    for (long k = 0; k < want; k++)
        for (size_t c = 0; c < ch; c++) {
            long i = start + k;
            float r = i >= 0 && i < a.frames ? ra[(size_t)i * ch + c] : 0.0f, o = rb[(size_t)k * ch + c];
            if (memcmp(&r, &o, sizeof r)) return printf("range: frame %ld channel %zu: %.9g, the soundtrack's %.9g\n", k, c, o, r), 1;
            nonzero += o != 0;
        }
    printf("range: %s: %ld frames equal %s's from frame %ld bit for bit (%ld samples not zero)\n", argv[3], want,
           argv[2], start, nonzero);
    free(ra);
    free(rb);
    return 0;
}

static int cmd_take_range(char **argv)
{
    fp_take_reader *r = NULL;
    char err[1024];
    if (fp_take_reader_open(argv[2], &r, err, sizeof err)) return fprintf(stderr, "%s\n", err), 1;
    const fp_take_header *h = fp_take_reader_header(r);
    SF_INFO si;
    memset(&si, 0, sizeof si);
    SNDFILE *sf = sf_open(argv[3], SFM_READ, &si);
    if (!sf) return fprintf(stderr, "%s: %s\n", argv[3], sf_strerror(NULL)), 1;
    sf_close(sf);
    fp_take_frame f;
    size_t a = (size_t)atol(argv[4]), b = strcmp(argv[5], "last") ? (size_t)atol(argv[5]) : fp_take_reader_frames(r) - 1;
    if (fp_take_reader_read(r, a, &f, err, sizeof err)) return fprintf(stderr, "%s\n", err), 1;
    int64_t ta = f.time_ns;
    if (fp_take_reader_read(r, b, &f, err, sizeof err)) return fprintf(stderr, "%s\n", err), 1;
    double start = h->soundtrack_offset_s + (double)(ta - h->time_origin_ns) * 1e-9;
    double dur = (double)(f.time_ns - ta) * 1e-9 + (double)h->rate.den / h->rate.num;
    printf("%.17g %lld\n", start, (long long)llround(dur * si.samplerate));
    fp_take_reader_close(&r);
    return 0;
}

int main(int argc, char **argv)
{
    if (argc >= 6 && !strcmp(argv[1], "take-range")) return cmd_take_range(argv);
    if (argc >= 4 && !strcmp(argv[1], "span")) return cmd_span(argv);
    if (argc >= 4 && !strcmp(argv[1], "ramp")) return cmd_ramp(argv);
    if (argc >= 3 && !strcmp(argv[1], "ramp-check")) return cmd_ramp_check(argv);
    if (argc >= 6 && !strcmp(argv[1], "range")) return cmd_range(argv);
    if (argc >= 7 && !strcmp(argv[1], "ltc")) return cmd_ltc(argv);
    if (argc >= 5 && !strcmp(argv[1], "sync")) return cmd_sync(argv);
    if (argc >= 6 && !strcmp(argv[1], "timecodes")) return cmd_timecodes(argv);
    if (argc >= 5 && !strcmp(argv[1], "jaw")) return cmd_jaw(argc, argv);
    fprintf(stderr, "usage: fp_audio_testtool ltc|sync|timecodes|jaw|span|ramp|ramp-check|range ... (see the source)\n");
    return 2;
}
