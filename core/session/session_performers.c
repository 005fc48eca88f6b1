/* Each performer's hands (performers.h): the inputs' performers, each performer's pose state,
 * calibration and placement at the opening; every performer's hands built each frame, the
 * further performers' given to the mapping as fp_frame_input.extra_* (plugin.h, ABI 1.3). */
#include "session_internal.h"

#include "fp_calib_file.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <string.h>

_Static_assert(FP_SESSION_MAX_INPUTS <= sizeof(((fp_performers *)0)->of_input), "every input has a performer");
_Static_assert(FP_SESSION_MAX_INPUTS <= FP_POSE_MAX_INPUTS, "every input has its filter state");

/* The calibration=FILE its inputs give performer p, read into *c: 1 (a unit far from the
 * mesh's warned, as --calibration's); 0 where none gives one; or the code: the file's
 * (fp_calib_file.h), -EINVAL where two of its inputs name two files (err names the SPEC). */
static int own_calibration(fp_session *s, const fp_session_options *opt, size_t p, fp_calibration *c,
                           char *err, size_t errlen)
{
    size_t first = s->input_count;
    for (size_t i = 0; i < s->input_count; i++) {
        if (s->performers.of_input[i] != p || !s->inputs[i].calibration[0]) continue;
        if (first == s->input_count) first = i;
        else if (strcmp(s->inputs[i].calibration, s->inputs[first].calibration))
            return fp_errorf(err, errlen, -EINVAL, "input '%s': calibration=%s: its performer is placed by "
                             "calibration=%s already (input %zu); one calibration a performer", opt->inputs[i],
                             s->inputs[i].calibration, s->inputs[first].calibration, first + 1);
    }
    if (first == s->input_count) return 0;
    char ferr[1024];
    int rc = fp_calibration_load(s->inputs[first].calibration, c, ferr, sizeof ferr);
    if (rc) return fp_errorf(err, errlen, rc, "input '%s': calibration=%s", opt->inputs[first], ferr);
    char source[1200]; /* its unit against the mesh's, as --calibration's (session_open.c) */
    snprintf(source, sizeof source, "input '%s': calibration=%s", s->inputs[first].name, s->inputs[first].calibration);
    fp__session_warn_calibration_unit(s, source, c->scale, opt->mesh_path, &s->head);
    return 1;
}

/* Workspace calibration of performer p (its pose state): the mesh's unit (given, else detected
 * from the head), then the calibration (its inputs' calibration=FILE; else, past the first,
 * its own by name in opt->performer_calibrations; else given: every performer's; else the
 * workspaces its own inputs state, or the default one, fitted life-size in front of the face;
 * placed as its hands arrive where none is stated), then the glove placement. With one
 * performer: all inputs. */
static int calibrate(fp_session *s, const fp_session_options *opt, size_t p, char *err, size_t errlen)
{
    fp_calibration c;
    int own = own_calibration(s, opt, p, &c, err, errlen);
    if (own < 0) return own;
    for (size_t k = 0; !own && p && k < opt->performer_calibration_count; k++) /* (by name) */
        if (opt->performer_calibrations[k].name &&
            !strcmp(opt->performer_calibrations[k].name, s->performers.names[p])) {
            c = opt->performer_calibrations[k].calibration;
            own = 1;
        }
    if (own) {
        fp_arrive_step_init(&s->arrive[p], FP_ARRIVE_PLACED_CALIBRATION); /* (allocates nothing) */
    } else if (opt->calibration) {
        c = *opt->calibration;
        if (!(c.scale > 0) || !isfinite(c.scale)) {
            snprintf(err, errlen, "calibration: scale must be > 0, got %g", c.scale);
            return -EINVAL;
        }
        s->head.mm_per_unit = 1.0 / c.scale;
        s->head.method = FP_HEAD_GIVEN;
        snprintf(s->head.how, sizeof s->head.how, "from the calibration");
        fp_arrive_step_init(&s->arrive[p], FP_ARRIVE_PLACED_CALIBRATION); /* (allocates nothing) */
    } else {
        fp_input *ins[FP_SESSION_MAX_INPUTS];
        size_t k = 0;
        for (size_t i = 0; i < s->input_count; i++)
            if (s->performers.of_input[i] == p) ins[k++] = s->inputs[i].input;
        float wmin[3], wmax[3];
        bool stated = fp_pose_inputs_workspace(ins, k, wmin, wmax);
        if (!stated) fp_pose_default_workspace(wmin, wmax); /* until the hands arrive */
        /* in the face's frame where it is turned (fp_calibration.face) */
        const fp_head *fh = s->canon ? &s->face_head : &s->head;
        fp_pose_fit_workspace(&c, fh->mm_per_unit, wmin, wmax, fh->min, fh->max);
        memcpy(c.face, s->face, sizeof c.face);
        /* a recording whose fingertips never move is held out, hovering; one whose
         * fingertips never come near where its range places them is brought toward the
         * face (step_arrive.h) */
        int held = stated ? fp_arrive_bring_in(&c, ins, k, s->touch_radius, fh, &s->engine, NULL, &s->log) : 0;
        if (held < 0 || fp_arrive_step_init(&s->arrive[p], stated ? FP_ARRIVE_PLACED_WORKSPACE : FP_ARRIVE_PLACED_AUTO)) {
            snprintf(err, errlen, "session: out of memory for the hands' placement");
            return -ENOMEM;
        }
        s->arrive[p].hovered = held == 1; /* (the hint's words) */
    }
    s->pose[p].calib = c;
    bool turned = fp_calibration_has_face(&c); /* (fitted here in the face's frame) */
    fp_pose_place_gloves(&s->pose[p], turned ? s->canon : s->loaded, s->n, turned ? &s->face_head : &s->head);
    return 0;
}

