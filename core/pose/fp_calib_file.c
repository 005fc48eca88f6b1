/* The calibration file: read and write (fp_calib_file.h). */
#define _GNU_SOURCE
#include "fp_calib_file.h"

#include "fp_error.h"
#include "fp_file.h"
#include "fp_text.h"

#include <cJSON.h>
#include <errno.h>
#include <stdbool.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* Reads a JSON array of n finite numbers at obj[key] (absent: returns 0, untouched). */
static int numbers(const char *path, const cJSON *obj, const char *prefix, const char *key,
                   double *out, int n, char *err, size_t errlen)
{
    const cJSON *a = cJSON_GetObjectItemCaseSensitive(obj, key);
    if (!a) return 0;
    if (!cJSON_IsArray(a) || cJSON_GetArraySize(a) != n)
        return fp_errorf(err, errlen, -EBADMSG, "%s: field %s%s: expected an array of %d numbers",
                         path, prefix, key, n);
    for (int i = 0; i < n; i++) {
        const cJSON *v = cJSON_GetArrayItem(a, i);
        if (!cJSON_IsNumber(v))
            return fp_errorf(err, errlen, -EBADMSG, "%s: field %s%s[%d]: expected a number", path,
                             prefix, key, i);
        if (!isfinite(v->valuedouble))
            return fp_errorf(err, errlen, -ERANGE, "%s: field %s%s[%d]: not finite", path, prefix, key, i);
        if (fabs(v->valuedouble) > 1e9) /* (1e308 made every hand point infinite downstream) */
            return fp_errorf(err, errlen, -ERANGE, "%s: field %s%s[%d]: %g is beyond 1e9", path,
                             prefix, key, i, v->valuedouble);
        out[i] = v->valuedouble;
    }
    return 1;
}

/* the largest calibration file read (a real one is a few hundred bytes) */
#define FP_CALIBRATION_MAX_BYTES ((size_t)1 << 20)

