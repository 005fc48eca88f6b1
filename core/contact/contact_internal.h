/*
 * contact_internal.h: the contact guard's insides (core/contact; the API is fp_contact.h), shared
 * by its files and by nothing else: the index (struct fp_contact), the incremental state
 * (struct track) with the envelopes' and the hierarchy's parts, the small inline helpers every
 * part uses, and the functions one file gives another (prefix fpc_).
 *
 * The files, by concern:
 *   contact_predicates.c  filtered orientation predicates, the triangle-triangle test
 *   contact_scan.c        the index (weld, own crossings, rest normals), the full check
 *                         (fp_contact_count_new) and the stateless guard (fp_contact_guard)
 *   contact_envelope.c    envelopes (3a): the dynamic grid, lists, renewals, their check,
 *                         the re-centring
 *   contact_bvh.c         the hierarchy (3b), its check: certificates, refit, walk, tasks
 *   contact_cluster.c     the hierarchy, its building: clusters, layout, boundary cycles
 *   contact_track.c       the incremental state: making, the moved vertices and triangles,
 *                         fp_contact_reference, the accessors and settings, fp_contact_set_pose
 *   contact_step.c        fp_contact_step: the first check, the local scale-back, the
 *                         bisection; fp_contact_hold
 *   contact_kd.c          the scale-back's k-d tree over the blocking vertices: nearest
 *                         distances (the ramp), weighted motion sums (the carry); its own
 *                         header, contact_kd.h, for its test
 *   contact_worker.c      the worker: jobs of tasks on two threads
 */
#ifndef FP_CONTACT_INTERNAL_H
#define FP_CONTACT_INTERNAL_H

#include "fp_vec.h"
#include "fp_contact.h"
#include "fp_select.h"
#include "contact_kd.h"

#include <errno.h>
#include <math.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

/* ---- the index ------------------------------------------------------------------------------ */

struct fp_contact {
    const uint32_t *tris;
    size_t t, n;
    uint32_t *weld;       /* n: the first vertex at the same position */
    uint8_t *moved;       /* n: vertex moved this check */
    uint32_t *ins;        /* triangles in the grid */
    float (*box)[6];      /* t: candidate bounding box (min xyz, max xyz) of inserted ones */
    struct cellrec *rec, *rec_tmp; /* the check's grid: (cell, triangle), sorted by cell */
    size_t rec_cap;
    struct cellrun *run;  /* one cell's triangles, as the check's sweep reads them */
    size_t run_cap;
    uint8_t *own;         /* t: the triangle crosses another in the weld shape */
    float (*nrm)[3];      /* t: the rest normals (flips are against them): the weld shape's
                             triangle normals (unnormalised), carried by fp_contact_set_pose */
    float (*nrm_weld)[3]; /* t: the weld shape's, kept at the first fp_contact_set_pose */
    struct track *tk;     /* the incremental guard (fp_contact_step), made on first use */
    float *weld_copy;     /* n x 3: the weld shape, the tracker's first P (freed then) */
    size_t prewarm;       /* fp_contact_set_prewarm */
    bool certify;         /* fp_contact_set_certify */
    int threads;          /* fp_contact_set_threads: 1 or 2 */
    size_t share_min;     /* fp_contact_set_threads: moved triangles from which a check is shared */
    double local_r;       /* fp_contact_set_local: 0, a scale-back is global */
    bool carry;           /* fp_contact_set_carry (default true) */
    size_t gallop_min;    /* fp_contact_set_gallop (default FP_CONTACT_GALLOP_MIN_TRIS) */
};

/* ---- the incremental guard (fp_contact.h "The incremental guard") ------------------------- */

#define FP_TRACK_NONE UINT32_MAX
#define FP_TRACK_BIG_CELLS 4096.0 /* a box over more grid cells goes to a list of its own */
#define FP_TRACK_SKIN 0.1         /* an envelope: the box grown by this share of its extent */
#define FP_TRACK_RECENTRE 0.5     /* after a step, a moved triangle whose box in P comes within
                                     this share of the skin of its envelope's side gets a new
                                     one around that box (recentre, on the worker) */

