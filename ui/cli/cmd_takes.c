/* facepuppet takes: the takes of a folder as a table or JSON (fp_take_list), a take's rating
 * and description rewritten (takes rate, takes describe: fp_take_edit_header); and
 * fp_app_take_info for `facepuppet info TAKE`. */
#define _GNU_SOURCE
#include "app_getopt.h"
#include "app_util.h"
#include "command.h"
#include "fp_take.h"
#include "app_stack.h"

#include <cjson/cJSON.h>
#include "fp_text.h"
#include <errno.h>
#include <getopt.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

static void usage(FILE *f)
{
    fprintf(f, "usage: facepuppet takes [DIR] [--json]\n"
               "       facepuppet takes rate TAKE N          (N: 1..5 stars, 0 none)\n"
               "       facepuppet takes describe TAKE TEXT   (TEXT: one argument; \"\" clears)\n\n"
               "The takes (SLATE_TNNN.fptake) in DIR (default: the current folder), by slate and\n"
               "take number: timecode in and out, duration, frames, mesh, mapping, rating, STATE\n"
               "and the description (the table shows its first line, cut at 60 characters);\n"
               "STATE says ok, \"cut\" (damaged or cut short, e.g. the recording process died: the\n"
               "frames before the damage play) or \"open\" (no end chunk yet). A *.fptake file\n"
               "that is no take, or whose signature or header is damaged, is \"unreadable\": its\n"
               "slate and take number are what its name gives, it has no timecode, duration or\n"
               "frames (\"-\"; null in JSON), and the reason is under the table (\"message\").\n"
               "Then the stacks (*.fpstack, layers of takes: docs/stack.md), each with its layers\n"
               "(take, region, mode, range, mute, solo).\n"
               "  --json   one JSON array instead of the table: the takes (\"kind\": \"take\"; their\n"
               "           \"reach\", info's reach line: vectors, median, p10, longest_drag_mm,\n"
               "           held; null where none), then the stacks (\"kind\": \"stack\", \"path\",\n"
               "           \"state\", \"message\", \"layers\":\n"
               "           take, region, mode, in_s, out_s (null: to the end), fade_s, offset_s,\n"
               "           gain, mute, solo)\n\n"
               "rate and describe rewrite the take's header (its \"rating\" and \"description\";\n"
               "`info`, `takes` and `play` show them) atomically: a temporary file beside the\n"
               "take renamed over it, every other byte as it was. TAKE is the file (the\n"
               ".fptake may be left out). A take with no end chunk may still be recording and\n"
               "is refused unless --force.\n"
               "  --force  rewrite a take that has no end chunk (before TAKE, or last)\n\n"
               "Exit status: 0 once the folder is listed, whatever the files' states (see STATE),\n"
               "or the take rewritten; 64 usage, 65 a damaged take, 66 the folder or take cannot\n"
               "be read, 73 the take cannot be rewritten (or has no end chunk, without --force).\n");
}

static const char *state_of(const fp_take_info *t)
{
    return t->error ? "unreadable" : t->message[0] ? "cut" : t->complete ? "ok" : "open";
}

/* A description for the table: its first line, made UTF-8 text (fp_text_clean: tabs too
 * become U+FFFD, so they are made spaces first), cut at 60 characters with "...". */
static void description_line(const char *d, char *out, size_t n)
{
    char line[512];
    size_t len = strcspn(d, "\n");
    snprintf(line, sizeof line, "%.*s", (int)len, d);
    for (char *p = line; *p; p++)
        if (*p == '\t' || *p == '\r') *p = ' ';
    fp_text_clean(line, out, n);
    size_t chars = 0, cut = 0;
    for (size_t i = 0; out[i]; i++) /* (a character: a byte that is no UTF-8 continuation byte) */
        if (((unsigned char)out[i] & 0xC0) != 0x80 && chars++ == 57) cut = i;
    if (chars > 60 && cut + 4 <= n) memcpy(out + cut, "...", 4);
}

