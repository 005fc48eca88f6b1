/* fp_select.c: the median split of index lists by a coordinate (fp_select.h). */
#include "fp_select.h"

/* order[lo .. hi) partially sorted so that order[mid] has the mid-th key on axis a (keys
 * key[3 item + a], 3 per item: a cluster's mean centroid, a vertex's position; Hoare
 * partitions, median of three) */
void fp_select_mid(uint32_t *order, size_t lo, size_t hi, size_t mid, int a, const float *key)
{
#define KEY(i) key[3 * (size_t)order[i] + a]
    while (hi - lo > 1) {
        size_t m = lo + (hi - lo) / 2;
        float x = KEY(lo), y = KEY(m), z = KEY(hi - 1);
        float piv = x < y ? (y < z ? y : (x < z ? z : x)) : (x < z ? x : (y < z ? z : y));
        size_t i = lo, j = hi - 1;
        for (;;) {
            while (KEY(i) < piv) i++;
            while (piv < KEY(j)) j--;
            if (i >= j) break;
            uint32_t tmp = order[i];
            order[i] = order[j];
            order[j] = tmp;
            i++;
            j--;
        }
        if (i == j) { /* [lo, j) <= piv == order[j] <= (j, hi): order[j] is in place */
            if (mid == j) return;
            if (mid < j) hi = j;
            else lo = j + 1;
            continue;
        }
        /* i > j: [lo, j] <= piv <= [j + 1, hi), both sides non-empty */
        if (mid <= j) hi = j + 1;
        else lo = j + 1;
    }
#undef KEY
}
