/* fp-selfx [--away RINGS] BEFORE AFTER: the triangle pairs that cross in AFTER but not in
 * BEFORE (two meshes with the same vertices and triangles, e.g. a face and its deformation
 * written by `facepuppet run --out`); with --away, only the pairs away from BEFORE's own
 * crossings (the trust issue's measure, fp_selfx_count_new_away). Prints the counts and the
 * first new pairs; exit 0 when there is no new crossing, 1 when there are, 2 on an error
 * (unreadable file, different topology), 64 on usage (a bad --away named). */
#include "fp_mesh.h"
#include "selfx.h"
#include <facepuppet/decimal.h> /* fp_parse_whole: a count as in every option */

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

int main(int argc, char **argv)
{
    int rings = -1; /* -1: every new pair */
    if (argc == 5 && !strcmp(argv[1], "--away")) {
        unsigned long long r;
        if (!fp_parse_whole(argv[2], 8, &r)) {
            fprintf(stderr, "fp-selfx: --away takes a ring count 0..8, got '%s'\n", argv[2]);
            return 64;
        }
        rings = (int)r;
        argv += 2;
        argc -= 2;
    }
    const int help = argc == 2 && !strcmp(argv[1], "--help");
    if (argc != 3 || help) {
        fprintf(help ? stdout : stderr,
                "usage: fp-selfx [--away RINGS] BEFORE AFTER\n"
                "Counts the triangle pairs that cross (exactly, CGAL) in AFTER but not in\n"
                "BEFORE; adjacent triangles (a shared vertex or edge, vertices welded by\n"
                "position) are not crossings. --away RINGS leaves out pairs within RINGS vertex\n"
                "rings of a triangle that crosses in BEFORE (the input's own crossings move\n"
                "under any deformation). Exit 0: none new, 1: new crossings, 2: error,\n"
                "64: usage.\n");
        return help ? 0 : 64;
    }
    char err[512];
    fp_mesh *a = NULL, *b = NULL;
    if (fp_mesh_load(argv[1], &a, err, sizeof err) < 0 ||
        fp_mesh_load(argv[2], &b, err, sizeof err) < 0) {
        fprintf(stderr, "fp-selfx: %s\n", err);
        fp_mesh_free(&a);
        return 2;
    }
    if (a->vertex_count != b->vertex_count || a->triangle_count != b->triangle_count ||
        memcmp(a->triangles, b->triangles, a->triangle_count * 3 * sizeof(uint32_t))) {
        fprintf(stderr, "fp-selfx: %s and %s differ in vertices or triangles (%zu/%zu vs %zu/%zu)\n",
                argv[1], argv[2], a->vertex_count, a->triangle_count, b->vertex_count,
                b->triangle_count);
        fp_mesh_free(&a);
        fp_mesh_free(&b);
        return 2;
    }
    enum { SHOW = 20 };
    uint32_t pairs[2 * SHOW];
    long own = 0, near_own = 0;
    long n = rings < 0 ? fp_selfx_count_new(a->positions, b->positions, a->vertex_count,
                                            a->triangles, a->triangle_count, pairs, SHOW, &own)
                       : fp_selfx_count_new_away(a->positions, b->positions, a->vertex_count,
                                                 a->triangles, a->triangle_count, rings, pairs,
                                                 SHOW, &own, &near_own);
    if (n < 0) {
        fprintf(stderr, "fp-selfx: counting failed (%ld)\n", n);
        fp_mesh_free(&a);
        fp_mesh_free(&b);
        return 2;
    }
    printf("new crossings: %ld (BEFORE's own crossings: %ld; %zu triangles", n, own,
           a->triangle_count);
    if (rings >= 0) printf("; %ld more within %d rings of BEFORE's own", near_own, rings);
    printf(")\n");
    for (long k = 0; k < n && k < SHOW; k++)
        printf("  triangles %u and %u\n", pairs[2 * k], pairs[2 * k + 1]);
    if (n > SHOW) printf("  ... %ld more\n", n - SHOW);
    fp_mesh_free(&a);
    fp_mesh_free(&b);
    return n > 0;
}
