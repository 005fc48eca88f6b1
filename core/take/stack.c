/* fp_stack: the stack file (fp_stack.h, docs/stack.md): parse, check, write, --layer specs. */
#define _XOPEN_SOURCE 700 /* realpath */
#include "fp_stack.h"
#include "fp_take.h"
#include "fp_error.h"
#include "fp_file.h"
#include "fp_text.h"

#include <cjson/cJSON.h>
#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>
#include <unistd.h>

#define STACK_FORMAT "facepuppet-stack"
#define STACK_FILE_MAX (16u << 20)   /* a stack file is small: 16 MiB at most */
#define DEFAULT_FADE_S 0.05

bool fp_stack_is_stack_path(const char *path)
{
    size_t n = path ? strlen(path) : 0, e = strlen(FP_STACK_EXTENSION);
    return n > e && !strcasecmp(path + n - e, FP_STACK_EXTENSION);
}

fp_stack *fp_stack_create(void) { return calloc(1, sizeof(fp_stack)); }

void fp_stack_region_clear(fp_stack_region *r)
{
    if (!r) return;
    free(r->vertices);
    r->vertices = NULL;
    r->vertex_count = 0;
}

void fp_stack_free(fp_stack **s)
{
    if (!s || !*s) return;
    for (size_t i = 0; i < (*s)->layer_count; i++)
        fp_stack_region_clear(&(*s)->layers[i].region);
    free(*s);
    *s = NULL;
}

void fp_stack_layer_init(fp_stack_layer *l, const char *take)
{
    memset(l, 0, sizeof *l);
    snprintf(l->take, sizeof l->take, "%s", take ? take : "");
    l->mode = FP_STACK_REPLACE;
    l->in_s = 0;
    l->out_s = INFINITY;
    l->fade_s = DEFAULT_FADE_S;
    l->gain = 1;
}

/* ---- parsing ------------------------------------------------------------------------- */

typedef struct pctx {
    const char *name;
    char *err;
    size_t errlen;
} pctx;

static int bad(const pctx *c, const char *where, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));
static int bad(const pctx *c, const char *where, const char *fmt, ...)
{
    char what[512];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(what, sizeof what, fmt, ap);
    va_end(ap);
    return fp_errorf(c->err, c->errlen, -EBADMSG, "%s: %s: %s", c->name, where, what);
}

static int check_members(const pctx *c, const cJSON *o, const char *where,
                         const char *const *known)
{
    for (const cJSON *m = o->child; m; m = m->next) {
        bool ok = false;
        for (size_t k = 0; known[k] && !ok; k++) ok = m->string && !strcmp(m->string, known[k]);
        if (!ok) return bad(c, where, "unknown member \"%s\"", m->string ? m->string : "");
        /* each once: cJSON finds the first, so a second was read nowhere */
        for (const cJSON *e = o->child; e != m; e = e->next)
            if (!strcmp(e->string, m->string)) return bad(c, where, "member \"%s\" given twice", m->string);
    }
    return 0;
}

/* A number member: absent keeps *v; present must be a finite number in [lo, hi]. */
static int get_num(const pctx *c, const cJSON *o, const char *where, const char *key, double lo,
                   double hi, double *v)
{
    const cJSON *m = cJSON_GetObjectItemCaseSensitive(o, key);
    if (!m) return 0;
    if (!cJSON_IsNumber(m) || !isfinite(m->valuedouble))
        return bad(c, where, "\"%s\": expected a number", key);
    if (m->valuedouble < lo || m->valuedouble > hi)
        return bad(c, where, "\"%s\": %g outside [%g, %g]", key, m->valuedouble, lo, hi);
    *v = m->valuedouble;
    return 0;
}

static int get_bool(const pctx *c, const cJSON *o, const char *where, const char *key, bool *v)
{
    const cJSON *m = cJSON_GetObjectItemCaseSensitive(o, key);
    if (!m) return 0;
    if (!cJSON_IsBool(m)) return bad(c, where, "\"%s\": expected true or false", key);
    *v = cJSON_IsTrue(m);
    return 0;
}

static int get_names(const pctx *c, const cJSON *a, const char *where, fp_stack_region *r)
{
    if (!cJSON_IsArray(a) || cJSON_GetArraySize(a) < 1 || cJSON_GetArraySize(a) > FP_STACK_MAX_NAMES)
        return bad(c, where, "expected an array of 1 to %d names", FP_STACK_MAX_NAMES);
    for (const cJSON *e = a->child; e; e = e->next) {
        if (!cJSON_IsString(e) || !e->valuestring[0] || strlen(e->valuestring) >= FP_STACK_NAME_MAX)
            return bad(c, where, "expected names of 1 to %d bytes", FP_STACK_NAME_MAX - 1);
        snprintf(r->names[r->name_count++], FP_STACK_NAME_MAX, "%s", e->valuestring);
    }
    return 0;
}