#define FP_CONTACT_LOCAL_ROUNDS 5 /* a local scale-back: times its blocking set may grow */
#define FP_CONTACT_GALLOP 16 /* a scale-back after one that kept at most 1/16 near the
                                 blocking triangles (skin a blocked finger holds, frame after
                                 frame) tries its t first, then doubles it, before halving
                                 (steps of fp_contact_set_gallop's triangles or more) */
#define FP_CONTACT_LOCAL_NARROW 4.0 /* its first ramp: local_r / this, doubled each round */
#define FP_CONTACT_CARRY_ROUNDS 3 /* its rounds that try the held skin carried first (r / 4,
                                     r / 2, r: later ones never passed on the recordings) */
#define FP_CONTACT_CARRY_RIGID 4.0 /* a carried round held back for flips alone whose blocking
                                     vertices span at most this many r (their box's diagonal in
                                     P) carries the held skin by one translation, their mean
                                     motion (carry_rigid): a few triangles that earlier motion
                                     left near a right angle from the loaded face keep their
                                     normals, where a carry that varies over them turned them
                                     past it (issue 51) */
#define FP_CONTACT_CARRY_MAX_TRIS 200000 /* a step with more moved triangles tries none (a
                                     carried check that fails costs a check: 0.1-1 s on the
                                     1.7M face) */
#define FP_TRACK_INLINE 6          /* list entries kept in the dyn itself (one cache line) */

#define FP_CONTACT_MAX_THREADS 2  /* the caller and one worker (fp_contact_set_threads) */
#define FP_BVH_LEAF 24            /* triangles in a leaf of the hierarchy, at most */
#define FP_CERT_MIN 48            /* a patch (node) with this many triangles or more ... */
#define FP_CERT_MAX 65536         /* ... and no more may be certified (its boundary made once;
                                     262,144 or 1,048,576 certified no more patches of the
                                     1.68M face, 28 a frame, and its failed tries cost more) */
#define FP_BLOCK_SHIFT 6  /* bstamp: blocks of 64 places */
#define FP_SUPER_SHIFT 12 /* sbstamp: blocks of 4096 places */
#define FP_WALK_GRAIN 16384       /* triangles of a node (pair) walked whole by one task, at most */
#define FP_ACCEPT_GRAIN 2048      /* moved vertices of one accept_range task */

typedef struct bnode {            /* a node of the hierarchy: a patch of triangles (64 bytes,
                                     one cache line; its stamp is in nstamp) */
    float box[6];                 /* its triangles' box in P (in the shape checked, in a check) */
    uint32_t first, count;        /* its triangles: order[first .. first + count) */
    uint32_t right;               /* its right child (the left one is the next node); 0: leaf */
    uint32_t cert;                /* its boundary cycle (index into cert); FP_TRACK_NONE: none */
    float nlo[3], nhi[3];         /* a box that holds its triangles' unit normals (in P) */
} bnode;
_Static_assert(sizeof(bnode) == 64, "a node is one cache line");

typedef struct cert {             /* a patch whose boundary is one simple cycle */
    uint32_t start, len;          /* the cycle's vertices: cyc[start .. start + len) */
} cert;


typedef struct dyn {              /* a triangle that has left the weld shape */
    float env[6];                 /* its envelope: holds its box in P (and in the candidate) */
    uint32_t tri;
    uint32_t len, cap;            /* its list: every triangle whose envelope meets env (and
                                     maybe some more); cap 0: in inl */
    bool big;                     /* registered in the big list, not in the grid */
    union {
        uint32_t inl[FP_TRACK_INLINE];
        uint32_t *heap;
    } u;
} dyn;

static inline uint32_t *dyn_list(dyn *d) { return d->cap ? d->u.heap : d->u.inl; }

typedef struct rq_cell {          /* a cell of a renewed envelope */
    int64_t key[3];
    uint32_t r;                   /* the request (index into rq) */
} rq_cell;