static void print_table(const fp_take_info *v, size_t n)
{
    printf("%-16s %4s  %-11s  %-11s  %9s  %7s  %-6s  %-10s  %-28s  %-10s  %s\n", "SLATE", "TAKE",
           "TC IN", "TC OUT", "DURATION", "FRAMES", "RATING", "MAPPING", "MESH", "STATE",
           "DESCRIPTION");
    for (size_t i = 0; i < n; i++) {
        const fp_take_info *t = &v[i];
        char in[32] = "-", out[32] = "-", rate[8] = "-", take[16] = "-", dur[32] = "-", fr[32] = "-";
        if (!t->error) { /* (an unreadable file has none of these: "-", not zeros) */
            fp_timecode_format(&t->timecode_in, in, sizeof in);
            fp_timecode_format(&t->timecode_out, out, sizeof out);
            snprintf(dur, sizeof dur, "%.2fs", t->duration_s);
            snprintf(fr, sizeof fr, "%llu", (unsigned long long)t->frames);
        }
        if (t->take) snprintf(take, sizeof take, "%u", t->take); /* (an unreadable one's: its name's) */
        if (t->rating) snprintf(rate, sizeof rate, "%d/5", t->rating);
        const char *mesh = strrchr(t->mesh, '/') ? strrchr(t->mesh, '/') + 1 : t->mesh;
        char cm[1024], cp[256]; /* shown as UTF-8 text: a terminal obeys no byte of a file */
        fp_text_clean(mesh, cm, sizeof cm);
        fp_text_clean(t->mapping, cp, sizeof cp);
        char cs[4 * FP_TAKE_SLATE_MAX];
        char cd[4 * 64];
        description_line(t->description, cd, sizeof cd);
        printf("%-16s %4s  %-11s  %-11s  %9s  %7s  %-6s  %-10s  %-28.28s  %-10s  %s\n",
               fp_text_clean(t->slate, cs, sizeof cs), take, in, out, dur, fr, rate, cp[0] ? cp : "-",
               cm[0] ? cm : "-", state_of(t), cd[0] ? cd : "-");
    }
    for (size_t i = 0; i < n; i++)
        if (v[i].message[0]) {
            char cmsg[1024];
            if (v[i].error) /* not a take: the reader's message names the file, not a slate */
                printf("  %s\n", fp_text_clean(v[i].message, cmsg, sizeof cmsg));
            else
                printf("  %s_T%03u: %s\n", v[i].slate, v[i].take,
                       fp_text_clean(v[i].message, cmsg, sizeof cmsg));
        }
}

static int print_json(const fp_take_info *v, size_t n, const char *dir)
{
    cJSON *arr = cJSON_CreateArray();
    for (size_t i = 0; arr && i < n; i++) {
        const fp_take_info *t = &v[i];
        cJSON *o = cJSON_CreateObject();
        char in[32] = "", out[32] = "", c[4 * 4096]; /* c: a string made UTF-8 text (fp_text.h) */
        cJSON_AddStringToObject(o, "kind", "take");
        if (!t->error) {
            fp_timecode_format(&t->timecode_in, in, sizeof in);
            fp_timecode_format(&t->timecode_out, out, sizeof out);
        }
        cJSON_AddStringToObject(o, "path", fp_text_clean(t->path, c, sizeof c));
        cJSON_AddStringToObject(o, "slate", fp_text_clean(t->slate, c, sizeof c));
        if (t->take) cJSON_AddNumberToObject(o, "take", t->take); /* (unreadable: its name's) */
        else cJSON_AddNullToObject(o, "take");
        cJSON_AddStringToObject(o, "timecode_in", in);
        cJSON_AddStringToObject(o, "timecode_out", out);
        if (t->error) { /* not read: unknown, not zero */
            cJSON_AddNullToObject(o, "duration_s");
            cJSON_AddNullToObject(o, "frames");
        } else {
            cJSON_AddNumberToObject(o, "duration_s", t->duration_s);
            cJSON_AddNumberToObject(o, "frames", (double)t->frames);
        }
        char rate[32];
        snprintf(rate, sizeof rate, "%u/%u", t->rate.num, t->rate.den);
        cJSON_AddStringToObject(o, "frame_rate", t->error ? "" : rate);
        cJSON_AddStringToObject(o, "mesh", fp_text_clean(t->mesh, c, sizeof c));
        cJSON_AddStringToObject(o, "mapping", fp_text_clean(t->mapping, c, sizeof c));
        cJSON_AddNumberToObject(o, "rating", t->rating);
        /* (line breaks and tabs kept, JSON escapes them; anything else not text cleaned) */
        cJSON_AddStringToObject(o, "description", fp_text_ok(t->description, true) ? t->description
                                : fp_text_clean(t->description, c, sizeof c));
        cJSON_AddStringToObject(o, "date", fp_text_clean(t->date, c, sizeof c));
        cJSON_AddStringToObject(o, "state", state_of(t));
        if (t->reach.vectors) { /* how far the skin followed (the take's end chunk) */
            cJSON *r = cJSON_AddObjectToObject(o, "reach");
            cJSON_AddNumberToObject(r, "vectors", (double)t->reach.vectors);
            cJSON_AddNumberToObject(r, "median", t->reach.median);
            cJSON_AddNumberToObject(r, "p10", t->reach.p10);
            cJSON_AddNumberToObject(r, "longest_drag_mm", t->reach.longest_drag_mm);
            cJSON_AddNumberToObject(r, "held", (double)t->reach.held);
        } else {
            cJSON_AddNullToObject(o, "reach");
        }
        cJSON_AddStringToObject(o, "message", fp_text_clean(t->message, c, sizeof c));
        cJSON_AddItemToArray(arr, o);
    }
    cJSON *stacks = fp_app_stack_list_json(dir); /* then the stacks, each with its layers */
    for (cJSON *e; arr && stacks && (e = cJSON_DetachItemFromArray(stacks, 0));) cJSON_AddItemToArray(arr, e);
    cJSON_Delete(stacks);
    char *text = arr ? cJSON_Print(arr) : NULL;
    cJSON_Delete(arr);
    if (!text) {
        fprintf(stderr, "facepuppet takes: out of memory\n");
        return FP_EXIT_SOFTWARE;
    }
    printf("%s\n", text);
    free(text);
    return FP_EXIT_OK;
}