/* "vertices": indices and [first, last] spans (as the rig's regions), FP_STACK_MAX_GROUP
 * indices at most in all: the first pass counts the spans by their lengths (a hostile file's
 * thousands of spans of 2^24 are refused there, not walked or allocated), the second fills. */
static int get_vertices(const pctx *c, const cJSON *a, const char *where, fp_stack_region *r)
{
    if (!cJSON_IsArray(a) || !a->child) return bad(c, where, "expected an array of vertex indices");
    size_t n = 0;
    for (int pass = 0; pass < 2; pass++) {
        n = 0;
        for (const cJSON *e = a->child; e; e = e->next) {
            double lo, hi;
            if (cJSON_IsNumber(e)) lo = hi = e->valuedouble;
            else if (cJSON_IsArray(e) && cJSON_GetArraySize(e) == 2 && cJSON_IsNumber(e->child) &&
                     cJSON_IsNumber(e->child->next))
                lo = e->child->valuedouble, hi = e->child->next->valuedouble;
            else return bad(c, where, "expected an index or [first, last]");
            if (!(lo >= 0 && hi >= lo && hi < 16777216.0) || lo != floor(lo) || hi != floor(hi))
                return bad(c, where, "a vertex span [%g, %g] that is not 0 <= first <= last < 2^24", lo, hi);
            size_t len = (size_t)(hi - lo) + 1;
            if (len > FP_STACK_MAX_GROUP - n)
                return bad(c, where, "more than %u vertex indices in the group", (unsigned)FP_STACK_MAX_GROUP);
            if (pass)
                for (uint32_t v = (uint32_t)lo; v <= (uint32_t)hi; v++) r->vertices[n++] = v;
            else n += len;
        }
        if (!pass && !(r->vertices = malloc(n * sizeof *r->vertices)))
            return fp_errorf(c->err, c->errlen, -ENOMEM, "%s: out of memory", c->name);
    }
    r->vertex_count = n;
    return 0;
}

static int parse_region(const pctx *c, const cJSON *o, const char *where, fp_stack_region *r)
{
    static const char *const known[] = {"name", "rig_region", "landmarks", "vertices", "channels",
                                        "core_mm", "falloff_mm", NULL};
    if (!cJSON_IsObject(o)) return bad(c, where, "expected an object");
    int rc = check_members(c, o, where, known);
    if (rc) return rc;
    const cJSON *nm = cJSON_GetObjectItemCaseSensitive(o, "name");
    if (nm && (!cJSON_IsString(nm) || strlen(nm->valuestring) >= FP_STACK_NAME_MAX))
        return bad(c, where, "\"name\": expected a string of at most %d bytes", FP_STACK_NAME_MAX - 1);
    if (nm) snprintf(r->name, sizeof r->name, "%s", nm->valuestring);
    const cJSON *rr = cJSON_GetObjectItemCaseSensitive(o, "rig_region");
    const cJSON *lm = cJSON_GetObjectItemCaseSensitive(o, "landmarks");
    const cJSON *vs = cJSON_GetObjectItemCaseSensitive(o, "vertices");
    const cJSON *ch = cJSON_GetObjectItemCaseSensitive(o, "channels");
    if (!!rr + !!lm + !!vs + !!ch != 1)
        return bad(c, where, "give exactly one of rig_region, landmarks, vertices, channels");
    char sub[160];
    if (rr) {
        if (!cJSON_IsString(rr) || !rr->valuestring[0] || strlen(rr->valuestring) >= FP_STACK_NAME_MAX)
            return bad(c, where, "\"rig_region\": expected a region's name");
        r->kind = FP_STACK_REGION_RIG;
        snprintf(r->names[0], FP_STACK_NAME_MAX, "%s", rr->valuestring);
        r->name_count = 1;
    } else if (lm) {
        r->kind = FP_STACK_REGION_LANDMARKS;
        snprintf(sub, sizeof sub, "%s.landmarks", where);
        if ((rc = get_names(c, lm, sub, r))) return rc;
    } else if (ch) {
        r->kind = FP_STACK_REGION_CHANNELS;
        snprintf(sub, sizeof sub, "%s.channels", where);
        if ((rc = get_names(c, ch, sub, r))) return rc;
    } else {
        r->kind = FP_STACK_REGION_VERTICES;
        snprintf(sub, sizeof sub, "%s.vertices", where);
        if ((rc = get_vertices(c, vs, sub, r))) return rc;
    }
    if ((rc = get_num(c, o, where, "core_mm", 0, 1e6, &r->core_mm)) ||
        (rc = get_num(c, o, where, "falloff_mm", 0, 1e6, &r->falloff_mm)))
        return rc;
    if (r->kind == FP_STACK_REGION_LANDMARKS && r->core_mm + r->falloff_mm <= 0)
        return bad(c, where, "landmarks need core_mm or falloff_mm > 0");
    return 0;
}