typedef struct centry {           /* a triangle registered in a cell, with a copy of its
                                     envelope and welded vertices (read in order, not through
                                     slot, dyn and the mesh) */
    float env[6];
    uint32_t tri;
    uint32_t w[3];
} centry;

typedef struct cellvec {          /* a cell of the dynamic grid */
    int64_t key[3];
    centry *ids;
    uint32_t len, cap;
    bool used;
} cellvec;

/* new pairs a check keeps for the step's next bisection checks to try first, per thread */
#define FP_PAIR_PROBE 8

typedef struct lane {             /* one thread's part of a hierarchy check: scratch and counts */
    double *xy;                   /* a contour's projection (2 per vertex) */
    size_t cap_xy;
    uint32_t *gcount, *gseg;      /* its segments by grid cell */
    size_t cap_gcount, cap_gseg;
    uint16_t (*grange)[4];        /* each segment's cells (x0, x1, y0, y1) */
    size_t cap_grange;
    float (*sbox)[4];             /* each segment's box in float, rounded outwards (x0, x1,
                                     y0, y1; the upper corner over the margin el) */
    size_t cap_sbox;
    size_t certified, tested;     /* patches certified, triangle pairs tested */
    size_t node_pairs, leaf_pairs; /* node pairs reached, leaf pairs whose boxes met */
    size_t moved;                 /* moved triangles its refit tasks met */
    uint32_t *mq;                 /* one refit task's moved places (gather) */
    size_t nmq, cap_mq;
    uint32_t *mv, *mo;            /* its share of the marking (collect_mark): moved vertices,
                                     moved own triangles */
    size_t nmv, nmo, cap_mv, cap_mo;
    long found, flips;            /* its tasks' new pairs and flips; -ENOMEM sticks */
    uint32_t *rec;                /* the blocking triangles it found: the newly flipped ones
                                     of a check's update, and with record those of its new
                                     pairs (their vertices into off: rec_merge) */
    size_t nrec, cap_rec;
    uint32_t pairs[2 * FP_PAIR_PROBE]; /* the first new pairs its walk tasks found (a, b) */
    size_t npairs;
} lane;