/* TAKE of rate/describe: the file, or TAKE.fptake when TAKE is not there and that is. */
static const char *take_file(const char *take, char *buf, size_t len)
{
    struct stat st;
    if (stat(take, &st) && errno == ENOENT) {
        snprintf(buf, len, "%s%s", take, FP_TAKE_EXTENSION);
        if (!stat(buf, &st)) return buf;
    }
    return take;
}

/* `takes rate TAKE N` and `takes describe TAKE TEXT` (argv[0] the verb). */
static int takes_edit(int argc, char **argv)
{
    static const struct option opts[] = {{"force", no_argument, 0, 'f'},
                                         {"help", no_argument, 0, 'h'}, {0, 0, 0, 0}};
    const bool rate = !strcmp(argv[0], "rate");
    char prog[48]; /* getopt's messages start "facepuppet takes VERB: " */
    snprintf(prog, sizeof prog, "facepuppet takes %s", rate ? "rate" : "describe");
    argv[0] = prog;
    fp_take_edit e = {0};
    optind = 1;
    for (int c; (c = fp_app_getopt(argc, argv, "+h", opts)) != -1;) {
        if (c == 'f') e.open_ok = true;
        else if (c == 'h') { usage(stdout); return FP_EXIT_OK; }
        else { usage(stderr); return FP_EXIT_USAGE; }
    }
    /* options end at TAKE (a TEXT may start with '-'), but the --force that the refusal of an
     * open take asks for is taken after TAKE N / TAKE TEXT too */
    if (argc - optind == 3 && !strcmp(argv[optind + 2], "--force")) {
        e.open_ok = true;
        argc--;
    }
    if (argc - optind != 2) {
        fprintf(stderr, "%s: give %s (see --help)\n", prog,
                rate ? "TAKE N" : "TAKE TEXT (quote the text: one argument)");
        return FP_EXIT_USAGE;
    }
    char buf[4200];
    const char *path = take_file(argv[optind], buf, sizeof buf), *arg = argv[optind + 1];
    unsigned long long n = 0;
    if (rate && !fp_parse_whole(arg, 5, &n)) {
        fprintf(stderr, "facepuppet takes rate: N must be a whole number 0..5 (0: none), got '%s'\n",
                arg);
        return FP_EXIT_USAGE;
    }
    if (!rate && !fp_text_ok(arg, true)) {
        fprintf(stderr, "facepuppet takes describe: TEXT must be UTF-8 text without control "
                "characters (tabs and line breaks allowed)\n");
        return FP_EXIT_USAGE;
    }
    e.set_rating = rate;
    e.rating = (int)n;
    e.description = rate ? NULL : arg;
    struct stat st;
    if (stat(path, &st)) { /* (a take missing is an input: 66, not an output's 73) */
        fprintf(stderr, "%s: %s: %s\n", prog, path, strerror(errno));
        return fp_app_exit_code(-errno, FP_APP_INPUT);
    }
    char err[1024];
    int rc = fp_take_edit_header(path, &e, err, sizeof err);
    if (rc) {
        fprintf(stderr, "%s: %s%s\n", prog, err,
                rc == -EBUSY ? " (--force rewrites it anyway)" : "");
        return fp_app_exit_code(rc, FP_APP_OUTPUT);
    }
    if (rate) printf("%s: rating %llu/5\n", path, n);
    else printf("%s: description %s\n", path, arg[0] ? arg : "cleared");
    return FP_EXIT_OK;
}