static int parse_layer(const pctx *c, const cJSON *o, size_t i, fp_stack_layer *l)
{
    static const char *const known[] = {"take", "region", "mode", "in", "out", "fade", "offset",
                                        "gain", "mute", "solo", NULL};
    char where[64];
    snprintf(where, sizeof where, "layers[%zu]", i);
    if (!cJSON_IsObject(o)) return bad(c, where, "expected an object");
    int rc = check_members(c, o, where, known);
    if (rc) return rc;
    const cJSON *t = cJSON_GetObjectItemCaseSensitive(o, "take");
    if (!cJSON_IsString(t) || !t->valuestring[0] || strlen(t->valuestring) >= FP_STACK_PATH_MAX)
        return bad(c, where, "\"take\": expected a take's path");
    fp_stack_layer_init(l, t->valuestring);
    const cJSON *m = cJSON_GetObjectItemCaseSensitive(o, "mode");
    if (m) {
        if (cJSON_IsString(m) && !strcmp(m->valuestring, "replace")) l->mode = FP_STACK_REPLACE;
        else if (cJSON_IsString(m) && !strcmp(m->valuestring, "add")) l->mode = FP_STACK_ADD;
        else return bad(c, where, "\"mode\": expected \"replace\" or \"add\"");
    }
    const cJSON *r = cJSON_GetObjectItemCaseSensitive(o, "region");
    if (r && !cJSON_IsNull(r)) {
        char sub[96];
        snprintf(sub, sizeof sub, "%s.region", where);
        if ((rc = parse_region(c, r, sub, &l->region))) return rc;
    }
    const cJSON *out = cJSON_GetObjectItemCaseSensitive(o, "out");
    if (out && !cJSON_IsNull(out) && (rc = get_num(c, o, where, "out", -1e9, 1e9, &l->out_s)))
        return rc;
    if ((rc = get_num(c, o, where, "in", -1e9, 1e9, &l->in_s)) ||
        (rc = get_num(c, o, where, "fade", 0, 3600, &l->fade_s)) ||
        (rc = get_num(c, o, where, "offset", -1e9, 1e9, &l->offset_s)) ||
        (rc = get_num(c, o, where, "gain", 0, 2, &l->gain)) ||
        (rc = get_bool(c, o, where, "mute", &l->mute)) || (rc = get_bool(c, o, where, "solo", &l->solo)))
        return rc;
    if (l->out_s < l->in_s) return bad(c, where, "\"out\" %g before \"in\" %g", l->out_s, l->in_s);
    if (i == 0 && (l->region.kind != FP_STACK_REGION_ALL || l->mode != FP_STACK_REPLACE))
        return bad(c, where, "the base layer (the first) is the whole face in replace mode: "
                             "give it no region and no mode");
    return 0;
}

/* Whether text (n bytes) ends inside a string; *open: the objects and arrays left open. */
static bool json_unclosed(const char *text, size_t n, size_t *open)
{
    bool str = false, esc = false;
    size_t depth = 0;
    for (size_t i = 0; i < n; i++) {
        const char ch = text[i];
        if (str) {
            if (esc) esc = false;
            else if (ch == '\\') esc = true;
            else if (ch == '"') str = false;
        } else if (ch == '"') {
            str = true;
        } else if (ch == '{' || ch == '[') {
            depth++;
        } else if ((ch == '}' || ch == ']') && depth) {
            depth--;
        }
    }
    *open = depth;
    return str;
}

