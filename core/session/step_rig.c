/* Step 4 of the frame: the rig (a pass-through until the rigs issue attaches one). */
#include "step_rig.h"

const fp_control_set *fp_rig_step_run(fp_rig_step *st, const fp_control_set *cs)
{
    (void)st;
    return cs;
}
