/* fp-export-check TAKE|STACK FILE [--max-error MM]: checks an export against its take
 * (a stack: its composite, fp_take_player_positions), frame by frame. The take is played
 * again (fp_take_player: bit-identical frames), and:
 *   .pc2 / .mdd  read back with their own header parsing here: points, frames (and MDD's
 *                times) as the take says, every float32 bit-identical to the played frame;
 *   .gltf / .glb read back with tinygltf (gltf_anim.cpp, not core/mesh); the animation
 *                evaluated at each frame's time (its own sampler interpolation), positions
 *                base + sum w_k target_k in float32, each glTF vertex against its mesh vertex,
 *                within MM millimetres (mm per unit from fp_take_player_mm_per_unit); the
 *                mesh's node placed in metres (the scale above it mm per unit / 1000),
 *                asset.extras.frameRate the take's rate, and every weight in [0, 1] (Blender
 *                3.4's importer clamps shape keys to their [0, 1] slider range).
 * Prints one line of figures; exit 0 when everything holds, 1 otherwise, 64 on usage (a bad
 * or unknown option named). */
#define _GNU_SOURCE
#include "fp_take_player.h"
#include "fp_mesh.h"
#include "gltf_anim.h"
#include <facepuppet/plugin_util.h> /* fp_parse_decimal: numbers as in every option */

#include <math.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static uint32_t rd32(const unsigned char *p, int big)
{
    return big ? (uint32_t)p[0] << 24 | (uint32_t)p[1] << 16 | (uint32_t)p[2] << 8 | p[3]
               : (uint32_t)p[3] << 24 | (uint32_t)p[2] << 16 | (uint32_t)p[1] << 8 | p[0];
}

static unsigned char *slurp(const char *path, size_t *n)
{
    FILE *f = fopen(path, "rb");
    if (!f) return NULL;
    fseek(f, 0, SEEK_END);
    long len = ftell(f);
    fseek(f, 0, SEEK_SET);
    unsigned char *b = malloc((size_t)len + 1);
    if (b && fread(b, 1, (size_t)len, f) != (size_t)len) { free(b); b = NULL; }
    fclose(f);
    *n = (size_t)len;
    return b;
}

/* v turned by the unit quaternion q (x, y, z, w): v + 2w (q x v) + 2 q x (q x v). */
static void rotate(const double q[4], double v[3])
{
    const double t[3] = {2 * (q[1] * v[2] - q[2] * v[1]), 2 * (q[2] * v[0] - q[0] * v[2]),
                         2 * (q[0] * v[1] - q[1] * v[0])};
    const double u[3] = {q[1] * t[2] - q[2] * t[1], q[2] * t[0] - q[0] * t[2], q[0] * t[1] - q[1] * t[0]};
    for (int c = 0; c < 3; c++) v[c] += q[3] * t[c] + u[c];
}