int fp_calibration_load(const char *path, fp_calibration *out, char *err, size_t errlen)
{
    char *text;
    size_t len;
    int code = fp_file_read_all(path, FP_CALIBRATION_MAX_BYTES, &text, &len); /* (a folder,
                                                           FIFO or device: refused) */
    if (code == -EFBIG) /* (not parsed in part: its end would read as the error) */
        return fp_errorf(err, errlen, -EBADMSG, "%s: larger than 1 MiB (a calibration is a "
                         "JSON object of a few hundred bytes)", path);
    if (code == -ENOMEM) return fp_errorf(err, errlen, -ENOMEM, "%s: out of memory", path);
    if (code == -EIO) return fp_errorf(err, errlen, -EIO, "%s: read error", path);
    if (code) return fp_errorf(err, errlen, code, "%s: %s", path, fp_file_error_text(code));
    const char *end = NULL;
    cJSON *root = cJSON_ParseWithLengthOpts(text, len, &end, false);
    int rc = 0;
    /* where the text stops being one JSON value and white space */
    const char *at = root ? fp_text_after_space(end, text + len) : NULL;
    if (at) {
        cJSON_Delete(root);
        root = NULL;
    }
    if (!root) { /* where the parse stopped, as line:column */
        long line, col;
        const bool after = at != NULL;
        if (!at) at = cJSON_GetErrorPtr();
        if (!(at >= text && at <= text + len)) at = text;
        fp_text_line_col(text, at, &line, &col);
        rc = fp_errorf(err, errlen, -EBADMSG, "%s:%ld:%ld: %s", path, line, col,
                       after ? "text after the JSON object"
                       : at == text + len ? "not valid JSON (it ends too soon)" : "not valid JSON");
        goto done;
    }
    if (!cJSON_IsObject(root)) {
        rc = fp_errorf(err, errlen, -EBADMSG, "%s:1: not a JSON object (a calibration is one)", path);
        goto done;
    }
    /* every field known, once: a misspelt "rotaton" would otherwise be ignored in silence */
    static const char *const known[] = {"comment", "mm_per_unit", "scale", "rotation", "offset",
                                        "left", "right"};
    for (const cJSON *a = root->child; a; a = a->next) {
        bool ok = false;
        for (size_t i = 0; i < sizeof known / sizeof known[0]; i++) ok |= !strcmp(a->string, known[i]);
        if (!ok) {
            rc = fp_errorf(err, errlen, -EBADMSG, "%s: unknown field \"%s\" (comment, mm_per_unit "
                           "or scale, rotation, offset, left, right)", path, a->string);
            goto done;
        }
        for (const cJSON *b = root->child; b != a; b = b->next)
            if (!strcmp(a->string, b->string)) {
                rc = fp_errorf(err, errlen, -EBADMSG, "%s: field %s given twice", path, a->string);
                goto done;
            }
    }
    const cJSON *comment = cJSON_GetObjectItemCaseSensitive(root, "comment");
    if (comment && !cJSON_IsString(comment)) {
        rc = fp_errorf(err, errlen, -EBADMSG, "%s: field comment: expected a string", path);
        goto done;
    }
    for (int h = 0; h < 2; h++) { /* left and right hold an offset only */
        const cJSON *o = cJSON_GetObjectItemCaseSensitive(root, h ? "right" : "left");
        for (const cJSON *a = o && cJSON_IsObject(o) ? o->child : NULL; a; a = a->next)
            if (strcmp(a->string, "offset") || a != o->child) {
                rc = fp_errorf(err, errlen, -EBADMSG, "%s: field %s.%s: %s", path,
                               h ? "right" : "left", a->string,
                               strcmp(a->string, "offset") ? "unknown (only offset)" : "given twice");
                goto done;
            }
    }
    fp_calibration c;
    memset(&c, 0, sizeof c);
    c.rotation[0] = 1;
    const cJSON *mpu = cJSON_GetObjectItemCaseSensitive(root, "mm_per_unit");
    const cJSON *sc = cJSON_GetObjectItemCaseSensitive(root, "scale");
    if (mpu && sc) {
        rc = fp_errorf(err, errlen, -EBADMSG, "%s: give mm_per_unit or scale, not both", path);
        goto done;
    }
    const cJSON *one = mpu ? mpu : sc;
    const char *name = mpu ? "mm_per_unit" : "scale";
    if (!one) {
        rc = fp_errorf(err, errlen, -EBADMSG, "%s: field mm_per_unit (or scale) is missing", path);
        goto done;
    }
    if (!cJSON_IsNumber(one)) {
        rc = fp_errorf(err, errlen, -EBADMSG, "%s: field %s: expected a number", path, name);
        goto done;
    }
    if (!isfinite(one->valuedouble) || !(one->valuedouble > 0)) {
        rc = fp_errorf(err, errlen, -ERANGE, "%s: field %s: must be a finite number > 0, got %g",
                       path, name, one->valuedouble);
        goto done;
    }
    c.scale = mpu ? 1.0 / one->valuedouble : one->valuedouble;
    /* both the scale and its inverse (what save writes) must be normal finite numbers: a
     * subnormal mm_per_unit would give an infinite scale (found by tests/fuzz/fuzz_calib) */
    if (!isnormal(c.scale) || !isnormal(1.0 / c.scale) || !(1.0 / c.scale >= 1e-6 && 1.0 / c.scale <= 1e9)) {
        /* (mm per mesh unit from a micrometre to a kilometre's thousand: beyond, a slip of
         * units, and a face no hand reaches) */
        rc = fp_errorf(err, errlen, -ERANGE, "%s: field %s: %g is out of range (mm_per_unit 1e-6 "
                       "to 1e9)", path, name, one->valuedouble);
        goto done;
    }
    if ((rc = numbers(path, root, "", "rotation", c.rotation, 4, err, errlen)) < 0) goto done;
    /* the norm scaled by the largest component, so that squares never overflow */
    double qmax = 0;
    for (int i = 0; i < 4; i++) qmax = fmax(qmax, fabs(c.rotation[i]));
    double qn = 0;
    if (qmax > 0) {
        for (int i = 0; i < 4; i++) qn += (c.rotation[i] / qmax) * (c.rotation[i] / qmax);
        qn = qmax * sqrt(qn);
    }
    if (!(qn > 1e-6) || !isfinite(qn)) {
        rc = fp_errorf(err, errlen, -ERANGE, "%s: field rotation: a quaternion of norm %g", path, qn);
        goto done;
    }
    for (int i = 0; i < 4; i++) c.rotation[i] /= qn;
    if ((rc = numbers(path, root, "", "offset", c.offset, 3, err, errlen)) < 0) goto done;
    static const char *hands[FP_HANDS] = {"left", "right"};
    for (int h = 0; h < FP_HANDS; h++) {
        const cJSON *o = cJSON_GetObjectItemCaseSensitive(root, hands[h]);
        if (!o) continue;
        if (!cJSON_IsObject(o)) {
            rc = fp_errorf(err, errlen, -EBADMSG, "%s: field %s: expected an object", path, hands[h]);
            goto done;
        }
        char prefix[16];
        snprintf(prefix, sizeof prefix, "%s.", hands[h]);
        if ((rc = numbers(path, o, prefix, "offset", c.hand_offset[h], 3, err, errlen)) < 0) goto done;
    }
    rc = 0;
    *out = c;
done:
    cJSON_Delete(root);
    free(text);
    return rc;
}

