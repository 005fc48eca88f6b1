/* fp_take_player: the frame loop of play and export (fp_take_player.h). */
#include "fp_take_player.h"
#include "fp_stack_player.h"
#include "fp_session_take.h"
#include "fp_error.h"
#include "fp_mesh.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

struct fp_take_player {
    fp_stack_player *stack;    /* a stack: its base layer's player does the rest */
    fp_take_reader *reader;
    fp_session *session;
    const char *mesh;
};

int fp_take_player_open(const char *take_path, const char *mesh_path,
                        const fp_plugin_path *plugin_path, fp_take_player **out, char *err,
                        size_t errlen)
{
    return fp_take_player_open_logged(take_path, mesh_path, plugin_path, NULL, NULL, out, err,
                                      errlen);
}

int fp_take_player_open_logged(const char *take_path, const char *mesh_path,
                               const fp_plugin_path *plugin_path, fp_session_log_fn log,
                               void *log_user, fp_take_player **out, char *err, size_t errlen)
{
    if (out)
        *out = NULL;
    if (!take_path || !out)
        return fp_errorf(err, errlen, -EINVAL, "play: no take");
    fp_take_player *p = calloc(1, sizeof *p);
    if (!p)
        return fp_errorf(err, errlen, -ENOMEM, "play: out of memory");
    if (fp_stack_is_stack_path(take_path)) {
        int rc = fp_stack_player_open(take_path, mesh_path, plugin_path, log, log_user, &p->stack,
                                      err, errlen);
        if (rc) {
            free(p);
            return rc;
        }
        *out = p;
        return 0;
    }
    int rc = fp_take_reader_open(take_path, &p->reader, err, errlen);
    if (rc) {
        free(p);
        return rc;
    }
    const fp_take_header *h = fp_take_reader_header(p->reader);
    p->mesh = mesh_path ? mesh_path : h->mesh_path;
    if (!p->mesh) {
        rc = fp_errorf(err, errlen, -EINVAL, "%s names no mesh: give the mesh", take_path);
        goto fail;
    }
    /* the mesh first: the take's (checksum) before any rig is bound to it */
    {
        fp_mesh *m = NULL;
        if ((rc = fp_mesh_load(p->mesh, &m, err, errlen))) {
            if (!mesh_path && rc == -ENOENT) { /* the header's path, relative to the recording's cwd */
                char why[1024];
                snprintf(why, sizeof why, "%s", err);
                fp_errorf(err, errlen, rc, "%s: the take's mesh %s is not there from this folder "
                          "(%s): a relative path is the one given to the recording run, from the "
                          "folder it ran in; play from there or give the mesh (--mesh FILE)",
                          take_path, p->mesh, why);
            }
            goto fail;
        }
        char why[1024];
        rc = fp_take_check_positions(m->positions, m->vertex_count, p->mesh, h, why, sizeof why);
        fp_mesh_free(&m);
        if (rc) {
            fp_errorf(err, errlen, rc, "%s: %s", take_path, why);
            goto fail;
        }
    }
    /* a session on the take's mesh with no inputs; its mapping is never called */
    char radius_name[4200];
    snprintf(radius_name, sizeof radius_name, "%s: the take's radius", take_path);
    fp_session_options so = {.mesh_path = p->mesh, .mapping = "anchored", .radius = h->radius,
                             .radius_name = radius_name,
                             .plugin_path = plugin_path,
                             .rig_path = h->rig_path ? h->rig_path : "none",
                             .log = log, .log_user = log_user};
    for (int i = 0; i < 3; i++) /* (1.4: the face's axes, for the camera) */
        so.face_up[i] = (float)h->face_up[i], so.face_facing[i] = (float)h->face_facing[i];
    if ((rc = fp_session_create(&so, &p->session, err, errlen))) {
        if (h->rig_path && strstr(err, h->rig_path)) { /* the take's rig: say it is the take's */
            char why[2048];
            snprintf(why, sizeof why, "%s", err);
            fp_errorf(err, errlen, rc, "%s: the take's rig %s (the rig it was recorded with: "
                      "put it back there to play the take): %s", take_path, h->rig_path, why);
        }
        goto fail;
    }
    if ((rc = fp_session_take_check_mesh(p->session, p->mesh, h, err, errlen)))
        goto fail;
    *out = p;
    return 0;
fail:
    fp_take_player_close(&p);
    return rc;
}

int fp_take_player_next(fp_take_player *p, fp_take_frame *frame, fp_frame_stats *st,
                        char *err, size_t errlen)
{
    if (p->stack)
        return fp_stack_player_next(p->stack, frame, st, err, errlen);
    int rc = fp_take_reader_next(p->reader, frame, err, errlen);
    if (rc != 1)
        return rc;
    fp_frame_stats local;
    fp_session_play_frame(p->session, frame, st ? st : &local);
    return 1;
}

/* The player that holds the session and reader: a stack's base layer's, or p. */
static const fp_take_player *own(const fp_take_player *p)
{
    return p->stack ? fp_stack_player_base(p->stack) : p;
}

fp_session *fp_take_player_session(fp_take_player *p) { return own(p)->session; }
fp_take_reader *fp_take_player_reader(fp_take_player *p) { return own(p)->reader; }
const fp_take_header *fp_take_player_header(const fp_take_player *p)
{
    return fp_take_reader_header(own(p)->reader);
}
const char *fp_take_player_mesh_path(const fp_take_player *p) { return own(p)->mesh; }
fp_stack_player *fp_take_player_stack(fp_take_player *p) { return p->stack; }

const float *fp_take_player_positions(const fp_take_player *p)
{
    return p->stack ? fp_stack_player_positions(p->stack) : fp_session_positions(p->session);
}

int fp_take_player_save(const fp_take_player *p, const char *path, unsigned *dropped, char *err,
                        size_t errlen)
{
    const fp_session *s = own(p)->session;
    if (!p->stack)
        return fp_session_save_ex(s, path, dropped, err, errlen);
    fp_mesh out = *fp_session_mesh(s);
    out.positions = (float *)fp_stack_player_positions(p->stack);
    out.normals = malloc(out.vertex_count * 3 * sizeof(float));
    if (!out.normals)
        return fp_errorf(err, errlen, -ENOMEM, "%s: out of memory", path);
    fp_mesh_compute_normals(&out);
    int rc = fp_mesh_save_ex(&out, path, dropped, err, errlen);
    free(out.normals);
    return rc;
}

double fp_take_player_mm_per_unit(const fp_take_player *p)
{
    p = own(p);
    const fp_take_header *h = fp_take_reader_header(p->reader);
    for (int k = 0; k < FP_HANDS; k++)
        if (h->calibration[k].present && h->calibration[k].scale > 0)
            return 1.0 / h->calibration[k].scale;
    const fp_head *head = fp_session_head(p->session);
    return head && head->mm_per_unit > 0 ? head->mm_per_unit : 1.0;
}

void fp_take_player_close(fp_take_player **pp)
{
    if (!pp || !*pp)
        return;
    fp_take_player *p = *pp;
    fp_stack_player_close(&p->stack);
    fp_session_destroy(&p->session);
    fp_take_reader_close(&p->reader);
    free(p);
    *pp = NULL;
}
