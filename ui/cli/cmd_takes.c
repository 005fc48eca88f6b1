/* facepuppet takes: the takes of a folder as a table or JSON (fp_take_list); and
 * fp_app_take_info for `facepuppet info TAKE`. */
#define _GNU_SOURCE
#include "app_util.h"
#include "command.h"
#include "fp_take.h"

#include <cjson/cJSON.h>
#include "fp_text.h"
#include <errno.h>
#include <getopt.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static void usage(FILE *f)
{
    fprintf(f, "usage: facepuppet takes [DIR] [--json]\n\n"
               "The takes (SLATE_TNNN.fptake) in DIR (default: the current folder), by slate and\n"
               "take number: timecode in and out, duration, frames, mesh, mapping, rating; STATE\n"
               "says ok, \"cut\" (damaged or cut short, e.g. the recording process died: the\n"
               "frames before the damage play) or \"open\" (no end chunk yet). A *.fptake file\n"
               "that is no take, or whose signature or header is damaged, is \"unreadable\": its\n"
               "slate and take number are what its name gives, it has no timecode, duration or\n"
               "frames (\"-\"; null in JSON), and the reason is under the table (\"message\").\n"
               "  --json   one JSON array instead of the table\n\n"
               "Exit status: 0 once the folder is listed, whatever the files' states (see STATE),\n"
               "64 usage, 66 the folder cannot be read.\n");
}

static const char *state_of(const fp_take_info *t)
{
    return t->error ? "unreadable" : t->message[0] ? "cut" : t->complete ? "ok" : "open";
}

static void print_table(const fp_take_info *v, size_t n)
{
    printf("%-16s %4s  %-11s  %-11s  %9s  %7s  %-6s  %-10s  %-28s  %s\n", "SLATE", "TAKE",
           "TC IN", "TC OUT", "DURATION", "FRAMES", "RATING", "MAPPING", "MESH", "STATE");
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
        printf("%-16s %4s  %-11s  %-11s  %9s  %7s  %-6s  %-10s  %-28.28s  %s\n",
               fp_text_clean(t->slate, cs, sizeof cs), take, in, out, dur, fr, rate, cp[0] ? cp : "-",
               cm[0] ? cm : "-", state_of(t));
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

static int print_json(const fp_take_info *v, size_t n)
{
    cJSON *arr = cJSON_CreateArray();
    for (size_t i = 0; arr && i < n; i++) {
        const fp_take_info *t = &v[i];
        cJSON *o = cJSON_CreateObject();
        char in[32] = "", out[32] = "", c[4 * 4096]; /* c: a string made UTF-8 text (fp_text.h) */
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
        cJSON_AddStringToObject(o, "date", fp_text_clean(t->date, c, sizeof c));
        cJSON_AddStringToObject(o, "state", state_of(t));
        cJSON_AddStringToObject(o, "message", fp_text_clean(t->message, c, sizeof c));
        cJSON_AddItemToArray(arr, o);
    }
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

static int takes_main(int argc, char **argv)
{
    static const struct option opts[] = {{"json", no_argument, 0, 'j'},
                                         {"help", no_argument, 0, 'h'}, {0, 0, 0, 0}};
    bool json = false;
    optind = 1;
    for (int c; (c = getopt_long(argc, argv, "h", opts, NULL)) != -1;) {
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
    if (json) status = print_json(v, n);
    else if (!n) printf("no takes in %s\n", dir);
    else print_table(v, n);
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
    printf("%s\n  format       facepuppet take %u.%u\n  slate        %s\n  take         %u\n"
           "  date         %s\n  frame rate   %u/%u (%.3f fps)\n  timecode     %s - %s\n"
           "  frames       %llu (session frames %llu..%llu)\n  duration     %.3f s\n",
           path, s->version_major, s->version_minor, h->slate, h->take, fp_text_clean(h->date, a, sizeof a),
           h->rate.num, h->rate.den, (double)h->rate.num / h->rate.den, in, out,
           (unsigned long long)s->frames, (unsigned long long)s->first_frame,
           (unsigned long long)s->last_frame, s->duration_s);
    printf("  mesh         %s (%llu vertices, crc32 %08x of its %s)\n",
           h->mesh_path ? fp_text_clean(h->mesh_path, a, sizeof a) : "-",
           (unsigned long long)h->mesh_vertices, h->mesh_crc32,
           h->mesh_crc_of ? fp_text_clean(h->mesh_crc_of, b, sizeof b) : "?");
    printf("  rig          %s\n", h->rig_path ? fp_text_clean(h->rig_path, a, sizeof a) : "-");
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
    if (h->description && h->description[0])
        printf("  description  %s\n", fp_text_clean(h->description, a, sizeof a));
    printf("  rating       %d/5\n", h->rating);
    printf("  end          %s", s->complete ? "closed normally" : "no end chunk (not closed)");
    if (s->complete) printf(", %llu dropped, status %d%s%s", (unsigned long long)s->dropped,
                            s->end_status, s->end_status ? " " : "",
                            s->end_status ? fp_strerror(s->end_status) : "");
    printf("\n  file size    %llu bytes\n", (unsigned long long)s->file_size);
    int status = FP_EXIT_OK;
    if (fp_take_reader_warning(r)[0]) {
        printf("  warning      %s\n", fp_take_reader_warning(r));
        fprintf(stderr, "facepuppet info: warning: %s\n", fp_take_reader_warning(r));
    }
    fp_take_reader_close(&r);
    return status;
}