int fp_calibration_save(const char *path, const fp_calibration *given, const char *comment, char *err,
                        size_t errlen)
{
    fp_calibration flat; /* (a face's frame folded into the rotation and the offsets) */
    fp_calibration_flatten(given, &flat);
    const fp_calibration *c = &flat;
    if (!(c->scale > 0)) return fp_errorf(err, errlen, -EINVAL, "%s: scale must be > 0", path);
    fp_file_output o;
    int rc = fp_file_open_output(path, "", "w", 0, &o); /* a link's end; no folder or device */
    if (rc < 0 && o.failed == FP_FILE_STEP_TARGET)
        return fp_errorf(err, errlen, rc == -EISDIR || rc == -ENXIO ? -EEXIST : rc,
                         "%s: cannot replace it: %s", path, fp_file_error_text(rc));
    path = o.path;
    if (rc < 0 && o.failed == FP_FILE_STEP_TEMP)
        return fp_errorf(err, errlen, rc, "%s: cannot create a file in its folder: %s", path,
                         strerror(-rc));
    if (rc < 0) return fp_errorf(err, errlen, rc, "%s: %s", path, strerror(-rc));
    FILE *f = o.f;
    fprintf(f, "{\n");
    if (comment) {
        cJSON *s = cJSON_CreateString(comment);
        char *q = s ? cJSON_PrintUnformatted(s) : NULL;
        if (q) fprintf(f, "  \"comment\": %s,\n", q);
        free(q);
        cJSON_Delete(s);
    }
    fprintf(f, "  \"mm_per_unit\": %.17g,\n", 1.0 / c->scale);
    double q[4] = {c->rotation[0], c->rotation[1], c->rotation[2], c->rotation[3]};
    if (q[0] == 0 && q[1] == 0 && q[2] == 0 && q[3] == 0) q[0] = 1;
    fprintf(f, "  \"rotation\": [%.17g, %.17g, %.17g, %.17g],\n", q[0], q[1], q[2], q[3]);
    fprintf(f, "  \"offset\": [%.17g, %.17g, %.17g],\n", c->offset[0], c->offset[1], c->offset[2]);
    fprintf(f, "  \"left\": {\"offset\": [%.17g, %.17g, %.17g]},\n", c->hand_offset[0][0],
            c->hand_offset[0][1], c->hand_offset[0][2]);
    fprintf(f, "  \"right\": {\"offset\": [%.17g, %.17g, %.17g]}\n}\n", c->hand_offset[1][0],
            c->hand_offset[1][1], c->hand_offset[1][2]);
    int e = -fp_file_output_commit(&o);
    if (e)
        return fp_errorf(err, errlen, e == ENOSPC ? -ENOSPC : -EIO, "%s: cannot write: %s", path,
                         strerror(e));
    return 0;
}
