/* facepuppet pose: the mesh posed by its rig's channels, without hands (for rig authors and
 * checks). Also fp_app_rig_info(), the `facepuppet info RIG.json` description. */
#define _GNU_SOURCE
#include "app_getopt.h"
#include "app_util.h"
#include "command.h"
#include "fp_mesh.h"
#include "fp_rig.h"

#include <errno.h>
#include <getopt.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static void pose_usage(FILE *f)
{
    fprintf(f, "usage: facepuppet pose --mesh MESH [--rig RIG.json] --set NAME=VALUE [--set ...] --out FILE\n"
               "                      [--force]\n\n"
               "Writes the mesh posed by its rig (the jaw about its hinge, the soft tissue by the\n"
               "rig's falloff), without hands. Without --rig the rig is found among the rig files\n"
               "(by the mesh's checksum, else its vertex count, else as the rig's own mesh\n"
               "split at seams, by its vertices' positions): $FACEPUPPET_RIGS, else\n"
               "<bin>/../share/facepuppet/rigs when installed, else the source tree's rigs/.\n"
               "Values outside a channel's range are refused. The output format follows FILE's\n"
               "extension (OBJ, PLY, OFF, STL, glTF, GLB); it is written atomically, and an\n"
               "existing FILE is refused before any work unless --force.\n"
               "  -m, --mesh MESH        the face\n"
               "  -r, --rig RIG.json     its rig (default: found by the mesh)\n"
               "  -s, --set NAME=VALUE   a channel's value (jaw.open=0.5)\n"
               "  -o, --out FILE         the posed mesh\n"
               "      --force            overwrite FILE when it exists\n"
               "  -h, --help             this text\n\n"
               "Exit status: 0 written, 64 usage (a value out of range), 65 bad mesh or rig,\n"
               "66 missing, 73 FILE not writable or existing without --force.\n");
}

static int pose_main(int argc, char **argv)
{
    static const struct option opts[] = {{"mesh", required_argument, NULL, 'm'},
                                         {"rig", required_argument, NULL, 'r'},
                                         {"set", required_argument, NULL, 's'},
                                         {"out", required_argument, NULL, 'o'},
                                         {"help", no_argument, NULL, 'h'},
                                         {"force", no_argument, NULL, 'F'},
                                         {NULL, 0, NULL, 0}};
    const char *mesh_path = NULL, *rig_path = NULL, *out_path = NULL;
    bool force = false;
    const char *sets[FP_RIG_MAX_CHANNELS];
    size_t nsets = 0;
    optind = 1;
    for (int c; (c = fp_app_getopt(argc, argv, "m:r:s:o:h", opts)) != -1;) {
        switch (c) {
        case 'm': mesh_path = optarg; break;
        case 'r': rig_path = optarg; break;
        case 'o': out_path = optarg; break;
        case 'F': force = true; break;
        case 's':
            if (nsets == FP_RIG_MAX_CHANNELS) {
                fprintf(stderr, "facepuppet pose: more than %d --set\n", FP_RIG_MAX_CHANNELS);
                return FP_EXIT_USAGE;
            }
            sets[nsets++] = optarg;
            break;
        case 'h': pose_usage(stdout); return FP_EXIT_OK;
        default: pose_usage(stderr); return FP_EXIT_USAGE;
        }
    }
    if (!mesh_path || !out_path || optind != argc) {
        fprintf(stderr, "facepuppet pose: %s\n\n", !mesh_path ? "--mesh FILE is required"
                        : !out_path ? "--out FILE is required" : "unexpected argument (see below)");
        pose_usage(stderr);
        return FP_EXIT_USAGE;
    }
    if (rig_path && !strcmp(rig_path, "none")) { /* (run's word for no rig; pose needs one) */
        fprintf(stderr, "facepuppet pose: --rig none: pose moves a rig's channels, it needs a rig "
                        "(give RIG.json, or leave --rig out to find one by the mesh's checksum)\n");
        return FP_EXIT_USAGE;
    }
    int oc = fp_app_check_mesh_name("facepuppet pose", "--out", out_path);
    if (!oc) oc = fp_app_check_new_output("facepuppet pose", "--out", out_path, force);
    if (oc) return oc;
    char err[2048];
    fp_mesh *m = NULL;
    int rc = fp_app_load_mesh("facepuppet pose", false, mesh_path, &m, err, sizeof err);
    if (rc != FP_MESH_OK) {
        fprintf(stderr, "facepuppet pose: %s\n", err);
        return fp_app_exit_code(rc, FP_APP_INPUT);
    }
    char found[4096], root[4096];
    uint32_t *split = NULL; /* the mesh is the rig's own, split at seams: its vertices' rig vertices */
    if (!rig_path) {
        char dir[4096];
        fp_rig_default_dir(fp_app_exe_dir(), dir, sizeof dir);
        rc = fp_rig_find(dir, m->vertex_count, m->positions, found, sizeof found, err, sizeof err);
        if (rc == -ENOENT && fp_app_data_root(root, sizeof root) &&
            fp_rig_find_split(dir, root, m->vertex_count, m->positions, found, sizeof found, &split,
                              NULL, 0) == 0)
            rc = 0;
        if (rc) {
            fprintf(stderr, "facepuppet pose: %s\n", err);
            fp_mesh_free(&m);
            return FP_EXIT_NOINPUT;
        }
        rig_path = found;
    }
    fp_rig *rig = NULL;
    if (split) { /* as the session does (fp_session_options.rig_mesh_root) */
        rc = fp_rig_load(rig_path, &rig, err, sizeof err);
        if (!rc) rc = fp_rig_remap(rig, m->vertex_count, split, m->positions, err, sizeof err);
        if (!rc) rc = fp_rig_bind(rig, m->vertex_count, m->positions, err, sizeof err);
        if (rc) fp_rig_free(&rig);
        free(split);
    } else {
        rc = fp_rig_load_for_mesh(rig_path, m->vertex_count, m->positions, &rig, err, sizeof err);
    }
    if (!rc && (rc = fp_rig_unfold_jaw(rig, m->positions, m->triangles, m->triangle_count, NULL)))
        snprintf(err, sizeof err, "%.1000s: out of memory for the jaw weights", rig_path);
    if (rc) {
        fprintf(stderr, "facepuppet pose: %s\n", err);
        fp_mesh_free(&m);
        return fp_app_exit_code(rc, FP_APP_INPUT);
    }
    float values[FP_RIG_MAX_CHANNELS];
    fp_rig_channel_values(rig, NULL, NULL, 0, values);
    int status = FP_EXIT_OK;
    for (size_t i = 0; i < nsets && status == FP_EXIT_OK; i++) {
        char name[64];
        const char *eq = strchr(sets[i], '=');
        double v = 0;
        if (!eq || (size_t)(eq - sets[i]) >= sizeof name || !fp_parse_decimal(eq + 1, &v)) {
            fprintf(stderr, "facepuppet pose: --set %s: expected NAME=NUMBER\n", sets[i]);
            status = FP_EXIT_USAGE;
            break;
        }
        memcpy(name, sets[i], (size_t)(eq - sets[i]));
        name[eq - sets[i]] = '\0';
        rc = fp_rig_channel_check(rig, name, v, err, sizeof err);
        if (rc) {
            fprintf(stderr, "facepuppet pose: --set %s: %s\n", sets[i], err);
            status = FP_EXIT_USAGE;
            break;
        }
        values[fp_rig_channel_index(rig, name)] = (float)v;
    }
    if (status == FP_EXIT_OK) {
        fp_rig_pose(rig, m->positions, values, m->positions);
        fp_mesh_compute_normals(m);
        rc = fp_mesh_save(m, out_path, err, sizeof err);
        if (rc != FP_MESH_OK) {
            fprintf(stderr, "facepuppet pose: %s\n", err);
            remove(out_path); /* nothing half-written */
            status = FP_EXIT_CANTCREAT;
        }
    }
    fp_rig_free(&rig);
    fp_mesh_free(&m);
    return status;
}