struct track {
    float *p;                     /* n x 3: P, the shape last accepted */
    uint32_t *vt_start, *vt;      /* vertex v's triangles: vt[vt_start[v] .. vt_start[v + 1]) */
    uint32_t *dp;                 /* D_P: every vertex where P may differ from the reference */
    size_t ndp;
    uint8_t *in_dp;               /* n */
    uint32_t *mv;                 /* moved vertices (P -> candidate) */
    size_t nmv, cap_mv;
    float *pv, *cv;               /* their positions in P and in the candidate (3 each) */
    size_t cap_pv;
    uint32_t *mt;                 /* moved triangles, own ones left out */
    float (*mbox)[6];             /* their boxes in the candidate */
    size_t nmt, cap_mt, cap_mbox;
    uint32_t *mo;                 /* moved own triangles: checked for flips only */
    size_t nmo, cap_mo;
    uint32_t *tstamp, tclock;     /* t: == tclock when in mt */
    uint32_t *qstamp, qclock;     /* t: == qclock when seen by this query */
    double ih;                    /* the grid cell's inverse (cell_coord) */
    uint32_t *slot;               /* t: index into dyn; FP_TRACK_NONE: static (P = weld shape) */
    dyn *dyn;
    size_t ndyn, cap_dyn;
    cellvec *cells;               /* the dynamic grid: open addressing, cap a power of 2 */
    size_t cap_cells, used_cells;
    uint32_t *dbig;
    size_t ndbig, cap_dbig;
    uint32_t *q;                  /* one query's triangles */
    size_t nq, cap_q;
    uint32_t *rq;                 /* triangles with a new envelope, their lists to make */
    size_t nrq, cap_rq;
    struct rq_cell *rc, *rcs;     /* (cell, request) of the batch, and sorted by hashed cell */
    size_t cap_rc, cap_rcs;
    uint32_t *rcb, *rr;           /* the sort's buckets; one cell's requests */
    size_t cap_rcb, cap_rr;
    uint32_t *rx;                 /* one cell's requests: their triangles, envelopes and
                                     welded vertices */
    float *renv;                  /* their envelopes by coordinate: renv[a nr + i] (nr of them) */
    uint32_t (*rw)[3];
    uint32_t *rlo;                /* the axes (bits 0-2) where its envelope's lower corner is
                                     in the cell */
    size_t cap_rx, cap_renv, cap_rw, cap_rlo;
    size_t renewed;               /* envelopes renewed, for fp_contact_result */
    bool tree;                    /* the hierarchy (below), not envelopes (a large mesh) */
    bnode *node;                  /* the hierarchy over the triangles not own, root node[0] */
    uint32_t *nstamp;             /* by node: == tclock when it holds a moved triangle */
    size_t nnode;
    uint32_t *order;              /* its triangles, by node */
    uint32_t *tpos;               /* t: a triangle's place in order (FP_TRACK_NONE: own) */
    float (*tn)[3];               /* by place in order: its normal in P (tri_normal_f) */
    float (*tbox)[6];             /* by place in order: its box in P */
    uint32_t *pstamp;             /* by place in order: == tclock when moved (gather) */
    uint32_t *vstamp;             /* n: == tclock when the vertex moved (mark_range); in
                                     tree_build, boundary's check numbers first (bgen) */
    uint32_t bgen;                /* boundary: the last check's number */
    uint32_t *bidx;               /* n, tree_build only: boundary's edge index by source */
    uint8_t *has_own;             /* n: the vertex has an own triangle */
    uint32_t *bstamp, *sbstamp;   /* by block of 64 and of 4096 places: == rclock when one of
                                     them has a vertex in D_P (the region: every moved
                                     triangle is in it; the refit looks for them there,
                                     maybe_moved) */
    uint32_t rclock;              /* the region's clock: a new one when D_P is emptied */
    uint32_t *vtp;                /* beside vt: the triangle's place in order (tpos) */
    uint32_t (*ow)[3];            /* by place in order: its vertices welded (adjacency) */
    uint32_t (*ov)[3];            /* by place in order: its vertices */
    size_t nmq;                   /* the hierarchy's moved triangles (counted by the refit) */
    cert *cert;
    size_t ncert;
    uint32_t *cyc;                /* the certifiable patches' boundary cycles */
    lane lane[FP_CONTACT_MAX_THREADS]; /* [0]: the caller's thread; [1]: the pool's worker */
    struct pool *pool;            /* the worker (fp_contact_set_threads), made on first use */
    size_t shared;                /* this step: checks shared with the worker */
    int64_t waited_ns;            /* the caller's waits for the worker's tasks (job_finish), ns,
                                     all told */
    uint32_t *off;                /* a local scale-back: the blocking triangles' vertices */
    size_t noff, cap_off;
    uint8_t *off_mark;            /* n: in off */
    double *ramp;                 /* per moved vertex: the share of its motion always kept */
    size_t cap_ramp;
    float *carry;                 /* per moved vertex (x3): a carried round's translation of
                                     P, or NULL use (local_scale_back, carry_on) */
    size_t cap_carry;
    bool carry_on;                /* the passed ramp carries (track_lerp adds carry) */
    uint32_t t_hint;              /* the last step's scale-back, where its t was small (at most
                                     1 / FP_CONTACT_GALLOP of the motion): t x 2^iters, plus 1;
                                     0 when the last step kept more, or passed whole. The next
                                     scale-back searches up from it (contact_step.c) */
    size_t updates;               /* the hierarchy: tree_update calls so far */
    uint32_t *probe;              /* the hierarchy: triangles newly flipped in the step's last
                                     check that had any (a bisection's check tries them first) */
    size_t nprobe, cap_probe;
    uint32_t pair_probe[2 * FP_PAIR_PROBE * FP_CONTACT_MAX_THREADS]; /* the hierarchy: new
                                     pairs (a, b) of the step's last check that found any (a
                                     bisection's check tries them first) */
    size_t npair_probe;
    bool rec_pairs;               /* the hierarchy: the walk records its new pairs' triangles
                                     (lanes' rec) without record: set by fpc_tree_check for a
                                     step's first check (accepted), so that a local scale-back
                                     has its blocking set without a second check */
    fpc_kd kd;                    /* local_ramp's k-d tree over off's vertices (contact_kd.h) */
    double carry_r2;              /* carry_build's (2r)^2 */
    const float *carry_cand;      /* (the candidate, for the worker's ranges) */
    bool bg;                      /* a recentre job is posted to the worker (bg_join) */
    bool broken;                  /* a call ran out of memory half way: unusable */
};


