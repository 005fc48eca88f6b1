/*
 * contact_kd.h: the contact guard's k-d tree over a local scale-back's blocking vertices
 * (contact_step.c): the nearest of them to a point (the ramp's distance), and the weighted
 * sums of their motion around a point (a carried round's carry). Internal to fp_contact;
 * its own header so that tests/session/test_contact_kd.c checks it against brute force.
 *
 * Shapes: positions are float xyz triples indexed by vertex (pos[3 v + a]), in the mesh's
 * units; a tree holds the vertices it was built over, by index, and borrows pos until the
 * next build. Threads: build and moments on one thread; nearest and sums only read the tree,
 * so any number of threads may call them at once. Errors: -ENOMEM, the tree then unusable
 * until a build succeeds. Memory: the tree's own, grown as needed, freed by fpc_kd_free.
 */
#ifndef FP_CONTACT_KD_H
#define FP_CONTACT_KD_H

#include <stddef.h>
#include <stdint.h>

#define FP_KD_LEAF 8    /* vertices a leaf holds at most */
#define FP_KD_TERMS 15  /* a moment's polynomial terms (fpc_kd_sums) */

typedef struct fpc_kdnode {
    double lo[3], hi[3];                /* its vertices' box */
    uint32_t first, count, left, right; /* ix[first .. first + count); left == 0: a leaf (node
                                           0 is the root, children after their parent) */
} fpc_kdnode;

typedef struct fpc_kd {
    fpc_kdnode *node;
    size_t n, cap_node;  /* nodes now, and room */
    uint32_t *ix;        /* the vertices, in the tree's order */
    size_t nix, cap_ix;
    double *mom;         /* fpc_kd_moments: 4 x FP_KD_TERMS a node */
    size_t cap_mom;
    double o[3];         /* the moments' origin: the root's centre */
    const float *pos;    /* the positions it was built on (borrowed) */
} fpc_kd;

/** Build the tree over verts[0 .. n) (vertex indices into pos), splitting each node at the
 *  median of its box's longest side. n may be 0 (an empty tree: nearest finds nothing, sums
 *  are 0). 0 or -ENOMEM. */
int fpc_kd_build(fpc_kd *kd, const uint32_t *verts, size_t n, const float *pos);

/** The squared distance from p to the nearest of the tree's vertices when it is under
 *  bound2, else bound2 (in double, from pos's floats); the search stops at the first under
 *  enough2 (then some distance at most enough2, not always the least: -1 to find the
 *  least). *hint (a place in ix, 0 at first) seeds the search and becomes the place of the
 *  vertex found: consecutive points near one another search little. Reads only. */
double fpc_kd_nearest2(const fpc_kd *kd, const double p[3], double bound2, double enough2, uint32_t *hint);

/** Each node's moments of its vertices' motion cand - pos (cand indexed as pos), for
 *  fpc_kd_sums. 0 or -ENOMEM. */
int fpc_kd_moments(fpc_kd *kd, const float *cand);

/** At p: acc[0] = sum_j w_j and acc[1 + a] = sum_j w_j (cand_j - pos_j)[a] over the tree's
 *  vertices j, w_j = (1 - |p - pos_j|^2 / R2)^2 where |p - pos_j|^2 < R2, else 0 (the
 *  carry's weights, fp_contact.h). Exact to rounding: for a fixed p the weight is the square
 *  of a polynomial in pos_j, so a node wholly inside the sphere adds its moments
 *  (coefficients of p times its sums of the 15 terms, about o), a node wholly outside adds
 *  nothing, and only the leaves the sphere cuts are summed vertex by vertex. After
 *  fpc_kd_moments with the same cand. Reads only. */
void fpc_kd_sums(const fpc_kd *kd, const float *cand, const double p[3], double R2, double acc[4]);

/** Free the tree's memory (kd itself is the caller's); a zeroed fpc_kd is empty. */
void fpc_kd_free(fpc_kd *kd);

#endif