int fp_app_rig_info(const char *path)
{
    char err[2048];
    fp_rig *rig = NULL;
    int rc = fp_rig_load(path, &rig, err, sizeof err);
    if (rc) {
        fprintf(stderr, "facepuppet info: %s\n", err);
        return fp_app_exit_code(rc, FP_APP_INPUT);
    }
    fp_mesh *m = NULL;
    char mp[4096] = "";
    if (fp_rig_mesh_name(rig)[0]) {
        char rootbuf[4096];
        const char *root = fp_app_data_root(rootbuf, sizeof rootbuf); /* none: no mesh */
        if (root) {
            snprintf(mp, sizeof mp, "%s/%s", root, fp_rig_mesh_name(rig));
            if (fp_mesh_load(mp, &m, err, sizeof err) != FP_MESH_OK) m = NULL;
        }
    }
    int status = FP_EXIT_OK;
    if (m) {
        rc = fp_rig_bind(rig, m->vertex_count, m->positions, err, sizeof err);
        if (rc) status = FP_EXIT_DATAERR;
    }
    size_t need = fp_rig_describe(rig, m ? m->vertex_count : 0, m ? m->positions : NULL, NULL, 0);
    char *buf = malloc(need + 1);
    if (buf) {
        fp_rig_describe(rig, m ? m->vertex_count : 0, m ? m->positions : NULL, buf, need + 1);
        fputs(buf, stdout);
        free(buf);
    }
    if (m) printf("  mesh file  %s: %s\n", mp, status == FP_EXIT_OK ? "loaded, the rig binds" : err);
    else printf("  mesh file  not found (%s): not checked against positions\n", mp[0] ? mp : "none named");
    fp_mesh_free(&m);
    fp_rig_free(&rig);
    return status;
}

const fp_command fp_command_pose = {"pose", "write a mesh posed by its rig's channels (jaw.open)", pose_main};
