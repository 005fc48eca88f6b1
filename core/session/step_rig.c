/* Step 4 of the frame: the rig (step_rig.h). */
#include "step_rig.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* slopes takes the posed base on the ranges a commit left to it (slope_pend) */
static void slopes_take(fp_rig_step *st)
{
    if (!st->slope_npend) return;
    fp_rig_slope_index_update_ranges(st->slopes, st->posed, st->slope_pend, st->slope_npend);
    st->slope_npend = 0;
}

static void refresh_view(fp_rig_step *st)
{
    for (size_t i = 0; i < st->view.landmark_count; i++)
        memcpy(st->landmarks[i].position, &st->posed[3 * st->landmarks[i].vertex], sizeof(float[3]));
    for (size_t i = 0; i < st->view.channel_count; i++) st->channels[i].value = st->posed_values[i];
}

int fp_rig_step_init(fp_rig_step *st, fp_rig *rig, size_t n, const float *base)
{
    memset(st, 0, sizeof *st);
    if (!rig) return 0;
    st->rig = rig;
    st->n = n;
    size_t bytes = n * 3 * sizeof(float);
    st->posed = malloc(bytes);
    st->shown = malloc(bytes);
    st->commit = malloc(bytes);
    if (!st->posed || !st->shown || !st->commit || fp_rig_slope_index_create(rig, &st->slopes)) {
        fp_rig_step_free(st);
        return -ENOMEM;
    }
    fp_rig_step_neutral(st);
    st->dirty = true;
    st->max_displacement = fp_rig_max_finger_displacement(rig);
    st->cs.start = st->start;
    st->cs.end = st->end;
    fp_rig_view *v = &st->view;
    v->size = sizeof *v;
    v->name = fp_rig_name(rig);
    v->mm_per_unit = fp_rig_mm_per_unit(rig);
    fp_rig_axes(rig, v->up, v->forward, v->left);
    v->vertex_count = n;
    v->region = fp_rig_vertex_kinds(rig); /* FP_RIG_* == fp_rig_region */
    v->landmark_count = fp_rig_landmark_count(rig);
    for (size_t i = 0; i < v->landmark_count; i++)
        fp_rig_landmark_get(rig, i, &st->landmarks[i].name, &st->landmarks[i].vertex);
    v->landmarks = st->landmarks;
    v->channel_count = fp_rig_channel_count(rig);
    for (size_t i = 0; i < v->channel_count; i++) {
        fp_rig_channel_desc d;
        fp_rig_channel_get(rig, i, &d);
        st->channels[i] = (fp_rig_channel_info){d.name, d.min, d.max, d.neutral, d.neutral};
        snprintf(st->applied[i].name, sizeof st->applied[i].name, "%s", d.name); /* <= FP_RIG_NAME_MAX */
    }
    v->channels = st->channels;
    fp_rig_hinge(rig, v->hinge[0], v->hinge[1], NULL, NULL);
    fp_rig_step_update(st, NULL, base, NULL);
    /* the blend of an engine output that equals the posed base (the session's output buffer
     * starts as a copy of it), so the first gesture blends its touched ranges only; and
     * every page of the commit buffer touched now, not in a frame (a ranged commit writes
     * a few scattered pages; a first touch costs a page fault each) */
    fp_rig_apply_mobility(rig, st->posed, st->posed, st->shown);
    st->shown_valid = true;
    memcpy(st->commit, base, bytes);
    return 0;
}

void fp_rig_step_free(fp_rig_step *st)
{
    fp_rig_slope_index_destroy(&st->slopes);
    free(st->slope_pend);
    fp_rig_free(&st->rig);
    free(st->posed);
    free(st->shown);
    free(st->commit);
    st->posed = st->shown = st->commit = NULL;
}

int fp_rig_step_set_channel(fp_rig_step *st, const char *name, float value)
{
    long i = st->rig ? fp_rig_channel_index(st->rig, name) : -ENOENT;
    if (i < 0) return -ENOENT;
    if (isnan(value)) return -ERANGE;
    fp_rig_channel_desc d;
    fp_rig_channel_get(st->rig, (size_t)i, &d);
    st->values[i] = fminf(d.max, fmaxf(d.min, value));
    return 0;
}

float fp_rig_step_channel(const fp_rig_step *st, const char *name)
{
    long i = st->rig ? fp_rig_channel_index(st->rig, name) : -ENOENT;
    return i < 0 ? NAN : st->values[i];
}

void fp_rig_step_neutral(fp_rig_step *st)
{
    for (size_t i = 0; st->rig && i < fp_rig_channel_count(st->rig); i++) {
        fp_rig_channel_desc d;
        fp_rig_channel_get(st->rig, i, &d);
        st->values[i] = d.neutral;
    }
}

void fp_rig_step_base_changed(fp_rig_step *st) { st->dirty = true; }

static void report_unknown(fp_rig_step *st, const char *name, const fp_slog *log)
{
    for (size_t k = 0; k < st->unknown_count; k++)
        if (!strncmp(st->unknown[k], name, sizeof st->unknown[k] - 1)) return;
    if (st->unknown_count < FP_RIG_STEP_UNKNOWN)
        snprintf(st->unknown[st->unknown_count++], sizeof st->unknown[0], "%s", name);
    fp_slog_printf(log, FP_LOG_WARNING, "rig", "%s: the mapping drives channel \"%.31s\", which the rig does not have; ignored",
                   fp_rig_source(st->rig), name);
}