int fp_stack_parse(const char *json, size_t len, const char *name, fp_stack **out, char *err,
                   size_t errlen)
{
    if (out) *out = NULL;
    if (!json || !out) return fp_errorf(err, errlen, -EINVAL, "fp_stack_parse: NULL argument");
    pctx c = {name ? name : "stack", err, errlen};
    const char *end = NULL;
    cJSON *root = cJSON_ParseWithLengthOpts(json, len, &end, false);
    if (!root) { /* where it stops: the end of a text cut short, else the byte cJSON stopped at */
        size_t open = 0;
        const bool in_string = json_unclosed(json, len, &open);
        char where[48];
        if (in_string || open) {
            snprintf(where, sizeof where, "byte %zu", len);
            return bad(&c, where, "not JSON: the text ends inside %s%zu unclosed object%s or array%s "
                       "(cut short?)", in_string ? "a string, " : "", open, open == 1 ? "" : "s",
                       open == 1 ? "" : "s");
        }
        const size_t at = end && end >= json && end < json + len ? (size_t)(end - json) : 0;
        snprintf(where, sizeof where, "byte %zu", at);
        const unsigned char ch = len ? (unsigned char)json[at] : 0;
        return bad(&c, where, "not JSON (at '%c', of %zu bytes)", ch >= 0x20 && ch < 0x7f ? ch : '?', len);
    }
    /* one stack per file: what follows the object is damage (two stacks pasted into one
     * file played the first in silence), as rigs and calibration files refuse it */
    const char *rest = fp_text_after_space(end, json + len);
    if (rest) {
        cJSON_Delete(root);
        char where[48];
        snprintf(where, sizeof where, "byte %zu", (size_t)(rest - json));
        return bad(&c, where, "text after the JSON object (a stack file holds one)");
    }
    fp_stack *s = fp_stack_create();
    int rc = s ? 0 : fp_errorf(err, errlen, -ENOMEM, "%s: out of memory", c.name);
    static const char *const known[] = {"format", "version", "layers", NULL};
    const cJSON *f = cJSON_GetObjectItemCaseSensitive(root, "format");
    const cJSON *v = cJSON_GetObjectItemCaseSensitive(root, "version");
    const cJSON *ls = cJSON_GetObjectItemCaseSensitive(root, "layers");
    if (rc) goto done;
    if (!cJSON_IsObject(root)) { rc = bad(&c, "(root)", "expected an object"); goto done; }
    if ((rc = check_members(&c, root, "(root)", known))) goto done;
    if (!cJSON_IsString(f) || strcmp(f->valuestring, STACK_FORMAT)) {
        rc = bad(&c, "format", "expected \"%s\"", STACK_FORMAT);
        goto done;
    }
    if (!cJSON_IsNumber(v) || v->valuedouble != FP_STACK_FORMAT_VERSION) {
        rc = bad(&c, "version", "expected %d", FP_STACK_FORMAT_VERSION);
        goto done;
    }
    if (!cJSON_IsArray(ls) || cJSON_GetArraySize(ls) < 1 || cJSON_GetArraySize(ls) > FP_STACK_MAX_LAYERS) {
        rc = bad(&c, "layers", "expected an array of 1 to %d layers", FP_STACK_MAX_LAYERS);
        goto done;
    }
    for (const cJSON *l = ls->child; l && !rc; l = l->next) {
        rc = parse_layer(&c, l, s->layer_count, &s->layers[s->layer_count]);
        s->layer_count++;  /* its vertices are freed with the stack, also on failure */
    }
    if (!rc && name) snprintf(s->path, sizeof s->path, "%s", name);
done:
    cJSON_Delete(root);
    if (rc) fp_stack_free(&s);
    *out = s;
    return rc;
}

int fp_stack_load(const char *path, fp_stack **out, char *err, size_t errlen)
{
    if (out) *out = NULL;
    if (!path || !out) return fp_errorf(err, errlen, -EINVAL, "fp_stack_load: NULL argument");
    int fd = fp_file_open_regular(path);
    if (fd < 0) return fp_errorf(err, errlen, fd, "%s: %s", path, fp_file_error_text(fd));
    char *buf = malloc(STACK_FILE_MAX + 1);
    size_t n = 0;
    ssize_t k = 0;
    while (buf && n < STACK_FILE_MAX && (k = read(fd, buf + n, STACK_FILE_MAX - n)) > 0) n += (size_t)k;
    int e = errno;
    close(fd);
    if (!buf) return fp_errorf(err, errlen, -ENOMEM, "%s: out of memory", path);
    int rc;
    if (k < 0) rc = fp_errorf(err, errlen, -EIO, "%s: read failed: %s", path, strerror(e));
    else if (n >= STACK_FILE_MAX) rc = fp_errorf(err, errlen, -EBADMSG, "%s: larger than 16 MiB", path);
    else rc = fp_stack_parse(buf, n, path, out, err, errlen);
    free(buf);
    return rc;
}

/* ---- writing ------------------------------------------------------------------------- */