int main(int argc, char **argv)
{
    if (argc < 3) {
        fprintf(stderr, "usage: fp-export-check TAKE FILE [--max-error MM]\n");
        return 64;
    }
    const char *take = argv[1], *file = argv[2];
    double max_mm = 0.1;
    for (int i = 3; i < argc; i += 2) {
        if (strcmp(argv[i], "--max-error") || i + 1 == argc) {
            fprintf(stderr, "fp-export-check: unknown or incomplete option '%s'\n", argv[i]);
            return 64;
        }
        if (!fp_parse_decimal(argv[i + 1], &max_mm) || !(max_mm > 0)) {
            fprintf(stderr, "fp-export-check: --max-error '%s': expected a number of mm > 0\n",
                    argv[i + 1]);
            return 64;
        }
    }
    char err[2048];
    fp_plugin_path path;
    const char *dir = getenv("FP_BUILD_DIR");
    char pdir[4096];
    snprintf(pdir, sizeof pdir, "%s/lib/facepuppet", dir ? dir : "build");
    const char *dirs[1] = {pdir};
    fp_plugin_path_init(&path, dirs, 1, NULL);
    fp_take_player *p = NULL;
    if (fp_take_player_open(take, NULL, &path, &p, err, sizeof err)) {
        fprintf(stderr, "fp-export-check: %s\n", err);
        return 1;
    }
    fp_session *s = fp_take_player_session(p);
    const size_t n = fp_session_vertex_count(s);
    const size_t frames = fp_take_reader_frames(fp_take_player_reader(p));
    const double mmu = fp_take_player_mm_per_unit(p);
    const char *ext = strrchr(file, '.');
    int bad = 0;
    fp_take_frame f;
    int64_t t0 = 0;
    if (ext && (!strcmp(ext, ".pc2") || !strcmp(ext, ".mdd"))) {
        const int big = !strcmp(ext, ".mdd");
        size_t len;
        unsigned char *b = slurp(file, &len);
        if (!b) { fprintf(stderr, "fp-export-check: cannot read %s\n", file); return 1; }
        size_t hdr, nframes, npoints;
        if (big) {
            nframes = rd32(b, 1); npoints = rd32(b + 4, 1); hdr = 8 + 4 * nframes;
        } else {
            if (memcmp(b, "POINTCACHE2\0", 12) || rd32(b + 12, 0) != 1) {
                fprintf(stderr, "fp-export-check: %s: not a PC2 version 1 file\n", file);
                return 1;
            }
            float start, rate;
            uint32_t u = rd32(b + 20, 0); memcpy(&start, &u, 4);
            u = rd32(b + 24, 0); memcpy(&rate, &u, 4);
            if (start != 0.0f || rate != 1.0f) bad++;
            npoints = rd32(b + 16, 0); nframes = rd32(b + 28, 0); hdr = 32;
        }
        if (npoints != n || nframes != frames || len != hdr + nframes * npoints * 12) {
            fprintf(stderr, "fp-export-check: %s: %zu points x %zu frames (%zu bytes); the take: "
                    "%zu x %zu\n", file, npoints, nframes, len, n, frames);
            return 1;
        }
        size_t k = 0, diff = 0;
        while (fp_take_player_next(p, &f, NULL, err, sizeof err) == 1) {
            if (k == 0) t0 = f.time_ns;
            const float *pos = fp_take_player_positions(p);
            const unsigned char *q = b + hdr + k * n * 12;
            for (size_t i = 0; i < 3 * n; i++) {
                uint32_t want;
                memcpy(&want, pos + i, 4);
                if (rd32(q + 4 * i, big) != want) diff++;
            }
            if (big) {
                float t, tw = (float)((double)(f.time_ns - t0) * 1e-9);
                uint32_t u = rd32(b + 8 + 4 * k, 1);
                memcpy(&t, &u, 4);
                if (t != tw) diff++;
            }
            k++;
        }
        printf("%s: %zu frames x %zu points, %zu values differ (bit-exact: %s)\n", file, k, n,
               diff, diff ? "no" : "yes");
        bad += diff != 0 || k != frames;
        free(b);
    } else {
        fp_test_gltf_anim a;
        if (fp_test_gltf_anim_load(file, n, &a, err, sizeof err)) {
            fprintf(stderr, "fp-export-check: %s\n", err);
            return 1;
        }
        if (a.keys != frames || a.target_names != a.targets) {
            fprintf(stderr, "fp-export-check: %s: %zu keys, %zu targets, %zu names; the take "
                    "has %zu frames\n", file, a.keys, a.targets, a.target_names, frames);
            return 1;
        }
        /* every weight in [0, 1]: Blender 3.4's importer (Debian 12's) clamps a shape key's
         * value to its slider range, [0, 1] (widened only by the first key's weight) */
        size_t outside = 0;
        for (size_t i = 0; i < a.keys * a.targets; i++)
            outside += !(a.weights[i] >= 0 && a.weights[i] <= 1);
        if (outside)
            fprintf(stderr, "fp-export-check: %s: %zu of %zu weights outside [0, 1] (Blender 3.4 "
                    "clamps them)\n", file, outside, a.keys * a.targets);
        bad += outside != 0;
        float *w = malloc(a.targets * sizeof(float) + 4);
        double worst = 0;
        size_t worst_frame = 0, k = 0;
        while (fp_take_player_next(p, &f, NULL, err, sizeof err) == 1) {
            if (k == 0) t0 = f.time_ns;
            const float *pos = fp_take_player_positions(p);
            fp_test_gltf_anim_weights(&a, (double)(f.time_ns - t0) * 1e-9, w);
            for (size_t j = 0; j < a.vertices; j++) {
                const float *want = pos + 3 * (size_t)a.source_vertex[j];
                double e2 = 0;
                for (int c = 0; c < 3; c++) {
                    float x = a.base[3 * j + (size_t)c];   /* float32, as a renderer sums */
                    for (size_t t = 0; t < a.targets; t++)
                        x += w[t] * a.target[(t * a.vertices + j) * 3 + (size_t)c];
                    e2 += ((double)x - want[c]) * ((double)x - want[c]);
                }
                if (sqrt(e2) > worst) { worst = sqrt(e2); worst_frame = k; }
            }
            k++;
        }
        /* in metres (the mesh's node under a scale of mm per unit / 1000), the take's rate named */
        const fp_take_rate rate = fp_take_player_header(p)->rate;
        const double want_rate = rate.den ? (double)rate.num / rate.den : 0;
        const bool metres = fabs(a.unit_scale - mmu / 1000) <= 1e-9 * (mmu / 1000);
        const bool rate_ok = fabs(a.frame_rate - want_rate) <= 1e-9 * want_rate;
        /* glTF's +y up and +z front: the root's rotation takes the take's face axes there (a
         * Z-up face, --up +z --facing -y, lay on its back in Blender without it) */
        const fp_take_header *h = fp_take_player_header(p);
        const bool axes = h->face_up[0] != 0 || h->face_up[1] != 0 || h->face_up[2] != 0;
        double up[3] = {0, 1, 0}, front[3] = {0, 0, 1};
        if (axes)
            for (int c = 0; c < 3; c++) up[c] = h->face_up[c], front[c] = h->face_facing[c];
        rotate(a.rotation, up);
        rotate(a.rotation, front);
        const bool upright = fabs(up[1] - 1) < 1e-6 && fabs(front[2] - 1) < 1e-6;
        printf("%s: the face's up turned to (%.4g %.4g %.4g), its front to (%.4g %.4g %.4g) "
               "(want +y and +z)\n", file, up[0], up[1], up[2], front[0], front[1], front[2]);
        bad += !upright;
        printf("%s: %zu frames, %zu glTF vertices (mesh %zu), %zu triangles, "
               "%zu primitives, materials [%s], K = %zu, largest error %.6g mm at frame %zu "
               "(limit %.6g mm, %.6g mm per unit); scene scale %.6g (want %.6g: metres), "
               "asset.extras.frameRate %.6g (the take's %.6g)\n", file, k, a.vertices, n,
               a.triangles, a.primitives, a.material_names, a.targets, worst * mmu, worst_frame,
               max_mm, mmu, a.unit_scale, mmu / 1000, a.frame_rate, want_rate);
        bad += worst * mmu > max_mm || k != frames || !metres || !rate_ok;
        free(w);
        fp_test_gltf_anim_free(&a);
    }
    fp_take_player_close(&p);
    fp_plugin_path_clear(&path);
    return bad ? 1 : 0;
}
