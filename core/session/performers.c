/* Whose hands are whose: each input's performer (performers.h). */
#include "performers.h"

#include <errno.h>
#include <stdio.h>
#include <string.h>

/* The index of the performer named `name` ("" : the unnamed first), or count where none. */
static size_t find(const fp_performers *p, const char *name)
{
    for (size_t i = 0; i < p->count; i++)
        if (!strcmp(p->names[i], name)) return i;
    return p->count;
}

int fp_performers_assign(fp_performers *p, const fp_input_instance *inputs, size_t n,
                         const char *const *specs, char *err, size_t errlen)
{
    memset(p, 0, sizeof *p);
    p->count = 1;
    if (n > sizeof p->of_input) n = sizeof p->of_input;
    if (n) snprintf(p->names[0], sizeof p->names[0], "%s", inputs[0].performer);
    for (size_t i = 0; i < n; i++) {
        const char *name = inputs[i].performer;
        size_t k = name[0] ? find(p, name) : 0; /* no name: the first performer's */
        if (k == p->count) {
            if (p->count == FP_PERFORMER_CAPACITY) {
                char have[FP_PERFORMER_CAPACITY * (FP_PERFORMER_NAME_MAX + 4) + 32] = "";
                for (size_t j = 0; j < p->count; j++) {
                    size_t used = strlen(have);
                    snprintf(have + used, sizeof have - used, "%s%s", j ? ", " : "",
                             p->names[j][0] ? p->names[j] : "(the first, unnamed)");
                }
                return fp_errorf(err, errlen, -EINVAL, "input '%s': performer=%s: at most %d performers "
                                 "share a session (%s so far)", specs && specs[i] ? specs[i] : inputs[i].name,
                                 name, FP_PERFORMER_CAPACITY, have);
            }
            snprintf(p->names[k], sizeof p->names[k], "%s", name);
            p->count++;
        }
        p->of_input[i] = (uint8_t)k;
    }
    return 0;
}

const char *fp_performers_label(const fp_performers *p, size_t i, char *buf, size_t len)
{
    if (i < p->count && p->names[i][0]) snprintf(buf, len, "performer '%s'", p->names[i]);
    else snprintf(buf, len, "the first performer");
    return buf;
}