/* ---- jobs for the worker (contact_worker.c) ---- */

enum { FP_JOB_MARK, FP_JOB_REFIT, FP_JOB_WALK, FP_JOB_RECENTRE, FP_JOB_CARRY };
typedef struct pool pool;

/* ---- the triangle-triangle test (contact_predicates.c) ---- */

/* A triangle t's plane for the tests of points against it: e1 = t[1] - t[0], e2 = t[2] - t[0],
 * the six products of orient3d's minors made once (n: e1 x e2 with the sign convention of
 * orient3d's expansion, f: the permanent's factors). plane_side(pl, q) is then
 * orient3d(t[0], q, t[1], t[2]) bit for bit (same operations in the same order), whose exact
 * sign is orient3d(t[0], t[1], t[2], q)'s (a cyclic permutation of the determinant's rows);
 * deg: e1 x e2 is exactly 0 in double (a degenerate triangle, which meets nothing here). */
typedef struct tplane {
    const double *o;
    double n[3], f[3];
    bool deg;
} tplane;

static inline void plane_of(const double t[3][3], tplane *pl)
{
    double ux = t[1][0] - t[0][0], uy = t[1][1] - t[0][1], uz = t[1][2] - t[0][2];
    double vx = t[2][0] - t[0][0], vy = t[2][1] - t[0][1], vz = t[2][2] - t[0][2];
    double m1 = uy * vz, m2 = uz * vy, m3 = ux * vz, m4 = uz * vx, m5 = ux * vy, m6 = uy * vx;
    pl->o = t[0];
    pl->n[0] = m1 - m2;
    pl->n[1] = m3 - m4;
    pl->n[2] = m5 - m6;
    pl->f[0] = fabs(m1) + fabs(m2);
    pl->f[1] = fabs(m3) + fabs(m4);
    pl->f[2] = fabs(m5) + fabs(m6);
    pl->deg = pl->n[0] == 0 && pl->n[1] == 0 && pl->n[2] == 0;
}

int fpc_tri_tri_pl(const double a[3][3], const tplane *pa, const double b[3][3], const tplane *pb);

/* b is not degenerate and shares a point with a, whose plane pa is made (a not degenerate) */
static inline bool meets_pl(const double a[3][3], const tplane *pa, const double b[3][3])
{
    tplane pb;
    plane_of(b, &pb);
    return !pb.deg && fpc_tri_tri_pl(a, pa, b, &pb);
}

/* neither triangle degenerate (tplane.deg) and fp_contact_tri_tri(a, b), each plane made
 * once */
static inline bool tris_meet(const double a[3][3], const double b[3][3])
{
    tplane pa;
    plane_of(a, &pa);
    return !pa.deg && meets_pl(a, &pa, b);
}

/* ---- small helpers, inline ---- */

static inline void tri_of(const float *pos, const uint32_t *v, double out[3][3])
{
    for (int i = 0; i < 3; i++)
        for (int k = 0; k < 3; k++) out[i][k] = pos[3 * (size_t)v[i] + k];
}

/* min and max of finite floats, inline (fminf and fmaxf are calls, for NaN's sake) */
static inline float min_f(float a, float b) { return b < a ? b : a; }
static inline float max_f(float a, float b) { return b > a ? b : a; }

static inline void tri_box(const float *pos, const uint32_t *v, float b[6])
{
    const float *p0 = pos + 3 * (size_t)v[0], *p1 = pos + 3 * (size_t)v[1], *p2 = pos + 3 * (size_t)v[2];
    for (int k = 0; k < 3; k++) {
        b[k] = min_f(p0[k], min_f(p1[k], p2[k]));
        b[3 + k] = max_f(p0[k], max_f(p1[k], p2[k]));
    }
}