static cJSON *region_json(const fp_stack_region *r)
{
    cJSON *o = cJSON_CreateObject();
    if (!o) return NULL;
    if (r->name[0]) cJSON_AddStringToObject(o, "name", r->name);
    if (r->kind == FP_STACK_REGION_RIG) {
        cJSON_AddStringToObject(o, "rig_region", r->names[0]);
    } else if (r->kind == FP_STACK_REGION_LANDMARKS || r->kind == FP_STACK_REGION_CHANNELS) {
        cJSON *a = cJSON_AddArrayToObject(o, r->kind == FP_STACK_REGION_CHANNELS ? "channels" : "landmarks");
        for (size_t i = 0; a && i < r->name_count; i++)
            cJSON_AddItemToArray(a, cJSON_CreateString(r->names[i]));
    } else {
        cJSON *a = cJSON_AddArrayToObject(o, "vertices");
        for (size_t i = 0; a && i < r->vertex_count;) { /* runs as [first, last] */
            size_t j = i;
            while (j + 1 < r->vertex_count && r->vertices[j + 1] == r->vertices[j] + 1) j++;
            if (j == i) cJSON_AddItemToArray(a, cJSON_CreateNumber(r->vertices[i]));
            else {
                cJSON *span = cJSON_CreateArray();
                cJSON_AddItemToArray(span, cJSON_CreateNumber(r->vertices[i]));
                cJSON_AddItemToArray(span, cJSON_CreateNumber(r->vertices[j]));
                cJSON_AddItemToArray(a, span);
            }
            i = j + 1;
        }
    }
    if (r->kind != FP_STACK_REGION_CHANNELS) {
        cJSON_AddNumberToObject(o, "core_mm", r->core_mm);
        cJSON_AddNumberToObject(o, "falloff_mm", r->falloff_mm);
    }
    return o;
}

char *fp_stack_to_json(const fp_stack *s)
{
    cJSON *root = cJSON_CreateObject();
    if (!root) return NULL;
    cJSON_AddStringToObject(root, "format", STACK_FORMAT);
    cJSON_AddNumberToObject(root, "version", FP_STACK_FORMAT_VERSION);
    cJSON *ls = cJSON_AddArrayToObject(root, "layers");
    for (size_t i = 0; ls && i < s->layer_count; i++) {
        const fp_stack_layer *l = &s->layers[i];
        cJSON *o = cJSON_CreateObject();
        if (!o) break;
        cJSON_AddItemToArray(ls, o);
        cJSON_AddStringToObject(o, "take", l->take);
        if (i > 0) {
            cJSON_AddItemToObject(o, "region", l->region.kind == FP_STACK_REGION_ALL
                                                   ? cJSON_CreateNull() : region_json(&l->region));
            cJSON_AddStringToObject(o, "mode", l->mode == FP_STACK_ADD ? "add" : "replace");
        }
        cJSON_AddNumberToObject(o, "in", l->in_s);
        if (isfinite(l->out_s)) cJSON_AddNumberToObject(o, "out", l->out_s);
        else cJSON_AddNullToObject(o, "out");
        cJSON_AddNumberToObject(o, "fade", l->fade_s);
        cJSON_AddNumberToObject(o, "offset", l->offset_s);
        cJSON_AddNumberToObject(o, "gain", l->gain);
        cJSON_AddBoolToObject(o, "mute", l->mute);
        cJSON_AddBoolToObject(o, "solo", l->solo);
    }
    char *text = cJSON_Print(root);
    cJSON_Delete(root);
    return text;
}

int fp_stack_save(const fp_stack *s, const char *path, char *err, size_t errlen)
{
    if (!s || !path) return fp_errorf(err, errlen, -EINVAL, "fp_stack_save: NULL argument");
    char *text = fp_stack_to_json(s);
    if (!text) return fp_errorf(err, errlen, -ENOMEM, "%s: out of memory", path);
    int fd = open(path, O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0644);
    if (fd < 0) {
        int e = -errno;
        free(text);
        return fp_errorf(err, errlen, e, "%s: %s", path, e == -EEXIST ? "exists (a stack is never "
                         "overwritten)" : strerror(-e));
    }
    size_t n = strlen(text), done = 0;
    int rc = 0;
    while (done < n && !rc) {
        ssize_t k = write(fd, text + done, n - done);
        if (k < 0 && errno != EINTR) rc = -errno;
        else if (k > 0) done += (size_t)k;
    }
    if (!rc && (write(fd, "\n", 1) != 1 || fsync(fd))) rc = -errno ? -errno : -EIO;
    if (close(fd) && !rc) rc = -EIO;
    free(text);
    if (rc) {
        unlink(path);
        return fp_errorf(err, errlen, rc, "%s: write failed: %s", path, strerror(-rc));
    }
    return 0;
}

int fp_stack_take_path(const fp_stack *s, size_t i, char *buf, size_t n)
{
    if (!s || i >= s->layer_count || !buf) return -EINVAL;
    const char *t = s->layers[i].take, *slash = strrchr(s->path, '/');
    int k;
    if (t[0] == '/' || !slash) k = snprintf(buf, n, "%s", t);
    else k = snprintf(buf, n, "%.*s/%s", (int)(slash - s->path), s->path, t);
    return k < 0 || (size_t)k >= n ? -ENAMETOOLONG : 0;
}