bool fp_rig_step_update(fp_rig_step *st, const fp_control_set *cs, const float *base, const fp_slog *log)
{
    if (!st->rig) return false;
    for (size_t k = 0; cs && cs->channels && k < cs->channel_count; k++) {
        char name[sizeof cs->channels[k].name];
        memcpy(name, cs->channels[k].name, sizeof name);
        name[sizeof name - 1] = '\0';
        int rc = fp_rig_step_set_channel(st, name, cs->channels[k].value);
        if (rc == -ENOENT) report_unknown(st, name, log);
        if (rc == -ERANGE && !st->nan_said) { /* (before: ignored without a word) */
            st->nan_said = true;
            fp_slog_printf(log, FP_LOG_WARNING, "rig", "%s: the mapping drives channel \"%.31s\" with "
                           "a value that is not a number; ignored (the channel keeps its value; said once)",
                           fp_rig_source(st->rig), name);
        }
    }
    size_t nc = fp_rig_channel_count(st->rig);
    if (!st->dirty && !memcmp(st->values, st->posed_values, nc * sizeof(float))) return false;
    fp_rig_pose(st->rig, base, st->values, st->posed);
    fp_rig_slope_index_set(st->slopes, st->posed); /* O(slope vertices), under the pose's O(n) */
    st->slope_npend = 0;                           /* (the whole posed base taken) */
    st->shown_valid = false;
    memcpy(st->posed_values, st->values, nc * sizeof(float));
    st->dirty = false;
    refresh_view(st);
    return true;
}

const float *fp_rig_step_posed(const fp_rig_step *st, const float *base)
{
    return st->rig ? st->posed : base;
}

const fp_control_set *fp_rig_step_run(fp_rig_step *st, const fp_control_set *cs)
{
    if (!st->rig) return cs;
    fp_control_set *o = &st->cs;
    float (*start)[3] = o->start, (*end)[3] = o->end;
    *o = *cs;
    o->start = start;
    o->end = end;
    /* the channels as posed, all of them: what a take records and plays back */
    o->channels = st->applied;
    o->channel_count = o->channel_capacity = st->view.channel_count;
    for (size_t i = 0; i < o->channel_count; i++) st->applied[i].value = st->posed_values[i];
    o->count = cs->count < FP_RIG_STEP_MAX_CONTROL ? cs->count : FP_RIG_STEP_MAX_CONTROL;
    o->capacity = FP_RIG_STEP_MAX_CONTROL;
    slopes_take(st);
    for (size_t i = 0; i < o->count; i++) {
        /* the rig's bound by direction (fp_rig.h): only a push toward a bone the segment's
         * supports reach is cut; the engine composes injective maps for the rest */
        memcpy(start[i], cs->start[i], sizeof start[i]);
        fp_rig_finger_clamp_indexed(st->slopes, cs->start[i], cs->end[i], cs->radius, end[i]);
    }
    return o;
}

const float *fp_rig_step_finish(fp_rig_step *st, const float *deformed, const uint32_t *ranges,
                                size_t nranges)
{
    if (!st->rig) return deformed;
    if (nranges == SIZE_MAX || !st->shown_valid) {
        fp_rig_apply_mobility(st->rig, st->posed, deformed, st->shown);
        st->shown_valid = true;
        return st->shown;
    }
    /* elsewhere deformed is posed now and was at the last call: shown holds its blend */
    for (size_t r = 0; r < nranges; r++)
        fp_rig_apply_mobility_range(st->rig, st->posed, deformed, st->shown, ranges[2 * r], ranges[2 * r + 1]);
    return st->shown;
}

const float *fp_rig_step_commit_shape(fp_rig_step *st, const float *base, const float *shown)
{
    if (!st->rig) return shown;
    fp_rig_unpose_range(st->rig, base, st->posed, st->posed_values, shown, st->commit, 0, st->n);
    return st->commit;
}

const float *fp_rig_step_commit_ranges(fp_rig_step *st, const float *base, const float *shown,
                                       const uint32_t *ranges, size_t nranges)
{
    if (!st->rig) return shown;
    for (size_t r = 0; r < nranges; r++)
        fp_rig_unpose_range(st->rig, base, st->posed, st->posed_values, shown, st->commit, ranges[2 * r],
                            ranges[2 * r + 1]);
    return st->commit;
}

bool fp_rig_step_posed_current(const fp_rig_step *st)
{
    return st->rig && !st->dirty &&
           !memcmp(st->values, st->posed_values, fp_rig_channel_count(st->rig) * sizeof(float));
}

void fp_rig_step_rebase_ranges(fp_rig_step *st, const float *base, float *deformed, const uint32_t *ranges,
                               size_t nranges)
{
    if (!st->rig) return;
    for (size_t r = 0; r < nranges; r++) {
        size_t v0 = ranges[2 * r], c = ranges[2 * r + 1];
        fp_rig_pose_range(st->rig, base, st->posed_values, st->posed, v0, c);
        memcpy(deformed + 3 * v0, st->posed + 3 * v0, 3 * c * sizeof(float));
        if (st->shown_valid) fp_rig_apply_mobility_range(st->rig, st->posed, deformed, st->shown, v0, c);
    }
    /* the slope index later (slopes_take): its scattered writes are not the commit's */
    slopes_take(st);
    if (nranges > st->slope_pend_cap) {
        uint32_t *q = realloc(st->slope_pend, 2 * nranges * sizeof *q);
        if (q) {
            st->slope_pend = q;
            st->slope_pend_cap = nranges;
        }
    }
    if (nranges <= st->slope_pend_cap) {
        if (nranges) memcpy(st->slope_pend, ranges, 2 * nranges * sizeof *ranges);
        st->slope_npend = nranges;
    } else { /* out of memory for them: now */
        fp_rig_slope_index_update_ranges(st->slopes, st->posed, ranges, nranges);
    }
    refresh_view(st);
}

const fp_rig_view *fp_rig_step_view(fp_rig_step *st) { return st->rig ? &st->view : NULL; }