static int takes_main(int argc, char **argv)
{
    if (argc >= 2 && (!strcmp(argv[1], "rate") || !strcmp(argv[1], "describe")))
        return takes_edit(argc - 1, argv + 1);
    static const struct option opts[] = {{"json", no_argument, 0, 'j'},
                                         {"help", no_argument, 0, 'h'}, {0, 0, 0, 0}};
    bool json = false;
    optind = 1;
    for (int c; (c = fp_app_getopt(argc, argv, "h", opts)) != -1;) {
        if (c == 'j') json = true;
        else if (c == 'h') { usage(stdout); return FP_EXIT_OK; }
        else { usage(stderr); return FP_EXIT_USAGE; }
    }
    if (argc - optind > 1) {
        fprintf(stderr, "facepuppet takes: one folder at most (see --help)\n");
        return FP_EXIT_USAGE;
    }
    const char *dir = optind < argc ? argv[optind] : ".";
    fp_take_info *v = NULL;
    size_t n = 0;
    char err[1024];
    int rc = fp_take_list(dir, &v, &n, err, sizeof err);
    if (rc) {
        fprintf(stderr, "facepuppet takes: %s\n", err);
        return fp_app_exit_code(rc, FP_APP_INPUT);
    }
    int status = FP_EXIT_OK;
    if (json) status = print_json(v, n, dir);
    else if (!n) printf("no takes in %s\n", dir);
    else print_table(v, n);
    if (!json) fp_app_stack_list(dir);  /* the stacks (issue 54), after the takes */
    free(v);
    return status;
}

const fp_command fp_command_takes = {"takes", "list the takes of a folder (table or --json)",
                                     takes_main};