int fp_stack_next_path(const char *dir, const char *slate, char *buf, size_t n)
{
    if (!dir || !buf || !fp_take_slate_valid(slate)) return -EINVAL;
    unsigned long top = 0;
    size_t sl = strlen(slate);
    DIR *d = opendir(dir);
    for (struct dirent *e; d && (e = readdir(d));) {
        char *end;
        if (strncmp(e->d_name, slate, sl) || strncmp(e->d_name + sl, "_S", 2)) continue;
        unsigned long k = strtoul(e->d_name + sl + 2, &end, 10);
        if (end != e->d_name + sl + 2 && !strcmp(end, FP_STACK_EXTENSION) && k > top) top = k;
    }
    if (d) closedir(d);
    int k = snprintf(buf, n, "%s/%s_S%03lu%s", dir, slate, top + 1, FP_STACK_EXTENSION);
    return k < 0 || (size_t)k >= n ? -ENAMETOOLONG : 0;
}

int fp_stack_append(fp_stack *s, const fp_stack_layer *layer, char *err, size_t errlen)
{
    if (!s || !layer) return fp_errorf(err, errlen, -EINVAL, "fp_stack_append: NULL argument");
    if (s->layer_count >= FP_STACK_MAX_LAYERS)
        return fp_errorf(err, errlen, -ENOSPC, "a stack holds at most %d layers", FP_STACK_MAX_LAYERS);
    fp_stack_layer *l = &s->layers[s->layer_count];
    *l = *layer;
    l->region.vertices = NULL;
    if (layer->region.vertex_count) {
        l->region.vertices = malloc(layer->region.vertex_count * sizeof *l->region.vertices);
        if (!l->region.vertices) return fp_errorf(err, errlen, -ENOMEM, "out of memory");
        memcpy(l->region.vertices, layer->region.vertices,
               layer->region.vertex_count * sizeof *l->region.vertices);
    }
    s->layer_count++;
    return 0;
}

/* ---- the command line's --layer REGION[:MODE] ------------------------------------------ */

/* The named regions: landmarks of the rigs of rigs/ (the ICT FaceKit's names). */
static const struct preset {
    const char *name;
    fp_stack_region_kind kind;
    const char *names[8];
    double core_mm, falloff_mm;
} presets[] = {
    {"mouth", FP_STACK_REGION_LANDMARKS,
     {"upper_lip", "lower_lip", "upper_lip_inner", "lower_lip_inner", "mouth_corner_left",
      "mouth_corner_right", NULL}, 6, 14},
    {"brows", FP_STACK_REGION_LANDMARKS,
     {"brow_left", "brow_right", "brow_inner_left", "brow_inner_right", "brow_outer_left",
      "brow_outer_right", NULL}, 8, 15},
    {"jaw", FP_STACK_REGION_CHANNELS, {"jaw.open", NULL}, 0, 0},
};

/* "a,b,c" into r->names. */
static int split_names(const char *list, fp_stack_region *r, char *err, size_t errlen)
{
    for (const char *p = list; *p;) {
        size_t k = strcspn(p, ",");
        if (!k || k >= FP_STACK_NAME_MAX || r->name_count >= FP_STACK_MAX_NAMES)
            return fp_errorf(err, errlen, -EINVAL, "--layer: \"%s\": give 1 to %d names of 1 to %d "
                             "bytes, separated by commas", list, FP_STACK_MAX_NAMES, FP_STACK_NAME_MAX - 1);
        snprintf(r->names[r->name_count++], FP_STACK_NAME_MAX, "%.*s", (int)k, p);
        p += k + (p[k] == ',');
    }
    return r->name_count ? 0 : fp_errorf(err, errlen, -EINVAL, "--layer: no names given");
}

/* "A-B,C" into r->vertices. */
static int split_vertices(const char *list, fp_stack_region *r, char *err, size_t errlen)
{
    for (int pass = 0; pass < 2; pass++) {
        size_t n = 0;
        for (const char *p = list; *p;) {
            char *end;
            unsigned long a = strtoul(p, &end, 10), b = a;
            if (end == p) goto bad;
            if (*end == '-') {
                const char *q = end + 1;
                b = strtoul(q, &end, 10);
                if (end == q || b < a) goto bad;
            }
            if (b >= 16777216ul || (*end && *end != ',')) goto bad;
            if (b - a + 1 > FP_STACK_MAX_GROUP - n) goto bad; /* counted, not walked */
            if (pass)
                for (unsigned long v = a; v <= b; v++) r->vertices[n++] = (uint32_t)v;
            else n += b - a + 1;
            p = end + (*end == ',');
        }
        if (!n) goto bad;
        if (!pass && !(r->vertices = malloc(n * sizeof *r->vertices)))
            return fp_errorf(err, errlen, -ENOMEM, "out of memory");
        r->vertex_count = n;
    }
    return 0;
bad:
    return fp_errorf(err, errlen, -EINVAL, "--layer: vertices \"%s\": give indices A or spans A-B "
                     "below 2^24, separated by commas, at most 2^24 in all", list);
}

