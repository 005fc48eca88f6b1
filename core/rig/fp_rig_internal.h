/*
 * fp_rig_internal.h: the layout of a rig, shared by fp_rig_parse.c (files, validation),
 * fp_rig.c (binding to a mesh, lookups), fp_rig_place.c (a moved copy of its mesh) and
 * fp_rig_pose.c (the jaw pose, the mobility blend, the finger limit).
 * Private to core/rig: everyone else goes through fp_rig.h.
 */
#ifndef FP_RIG_INTERNAL_H
#define FP_RIG_INTERNAL_H

#include "fp_rig.h"

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#define MAX_MOUTH_POINTS 16

typedef struct region {
    char name[FP_RIG_NAME_MAX + 1];
    int kind;
    size_t count;
} region;

typedef struct landmark {
    char name[FP_RIG_NAME_MAX + 1];
    uint32_t vertex;
    double ref[3];              /* where it lies on the rig's own mesh (mesh.landmark_positions) */
} landmark;

/* The rig's unit, coordinates and lengths (mesh units): as the file gives them, or carried
 * onto a moved copy of its mesh at each bind (fp_rig_place.c keeps the file's in parsed) */
typedef struct rig_geom {
    double mm_per_unit;
    double up[3], fwd[3], left[3];
    double hinge_r[3], hinge_l[3];
    double axis[3];             /* unit hinge axis, right -> left */
    double glide[2];            /* forward, down; mesh units at jaw.open = 1 */
    double mouth[MAX_MOUTH_POINTS][3];
    double lip_band, cheek_band, cheek_distance, corner_inset, inner_depth;
    double menton[3], gonion[3];
    double neck_band, back_band;
    double ramp;                /* mobility ramp, mesh units */
} rig_geom;

typedef struct channel {
    char name[FP_RIG_NAME_MAX + 1];
    float min, max, neutral;
} channel;

struct fp_rig {
    char name[128];
    char source[1024];
    char mesh_name[256];
    size_t n;
    uint32_t crc;
    rig_geom geom;              /* the unit, the face's axes, the jaw's coordinates, lengths */
    size_t region_count;
    region regions[FP_RIG_MAX_REGIONS];
    uint8_t *kind;              /* n */
    uint8_t *owner;             /* n: region index + 1 of each vertex, 0 in none */
    size_t landmark_count;
    landmark landmarks[FP_RIG_MAX_LANDMARKS];
    size_t channel_count;
    channel channels[FP_RIG_MAX_CHANNELS];
    long jaw_open;              /* index of jaw.open */
    /* jaw (its coordinates in geom) */
    double open_deg;
    double glide_start;         /* jaw.open where the glide begins (default 0) */
    size_t mouth_count;
    size_t weight_count;        /* jaw.weights: soft vertices whose weight the file gives */
    uint32_t *weight_v;         /* their indices, ascending */
    float *weight_w;            /* their weights in [0, 1] */
    uint32_t *weld;             /* n or NULL: after fp_rig_remap, the first vertex of each
                                   vertex's rig vertex (its split copies share it) */
    /* bound */
    float *w;                   /* n jaw weights */
    float *m;                   /* n mobility */
    float *g;                   /* n |grad m| (per mesh unit), 0 where m is flat */
    uint32_t *slope_v;          /* the vertices with g > 0, ascending */
    float *slope_dir;           /* slope_count x 3: grad m's unit direction at each (away
                                   from its nearest rigid vertex, in the bound shape) */
    size_t slope_count;
    /* placement (fp_rig_place.c) */
    bool has_ref;               /* every landmark has ref (mesh.landmark_positions given) */
    rig_geom parsed;            /* the file's geometry, kept at the end of fp_rig_parse */
    fp_rig_placement placement; /* the last bind's */
};

/* An error's context: the file and where its message goes (fp_rig_parse.c, fp_rig.c) */
typedef struct fpr_ctx {
    const char *file;
    char *err;
    size_t errlen;
} fpr_ctx;

/* -EBADMSG with "FILE: PATH: message" in c's buffer (PATH: the JSON path, "" the top) */
int fpr_bad(const fpr_ctx *c, const char *path, const char *fmt, ...) __attribute__((format(printf, 3, 4)));

/* the place of landmark `name` in r->landmarks, or r->landmark_count: none */
static inline size_t fpr_landmark_at(const fp_rig *r, const char *name)
{
    size_t k = 0;
    while (k < r->landmark_count && strcmp(r->landmarks[k].name, name)) k++;
    return k;
}

/* fp_rig_place.c: r's geometry back to the file's (r->parsed), then, when the landmarks'
 * vertices in pos (n x 3) lie elsewhere than their ref (a moved, turned or scaled copy of the
 * rig's mesh), carried there by the similarity that fits them best (r->placement says) */
void fpr_place(fp_rig *r, const float *pos);

/* fp_rig.c: the names of dir's *.json files, sorted, into *names (malloc()ed, each and the
 * array). Returns their count, or a negative errno. */
long fpr_json_names(const char *dir, char ***names);

/* fp_rig_near.c: for each soft vertex v (kind[v] == FP_RIG_SOFT) of the n (positions pos, n x 3),
 * the nearest vertex of another kind within reach2 (a squared distance, inclusive), its squared
 * distance as float differences squared and summed in double: bu[v] and best[v]; ties to the
 * smallest key[u]; none (and for the other vertices): best[v] = INFINITY, bu[v] = v. 0 or
 * -ENOMEM. A k-d tree: n log n. */
int fpr_nearest_rigid(const uint8_t *kind, size_t n, const float *pos, const uint64_t *key, double reach2,
                      uint32_t *bu, double *best);

#endif