/* `facepuppet info TAKE`: header, summary, warning. */
int fp_app_take_info(const char *path)
{
    fp_take_reader *r = NULL;
    char err[1024];
    int rc = fp_take_reader_open(path, &r, err, sizeof err);
    if (rc) {
        fprintf(stderr, "facepuppet info: %s\n", err);
        return fp_app_exit_code(rc, FP_APP_INPUT);
    }
    const fp_take_header *h = fp_take_reader_header(r);
    const fp_take_summary *s = fp_take_reader_summary(r);
    char in[32], out[32], a[4096], b[4096]; /* a, b: the file's strings made UTF-8 text */
    fp_timecode_format(&h->timecode_in, in, sizeof in);
    fp_timecode_format(&s->timecode_out, out, sizeof out);
    char span[64] = "(no intact frame)"; /* (a take killed before its first chunk: 0..0 is no range) */
    if (s->frames)
        snprintf(span, sizeof span, "(session frames %llu..%llu)", (unsigned long long)s->first_frame,
                 (unsigned long long)s->last_frame);
    printf("%s\n  format       facepuppet take %u.%u\n  slate        %s\n  take         %u\n"
           "  date         %s\n  frame rate   %u/%u (%.3f fps)\n  timecode     %s - %s\n"
           "  frames       %llu %s\n  duration     %.3f s\n",
           path, s->version_major, s->version_minor, h->slate, h->take, fp_text_clean(h->date, a, sizeof a),
           h->rate.num, h->rate.den, (double)h->rate.num / h->rate.den, in, out,
           (unsigned long long)s->frames, span, s->duration_s);
    printf("  mesh         %s (%llu vertices, crc32 %08x of its %s)\n",
           h->mesh_path ? fp_text_clean(h->mesh_path, a, sizeof a) : "-",
           (unsigned long long)h->mesh_vertices, h->mesh_crc32,
           h->mesh_crc_of ? fp_text_clean(h->mesh_crc_of, b, sizeof b) : "?");
    printf("  rig          %s\n", h->rig_path ? fp_text_clean(h->rig_path, a, sizeof a) : "-");
    if (h->face_up[0] || h->face_up[1] || h->face_up[2]) /* (1.4: a turned face) */
        printf("  face         up (%.2f, %.2f, %.2f), looking along (%.2f, %.2f, %.2f)\n", h->face_up[0],
               h->face_up[1], h->face_up[2], h->face_facing[0], h->face_facing[1], h->face_facing[2]);
    printf("  mapping      %s", h->mapping ? fp_text_clean(h->mapping, a, sizeof a) : "-");
    for (size_t i = 0; i < h->mapping_key_count; i++)
        printf(",%s=%s", fp_text_clean(h->mapping_keys[i].key, a, sizeof a),
               fp_text_clean(h->mapping_keys[i].value, b, sizeof b));
    printf("\n  radius       %.6g mesh units\n", h->radius);
    for (size_t i = 0; i < h->input_count; i++)
        printf("  input %-6zu %s\n", i, fp_text_clean(h->inputs[i], a, sizeof a));
    for (int hand = 0; hand < FP_HANDS; hand++) {
        const fp_take_calibration *c = &h->calibration[hand];
        if (c->present)
            printf("  calibration  %s: scale %.6g mesh units/mm, offset %.6g %.6g %.6g\n",
                   hand ? "right" : "left", c->scale, c->offset[0], c->offset[1], c->offset[2]);
    }
    for (size_t k = 0; h->performer_count > 1 && k < h->performer_count; k++) { /* (format 1.3) */
        const fp_take_performer *p = &h->performers[k];
        printf("  performer    %s: scale %.6g mesh units/mm, offset %.6g %.6g %.6g\n",
               p->name[0] ? fp_text_clean(p->name, a, sizeof a) : "(the first)", p->scale, p->offset[0],
               p->offset[1], p->offset[2]);
    }
    if (h->description && h->description[0])
        printf("  description  %s\n", fp_text_clean(h->description, a, sizeof a));
    printf("  rating       %d/5\n", h->rating);
    if (h->soundtrack_path) /* (format 1.2) */
        printf("  soundtrack   %s (crc32 %08x), offset %.6g s\n", fp_text_clean(h->soundtrack_path, a, sizeof a),
               (unsigned)h->soundtrack_crc32, h->soundtrack_offset_s);
    if (h->timecode_source)
        printf("  timecode by  %s\n", fp_text_clean(h->timecode_source, a, sizeof a));
    if (h->audio_in_path) /* (format 1.2, --audio-in) */
        printf("  microphone   %s (from %s), beside the take\n", fp_text_clean(h->audio_in_path, a, sizeof a),
               fp_text_clean(h->audio_in_device ? h->audio_in_device : "", b, sizeof b));
    printf("  end          %s", s->complete ? "closed normally" : "no end chunk (not closed)");
    if (s->complete) printf(", %llu dropped, status %d%s%s", (unsigned long long)s->dropped,
                            s->end_status, s->end_status ? " " : "",
                            s->end_status ? fp_strerror(s->end_status) : "");
    if (s->reach.vectors) {
        char line[512];
        fp_app_reach_sentence(line, sizeof line, s->reach.median, (size_t)s->reach.vectors, s->reach.p10,
                              s->reach.longest_drag_mm, "", (size_t)s->reach.held);
        printf("\n  reach        %s", line);
    }
    printf("\n  file size    %llu bytes\n", (unsigned long long)s->file_size);
    int status = FP_EXIT_OK;
    if (fp_take_reader_warning(r)[0]) {
        printf("  warning      %s\n", fp_take_reader_warning(r));
        fprintf(stderr, "facepuppet info: warning: %s\n", fp_take_reader_warning(r));
    }
    fp_take_reader_close(&r);
    return status;
}