int fp_stack_layer_spec(const char *spec, fp_stack_region *region, fp_stack_mode *mode,
                        char *err, size_t errlen)
{
    if (!spec || !region || !mode) return fp_errorf(err, errlen, -EINVAL, "--layer: NULL argument");
    memset(region, 0, sizeof *region);
    *mode = FP_STACK_REPLACE;
    char s[1024];
    if (snprintf(s, sizeof s, "%s", spec) >= (int)sizeof s)
        return fp_errorf(err, errlen, -EINVAL, "--layer: too long");
    char *colon = strrchr(s, ':');
    if (colon && (!strcmp(colon + 1, "replace") || !strcmp(colon + 1, "add"))) {
        *mode = colon[1] == 'a' ? FP_STACK_ADD : FP_STACK_REPLACE;
        *colon = 0;
    }
    char *at = strchr(s, '@');
    bool falloff_given = false;
    if (at) {
        *at = 0;
        char *end;
        double a = strtod(at + 1, &end), b = -1;
        if (*end == '+') b = strtod(end + 1, &end);
        if (end == at + 1 || *end || !(a >= 0) || a > 1e6 || (b != -1 && !(b >= 0 && b <= 1e6)))
            return fp_errorf(err, errlen, -EINVAL, "--layer %s: after @ give FALLOFF_MM or "
                             "CORE_MM+FALLOFF_MM (millimetres, >= 0)", spec);
        if (b == -1) region->falloff_mm = a;
        else region->core_mm = a, region->falloff_mm = b;
        falloff_given = true;
    }
    int rc = 0;
    const char *arg = strchr(s, ':') ? strchr(s, ':') + 1 : NULL;
    if (!strncmp(s, "rig:", 4)) {
        region->kind = FP_STACK_REGION_RIG;
        if (!arg[0] || strlen(arg) >= FP_STACK_NAME_MAX || strchr(arg, ','))
            return fp_errorf(err, errlen, -EINVAL, "--layer %s: rig:NAME names one region of the rig", spec);
        snprintf(region->names[0], FP_STACK_NAME_MAX, "%s", arg);
        region->name_count = 1;
    } else if (!strncmp(s, "landmark:", 9) || !strncmp(s, "landmarks:", 10)) {
        region->kind = FP_STACK_REGION_LANDMARKS;
        rc = split_names(arg, region, err, errlen);
        if (!rc && !falloff_given) region->core_mm = 6, region->falloff_mm = 14;
    } else if (!strncmp(s, "channels:", 9) || !strncmp(s, "channel:", 8)) {
        region->kind = FP_STACK_REGION_CHANNELS;
        rc = split_names(arg, region, err, errlen);
    } else if (!strncmp(s, "vertices:", 9)) {
        region->kind = FP_STACK_REGION_VERTICES;
        rc = split_vertices(arg, region, err, errlen);
    } else if (!strcmp(s, "all")) {
        region->kind = FP_STACK_REGION_ALL;
    } else {
        const struct preset *p = NULL;
        for (size_t i = 0; i < sizeof presets / sizeof *presets; i++)
            if (!strcmp(s, presets[i].name)) p = &presets[i];
        if (!p)
            return fp_errorf(err, errlen, -EINVAL, "--layer %s: give mouth, brows, jaw, all, rig:NAME, "
                             "landmark:NAME[,NAME], channels:NAME[,NAME] or vertices:A-B[,C], "
                             "then [@FALLOFF_MM][:replace|:add]", spec);
        region->kind = p->kind;
        snprintf(region->name, sizeof region->name, "%s", p->name);
        for (size_t i = 0; p->names[i]; i++)
            snprintf(region->names[region->name_count++], FP_STACK_NAME_MAX, "%s", p->names[i]);
        if (!falloff_given) region->core_mm = p->core_mm, region->falloff_mm = p->falloff_mm;
    }
    if (!rc && !falloff_given && (region->kind == FP_STACK_REGION_RIG || region->kind == FP_STACK_REGION_VERTICES))
        region->falloff_mm = 10;  /* a smooth edge by default: the blend's bound needs one */
    if (!rc && region->kind == FP_STACK_REGION_LANDMARKS && region->core_mm + region->falloff_mm <= 0)
        rc = fp_errorf(err, errlen, -EINVAL, "--layer %s: landmarks need a core or falloff > 0 mm", spec);
    if (rc) fp_stack_region_clear(region);
    return rc;
}

