/*
 * step_rig.h: step 4 of the frame (docs/architecture.md): the rig. The home of the rigs
 * issue: a rig (core/rig) turns channels into control vectors or morph-target weights. A
 * mapping drives rig channels through fp_control_set.channels (named scalars, e.g.
 * "jaw.open" in [0, 1]; channel_count <= channel_capacity, the host's arrays).
 *
 * Today this step is a documented pass-through: no rig is attached, the control set goes to
 * the engine unchanged and the channels are not read.
 *
 * Threads: the session thread. No allocation, no I/O.
 */
#ifndef FP_STEP_RIG_H
#define FP_STEP_RIG_H

#include <facepuppet/plugin.h>

#ifdef __cplusplus
extern "C" {
#endif

/** The rig step's state (none yet; the rigs issue adds the attached rig here). */
typedef struct fp_rig_step {
    int unused;
} fp_rig_step;

/** Apply the rig to the mapping's control set and return the set the engine takes. Today:
 *  returns cs unchanged (same pointer, nothing written). */
const fp_control_set *fp_rig_step_run(fp_rig_step *st, const fp_control_set *cs);

#ifdef __cplusplus
}
#endif
#endif