int fp__session_performers_open(fp_session *s, const fp_session_options *opt, char *err, size_t errlen)
{
    int rc = fp_performers_assign(&s->performers, s->inputs, s->input_count, opt->inputs, err, errlen);
    if (rc) return rc;
    for (size_t p = 1; p < s->performers.count; p++) /* ([0] at open_steps, as before) */
        fp_pose_init(&s->pose[p], opt->hand_size, NULL);
    for (size_t p = 0; p < s->performers.count; p++)
        if ((rc = calibrate(s, opt, p, err, errlen))) return rc;
    if (s->performers.count < 2) return 0;
    char line[1024] = "", who[64];
    for (size_t p = 0; p < s->performers.count; p++) {
        size_t used = strlen(line);
        snprintf(line + used, sizeof line - used, "%s%s:", p ? "; " : "",
                 fp_performers_label(&s->performers, p, who, sizeof who));
        for (size_t i = 0; i < s->input_count; i++) {
            if (s->performers.of_input[i] != p) continue;
            used = strlen(line);
            snprintf(line + used, sizeof line - used, " %s (input %zu)", s->inputs[i].name, i + 1);
        }
        /* the placement's lines and hints name whose hands */
        snprintf(s->arrive[p].who, sizeof s->arrive[p].who, "%s: ", who);
    }
    fp_slog_printf(&s->log, FP_LOG_INFO, "session", "%zu performers, each with a left and a right hand "
                   "of their own: %s", s->performers.count, line);
    return 0;
}

void fp__session_performers_build(fp_session *s, int64_t now_ns)
{
    for (size_t p = 0; p < s->performers.count; p++) {
        bool turned = fp_calibration_has_face(&s->pose[p].calib); /* (fitted in the face's frame) */
        /* a gesture held only on skin the rig keeps still (a fingertip that came to the skull
         * while the placement was provisional) does not hold the placement; where the placement
         * then moves the hands, that gesture, made under the old one, is let go (cancelled: it
         * moved nothing), and the mapping grabs again from where the hands are now */
        fp_calibration was = s->pose[p].calib;
        fp_arrive_step_place(&s->arrive[p], &s->pose[p], s->engaged && !s->engaged_still,
                             turned ? &s->face_head : &s->head, s->touch_radius, &s->engine, &s->log);
        if (s->engaged && s->engaged_still && memcmp(&was, &s->pose[p].calib, sizeof was)) {
            fp_intents_request(&s->intents, FP_INTENT_CANCEL);
            s->engaged_still = false; /* (once: the cancel ends it) */
        }
        fp_pose_build_at(&s->pose[p], now_ns);
    }
}

void fp__session_performers_frame(fp_session *s, fp_frame_input *in, float reach)
{
    memcpy(in->hands, s->pose[0].poses, sizeof in->hands);
    fp_engine_step_tip_distances(&s->engine, s->pose[0].poses, reach, in->tip_distance);
    in->extra_performers = (uint32_t)(s->performers.count - 1);
    if (!in->extra_performers) return; /* (NULL arrays: plugin.h) */
    for (size_t p = 1; p < s->performers.count; p++) {
        memcpy(&s->extra_hands[FP_HANDS * (p - 1)], s->pose[p].poses, sizeof s->pose[p].poses);
        fp_engine_step_tip_distances(&s->engine, s->pose[p].poses, reach, &s->extra_tips[FP_HANDS * (p - 1)]);
    }
    in->extra_hands = s->extra_hands;
    in->extra_tip_distance = (const float (*)[FP_FINGERS])s->extra_tips;
}

void fp__session_performers_check(fp_session *s, int64_t now_ns, const fp_frame_input *in)
{
    for (size_t p = 0; p < s->performers.count; p++) {
        const fp_hand_pose *hands = p ? &s->extra_hands[FP_HANDS * (p - 1)] : in->hands;
        const float (*tips)[FP_FINGERS] = p ? (const float (*)[FP_FINGERS])&s->extra_tips[FP_HANDS * (p - 1)]
                                            : (const float (*)[FP_FINGERS])in->tip_distance;
        fp_arrive_step_check(&s->arrive[p], now_ns, hands, tips, s->cs.active, s->touch_radius,
                             s->head.mm_per_unit, &s->engine, &s->log);
    }
}