/* the closed boxes meet; without a branch (track_check's filter takes it by the data) */
static inline bool boxes_meet(const float *a, const float *b)
{
    return (a[0] <= b[3]) & (b[0] <= a[3]) & (a[1] <= b[4]) & (b[1] <= a[4]) & (a[2] <= b[5]) & (b[2] <= a[5]);
}

/* n (e1 x e2 in double) turned by more than acos(FP_CONTACT_FLIP_COS) from the unit normal r:
 * d < FP_CONTACT_FLIP_COS |n|, without a square root */
static inline bool turned_from(const double n[3], const float r[3])
{
    double d = n[0] * r[0] + n[1] * r[1] + n[2] * r[2];
    return d < 0 || d * d < FP_CONTACT_FLIP_COS * FP_CONTACT_FLIP_COS * (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
}

/* The rest normals of triangle i that n is turned over from: bit 0 the pose's (c->nrm, the
 * weld shape's carried by fp_contact_set_pose), bit 1 the weld shape's own (c->nrm_weld,
 * kept once a pose was set): a triangle the pose turned 60 degrees may turn 30 more, not 90 */
static inline unsigned flips_n(const fp_contact *c, const double n[3], size_t i)
{
    return (unsigned)turned_from(n, c->nrm[i]) | (unsigned)(c->nrm_weld && turned_from(n, c->nrm_weld[i])) << 1;
}

/* flips_n of triangle i (vertices v) in pos */
unsigned fpc_flips(const fp_contact *c, const float *pos, const uint32_t *v, size_t i);

/* Triangle i newly turned over in s: turned from a rest normal (flips_n's bits: cand) that it
 * is not turned from in ref (so a triangle the pose itself turned past 90 degrees from the
 * loaded face is excused that, not a fold from where the pose put it) */
static inline bool fpc_new_flip(const fp_contact *c, unsigned cand, const float *ref, const uint32_t *v, size_t i)
{
    return cand && (cand & ~fpc_flips(c, ref, v, i));
}

/* grow *p (elements of size el) to hold need; 0 or -ENOMEM */
static inline int reserve(void **p, size_t *cap, size_t need, size_t el)
{
    if (need <= *cap) return 0;
    size_t nc = need < 16 ? 16 : need + need / 2;
    void *q = realloc(*p, nc * el);
    if (!q) return -ENOMEM;
    *p = q;
    *cap = nc;
    return 0;
}

/* A zero stored on every page of p's n bytes (volatile: a memset of fresh memory may be
 * folded into calloc, which leaves the pages untouched). Fresh pages fault at their first
 * read and again at their first write, microseconds each on a virtual machine (10 such
 * faults made the ICT face's first deforming frame 0.4-1.3 ms): memory a step writes is
 * written here, at the build, not in a gesture's first frames. */
static inline void write_pages(void *p, size_t n)
{
    for (size_t i = 0; p && i < n; i += 4096) ((volatile char *)p)[i] = 0;
}


/* reserve, then every page of the room written (write_pages) */
static inline int reserve_written(void **p, size_t *cap, size_t need, size_t el)
{
    if (reserve(p, cap, need, el)) return -ENOMEM;
    write_pages(*p, *cap * el);
    return 0;
}

static inline int push_u32(uint32_t **p, size_t *len, size_t *cap, uint32_t v)
{
    if (reserve((void **)p, cap, *len + 1, sizeof **p)) return -ENOMEM;
    (*p)[(*len)++] = v;
    return 0;
}

/* n values appended to the list (*p, *len, *cap); 0 or -ENOMEM */
static inline int append_u32(uint32_t **p, size_t *len, size_t *cap, const uint32_t *src, size_t n)
{
    if (reserve((void **)p, cap, *len + n, sizeof **p)) return -ENOMEM;
    if (n) memcpy(*p + *len, src, n * sizeof *src);
    *len += n;
    return 0;
}


/* the grid cell of coordinate x: floor(x ih), ih the cell's inverse (a product, not a
 * quotient: monotonic in x all the same, which is all the grid needs), clamped to +-1e15
 * (NaN: -1e15) */
static inline int64_t cell_coord(double x, double ih)
{
    double q = x * ih;
    if (!(q > -1e15)) q = -1e15;
    if (q > 1e15) q = 1e15;
    int64_t i = (int64_t)q;
    return i - (q < (double)i);
}

/* the grid cells of box b; returns their number (as a double: it may be huge) */
static inline double cells_of(double ih, const float b[6], int64_t lo[3], int64_t hi[3])
{
    double cnt = 1;
    for (int k = 0; k < 3; k++) {
        lo[k] = cell_coord(b[k], ih);
        hi[k] = cell_coord(b[3 + k], ih);
        cnt *= (double)(hi[k] - lo[k] + 1);
    }
    return cnt;
}

static inline bool same_key(const int64_t a[3], const int64_t b[3])
{
    return a[0] == b[0] && a[1] == b[1] && a[2] == b[2];
}

static inline uint64_t key_hash(int64_t x, int64_t y, int64_t z)
{
    uint64_t h = (uint64_t)x * 0x9E3779B97F4A7C15ull ^ (uint64_t)y * 0xC2B2AE3D27D4EB4Full ^
                 (uint64_t)z * 0x165667B19E3779F9ull;
    return h ^ (h >> 29);
}

/* box b's largest side, in double */
static inline double box_extent(const float b[6])
{
    return fmax(fmax((double)b[3] - b[0], (double)b[4] - b[1]), (double)b[5] - b[2]);
}

/* box b grown by m on every side into out */
static inline void box_grown(const float b[6], float m, float out[6])
{
    for (int i = 0; i < 3; i++) {
        out[i] = b[i] - m;
        out[3 + i] = b[3 + i] + m;
    }
}

static inline bool box_holds(const float *outer, const float *inner)
{
    return outer[0] <= inner[0] && outer[1] <= inner[1] && outer[2] <= inner[2] &&
           inner[3] <= outer[3] && inner[4] <= outer[4] && inner[5] <= outer[5];
}

/* bitwise, as memcmp (inline: three words) */
static inline bool vert_differs(const float *a, const float *b, size_t v)
{
    uint32_t x[3], y[3];
    memcpy(x, a + 3 * v, sizeof x);
    memcpy(y, b + 3 * v, sizeof y);
    return ((x[0] ^ y[0]) | (x[1] ^ y[1]) | (x[2] ^ y[2])) != 0;
}

/* two triangles given by their welded vertices share one (nine compares, no branch: most
 * boxes that meet in a leaf are neighbours', so a branch each was mispredicted often) */
static inline bool welded_adjacent(const uint32_t a[3], const uint32_t b[3])
{
    return ((a[0] == b[0]) | (a[0] == b[1]) | (a[0] == b[2]) | (a[1] == b[0]) | (a[1] == b[1]) | (a[1] == b[2]) |
            (a[2] == b[0]) | (a[2] == b[1]) | (a[2] == b[2])) != 0;
}

/* Triangle v's unit normal in pos (e1 x e2 normalised, as flipped; in double, stored as
 * floats) into out, or 0 when e1 x e2 is within 1e-10 |e1|_1 |e2|_1 of 0 (degenerate: its
 * direction there is rounding), NaN or beyond float's range. e1 x e2 (double) into nd for
 * the flip test. A certificate's test (certified: 1e-4 over a unit normal) then errs only
 * towards "not facing". */
static inline void tri_normal_f(const float *pos, const uint32_t *v, float out[3], double nd[3])
{
    const float *p0 = pos + 3 * (size_t)v[0], *p1 = pos + 3 * (size_t)v[1], *p2 = pos + 3 * (size_t)v[2];
    double e1[3], e2[3];
    for (int j = 0; j < 3; j++) {
        e1[j] = (double)p1[j] - p0[j];
        e2[j] = (double)p2[j] - p0[j];
    }
    nd[0] = e1[1] * e2[2] - e1[2] * e2[1];
    nd[1] = e1[2] * e2[0] - e1[0] * e2[2];
    nd[2] = e1[0] * e2[1] - e1[1] * e2[0];
    double l1 = fabs(nd[0]) + fabs(nd[1]) + fabs(nd[2]);
    double m = 1e-10 * (fabs(e1[0]) + fabs(e1[1]) + fabs(e1[2])) * (fabs(e2[0]) + fabs(e2[1]) + fabs(e2[2]));
    if (!(l1 > m) || !(l1 < 1e30)) {
        out[0] = out[1] = out[2] = 0.f;
        return;
    }
    double il = 1 / sqrt(nd[0] * nd[0] + nd[1] * nd[1] + nd[2] * nd[2]);
    for (int j = 0; j < 3; j++) out[j] = (float)(nd[j] * il);
}

/* min and max of finite doubles, inline */
static inline double dmin(double a, double b) { return b < a ? b : a; }
static inline double dmax(double a, double b) { return b > a ? b : a; }



/* ---- what one file gives another (each defined, with its comment, in the file named) ---- */

/* contact_scan.c */
/* (fpc_flips, fpc_new_flip: above, with flips_n) */

/* contact_envelope.c: an envelope for triangle x around box (a renewal request); the
 * requests' lists; the check over the lists; the re-centring job */
int fpc_envelope(fp_contact *c, uint32_t x, const float box[6]);
int fpc_renew_lists(fp_contact *c);
long fpc_track_check(fp_contact *c, const float *s, const float *ref, bool cand_boxes, size_t *flips,
                     bool record);
int fpc_recentre(fp_contact *c);
/* contact_step.c: a carried round's carry for the held vertices mv[x .. y) (FP_JOB_CARRY) */
void fpc_carry_range(fp_contact *c, uint32_t x, uint32_t y);

/* contact_bvh.c: the hierarchy's check and its tasks */
int fpc_rec_merge(fp_contact *c);
void fpc_update_subtree(fp_contact *c, lane *ln, const float *s, const float *ref, uint32_t x, size_t cut);
int fpc_mark_range(fp_contact *c, lane *ln, const float *a, uint32_t x, uint32_t y, uint32_t z);
long fpc_node_pairs(fp_contact *c, lane *ln, const float *s, const float *ref, uint32_t x, uint32_t y,
                    bool record);
long fpc_node_self(fp_contact *c, lane *ln, const float *s, const float *ref, uint32_t x, bool record);
long fpc_tree_update(fp_contact *c, const float *s, const float *ref, bool record);
long fpc_tree_check(fp_contact *c, const float *s, const float *ref, size_t *flips, bool record,
                    bool *accepted);

/* contact_cluster.c: the hierarchy's building (its median split, as the k-d tree's: fp_select.h) */
int fpc_tree_build(fp_contact *c, struct track *k);

/* contact_track.c: the incremental state */
void fpc_track_free(struct track *k);
int fpc_track_build(fp_contact *c);
void fpc_tick(fp_contact *c);
int fpc_mark_tris(fp_contact *c, uint32_t v);
long fpc_own_flips(fp_contact *c, const float *s, const float *ref, bool record);
int fpc_collect_moved(fp_contact *c, const float *a, const uint32_t *ranges, size_t nranges);
int fpc_collect_mark(fp_contact *c, const float *a, const uint32_t *ranges, size_t nranges);
int fpc_add_off(fp_contact *c, const uint32_t *v);

/* contact_worker.c: the worker's jobs (FP_JOB_*) */
void fpc_pool_free(pool *p);
pool *fpc_pool_get(fp_contact *c);
int fpc_job_open(fp_contact *c, pool *p, int kind, const float *s, const float *ref, bool record);
void fpc_add_task(fp_contact *c, pool *p, uint32_t x, uint32_t y, uint32_t z);
void fpc_job_finish(fp_contact *c, pool *p);
long fpc_lanes_sum(const struct track *k, bool flips);
void fpc_bg_post(fp_contact *c);
void fpc_bg_join(fp_contact *c);

#endif