const char *fp_stack_region_text(const fp_stack_region *r, char *buf, size_t n)
{
    static const char *const kinds[] = {"all", "rig region", "landmarks", "vertex group", "channels"};
    int k = snprintf(buf, n, "%s%s%s", r->name[0] ? r->name : "", r->name[0] ? " (" : "",
                     kinds[r->kind]);
    for (size_t i = 0; i < r->name_count && k > 0 && (size_t)k < n; i++)
        k += snprintf(buf + k, n - (size_t)k, "%s%s", i ? "," : " ", r->names[i]);
    if (r->kind == FP_STACK_REGION_VERTICES && k > 0 && (size_t)k < n)
        k += snprintf(buf + k, n - (size_t)k, " of %zu", r->vertex_count);
    if (r->kind != FP_STACK_REGION_ALL && r->kind != FP_STACK_REGION_CHANNELS && k > 0 && (size_t)k < n)
        k += snprintf(buf + k, n - (size_t)k, ", core %g mm, falloff %g mm", r->core_mm, r->falloff_mm);
    if (r->name[0] && k > 0 && (size_t)k < n) snprintf(buf + k, n - (size_t)k, ")");
    return buf;
}

/* ---- overdub --------------------------------------------------------------------------- */

int fp_stack_over_open(const char *over, fp_stack **out, char *err, size_t errlen)
{
    if (out) *out = NULL;
    if (!over || !out) return fp_errorf(err, errlen, -EINVAL, "--over: no stack or take");
    if (fp_stack_is_stack_path(over)) return fp_stack_load(over, out, err, errlen);
    fp_take_reader *r = NULL;
    int rc = fp_take_reader_open(over, &r, err, errlen);
    fp_take_reader_close(&r);
    if (rc) return rc;
    fp_stack *s = fp_stack_create();
    if (!s) return fp_errorf(err, errlen, -ENOMEM, "out of memory");
    fp_stack_layer base;
    fp_stack_layer_init(&base, over);
    if ((rc = fp_stack_append(s, &base, err, errlen))) fp_stack_free(&s);
    *out = s;
    return rc;
}

int fp_stack_over_take_path(const char *over, const fp_stack *s, size_t i, char *buf, size_t n)
{
    if (fp_stack_is_stack_path(over)) return fp_stack_take_path(s, i, buf, n);
    return snprintf(buf, n, "%s", over) < (int)n ? 0 : -ENAMETOOLONG;
}

/* path as stored in a stack in dir: its name alone when it lies in dir, else absolute. */
static int stack_relative(const char *dir, const char *path, char *buf, size_t n)
{
    char *rd = realpath(dir, NULL), *rp = realpath(path, NULL);
    int rc = rd && rp ? 0 : -errno;
    if (!rc) {
        const char *slash = strrchr(rp, '/');
        size_t k = strlen(rd);
        const char *name = slash && (size_t)(slash - rp) == k && !strncmp(rp, rd, k) ? slash + 1 : rp;
        rc = snprintf(buf, n, "%s", name) < (int)n ? 0 : -ENAMETOOLONG;
    }
    free(rd);
    free(rp);
    return rc;
}

int fp_stack_over_save(const char *over, const fp_stack *old, const fp_stack_layer *pass,
                       const char *dir, const char *take_path, const char *slate,
                       char *path_out, size_t n, char *err, size_t errlen)
{
    if (!over || !old || !pass || !dir || !take_path || !path_out)
        return fp_errorf(err, errlen, -EINVAL, "fp_stack_over_save: NULL argument");
    fp_stack *s = fp_stack_create();
    if (!s) return fp_errorf(err, errlen, -ENOMEM, "out of memory");
    char p[FP_STACK_PATH_MAX];
    int rc = 0;
    for (size_t i = 0; !rc && i < old->layer_count; i++) {
        fp_stack_layer l = old->layers[i];
        if ((rc = fp_stack_over_take_path(over, old, i, p, sizeof p)) ||
            (rc = stack_relative(dir, p, l.take, sizeof l.take)))
            fp_errorf(err, errlen, rc, "%s: %s", p, strerror(-rc));
        else rc = fp_stack_append(s, &l, err, errlen);
    }
    fp_stack_layer top = *pass;
    if (!rc && (rc = stack_relative(dir, take_path, top.take, sizeof top.take)))
        fp_errorf(err, errlen, rc, "%s: %s", take_path, strerror(-rc));
    if (!rc) rc = fp_stack_append(s, &top, err, errlen);
    if (!rc && (rc = fp_stack_next_path(dir, slate ? slate : "take", path_out, n)))
        fp_errorf(err, errlen, rc, "%s: no stack name for slate %s", dir, slate ? slate : FP_TAKE_DEFAULT_SLATE);
    if (!rc) rc = fp_stack_save(s, path_out, err, errlen);
    fp_stack_free(&s);
    return rc;
}
